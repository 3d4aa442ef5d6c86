//! Tracked views of a known head, to learn the landmark network's bias that follows the view
//! from (`visage-morphable`'s `ViewCorrection`): a neutral ICT-FaceKit head, textured with the
//! real face ([`HeadRender`]), rendered over a grid of yaws and pitches — a serpentine, so the
//! tracker follows it as it follows a video — and tracked by MediaPipe's networks
//! ([`FaceTracker`]). Each tracked view keeps the landmarks, the face's own landmark points,
//! the true pose, and the pose a rigid fit of the uncorrected landmarks gives from the truth
//! (the view the fit reads the table at).

use visage_camera::RigidTransform;
use visage_face::FaceTracker;
use visage_morphable::fit::rigid_pose::refine_pose;
use visage_morphable::fit::ViewSample;
use visage_morphable::FaceModel;
use visage_rig::EyeGaze;

use crate::{EvalError, HeadPose, HeadRender, RenderWork};

/// Gauss–Newton steps of the rigid fit from the true pose (converged).
const ESTIMATE_ITERATIONS: usize = 10;

/// The grid of views: yaw from −max to +max and pitch likewise (degrees), in steps of
/// `step_deg`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewGrid {
    pub yaw_max_deg: f64,
    pub pitch_max_deg: f64,
    pub step_deg: f64,
}

impl Default for ViewGrid {
    /// ±45° yaw, ±30° pitch, 5° steps: past the expression benchmark's ±40° / ±25°.
    fn default() -> Self {
        ViewGrid {
            yaw_max_deg: 45.0,
            pitch_max_deg: 30.0,
            step_deg: 5.0,
        }
    }
}

impl ViewGrid {
    /// The head poses, serpentine: each pitch row's yaws alternate in direction.
    pub fn poses(&self) -> Vec<HeadPose> {
        let steps = |max: f64| {
            let n = (max / self.step_deg).floor() as i64;
            (-n..=n)
                .map(|i| (i as f64 * self.step_deg).to_radians())
                .collect::<Vec<_>>()
        };
        let (yaws, pitches) = (steps(self.yaw_max_deg), steps(self.pitch_max_deg));
        let mut poses = Vec::with_capacity(yaws.len() * pitches.len());
        for (row, &pitch) in pitches.iter().enumerate() {
            let mut row_yaws = yaws.clone();
            if row % 2 == 1 {
                row_yaws.reverse();
            }
            poses.extend(row_yaws.into_iter().map(|yaw| HeadPose {
                angles: [yaw, pitch, 0.0],
                shift_m: [0.0; 3],
            }));
        }
        poses
    }

    /// The largest yaw and pitch, radians.
    pub fn max_view(&self) -> [f64; 2] {
        [
            self.yaw_max_deg.to_radians(),
            self.pitch_max_deg.to_radians(),
        ]
    }
}

/// One tracked view: what the landmark table learns from, and what the eye network found
/// (frame pixels, the subject's `[right, left]`; the eyes look straight ahead): the irises'
/// centres and the contours' two corners.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackedView {
    pub sample: ViewSample,
    pub irises: Option<[[f64; 2]; 2]>,
    pub contour_corners: Option<[[[f64; 2]; 2]; 2]>,
}

/// Renders the neutral head with `identity` at each of `grid`'s poses and tracks it; the
/// rigid fit of the uncorrected landmarks uses `rigid_weights` (one per landmark, the fit's).
/// A render without a face is left out.
///
/// # Errors
/// A failing render or network; identity weights that do not match the model.
pub fn tracked_views(
    render: &HeadRender,
    model: &FaceModel,
    tracker: &mut FaceTracker,
    identity: &[f64],
    grid: &ViewGrid,
    rigid_weights: &[f64],
) -> Result<Vec<TrackedView>, EvalError> {
    let ict = render.model();
    let neutral = vec![0.0; ict.expression_modes.len()];
    let mut shape = Vec::new();
    ict.shape(identity, &neutral, &mut shape)?;
    let points = model.landmark_points(&shape);
    let pivot = render.pivot(identity)?;
    let k = *render.intrinsics();
    let mut work = RenderWork::default();
    tracker.reset();
    let mut samples = Vec::new();
    for pose in grid.poses() {
        let image = render.render(
            identity,
            &neutral,
            [EyeGaze::default(); 2],
            &pose,
            pivot,
            &mut work,
        )?;
        let Some(face) = tracker.track(&image)?.face else {
            tracker.reset();
            continue;
        };
        let (rotation, translation) = render.camera_from_model(&pose, pivot);
        let truth = RigidTransform {
            rotation,
            translation,
        };
        let landmarks_px: Vec<[f64; 2]> = face.landmarks.points[..points.len()]
            .iter()
            .map(|p| [p[0] as f64, p[1] as f64])
            .collect();
        let mut estimated_pose = truth;
        refine_pose(
            &k,
            &mut estimated_pose,
            &points,
            &landmarks_px,
            rigid_weights,
            ESTIMATE_ITERATIONS,
        );
        let iris = |e: &visage_face::EyeLandmarks| {
            let c = e.iris_center();
            [c[0] as f64, c[1] as f64]
        };
        samples.push(TrackedView {
            sample: ViewSample {
                landmarks_px,
                points: points.clone(),
                pose: truth,
                estimated_pose,
            },
            irises: face.eyes.as_ref().map(|e| [iris(&e.right), iris(&e.left)]),
            contour_corners: face.eyes.as_ref().and_then(|e| {
                let corners =
                    |e: &visage_face::EyeLandmarks| e.lid_points().map(|[_, _, a, b]| [a, b]);
                Some([corners(&e.right)?, corners(&e.left)?])
            }),
        });
    }
    Ok(samples)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_is_a_serpentine_through_every_view() {
        let grid = ViewGrid {
            yaw_max_deg: 10.0,
            pitch_max_deg: 5.0,
            step_deg: 5.0,
        };
        let poses = grid.poses();
        assert_eq!(poses.len(), 5 * 3);
        // Neighbouring poses are one step apart: the tracker follows.
        for w in poses.windows(2) {
            let d =
                (w[0].angles[0] - w[1].angles[0]).abs() + (w[0].angles[1] - w[1].angles[1]).abs();
            assert!((d - 5f64.to_radians()).abs() < 1e-12, "{d}");
        }
    }
}
