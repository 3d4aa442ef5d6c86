//! Camera model and depth maps: paper §2.
//!
//! Conventions used across visage (the paper's and OpenCV's):
//! - camera coordinates: x right, y down, z forward (into the scene), metres;
//! - pixel coordinates: `u` to the right, `v` down, the centre of pixel `(i, j)` at `(i, j)`
//!   (so `cx = (width − 1)/2` puts the principal point at the image centre);
//! - a depth map stores, per pixel, either the z coordinate of the surface point (z-depth, what
//!   Kinect/RealSense/TUM recordings store) or its distance along the ray (the paper's `D`),
//!   see [`DepthKind`].

#![forbid(unsafe_code)]

mod depth_kind;
mod depth_map;
mod depth_png;
mod error;
mod intrinsics;
mod number;
mod rigid_fit;
mod rigid_transform;
pub mod vec3;

pub use depth_kind::DepthKind;
pub use depth_map::DepthMap;
pub use depth_png::{parse_depth_png, read_depth_png, write_depth_png};
pub use error::CameraError;
pub use intrinsics::{
    Intrinsics, DEFAULT_FOV_DEG, FOV_RANGE_DEG, MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE,
};
pub use number::number;
pub use rigid_fit::{horn_rotation, quaternion_to_matrix};
pub use rigid_transform::{RigidTransform, ROTATION_TOLERANCE};
