//! Fitting the face model to tracked landmarks: head pose, this person's identity, per-frame
//! expression weights.

pub mod bounded_least_squares;
mod contour;
mod face_fitter;
mod landmark_basis;
pub mod perspective;
pub mod region_evidence;
pub mod rigid_pose;
mod shape_error;
pub mod view_correction;

pub use contour::Contour;
pub use face_fitter::{FaceFit, FaceFitter, FitOptions, FACE_OVAL, FRONTAL};
pub use landmark_basis::LandmarkBasis;
pub use shape_error::rms_after_scale;
pub use view_correction::{ViewCorrection, ViewSample};
