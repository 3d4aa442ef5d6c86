//! The FaceMesh landmark network (`face_landmark.tflite`, MediaPipe `face_landmark_cpu`):
//! a 192×192 RGB crop in, 468 landmarks and a face-presence logit out.

use std::path::Path;

use crate::checked_network::compile_checked;
use crate::{FaceError, ModelFile};
use visage_nn::Network;

/// Input side of the landmark network, pixels.
pub const LANDMARK_INPUT: usize = 192;
/// Number of FaceMesh landmarks (without the iris refinement), paper §3: N = 468.
pub const NUM_LANDMARKS: usize = 468;

/// Raw output of the landmark network for one crop.
#[derive(Clone, Debug, PartialEq)]
pub struct CropLandmarks {
    /// 468 × `(x, y, z)` in crop pixels: `x, y ∈ [0, 192]` with the crop's left/top edge at 0
    /// (MediaPipe's convention: normalised × 192); `z` is relative depth with the scale of `x`,
    /// negative towards the camera, centred near the face's centre of mass.
    pub points: Vec<[f32; 3]>,
    /// Face-presence logit; `sigmoid(logit)` is MediaPipe's face presence score.
    pub presence_logit: f32,
}

impl CropLandmarks {
    /// `sigmoid(presence_logit)` ∈ [0, 1].
    pub fn presence(&self) -> f32 {
        crate::sigmoid(self.presence_logit)
    }
}

/// The compiled landmark network. Allocation-free per call.
#[derive(Clone, Debug)]
pub struct LandmarkNetwork {
    net: Network,
}

impl LandmarkNetwork {
    /// Loads and verifies `face_landmark.tflite` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        let bytes = ModelFile::FaceLandmark.read(models)?;
        Self::from_bytes(&bytes)
    }

    /// Compiles the network from the bytes of `face_landmark.tflite`.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FaceError> {
        let outputs = [("conv2d_21", NUM_LANDMARKS * 3), ("conv2d_31", 1)];
        let net = compile_checked(ModelFile::FaceLandmark, bytes, LANDMARK_INPUT, &outputs)?;
        Ok(LandmarkNetwork { net })
    }

    /// The input tensor `[192, 192, 3]` (RGB in [0, 1]) to fill before [`LandmarkNetwork::run`].
    pub fn input_mut(&mut self) -> &mut [f32] {
        self.net.input_mut()
    }

    /// Runs the network on the current input tensor.
    pub fn run(&mut self) -> CropLandmarks {
        self.net.run();
        let raw = self.net.output_named("conv2d_21").unwrap_or(&[]);
        let points = raw.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        let presence_logit = self
            .net
            .output_named("conv2d_31")
            .and_then(|v| v.first().copied())
            .unwrap_or(f32::NEG_INFINITY);
        CropLandmarks {
            points,
            presence_logit,
        }
    }

    /// Runs on an 8-bit RGB crop of 192 × 192 pixels (row-major, 3 bytes per pixel), scaled to
    /// [0, 1] as MediaPipe's `ImageToTensorCalculator` does for this model.
    pub fn run_rgb8(&mut self, rgb: &[u8]) -> Result<CropLandmarks, FaceError> {
        let input = self.net.input_mut();
        if rgb.len() != input.len() {
            return Err(FaceError::InputSize {
                what: "landmark crop",
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
