//! MediaPipe's attention face mesh (`face_landmark_with_attention.tflite`, the network behind
//! MediaPipe's `refine_landmarks=True`, from the PyPI wheel `mediapipe==0.10.21`): the same
//! 192×192 RGB crop as the FaceMesh landmark network in; out the 468 mesh points, and the lips
//! (80 points), each eye's contour and brow (71) and iris (5) regressed again by small heads on
//! crops of an early feature map placed by the mesh (the network's three MediaPipe custom
//! operators, run by `visage-nn`), and the presence logit. [`AttentionLandmarks::refined`]
//! merges them into MediaPipe's 478 refined landmarks.
//!
//! The mesh indices of the heads' points are MediaPipe's
//! (`mediapipe/modules/face_landmark/tensors_to_face_landmarks_with_attention.pbtxt`). Each
//! eye's 71 points come in the iris network's order ([`crate::IrisNetwork`]'s contour: the
//! lower lid from corner to corner, the upper lid, then the halos and the brow): on the
//! reference crops, the iris network's contour mapped to the frame and the attention model's
//! points of the same eye are matched best, point for point, in that order.

use std::path::Path;

use crate::checked_network::compile_checked;
use crate::{FaceError, ModelFile, LANDMARK_INPUT, NUM_IRIS_POINTS, NUM_LANDMARKS};
use visage_nn::Network;

/// Points of the lips head.
pub const NUM_LIP_POINTS: usize = 80;
/// Points of each eye head: the eye's contour and brow (as the iris network's contour).
pub const NUM_EYE_POINTS: usize = 71;
/// MediaPipe's refined landmarks: the 468 mesh points, then the subject's right iris (468–472)
/// and left iris (473–477).
pub const NUM_REFINED_LANDMARKS: usize = NUM_LANDMARKS + 2 * NUM_IRIS_POINTS;

/// The eye points listed first of each eye's 71, the eye's contour (lower lid, then upper lid):
/// their mean mesh depth is the iris's depth in the refined landmarks.
const EYE_CONTOUR_POINTS: usize = 16;

/// Mesh index of each point of the lips head, in output order (outer lip contour, inner,
/// then the rings between them).
pub const LIPS_MESH_INDICES: [usize; NUM_LIP_POINTS] = [
    61, 146, 91, 181, 84, 17, 314, 405, 321, 375, 291, 185, 40, 39, 37, 0, 267, 269, 270,
    409, //
    78, 95, 88, 178, 87, 14, 317, 402, 318, 324, 308, 191, 80, 81, 82, 13, 312, 311, 310,
    415, //
    76, 77, 90, 180, 85, 16, 315, 404, 320, 307, 306, 184, 74, 73, 72, 11, 302, 303, 304,
    408, //
    62, 96, 89, 179, 86, 15, 316, 403, 319, 325, 292, 183, 42, 41, 38, 12, 268, 271, 272, 407,
];

/// Mesh index of each point of the subject's right eye (image left; corners 33 and 133; the
/// network's `output_left_eye`), in output order.
pub const RIGHT_EYE_MESH_INDICES: [usize; NUM_EYE_POINTS] = [
    33, 7, 163, 144, 145, 153, 154, 155, 133, 246, 161, 160, 159, 158, 157, 173, //
    130, 25, 110, 24, 23, 22, 26, 112, 243, 247, 30, 29, 27, 28, 56, 190, //
    226, 31, 228, 229, 230, 231, 232, 233, 244, 113, 225, 224, 223, 222, 221, 189, //
    35, 124, 46, 53, 52, 65, 143, 111, 117, 118, 119, 120, 121, 128, 245, //
    156, 70, 63, 105, 66, 107, 55, 193,
];

/// Mesh index of each point of the subject's left eye (image right; corners 362 and 263; the
/// network's `output_right_eye`), in output order.
pub const LEFT_EYE_MESH_INDICES: [usize; NUM_EYE_POINTS] = [
    263, 249, 390, 373, 374, 380, 381, 382, 362, 466, 388, 387, 386, 385, 384, 398, //
    359, 255, 339, 254, 253, 252, 256, 341, 463, 467, 260, 259, 257, 258, 286, 414, //
    446, 261, 448, 449, 450, 451, 452, 453, 464, 342, 445, 444, 443, 442, 441, 413, //
    265, 353, 276, 283, 282, 295, 372, 340, 346, 347, 348, 349, 350, 357, 465, //
    383, 300, 293, 334, 296, 336, 285, 417,
];

