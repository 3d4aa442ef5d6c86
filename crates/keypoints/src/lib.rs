//! SIFT keypoints (paper §3, Eq. (3.1); Lowe, IJCV 2004), written for this project and
//! following OpenCV's `SIFT` in its conventions: pixel centres at integer coordinates, `size` the
//! keypoint's diameter in pixels, `angle` in degrees in `[0, 360)` measured the way OpenCV
//! measures it, descriptors as 128 bytes.
//!
//! [`Sift`] detects and describes; [`match_descriptors`] pairs two sets by nearest neighbours
//! with Lowe's ratio test and a mutual check; [`estimate_rigid_motion`] turns matched keypoints
//! lifted to 3-D into a rigid motion by RANSAC. [`KeypointsFile`] and [`MatchesFile`] are the
//! files `visage keypoints` and `visage match` write; [`Canvas`] draws keypoints and matches.

// Unsafe code is denied except in `gaussian_blur`, whose one block calls the AVX2 build of the
// blur after the run-time CPU check (`SAFETY:` there).
#![deny(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn, clippy::undocumented_unsafe_blocks)]

mod descriptor;
mod draw;
mod extrema;
mod fast_math;
#[allow(unsafe_code)]
mod gaussian_blur;
mod gray_image;
mod keypoint;
mod keypoints_file;
mod matches_file;
mod matching;
mod orientation;
mod rigid_ransac;
mod scale_space;
mod sift;

pub use draw::{Canvas, KEYPOINT_COLOUR, MATCH_COLOURS};
pub use gray_image::GrayImage;
pub use keypoint::{Descriptor, Features, Keypoint, DESCRIPTOR_LEN};
pub use keypoints_file::{KeypointsFile, KeypointsFileError};
pub use matches_file::{MatchRecord, MatchesFile};
pub use matching::{match_descriptors, Match, MatchOptions};
pub use rigid_ransac::{estimate_rigid_motion, RansacOptions, RigidMotionEstimate};
pub use sift::{Sift, SiftOptions};
