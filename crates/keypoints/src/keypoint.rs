//! A keypoint and its descriptor, in OpenCV's conventions.

use serde::{Deserialize, Serialize};

/// Bytes in a SIFT descriptor: a 4 × 4 grid of 8-bin orientation histograms.
pub const DESCRIPTOR_LEN: usize = 128;

/// A SIFT descriptor, stored as OpenCV stores it: the unit vector clipped at 0.2,
/// renormalised, times 512, rounded and saturated to a byte.
pub type Descriptor = [u8; DESCRIPTOR_LEN];

/// A scale-space keypoint, as OpenCV's `cv::KeyPoint`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Keypoint {
    /// Column, pixels; pixel centres are at integer coordinates.
    pub x: f32,
    /// Row, pixels (down).
    pub y: f32,
    /// Diameter of the meaningful neighbourhood, pixels (2 × the scale σ of its level, in
    /// input-image pixels, times 2 as OpenCV reports it).
    pub size: f32,
    /// Dominant orientation, degrees in `[0, 360)`, as OpenCV reports it.
    pub angle: f32,
    /// Absolute interpolated difference-of-Gaussians value (intensities in 0–1).
    pub response: f32,
    /// OpenCV's packed octave: octave (−1 for the upsampled one) in the low byte, the layer in
    /// the next byte, the sub-layer offset scaled to 0–255 in the third.
    pub octave: i32,
}

/// Keypoints and their descriptors, `descriptors[i]` describing `keypoints[i]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Features {
    /// The keypoints.
    pub keypoints: Vec<Keypoint>,
    /// One descriptor per keypoint.
    pub descriptors: Vec<Descriptor>,
}

impl Features {
    /// Number of keypoints.
    pub fn len(&self) -> usize {
        self.keypoints.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.keypoints.is_empty()
    }
}
