//! Gaze from the irises: each eye is a sphere fixed in the head, and the iris centre seen in
//! the image fixes where on that sphere the eye points.
//!
//! The eye turns about a centre [`EYEBALL_DEPTH_M`] behind the midpoint of the eye's corners,
//! along the head's backward axis, and the iris centre — the middle of the limbus, which the
//! iris network outlines — lies [`IRIS_ROTATION_RADIUS_M`] from it. An adult eye turns about a
//! point 13.5 mm behind its corneal apex, and the limbus lies about 2.5 mm behind the apex; the
//! apex stands about 7.5 mm in front of the corners' midpoint (ICT-FaceKit's eyes, placed on
//! scans of real heads). So the iris of an eye looking ahead sits 5 mm in front of the corners,
//! where the model must put it: a model iris at another depth reads a turn of the head as a
//! glance the other way (2 mm off ≈ 6° at 35° of yaw). The iris centre's pixel ray meets the
//! sphere of that radius; the direction from the centre to that point, in head coordinates, is
//! the gaze. Its yaw and pitch
//! drive the eye rotations of Live Link Face's CSV and ARKit's `eyeLook*` shapes, which reach 1
//! at [`EYE_LOOK_FULL_RAD`].
//!
//! Where the eye network's contour is found, the eye is placed by it rather than by the fitted
//! head alone: the iris and the contour come from the same crop of the same network, while the
//! fitted pose is a few degrees off at a large turn, and a degree of head yaw moves the eye's
//! centre against the iris by about 3° of gaze. The contour's corners' midpoint lies
//! [`CONTOUR_CORNERS_OFFSET_M`] from the face's corners' midpoint; the eye is shifted, at its
//! depth, until that point falls on the contour's. The contour follows the iris part of the way
//! as the eye turns (on renders by 0.44 across and 0.66 up and down: the lids follow a vertical
//! gaze), so a gaze read this way is smaller than the eye's turn; it is left so, because
//! scaling it back up made it noisier than the gaze placed by the head.

use visage_camera::{Intrinsics, RigidTransform};

/// Distance of the iris centre from the eye's centre of rotation (metres).
pub const IRIS_ROTATION_RADIUS_M: f64 = 0.011;

/// Depth of the eye's centre of rotation behind the eye corners' midpoint (metres).
pub const EYEBALL_DEPTH_M: f64 = 0.006;

/// Where the eye network's contour puts the midpoint of an eye's two corners, from the
/// midpoint of the face's eye-corner landmarks (model frame: towards the temple, up, forward;
/// metres). Measured on renders of eyes looking ahead, over ±45° of yaw and ±30° of pitch
/// (`visage-eval`'s `landmark_view_correction` example).
pub const CONTOUR_CORNERS_OFFSET_M: [f64; 3] = [-0.00155, -0.00161, 0.00287];

/// The eye rotation at which an `eyeLook*` shape reaches 1 (radians, about 25°).
pub const EYE_LOOK_FULL_RAD: f64 = 0.436;

/// One eye's gaze relative to the head: yaw (positive towards the subject's left) and pitch
/// (positive up), radians.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EyeGaze {
    pub yaw: f64,
    pub pitch: f64,
}

