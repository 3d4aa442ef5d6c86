//! Both eyes of a frame into the rig: the lids' blink and wide-eye weights ([`Eyelids`]), and
//! the gaze from the irises ([`eye_gaze`]) relative to the person's resting gaze, held while
//! a lid covers the iris ([`LidGate`]), as `eyeLook*` weights and Live Link Face's eye
//! rotations.
//!
//! As the head turns away, the eye on the far side is seen ever more obliquely, partly behind
//! the nose, and its contour's lids and its iris drift: from [`FAR_EYE_FROM_DEG`] of turn it
//! takes the near eye's lids and gaze, wholly from [`FAR_EYE_FULL_DEG`] (the eyes' vergence is
//! then lost). A wink of the far eye keeps its own lids: while the far eye reads clearly closed
//! (its aperture under [`WINK_OPENNESS`] of its open one, its upper lid under [`WINK_UPPER`] of
//! its open height) and the near eye reads open.
//!
//! Blinks are bilateral and the eyes turn together, so the gate holds both eyes' gazes while
//! either eye's lid covers its iris: a closing lid pushes the iris the network finds down
//! before the lid's own aperture has dropped much, and the other eye's lid is often a frame
//! ahead.

use visage_camera::{Intrinsics, RigidTransform};
use visage_morphable::fit::view_correction::view_of;

use crate::eyelids::{opening, Eyelids, LidPoints, LidReading};
use crate::gaze::{eye_gaze, eye_look_weights, EyeGaze};
use crate::lid_gate::LidGate;
use crate::{BlendshapeFrame, RestPose, ARKIT_BLENDSHAPES};

/// What the eye networks saw of one eye in a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeObservation {
    /// The lids and corners from the eye network's contour (frame pixels); `None` without it.
    pub lids: Option<LidPoints>,
    /// The iris centre (frame pixels).
    pub iris_px: [f64; 2],
    /// The eye's corners on the fitted face (model frame, metres).
    pub corners: [[f64; 3]; 2],
}

/// The eyes' state over a clip.
#[derive(Clone, Debug, Default)]
pub struct EyeRig {
    eyelids: Eyelids,
    gate: LidGate<EyeGaze>,
}

impl EyeRig {
    /// Forgets the held gazes (the face was lost); the lids' calibration stays.
    pub fn lose_track(&mut self) {
        self.gate.lose_track();
    }

    /// Writes both eyes (`[right, left]`, the subject's) into `frame`: blink and wide-eye
    /// weights from the lids (where the contour is missing, the fit's weights stay), the
    /// `eyeLook*` weights and the eye rotations. `pose` is the head's fitted pose.
    pub fn apply(
        &mut self,
        k: &Intrinsics,
        pose: &RigidTransform,
        eyes: [EyeObservation; 2],
        mut rest: Option<&mut RestPose>,
        frame: &mut BlendshapeFrame,
    ) {
        let centers = eyes.map(|e| -> [f64; 3] {
            std::array::from_fn(|i| 0.5 * (e.corners[0][i] + e.corners[1][i]))
        });
        let mut readings = [None; 2];
        for (left, eye) in [false, true].into_iter().zip(&eyes) {
            readings[left as usize] = eye
                .lids
                .and_then(|lids| opening(k, pose, eye.corners, &lids))
                .map(|o| {
                    self.eyelids
                        .read(left, o, view_of(pose, centers[left as usize]))
                });
        }
        // The eye turned away from the camera takes the other's lids as the turn grows.
        let far = far_eye(pose, centers);
        if let (Some((far, share)), [Some(right), Some(left)]) = (far, readings) {
            let (f, n) = if far { (left, right) } else { (right, left) };
            let wink = f.openness < WINK_OPENNESS && f.upper < WINK_UPPER && n.blink < WINK_NEAR;
            let mix = |a: f64, b: f64| (1.0 - share) * a + share * b;
            if !wink {
                readings[far as usize] = Some(LidReading {
                    openness: mix(f.openness, n.openness),
                    upper: mix(f.upper, n.upper),
                    blink: mix(f.blink, n.blink),
                    wide: mix(f.wide, n.wide),
                });
            }
        }
        let mut blinks = [0.0; 2];
        for (left, reading) in [false, true].into_iter().zip(readings) {
            blinks[left as usize] = match reading {
                Some(r) => {
                    set(frame, "eyeBlink", left, r.blink);
                    set(frame, "eyeWide", left, r.wide);
                    r.blink
                }
                None => get(frame, "eyeBlink", left),
            };
        }
        let blink = blinks[0].max(blinks[1]);
        let open = [false, true].map(|left| self.gate.is_open(left, blink));
        let mut gazes = [None; 2];
        for (left, eye) in [false, true].into_iter().zip(&eyes) {
            if open[left as usize] {
                gazes[left as usize] = eye_gaze(
                    k,
                    pose,
                    eye.corners,
                    eye.iris_px,
                    eye.lids.map(|l| l.corners),
                )
                .map(|g| match &mut rest {
                    Some(rest) => rest.calibrate_gaze(left, g),
                    None => g,
                });
            }
        }
        // The eyes turn together: the eye turned away follows the near one's gaze as the
        // turn grows, as it takes its lids.
        if let (Some((far, share)), [Some(right), Some(left)]) = (far, gazes) {
            let (f, n) = if far { (left, right) } else { (right, left) };
            gazes[far as usize] = Some(EyeGaze {
                yaw: (1.0 - share) * f.yaw + share * n.yaw,
                pitch: (1.0 - share) * f.pitch + share * n.pitch,
            });
        }
        for (left, eye_open) in [false, true].into_iter().zip(open) {
            let gaze = if eye_open {
                if let Some(g) = gazes[left as usize] {
                    self.gate.keep(left, g);
                }
                gazes[left as usize]
            } else {
                // The lid covers the iris: the last gaze of the open eye.
                self.gate.held(left)
            };
            let Some(gaze) = gaze else {
                continue;
            };
            for (name, w) in ["Up", "Down", "In", "Out"]
                .iter()
                .zip(eye_look_weights(gaze, left))
            {
                set(frame, &format!("eyeLook{name}"), left, w);
            }
            // Live Link Face: yaw positive towards the subject's right, pitch down.
            let angles = [-gaze.yaw as f32, -gaze.pitch as f32, 0.0];
            if left {
                frame.left_eye = angles;
            } else {
                frame.right_eye = angles;
            }
        }
    }
}

