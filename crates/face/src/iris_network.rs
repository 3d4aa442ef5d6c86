//! MediaPipe's iris landmark network (`iris_landmark.tflite`, MediaPipe Iris, from the PyPI wheel
//! `mediapipe==0.10.21`): a 64×64 RGB eye crop in, 71 eye-contour and eyebrow points and 5 iris
//! points out.

use std::path::Path;

use crate::checked_network::compile_checked;
use crate::{FaceError, ModelFile};
use visage_nn::Network;

/// Input side of the iris network, pixels.
pub const IRIS_INPUT: usize = 64;
/// Eye-contour and eyebrow points the network gives per eye.
pub const NUM_EYE_CONTOUR: usize = 71;
/// Iris points the network gives per eye: the centre, then four on the rim.
pub const NUM_IRIS_POINTS: usize = 5;

/// Output tensor `[1, 213]`: 71 × `(x, y, z)` eye contour and brow, crop pixels.
const CONTOUR_OUTPUT: &str = "output_eyes_contours_and_brows";
/// Output tensor `[1, 15]`: 5 × `(x, y, z)` iris (centre first), crop pixels.
const IRIS_OUTPUT: &str = "output_iris";

/// Raw output of the iris network for one 64×64 crop, in crop pixels of the crop as given
/// (`x, y ∈ [0, 64]`, left/top edge at 0; `z` relative depth with the scale of `x`).
#[derive(Clone, Debug, PartialEq)]
pub struct CropEye {
    /// 71 eye-contour and eyebrow points (`output_eyes_contours_and_brows`).
    pub contour: Vec<[f32; 3]>,
    /// The iris centre, then four points on its rim (`output_iris`): right of, above, left of
    /// and below the centre in the crop (for a right eye: nose side, up, temple side, down).
    pub iris: [[f32; 3]; NUM_IRIS_POINTS],
}

/// The compiled iris network. Allocation-free per call except the output's contour.
#[derive(Clone, Debug)]
pub struct IrisNetwork {
    net: Network,
}

impl IrisNetwork {
    /// Loads and verifies `iris_landmark.tflite` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        let bytes = ModelFile::IrisLandmark.read(models)?;
        Self::from_bytes(&bytes)
    }

    /// Compiles the network from the bytes of `iris_landmark.tflite`, checking its input shape
    /// and its two outputs.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FaceError> {
        let outputs = [
            (CONTOUR_OUTPUT, NUM_EYE_CONTOUR * 3),
            (IRIS_OUTPUT, NUM_IRIS_POINTS * 3),
        ];
        let net = compile_checked(ModelFile::IrisLandmark, bytes, IRIS_INPUT, &outputs)?;
        Ok(IrisNetwork { net })
    }

    /// The input tensor `[64, 64, 3]` (RGB in [0, 1]) to fill before [`IrisNetwork::run`].
    pub fn input_mut(&mut self) -> &mut [f32] {
        self.net.input_mut()
    }

    /// Runs the network on the current input tensor.
    pub fn run(&mut self) -> CropEye {
        self.net.run();
        let contour = self
            .net
            .output_named(CONTOUR_OUTPUT)
            .unwrap_or(&[])
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        let mut iris = [[0.0; 3]; NUM_IRIS_POINTS];
        let raw = self.net.output_named(IRIS_OUTPUT).unwrap_or(&[]);
        for (q, p) in iris.iter_mut().zip(raw.chunks_exact(3)) {
            *q = [p[0], p[1], p[2]];
        }
        CropEye { contour, iris }
    }

    /// Runs on an 8-bit RGB crop of 64 × 64 pixels (row-major, 3 bytes per pixel), scaled to
    /// [0, 1].
    pub fn run_rgb8(&mut self, rgb: &[u8]) -> Result<CropEye, FaceError> {
        let input = self.net.input_mut();
        if rgb.len() != input.len() {
            return Err(FaceError::InputSize {
                what: "iris crop",
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