/// The gaze of an eye whose corners are at `corners` (model frame: x to the subject's left, y
/// up, z out of the face; metres) in a head at `pose` (model frame → camera), with its iris
/// centre at pixel `iris_px` and, where the eye network found them, the contour's corners at
/// `contour_corners_px`. `None` when the iris ray misses the eyeball.
pub fn eye_gaze(
    k: &Intrinsics,
    pose: &RigidTransform,
    corners: [[f64; 3]; 2],
    iris_px: [f64; 2],
    contour_corners_px: Option<[[f64; 2]; 2]>,
) -> Option<EyeGaze> {
    let mid: [f64; 3] = std::array::from_fn(|c| 0.5 * (corners[0][c] + corners[1][c]));
    let centre_model = [mid[0], mid[1], mid[2] - EYEBALL_DEPTH_M];
    let mut centre = pose.apply(centre_model);
    if let Some([a, b]) = contour_corners_px {
        // The contour's midpoint, at the depth the fitted head puts it; the eye moves with it.
        let [ox, oy, oz] = CONTOUR_CORNERS_OFFSET_M;
        let side = if mid[0] < 0.0 { -1.0 } else { 1.0 };
        let placed = pose.apply([mid[0] + side * ox, mid[1] + oy, mid[2] + oz]);
        let ray = k.ray(0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]));
        let s = placed[2] / ray[2];
        for (c, (r, p)) in centre.iter_mut().zip(ray.iter().zip(placed)) {
            *c += s * r - p;
        }
    }
    // The iris ray from the camera centre: |s·d − c|² = r², nearer root.
    let ray = k.ray(iris_px[0], iris_px[1]);
    let dc: f64 = (0..3).map(|i| ray[i] * centre[i]).sum();
    let cc: f64 = (0..3).map(|i| centre[i] * centre[i]).sum();
    let disc = dc * dc - (cc - IRIS_ROTATION_RADIUS_M * IRIS_ROTATION_RADIUS_M);
    // A ray that misses (the iris off the modelled eyeball) takes the sphere's nearest point.
    let s = if disc >= 0.0 { dc - disc.sqrt() } else { dc };
    let hit: [f64; 3] = std::array::from_fn(|i| s * ray[i] - centre[i]);
    let r = &pose.rotation;
    let d: [f64; 3] =
        std::array::from_fn(|i| r[0][i] * hit[0] + r[1][i] * hit[1] + r[2][i] * hit[2]);
    let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if norm.is_nan() || norm <= 0.0 {
        return None;
    }
    let d = d.map(|c| c / norm);
    Some(EyeGaze {
        yaw: d[0].atan2(d[2]),
        pitch: d[1].clamp(-1.0, 1.0).asin(),
    })
}

/// ARKit's `eyeLook{Up,Down,In,Out}` weights of one eye from its gaze; `left_eye` says which
/// side "in" (towards the nose) is: the subject's left eye looks in towards the subject's
/// right (negative yaw).
pub fn eye_look_weights(gaze: EyeGaze, left_eye: bool) -> [f64; 4] {
    let w = |a: f64| (a / EYE_LOOK_FULL_RAD).clamp(0.0, 1.0);
    let towards_left = w(gaze.yaw);
    let towards_right = w(-gaze.yaw);
    let (inward, outward) = if left_eye {
        (towards_right, towards_left)
    } else {
        (towards_left, towards_right)
    };
    [w(gaze.pitch), w(-gaze.pitch), inward, outward]
}