/// The head's turn from the camera (degrees of yaw) from which the eye turned away takes the
/// other eye's lids, and at which it takes them wholly.
pub const FAR_EYE_FROM_DEG: f64 = 15.0;
pub const FAR_EYE_FULL_DEG: f64 = 30.0;

/// A far eye reading under this of its open aperture, with its upper lid under [`WINK_UPPER`]
/// of its open height, while the near eye's blink is under [`WINK_NEAR`], winks: it keeps its
/// own lids. Both well inside a closed eye's readings (the closed aperture is 0.4 or more; a
/// blink's strongest frame has the upper lid at 0.45–0.53 of open at the median): the far
/// eye's lids drift, and an open far eye at 30–45° of turn reads down to 0.3 of its aperture.
pub const WINK_OPENNESS: f64 = 0.3;
pub const WINK_UPPER: f64 = 0.45;
pub const WINK_NEAR: f64 = 0.1;

/// The eye turned away from the camera (`true`: the subject's left) and how much of the other
/// eye's lids it takes, for a head at `pose` with its eyes' centres at `centers` (`[right,
/// left]`, model frame); `None` when neither is turned away by [`FAR_EYE_FROM_DEG`].
fn far_eye(pose: &RigidTransform, centers: [[f64; 3]; 2]) -> Option<(bool, f64)> {
    let mid: [f64; 3] = std::array::from_fn(|i| 0.5 * (centers[0][i] + centers[1][i]));
    let camera = pose.apply_inverse([0.0; 3]);
    let v: [f64; 3] = std::array::from_fn(|i| camera[i] - mid[i]);
    let yaw = v[0].atan2(v[2]).to_degrees();
    let share =
        ((yaw.abs() - FAR_EYE_FROM_DEG) / (FAR_EYE_FULL_DEG - FAR_EYE_FROM_DEG)).clamp(0.0, 1.0);
    // The far eye lies on the side the camera is not.
    let left_side = centers[1][0] - centers[0][0];
    (share > 0.0).then_some((v[0] * left_side < 0.0, share))
}

/// The index of ARKit's `{shape}Left` or `{shape}Right`.
fn index(shape: &str, left: bool) -> Option<usize> {
    let name = format!("{shape}{}", if left { "Left" } else { "Right" });
    ARKIT_BLENDSHAPES.iter().position(|n| *n == name)
}

fn set(frame: &mut BlendshapeFrame, shape: &str, left: bool, w: f64) {
    if let Some(i) = index(shape, left) {
        frame.weights[i] = w as f32;
    }
}