/// Output `[1, 1, 1, 1404]`: 468 × `(x, y, z)` mesh points, crop pixels.
const MESH_OUTPUT: &str = "output_mesh_identity";
/// Output `[1, 1, 1, 160]`: 80 × `(x, y)` lip points.
const LIPS_OUTPUT: &str = "output_lips";
/// Output `[1, 1, 1, 142]`: 71 × `(x, y)`, the subject's right eye (MediaPipe's model names
/// eyes by the image side).
const RIGHT_EYE_OUTPUT: &str = "output_left_eye";
/// Output `[1, 1, 1, 142]`: 71 × `(x, y)`, the subject's left eye.
const LEFT_EYE_OUTPUT: &str = "output_right_eye";
/// Output `[1, 1, 1, 10]`: 5 × `(x, y)`, the subject's right iris.
const RIGHT_IRIS_OUTPUT: &str = "output_left_iris";
/// Output `[1, 1, 1, 10]`: 5 × `(x, y)`, the subject's left iris.
const LEFT_IRIS_OUTPUT: &str = "output_right_iris";
/// Output `[1, 1, 1, 1]`: the face-presence logit.
const PRESENCE_OUTPUT: &str = "conv_faceflag";

/// Every output with its number of values.
const OUTPUTS: [(&str, usize); 7] = [
    (MESH_OUTPUT, NUM_LANDMARKS * 3),
    (LIPS_OUTPUT, NUM_LIP_POINTS * 2),
    (RIGHT_EYE_OUTPUT, NUM_EYE_POINTS * 2),
    (LEFT_EYE_OUTPUT, NUM_EYE_POINTS * 2),
    (RIGHT_IRIS_OUTPUT, NUM_IRIS_POINTS * 2),
    (LEFT_IRIS_OUTPUT, NUM_IRIS_POINTS * 2),
    (PRESENCE_OUTPUT, 1),
];

/// Raw output of the attention face mesh for one crop, in crop pixels of the crop as given
/// (`x, y ∈ [0, 192]`, left/top edge at 0, MediaPipe's convention as
/// [`crate::CropLandmarks`]). "Right" and "left" are the subject's, as in [`crate::Eye`].
#[derive(Clone, Debug, PartialEq)]
pub struct AttentionLandmarks {
    /// 468 × `(x, y, z)` mesh points; `z` relative depth with the scale of `x`.
    pub mesh: Vec<[f32; 3]>,
    /// 80 × `(x, y)` lip points, at the mesh indices [`LIPS_MESH_INDICES`].
    pub lips: Vec<[f32; 2]>,
    /// 71 × `(x, y)` points of the subject's right eye (image left), at
    /// [`RIGHT_EYE_MESH_INDICES`].
    pub right_eye: Vec<[f32; 2]>,
    /// 71 × `(x, y)` points of the subject's left eye (image right), at
    /// [`LEFT_EYE_MESH_INDICES`].
    pub left_eye: Vec<[f32; 2]>,
    /// The subject's right iris `(x, y)`: centre, then four points on its rim (refined
    /// landmarks 468–472).
    pub right_iris: [[f32; 2]; NUM_IRIS_POINTS],
    /// The subject's left iris (refined landmarks 473–477).
    pub left_iris: [[f32; 2]; NUM_IRIS_POINTS],
    /// Face-presence logit; `sigmoid(logit)` is MediaPipe's face presence score.
    pub presence_logit: f32,
}

impl AttentionLandmarks {
    /// `sigmoid(presence_logit)` ∈ [0, 1].
    pub fn presence(&self) -> f32 {
        crate::sigmoid(self.presence_logit)
    }