/// The gaze that ARKit's `eyeLook{Up,Down,In,Out}` weights `look` of one eye stand for: the
/// inverse of [`eye_look_weights`] for weights of which at most one of each opposing pair is
/// non-zero (opposing weights cancel). Each weight is clamped to [0, 1]; a weight of 1 is a
/// turn of [`EYE_LOOK_FULL_RAD`].
pub fn eye_look_gaze(look: [f64; 4], left_eye: bool) -> EyeGaze {
    let [up, down, inward, outward] =
        look.map(|w| if w.is_nan() { 0.0 } else { w.clamp(0.0, 1.0) });
    // The left eye looks out towards the subject's left (positive yaw), the right eye in.
    let towards_left = if left_eye {
        outward - inward
    } else {
        inward - outward
    };
    EyeGaze {
        yaw: towards_left * EYE_LOOK_FULL_RAD,
        pitch: (up - down) * EYE_LOOK_FULL_RAD,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use visage_morphable::fit::rigid_pose::{exp_so3, mat3_mul};
    use visage_morphable::fit::FRONTAL;

    /// An eye looking along `dir` (model frame) seen by a camera: the iris centre's pixel.
    fn iris_pixel(
        k: &Intrinsics,
        pose: &RigidTransform,
        corners: [[f64; 3]; 2],
        dir: [f64; 3],
    ) -> [f64; 2] {
        let mid: [f64; 3] = std::array::from_fn(|c| 0.5 * (corners[0][c] + corners[1][c]));
        let centre = [mid[0], mid[1], mid[2] - EYEBALL_DEPTH_M];
        let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        let p: [f64; 3] = std::array::from_fn(|c| centre[c] + IRIS_ROTATION_RADIUS_M * dir[c] / n);
        k.project(pose.apply(p))
    }

    #[test]
    fn recovers_the_gaze_of_a_turned_head() {
        let k = Intrinsics::from_fov(640, 480, 60.0).unwrap();
        let pose = RigidTransform {
            rotation: mat3_mul(&exp_so3([0.1, 0.3, 0.0]), &FRONTAL),
            translation: [0.02, 0.0, 0.6],
        };
        let corners = [[0.02, 0.03, 0.08], [0.05, 0.03, 0.075]];
        for (yaw, pitch) in [(0.0, 0.0), (0.3, 0.0), (-0.2, 0.15), (0.1, -0.25)] {
            let dir = [
                f64::sin(yaw) * f64::cos(pitch),
                f64::sin(pitch),
                f64::cos(yaw) * f64::cos(pitch),
            ];
            let px = iris_pixel(&k, &pose, corners, dir);
            let g = eye_gaze(&k, &pose, corners, px, None).unwrap();
            assert!(
                (g.yaw - yaw).abs() < 1e-6 && (g.pitch - pitch).abs() < 1e-6,
                "{g:?}"
            );
        }
        let look = eye_look_weights(
            EyeGaze {
                yaw: 0.2,
                pitch: -0.5,
            },
            true,
        );
        assert_eq!(look[0], 0.0);
        assert_eq!(look[1], 1.0);
        assert_eq!(look[2], 0.0);
        assert!((look[3] - 0.2 / EYE_LOOK_FULL_RAD).abs() < 1e-12);
    }

    #[test]
    fn the_contour_places_the_eye_where_the_fitted_head_misplaces_it() {
        let k = Intrinsics::from_fov(640, 480, 60.0).unwrap();
        let truth = RigidTransform {
            rotation: mat3_mul(&exp_so3([0.0, 0.5, 0.0]), &FRONTAL),
            translation: [0.0, 0.0, 0.5],
        };
        // The subject's left eye, 8 cm in front of the head's origin, looking ahead.
        let corners = [[0.018, 0.03, 0.08], [0.048, 0.03, 0.075]];
        let iris = iris_pixel(&k, &truth, corners, [0.0, 0.0, 1.0]);
        let mid: [f64; 3] = std::array::from_fn(|c| 0.5 * (corners[0][c] + corners[1][c]));
        let [ox, oy, oz] = CONTOUR_CORNERS_OFFSET_M;
        let contour_mid = k.project(truth.apply([mid[0] + ox, mid[1] + oy, mid[2] + oz]));
        let contour = [
            [contour_mid[0] - 20.0, contour_mid[1] + 1.0],
            [contour_mid[0] + 20.0, contour_mid[1] - 1.0],
        ];
        // A fit that reads the head's yaw 3° past the truth, about the head's origin.
        let fitted = RigidTransform {
            rotation: mat3_mul(&exp_so3([0.0, 0.5 + 3f64.to_radians(), 0.0]), &FRONTAL),
            translation: truth.translation,
        };
        let exact = eye_gaze(&k, &truth, corners, iris, Some(contour)).unwrap();
        assert!(
            exact.yaw.abs() < 1e-9 && exact.pitch.abs() < 1e-9,
            "{exact:?}"
        );
        let by_head = eye_gaze(&k, &fitted, corners, iris, None).unwrap();
        let by_contour = eye_gaze(&k, &fitted, corners, iris, Some(contour)).unwrap();
        // Placed by the head, the eye moves 4 mm against its iris: a glance of about 20°.
        assert!(by_head.yaw.to_degrees().abs() > 10.0, "{by_head:?}");
        // Placed by the contour, only the head's rotation error is left.
        assert!(by_contour.yaw.to_degrees().abs() < 3.5, "{by_contour:?}");
        assert!(by_contour.pitch.to_degrees().abs() < 0.5, "{by_contour:?}");
    }

    #[test]
    fn eye_look_weights_and_their_gaze_invert_each_other() {
        for left in [false, true] {
            for (yaw, pitch) in [(0.2, -0.1), (-0.3, 0.25), (0.0, 0.0), (0.436, -0.436)] {
                let gaze = EyeGaze { yaw, pitch };
                let back = eye_look_gaze(eye_look_weights(gaze, left), left);
                assert!((back.yaw - yaw).abs() < 1e-12, "{left} {yaw}: {back:?}");
                assert!(
                    (back.pitch - pitch).abs() < 1e-12,
                    "{left} {pitch}: {back:?}"
                );
            }
        }
        // Looking in turns the left eye towards the subject's right, the right eye to the left.
        assert!(eye_look_gaze([0.0, 0.0, 1.0, 0.0], true).yaw < 0.0);
        assert!(eye_look_gaze([0.0, 0.0, 1.0, 0.0], false).yaw > 0.0);
        assert!(eye_look_gaze([1.0, 0.0, 0.0, 0.0], true).pitch > 0.0);
    }
}