fn get(frame: &BlendshapeFrame, shape: &str, left: bool) -> f64 {
    index(shape, left).map_or(0.0, |i| frame.weights[i] as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CONTOUR_CORNERS_OFFSET_M;

    /// A frontal head 0.5 m away, its eyes 30 mm wide, `apertures` open (right, left), the
    /// irises `drop_m` below the eyes' centres.
    fn frame(
        apertures: [f64; 2],
        drop_m: f64,
    ) -> (Intrinsics, RigidTransform, [EyeObservation; 2]) {
        let k = Intrinsics::new(640, 480, 500.0, 500.0, 320.0, 240.0).unwrap();
        let pose = RigidTransform {
            rotation: [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
            translation: [0.0, 0.0, 0.5],
        };
        let eyes = [-0.03, 0.03].map(|x0: f64| [x0 - 0.015, x0 + 0.015]);
        let obs = std::array::from_fn(|e| {
            let [a, b] = eyes[e];
            let mid = 0.5 * (a + b);
            let p = |x: f64, y: f64| k.project(pose.apply([x, y, 0.0]));
            let h = 0.015 * apertures[e];
            // The contour's corners where the gaze model expects them.
            let [ox, oy, oz] = CONTOUR_CORNERS_OFFSET_M;
            let side = mid.signum();
            let contour = |x: f64| k.project(pose.apply([x + side * ox, oy, oz]));
            EyeObservation {
                lids: Some(LidPoints {
                    upper: p(mid, h),
                    lower: p(mid, -h),
                    corners: [contour(a), contour(b)],
                }),
                iris_px: p(mid, -drop_m),
                corners: [[a, 0.0, 0.0], [b, 0.0, 0.0]],
            }
        });
        (k, pose, obs)
    }

    /// A head 0.5 m in front of the camera, turned by `yaw_deg` about its own vertical axis.
    fn turned(yaw_deg: f64) -> RigidTransform {
        let (c, s) = (yaw_deg.to_radians().cos(), yaw_deg.to_radians().sin());
        // Model → camera: a half turn about x (frontal), after a turn about the model's y.
        let yaw = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]];
        let frontal = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
        RigidTransform {
            rotation: std::array::from_fn(|i| {
                std::array::from_fn(|j| (0..3).map(|k| frontal[i][k] * yaw[k][j]).sum())
            }),
            translation: [0.0, 0.0, 0.5],
        }
    }

    fn look_down(f: &BlendshapeFrame, left: bool) -> f64 {
        get(f, "eyeLookDown", left)
    }

    #[test]
    fn a_blink_of_one_eye_closes_it_and_holds_both_gazes_until_it_lifts() {
        let mut rig = EyeRig::default();
        for i in 0..30 {
            let (k, pose, eyes) = frame([0.33, 0.33], 0.0);
            let mut f = BlendshapeFrame::new(i, 0.0);
            rig.apply(&k, &pose, eyes, None, &mut f);
            assert!(get(&f, "eyeBlink", false) < 0.05 && look_down(&f, false) < 0.01);
        }
        // The right lid closes and drags the irises the network finds down by 4 mm.
        let (k, pose, eyes) = frame([0.05, 0.3], 0.004);
        let mut f = BlendshapeFrame::new(30, 0.0);
        rig.apply(&k, &pose, eyes, None, &mut f);
        assert!(get(&f, "eyeBlink", false) > 0.95, "{:?}", f.weights);
        assert!(get(&f, "eyeBlink", true) < 0.2, "{:?}", f.weights);
        assert!(look_down(&f, false) < 0.01 && look_down(&f, true) < 0.01);
        // Open again, looking down: held one frame more, then followed.
        let (k, pose, eyes) = frame([0.33, 0.33], 0.004);
        let mut f = BlendshapeFrame::new(31, 0.0);
        rig.apply(&k, &pose, eyes, None, &mut f);
        assert!(look_down(&f, false) < 0.01);
        let mut f = BlendshapeFrame::new(32, 0.0);
        rig.apply(&k, &pose, eyes, None, &mut f);
        assert!(
            look_down(&f, false) > 0.3 && look_down(&f, true) > 0.3,
            "{:?}",
            f.weights
        );
    }

    #[test]
    fn the_eye_turned_away_takes_the_near_eye_lids_as_the_head_turns() {
        let centers = [[-0.03, 0.0, 0.0], [0.03, 0.0, 0.0]];
        assert_eq!(far_eye(&turned(5.0), centers), None);
        let (far, share) = far_eye(&turned(40.0), centers).unwrap();
        assert_eq!(share, 1.0);
        let (other, half) = far_eye(&turned(-22.5), centers).unwrap();
        assert!(far != other && (half - 0.5).abs() < 0.05, "{half}");
        // The far eye is the one farther from the camera.
        let depth = |yaw: f64, eye: usize| turned(yaw).apply(centers[eye])[2];
        assert!(depth(40.0, far as usize) > depth(40.0, !far as usize));
    }

    #[test]
    fn the_eye_turned_away_keeps_a_wink_and_takes_the_near_eye_lids_otherwise() {
        let k = Intrinsics::new(640, 480, 500.0, 500.0, 320.0, 240.0).unwrap();
        let pose = turned(40.0);
        let centers = [[-0.03, 0.0, 0.0], [0.03, 0.0, 0.0]];
        let (far, _) = far_eye(&pose, centers).unwrap();
        // Each eye's upper and lower lids `[up, down]` metres from its corners' line.
        let eyes = |lids: [[f64; 2]; 2]| {
            std::array::from_fn(|e| {
                let x = centers[e][0];
                let p = |x: f64, y: f64| k.project(pose.apply([x, y, 0.0]));
                let [up, down] = lids[e];
                EyeObservation {
                    lids: Some(LidPoints {
                        upper: p(x, up),
                        lower: p(x, -down),
                        corners: [p(x - 0.015, 0.0), p(x + 0.015, 0.0)],
                    }),
                    iris_px: p(x, 0.0),
                    corners: [[x - 0.015, 0.0, 0.0], [x + 0.015, 0.0, 0.0]],
                }
            })
        };
        let open = [0.006, 0.004];
        let mut rig = EyeRig::default();
        for i in 0..30 {
            let mut f = BlendshapeFrame::new(i, 0.0);
            rig.apply(&k, &pose, eyes([open; 2]), None, &mut f);
        }
        let blinks = |rig: &mut EyeRig, far_lids: [f64; 2]| {
            let mut lids = [open; 2];
            lids[far as usize] = far_lids;
            let mut f = BlendshapeFrame::new(30, 0.0);
            rig.apply(&k, &pose, eyes(lids), None, &mut f);
            [far, !far].map(|left| get(&f, "eyeBlink", left))
        };
        // The far eye shut, its upper lid down to its lower one: a wink, kept.
        let [far_blink, near_blink] = blinks(&mut rig, [-0.0035, 0.004]);
        assert!(
            far_blink > 0.95 && near_blink < 0.05,
            "{far_blink} {near_blink}"
        );
        // Half shut (its lids drift as it turns away): the near eye's open lids.
        let [far_blink, _] = blinks(&mut rig, [0.003, 0.002]);
        assert!(far_blink < 0.05, "{far_blink}");
    }

    #[test]
    fn the_eye_turned_away_follows_the_near_eye_gaze() {
        use crate::gaze::{EYEBALL_DEPTH_M, IRIS_ROTATION_RADIUS_M};
        let k = Intrinsics::new(640, 480, 500.0, 500.0, 320.0, 240.0).unwrap();
        let pose = turned(40.0);
        let centers = [[-0.03, 0.0, 0.0], [0.03, 0.0, 0.0]];
        let (far, share) = far_eye(&pose, centers).unwrap();
        assert_eq!(share, 1.0);
        // Both eyes look ahead, but the far eye's iris is found 3 mm off towards its side.
        let eyes = std::array::from_fn(|e| {
            let x = centers[e][0];
            let off = if e == far as usize { 0.003 } else { 0.0 };
            let rest = [x + off, 0.0, IRIS_ROTATION_RADIUS_M - EYEBALL_DEPTH_M];
            EyeObservation {
                lids: None,
                iris_px: k.project(pose.apply(rest)),
                corners: [[x - 0.015, 0.0, 0.0], [x + 0.015, 0.0, 0.0]],
            }
        });
        let mut f = BlendshapeFrame::new(0, 0.0);
        EyeRig::default().apply(&k, &pose, eyes, None, &mut f);
        for name in ["eyeLookIn", "eyeLookOut", "eyeLookUp", "eyeLookDown"] {
            for left in [false, true] {
                assert!(get(&f, name, left) < 0.01, "{name} {left}: {:?}", f.weights);
            }
        }
        assert_eq!(f.left_eye, f.right_eye);
    }

    #[test]
    fn without_a_contour_the_fit_keeps_the_lids() {
        let mut rig = EyeRig::default();
        let (k, pose, mut eyes) = frame([0.33, 0.33], 0.0);
        eyes.iter_mut().for_each(|e| e.lids = None);
        let mut f = BlendshapeFrame::new(0, 0.0);
        set(&mut f, "eyeBlink", true, 0.7);
        rig.apply(&k, &pose, eyes, None, &mut f);
        assert_eq!(get(&f, "eyeBlink", true), 0.7f32 as f64);
    }
}
