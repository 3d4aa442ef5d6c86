//! The face front end of visage (paper §3, ERRATA 7–8): MediaPipe's face detectors (BlazeFace
//! short range, and full range for small faces) and FaceMesh landmark network run in pure Rust
//! from the original Apache-2.0 `.tflite` files, video tracking, and the metric face geometry
//! that turns 468 landmarks into a metric mesh.
//!
//! Layers: [`model_files`] (verified `.tflite` files) → the inference engine of `visage-nn`
//! ([`Network`](visage_nn::Network)) → networks ([`detector`], [`landmarker`], [`iris`], and
//! the attention face mesh [`attention_network`], which gives the lips, eyes and irises with the
//! landmarks — [`FaceMesh::load_attention`]; the pipeline runs FaceMesh and the iris network,
//! [`FaceMesh::load`]) → [`tracker`] → [`face_geometry`].

#![forbid(unsafe_code)]

mod checked_network;
mod error;
pub mod model_files;

pub use error::FaceError;
pub use model_files::{models_dir, ModelFile};
pub mod anchors;
pub mod landmark_network;

pub use landmark_network::{CropLandmarks, LandmarkNetwork, LANDMARK_INPUT, NUM_LANDMARKS};

/// The logistic function `1 / (1 + e^−x)`, with the logit clipped to ±100 as MediaPipe does.
pub fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x.clamp(-100.0, 100.0)).exp())
}
mod detection;
pub mod detector;
pub mod letterbox;
pub mod nms;

pub use detection::Detection;
pub use detector::{DetectorModel, DetectorOptions, FaceDetector, ResizeFilter};
pub mod crop;
mod face;
pub mod face_mesh;
mod landmark_smoothing;
pub mod landmarker;
pub mod roi;
mod shot_cut;
pub mod tracker;

pub use face::{points_bbox, Face};
pub use face_mesh::{DetectorUse, FaceMesh, FULL_RANGE_TILE};
pub use landmark_smoothing::{
    DistanceSmoother, LandmarkSmoother, CLIP_LATENCY_FRAMES, DEFAULT_DISTANCE_SMOOTHING,
    DEFAULT_FRAME_INTERVAL_S, DEFAULT_LANDMARK_SMOOTHING, DEFAULT_LATENCY_FRAMES,
    MAX_LATENCY_FRAMES,
};
pub use landmarker::{FaceLandmarker, FrameLandmarks};
pub use roi::Roi;
pub use shot_cut::{face_jumped, CutDetector, CUT_FACE_CHANGE, CUT_FACE_JUMP, CUT_PICTURE_CHANGE};
pub use tracker::{box_proximity, FaceTarget, FaceTracker, TrackStep};
pub mod eye_crop;
pub mod iris;
pub mod iris_network;

pub use eye_crop::{Eye, EyeCrop};
pub use iris::{EyeLandmarks, Eyes, IrisLandmarker};
pub use iris_network::{CropEye, IrisNetwork, IRIS_INPUT, NUM_EYE_CONTOUR, NUM_IRIS_POINTS};
pub mod attention_network;

pub use attention_network::{AttentionLandmarks, AttentionNetwork, NUM_REFINED_LANDMARKS};
pub mod canonical_mesh;
pub mod face_geometry;

pub use canonical_mesh::CanonicalMesh;
pub use face_geometry::{face_trimesh, fit_face_geometry, FaceGeometry, FacePose};
mod regions;

pub use regions::FaceRegion;