    /// MediaPipe's 478 refined landmarks (`LandmarksRefinementCalculator` as the attention
    /// face mesh's graph configures it), crop pixels: the 468 mesh points with `(x, y)` of the
    /// lips and both eyes replaced by their heads' points (`z` kept from the mesh), then the
    /// subject's right iris (468–472) and left iris (473–477), each at the mean mesh `z` of its
    /// eye's 16 contour points.
    pub fn refined(&self) -> Vec<[f32; 3]> {
        let mut points = self.mesh.clone();
        let heads = [
            (&self.lips, &LIPS_MESH_INDICES[..]),
            (&self.right_eye, &RIGHT_EYE_MESH_INDICES[..]),
            (&self.left_eye, &LEFT_EYE_MESH_INDICES[..]),
        ];
        for (head, indices) in heads {
            for (p, &i) in head.iter().zip(indices) {
                if let Some(q) = points.get_mut(i) {
                    q[0] = p[0];
                    q[1] = p[1];
                }
            }
        }
        let eyes = [
            (&self.right_iris, &RIGHT_EYE_MESH_INDICES),
            (&self.left_iris, &LEFT_EYE_MESH_INDICES),
        ];
        for (iris, eye) in eyes {
            let contour = &eye[..EYE_CONTOUR_POINTS];
            let z = contour
                .iter()
                .filter_map(|&i| self.mesh.get(i))
                .map(|p| p[2])
                .sum::<f32>()
                / EYE_CONTOUR_POINTS as f32;
            points.extend(iris.iter().map(|p| [p[0], p[1], z]));
        }
        points
    }
}

/// The compiled attention face mesh. Allocation-free per call except the output's vectors.
#[derive(Clone, Debug)]
pub struct AttentionNetwork {
    net: Network,
}

