//! The face outline's landmarks on the sides of the face are silhouette points: as the head
//! turns they slide over the skin instead of staying on one point of it. Per frame, each takes
//! the model vertex — from a horizontal strip around its calibrated point — whose projection
//! is nearest to it (the contour correspondence of 3-DMM fitters, e.g. eos: Huber et al.
//! 2016, "A Multiresolution 3D Morphable Face Model and Fitting Framework").

use visage_camera::{Intrinsics, RigidTransform};

use super::landmark_basis::{dot, LandmarkBasis};
use super::FACE_OVAL;
use crate::FaceModel;

/// An outline landmark slides when its calibrated point is at least this far from the face's
/// mid-plane (metres): the sides of the face, not the chin or the hairline.
pub const SLIDING_MIN_X_M: f64 = 0.03;

/// Half-width of the strip of candidate vertices, along the face's up axis (metres).
pub const STRIP_HALF_HEIGHT_M: f64 = 0.002;

/// How far from its calibrated point a sliding landmark may go (metres).
pub const SLIDE_RADIUS_M: f64 = 0.025;

/// A candidate vertex: its neutral position and its rows of `[U | B]` (x, y, z).
#[derive(Clone, Debug)]
struct Candidate {
    neutral: [f64; 3],
    rows: [Vec<f64>; 3],
}

#[derive(Clone, Debug)]
struct SlidingLandmark {
    landmark: usize,
    candidates: Vec<Candidate>,
}

/// The sliding outline landmarks of a model.
#[derive(Clone, Debug)]
pub struct Contour {
    landmarks: Vec<SlidingLandmark>,
}

impl Contour {
    /// The sliding outline landmarks of `model` (its landmark basis `basis`, which locates
    /// the calibrated points).
    pub fn new(model: &FaceModel, basis: &LandmarkBasis) -> Contour {
        let mode_count = basis.mode_count();
        let landmarks = FACE_OVAL
            .iter()
            .filter(|&&j| j < basis.landmark_count())
            .filter_map(|&j| {
                let at: [f64; 3] = std::array::from_fn(|c| basis.mean[3 * j + c]);
                if at[0].abs() < SLIDING_MIN_X_M {
                    return None;
                }
                // The calibrated offset goes with the landmark wherever it slides.
                let offset = model
                    .landmark_offsets
                    .get(j)
                    .map_or([0.0; 3], |o| o.map(f64::from));
                let candidates: Vec<Candidate> = model
                    .neutral
                    .iter()
                    .enumerate()
                    .filter(|(_, v)| {
                        let v = v.map(f64::from);
                        let d2: f64 = (0..3).map(|c| (v[c] - at[c]).powi(2)).sum();
                        (v[1] - at[1]).abs() <= STRIP_HALF_HEIGHT_M
                            && d2 <= SLIDE_RADIUS_M * SLIDE_RADIUS_M
                            && v[0] * at[0] > 0.0
                    })
                    .map(|(i, v)| Candidate {
                        neutral: std::array::from_fn(|c| v[c] as f64 + offset[c]),
                        rows: std::array::from_fn(|c| {
                            let mut row = Vec::with_capacity(mode_count);
                            row.extend(model.identity.iter().map(|m| m[i][c] as f64));
                            row.extend(model.expressions.iter().map(|m| m[i][c] as f64));
                            row
                        }),
                    })
                    .collect();
                (!candidates.is_empty()).then_some(SlidingLandmark {
                    landmark: j,
                    candidates,
                })
            })
            .collect();
        Contour { landmarks }
    }

    /// The sliding landmarks.
    pub fn landmarks(&self) -> impl Iterator<Item = usize> + '_ {
        self.landmarks.iter().map(|l| l.landmark)
    }

    /// Moves each sliding landmark of `basis` to the candidate vertex that, with the shape
    /// `state` (`[p; e]`) placed by `pose`, projects nearest to its tracked pixel.
    pub fn slide(
        &self,
        k: &Intrinsics,
        pose: &RigidTransform,
        state: &[f64],
        landmarks_px: &[[f64; 2]],
        basis: &mut LandmarkBasis,
    ) {
        for l in &self.landmarks {
            let target = landmarks_px[l.landmark];
            let mut best = (f64::MAX, 0usize);
            for (i, c) in l.candidates.iter().enumerate() {
                let x: [f64; 3] = std::array::from_fn(|a| c.neutral[a] + dot(&c.rows[a], state));
                let y = pose.apply(x);
                if y[2] <= 0.0 {
                    continue;
                }
                let u = k.project(y);
                let d = (u[0] - target[0]).powi(2) + (u[1] - target[1]).powi(2);
                if d < best.0 {
                    best = (d, i);
                }
            }
            let c = &l.candidates[best.1];
            basis.set_landmark(l.landmark, c.neutral, [&c.rows[0], &c.rows[1], &c.rows[2]]);
        }
    }
}