impl AttentionNetwork {
    /// Loads and verifies `face_landmark_with_attention.tflite` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        let bytes = ModelFile::FaceLandmarkWithAttention.read(models)?;
        Self::from_bytes(&bytes)
    }

    /// Like [`AttentionNetwork::load`], but `None` when the file is absent (the network is
    /// optional); a corrupt file is still an error.
    pub fn load_if_present(models: &Path) -> Result<Option<Self>, FaceError> {
        match Self::load(models) {
            Ok(n) => Ok(Some(n)),
            Err(FaceError::ModelMissing { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// Compiles the network from the bytes of `face_landmark_with_attention.tflite`, checking
    /// its input shape and its seven outputs' sizes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FaceError> {
        let net = compile_checked(
            ModelFile::FaceLandmarkWithAttention,
            bytes,
            LANDMARK_INPUT,
            &OUTPUTS,
        )?;
        Ok(AttentionNetwork { net })
    }

    /// The input tensor `[192, 192, 3]` (RGB in [0, 1]) to fill before
    /// [`AttentionNetwork::run`].
    pub fn input_mut(&mut self) -> &mut [f32] {
        self.net.input_mut()
    }

    /// Runs the network on the current input tensor.
    pub fn run(&mut self) -> AttentionLandmarks {
        self.net.run();
        let output = |name: &str| self.net.output_named(name).unwrap_or(&[]);
        let xy = |name: &str| -> Vec<[f32; 2]> {
            output(name).chunks_exact(2).map(|p| [p[0], p[1]]).collect()
        };
        let iris = |name: &str| {
            let mut iris = [[0.0; 2]; NUM_IRIS_POINTS];
            for (q, p) in iris.iter_mut().zip(output(name).chunks_exact(2)) {
                *q = [p[0], p[1]];
            }
            iris
        };
        AttentionLandmarks {
            mesh: output(MESH_OUTPUT)
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]])
                .collect(),
            lips: xy(LIPS_OUTPUT),
            right_eye: xy(RIGHT_EYE_OUTPUT),
            left_eye: xy(LEFT_EYE_OUTPUT),
            right_iris: iris(RIGHT_IRIS_OUTPUT),
            left_iris: iris(LEFT_IRIS_OUTPUT),
            presence_logit: output(PRESENCE_OUTPUT)
                .first()
                .copied()
                .unwrap_or(f32::NEG_INFINITY),
        }
    }

    /// Runs on an 8-bit RGB crop of 192 × 192 pixels (row-major, 3 bytes per pixel), scaled to
    /// [0, 1] as for [`crate::LandmarkNetwork::run_rgb8`].
    pub fn run_rgb8(&mut self, rgb: &[u8]) -> Result<AttentionLandmarks, FaceError> {
        let input = self.net.input_mut();
        if rgb.len() != input.len() {
            return Err(FaceError::InputSize {
                what: "attention landmark crop",
                expected: input.len(),
                found: rgb.len(),
            });
        }
        for (t, &v) in input.iter_mut().zip(rgb) {
            *t = v as f32 / 255.0;
        }
        Ok(self.run())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FaceRegion;
    use std::collections::BTreeSet;

    #[test]
    fn the_heads_cover_the_regions_lips_and_eyes_once_each() {
        let set = |v: &[usize]| v.iter().copied().collect::<BTreeSet<_>>();
        let heads = [
            &LIPS_MESH_INDICES[..],
            &RIGHT_EYE_MESH_INDICES,
            &LEFT_EYE_MESH_INDICES,
        ];
        let all: Vec<usize> = heads.concat();
        assert_eq!(set(&all).len(), all.len(), "no mesh point in two heads");
        assert!(all.iter().all(|&i| i < NUM_LANDMARKS));
        // The lips head starts with the two lip contours, each eye head with the eye's.
        assert_eq!(
            set(&LIPS_MESH_INDICES[..40]),
            set(&FaceRegion::Lips.landmarks())
        );
        let contours = [
            &RIGHT_EYE_MESH_INDICES[..EYE_CONTOUR_POINTS],
            &LEFT_EYE_MESH_INDICES[..EYE_CONTOUR_POINTS],
        ]
        .concat();
        assert_eq!(set(&contours), set(&FaceRegion::Eyes.landmarks()));
        // The right eye's corners are 33 and 133, the left eye's 263 and 362 (the iris
        // network's corners, contour points 0 and 8).
        assert_eq!(
            [RIGHT_EYE_MESH_INDICES[0], RIGHT_EYE_MESH_INDICES[8]],
            [33, 133]
        );
        assert_eq!(
            [LEFT_EYE_MESH_INDICES[0], LEFT_EYE_MESH_INDICES[8]],
            [263, 362]
        );
    }

    #[test]
    fn refinement_replaces_xy_keeps_z_and_appends_the_irises() {
        let mesh: Vec<[f32; 3]> = (0..NUM_LANDMARKS)
            .map(|i| [i as f32, -(i as f32), 0.5 * i as f32])
            .collect();
        let out = AttentionLandmarks {
            mesh: mesh.clone(),
            lips: vec![[1000.0, 2000.0]; NUM_LIP_POINTS],
            right_eye: vec![[3000.0, 4000.0]; NUM_EYE_POINTS],
            left_eye: vec![[5000.0, 6000.0]; NUM_EYE_POINTS],
            right_iris: [[7.0, 8.0]; NUM_IRIS_POINTS],
            left_iris: [[9.0, 10.0]; NUM_IRIS_POINTS],
            presence_logit: 0.0,
        };
        let r = out.refined();
        assert_eq!(r.len(), NUM_REFINED_LANDMARKS);
        assert_eq!(r[61], [1000.0, 2000.0, 30.5]);
        assert_eq!(r[193], [3000.0, 4000.0, 96.5]);
        assert_eq!(r[417], [5000.0, 6000.0, 208.5]);
        assert_eq!(r[1], mesh[1], "the nose is no head's");
        let mean_z = |eye: &[usize; NUM_EYE_POINTS]| {
            eye[..16].iter().map(|&i| 0.5 * i as f32).sum::<f32>() / 16.0
        };
        for k in 0..NUM_IRIS_POINTS {
            assert_eq!(r[468 + k], [7.0, 8.0, mean_z(&RIGHT_EYE_MESH_INDICES)]);
            assert_eq!(r[473 + k], [9.0, 10.0, mean_z(&LEFT_EYE_MESH_INDICES)]);
        }
    }
}
