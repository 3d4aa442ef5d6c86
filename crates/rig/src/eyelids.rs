//! The eyelids from the eye network's contour: how far each eye is open, and the blink and
//! wide-eye weights an animator expects from it.
//!
//! The 468-point face mesh barely closes its eyes: on the sample clips a full blink keeps 0.8
//! of the open aperture there, so a fit to those landmarks reads blinks as 0.05–0.3. The iris
//! network, run on each eye's crop every frame, also returns the eye's contour, and its lids
//! close to 0.2–0.45 of the open aperture at the same frames (MediaPipe's attention mesh:
//! 0.2–0.35). So the blink comes from the contour:
//!
//! - **Aperture**: the upper to lower lid centre distance over the corners' distance, both
//!   measured along the face's own vertical and horizontal axes at the eye (the fitted head
//!   pose's axes projected through the camera; the corners' distance corrected for their
//!   depths on the fitted face), so turning or tilting the head does not open or close the eye
//!   ([`opening`]).
//! - **Calibration per person**: the eye's open aperture is the [`OPEN_QUANTILE`] of its
//!   apertures so far (a face's eyes are open most of the time, and a high quantile still holds
//!   when they are closed for long stretches), but never below [`MIN_OPEN_APERTURE`] (a clip
//!   that starts with closed eyes). Relative to it, `eyeBlink` rises linearly from
//!   [`OPEN_EDGE`] (1 − `eyeBlink` = 0: the open eye's frame-to-frame spread stays below it) to
//!   the closed aperture (closed), and `eyeWide` from [`WIDE_EDGE`] to [`WIDE_FULL`].
//! - **The closed eye as seen**: the eye network's contour of a closed eye seen from below
//!   keeps its lids further apart than seen from above, while an open eye's aperture barely
//!   changes with the view. On renders of four identities playing a
//!   range-of-motion take, eyes played at `eyeBlink` ≥ 0.8 read a median 0.59 of the open
//!   aperture from 17–25° below, 0.33 from 17–25° above, while open eyes read 0.99–1.10 at
//!   every pitch. So the closed aperture is [`CLOSED_APERTURE`] head-on and from above, and
//!   rises by [`CLOSED_PER_PITCH_BELOW`] per radian of the eye's view from below
//!   ([`closed_aperture`]).
//! - **A squint is not a blink**: a squint raises the lower lid and narrows the aperture as a
//!   partial blink does, but a blink is the upper lid coming down. The upper lid's height
//!   above the corners, corrected for the view ([`upper_lid_seen`]) and taken relative to the
//!   person's open eye like the aperture, caps `eyeBlink`: an eye whose upper lid stays up
//!   cannot read closed ([`UPPER_OPEN_EDGE`], [`UPPER_CLOSED`]).

use visage_camera::{Intrinsics, RigidTransform};

use crate::histogram::Histogram;

/// One eye's lid points in frame pixels: the upper and lower lid centres and the two corners.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LidPoints {
    pub upper: [f64; 2],
    pub lower: [f64; 2],
    pub corners: [[f64; 2]; 2],
}

/// The open aperture is this quantile of the eye's apertures so far.
pub const OPEN_QUANTILE: f64 = 0.75;

/// The open aperture is never taken below this (the eye network's lids of an open adult eye
/// sit at 0.29–0.36 of its width on the sample clips).
pub const MIN_OPEN_APERTURE: f64 = 0.22;

/// Relative to the open aperture: where `eyeBlink` starts to rise. On the sample clips 95 % of
/// the frames whose eyes are open (by MediaPipe's attention mesh) stay above 0.88.
pub const OPEN_EDGE: f64 = 0.92;

/// Relative to the open aperture: a closed eye (`eyeBlink` 1). The eye network's lids of a
/// closed eye sit at 0.2–0.45 of the open aperture on the sample clips and at 0.3–0.5 on eye
/// crops of unseen closed eyes; on the pixel benchmark's tuning take 0.4 catches 95 % of the
/// played blinks (0.3: 84 %) with no false closure.
pub const CLOSED_APERTURE: f64 = 0.4;

/// How the closed aperture rises as the eye is seen from below, per radian of the eye's view
/// pitch: the slope of a line through the closed eyes' apertures against the pitch on renders
/// of four identities playing `alex_rom_3` (`docs/performance.md`, "the closed eye as seen").
/// Seen from above, a closed eye's lids already read under [`CLOSED_APERTURE`]; lowering it
/// there would only read a nearly closed eye as less closed (on the held-out takes, brief
/// closures of 0.81 seen from 20° above fell under the benchmark's bar), so it stays.
pub const CLOSED_PER_PITCH_BELOW: f64 = 0.35;

/// The view pitch (radians) past which the closed aperture stops rising: the lowest view of an
/// eye in the renders (37°; the head tilted back by 25° and the eye above the camera's axis).
const CLOSED_PITCH_RANGE: f64 = 0.65;

/// The closed aperture relative to the open one, for an eye seen at `pitch` (radians, the
/// camera above the eye positive: a head bowed toward the camera; below it negative).
pub fn closed_aperture(pitch: f64) -> f64 {
    let below = if pitch.is_finite() { -pitch } else { 0.0 };
    CLOSED_APERTURE + CLOSED_PER_PITCH_BELOW * below.clamp(0.0, CLOSED_PITCH_RANGE)
}

/// Relative to the open aperture: where `eyeWide` starts to rise, and where it reaches 1.
pub const WIDE_EDGE: f64 = 1.1;
pub const WIDE_FULL: f64 = 1.45;

/// Apertures above this are out of the histogram's range (a wide-open eye is about 0.45).
const MAX_APERTURE: f64 = 1.0;

/// How the upper lid's height over the eye's width shows with the view, per unit of the sine
/// of the eye's view pitch (camera above positive) and of its view yaw's size: the lid's centre
/// lies in front of the corners, so seen from above it shows lower, and a turned eye's lids
/// show closer to the corners' line. Both are the mean slopes of the open eyes' upper lids on
/// renders of two identities playing `alex_rom_3` (right and left eyes: pitch 0.08–0.16, yaw
/// 0.04–0.17; `docs/performance.md`, "a squint is not a blink").
pub const UPPER_PER_PITCH: f64 = 0.12;
pub const UPPER_PER_YAW: f64 = 0.11;

/// The upper lid's height over the eye's width as if seen head-on, from [`LidOpening::upper`]
/// seen at `view` (the eye's view yaw and pitch, radians).
pub fn upper_lid_seen(upper: f64, view: [f64; 2]) -> f64 {
    let [yaw, pitch] = view.map(|a| if a.is_finite() { a } else { 0.0 });
    upper + UPPER_PER_PITCH * pitch.sin() + UPPER_PER_YAW * yaw.sin().abs()
}

/// Relative to the upper lid's open height: at or above [`UPPER_OPEN_EDGE`] the eye cannot
/// read as blinking at all; `eyeBlink`'s cap falls linearly to 1 at [`UPPER_CLOSED`]. On the
/// renders, the frame of each played blink's strongest closure has its upper lid at 0.45–0.53
/// of the open height (median), at most 0.78–0.85; an eye that squints at 0.2–0.6 seen from
/// 25–30° below and turned 30–42° keeps it at 0.5–0.9 while its aperture reads 0.3–0.7.
pub const UPPER_OPEN_EDGE: f64 = 1.1;
pub const UPPER_CLOSED: f64 = 0.6;

/// The upper lid's open height is the [`OPEN_QUANTILE`] of its heights so far, never below this
/// (an open eye's is 0.24–0.28 of the eye's width on the renders).
const MIN_OPEN_UPPER: f64 = 0.13;

/// Upper-lid heights above this are out of the histogram's range.
const MAX_UPPER: f64 = 0.6;

/// One eye's reading in a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LidReading {
    /// The aperture over the eye's open aperture.
    pub openness: f64,
    /// The upper lid's height ([`upper_lid_seen`]) over its open height.
    pub upper: f64,
    /// ARKit's `eyeBlink` of the eye, [0, 1].
    pub blink: f64,
    /// ARKit's `eyeWide` of the eye, [0, 1].
    pub wide: f64,
}

/// How far an eye's lids are apart, and where its upper lid is, both over the eye's width.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LidOpening {
    /// The upper to lower lid centre distance.
    pub aperture: f64,
    /// The upper lid centre's height above the midpoint of the corners (negative below).
    pub upper: f64,
}

/// The opening of an eye ([`LidOpening`]): the lids' distances measured along the face's own vertical and horizontal axes at the eye (the fitted head
/// pose's axes projected through the camera), so turning or tilting the head does not open or
/// close the eye. The outer corner lies about a centimetre behind the inner one, so their
/// distance along the face's horizontal axis does not follow the head's turn exactly: it is
/// scaled by how the fitted face's own corners, `corners` (model frame, metres; x to the
/// face's left-to-right, y up), measure at this pose against their true distance. `pose` is the
/// head's (model frame → camera). `None` when the eye is seen edge-on or the corners coincide.
pub fn opening(
    k: &Intrinsics,
    pose: &RigidTransform,
    corners: [[f64; 3]; 2],
    lids: &LidPoints,
) -> Option<LidOpening> {
    let eye_center: [f64; 3] = std::array::from_fn(|i| 0.5 * (corners[0][i] + corners[1][i]));
    let width = (0..3)
        .map(|i| (corners[1][i] - corners[0][i]).powi(2))
        .sum::<f64>()
        .sqrt();
    let c = pose.apply(eye_center);
    if c[2] <= 0.0 || width <= 0.0 {
        return None;
    }
    // Pixels per metre along the face's x and y at the eye: the projection's Jacobian applied
    // to the rotated axes.
    let project = |v: [f64; 3]| {
        [
            k.fx * (v[0] - c[0] * v[2] / c[2]) / c[2],
            k.fy * (v[1] - c[1] * v[2] / c[2]) / c[2],
        ]
    };
    let r = &pose.rotation;
    let ax = project([r[0][0], r[1][0], r[2][0]]);
    let ay = project([r[0][1], r[1][1], r[2][1]]);
    let det = ax[0] * ay[1] - ay[0] * ax[1];
    if det.abs() < 1e-9 * (ax[0].hypot(ax[1]) * ay[0].hypot(ay[1])).max(f64::MIN_POSITIVE) {
        return None;
    }
    // [a, b] with a·ax + b·ay = d: a pixel offset in the face's own axes.
    let face_axes = |d: [f64; 2]| {
        [
            (d[0] * ay[1] - ay[0] * d[1]) / det,
            (ax[0] * d[1] - d[0] * ax[1]) / det,
        ]
    };
    let sub = |p: [f64; 2], q: [f64; 2]| [p[0] - q[0], p[1] - q[1]];
    let height = face_axes(sub(lids.upper, lids.lower))[1];
    let mid = [
        0.5 * (lids.corners[0][0] + lids.corners[1][0]),
        0.5 * (lids.corners[0][1] + lids.corners[1][1]),
    ];
    let upper = face_axes(sub(lids.upper, mid))[1];
    let seen_width = face_axes(sub(lids.corners[1], lids.corners[0]))[0].abs();
    let [c0, c1] = corners.map(|x| k.project(pose.apply(x)));
    let model_width = face_axes(sub(c1, c0))[0].abs();
    let scale = width / model_width;
    // The eye's turn from the camera: the direction to the camera, −c, in the model frame.
    let v: [f64; 3] = std::array::from_fn(|i| -(0..3).map(|j| r[j][i] * c[j]).sum::<f64>());
    let turn = v[0].atan2(v[2]).to_degrees().abs();
    let share = ((turn - SEEN_WIDTH_UNTIL_DEG) / (FACE_WIDTH_FROM_DEG - SEEN_WIDTH_UNTIL_DEG))
        .clamp(0.0, 1.0);
    let width = (1.0 - share) * seen_width * scale + share * width;
    (width > 0.0 && height.is_finite() && upper.is_finite() && scale.is_finite()).then(|| {
        LidOpening {
            aperture: height.max(0.0) / width,
            upper: upper / width,
        }
    })
}

/// The eye's width is the one its contour's corners show, corrected for their depths, while
/// the eye is turned from the camera by less than [`SEEN_WIDTH_UNTIL_DEG`]: the lids and the
/// corners then come from the same crop, and the crop's frame-to-frame jitter in scale cancels
/// in the ratio. From [`FACE_WIDTH_FROM_DEG`] it is the fitted face's: the contour's far corner
/// hides behind the eyeball's bulge and its corners drift.
pub const SEEN_WIDTH_UNTIL_DEG: f64 = 15.0;
pub const FACE_WIDTH_FROM_DEG: f64 = 30.0;

/// Both eyes' open apertures and upper lids so far (the subject's right eye, then the left).
#[derive(Clone, Debug)]
pub struct Eyelids {
    apertures: [Histogram; 2],
    uppers: [Histogram; 2],
}

impl Default for Eyelids {
    fn default() -> Self {
        Eyelids {
            apertures: std::array::from_fn(|_| Histogram::new(0.0, MAX_APERTURE)),
            uppers: std::array::from_fn(|_| Histogram::new(0.0, MAX_UPPER)),
        }
    }
}

impl Eyelids {
    /// Adds the eye's opening in this frame (`left`: the subject's left eye), seen at `view`
    /// (the eye's view yaw and pitch, radians: [`closed_aperture`], [`upper_lid_seen`]), and
    /// reads its blink and wide-eye weights relative to the person's open eye.
    pub fn read(&mut self, left: bool, opening: LidOpening, view: [f64; 2]) -> LidReading {
        let hist = &mut self.apertures[left as usize];
        hist.push(opening.aperture);
        let open = hist.quantile(OPEN_QUANTILE).max(MIN_OPEN_APERTURE);
        let openness = opening.aperture / open;
        let closed = closed_aperture(view[1]);
        let upper = upper_lid_seen(opening.upper, view);
        let hist = &mut self.uppers[left as usize];
        hist.push(upper);
        let upper = upper / hist.quantile(OPEN_QUANTILE).max(MIN_OPEN_UPPER);
        let cap = (UPPER_OPEN_EDGE - upper) / (UPPER_OPEN_EDGE - UPPER_CLOSED);
        LidReading {
            openness,
            upper,
            blink: ((OPEN_EDGE - openness) / (OPEN_EDGE - closed))
                .clamp(0.0, 1.0)
                .min(cap.clamp(0.0, 1.0)),
            wide: ((openness - WIDE_EDGE) / (WIDE_FULL - WIDE_EDGE)).clamp(0.0, 1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frontal() -> (Intrinsics, RigidTransform) {
        let k = Intrinsics::new(640, 480, 500.0, 500.0, 320.0, 240.0).unwrap();
        // Model y up → camera y down: a half turn about x.
        let pose = RigidTransform {
            rotation: [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
            translation: [0.0, 0.0, 0.5],
        };
        (k, pose)
    }

    /// The corners of an eye 30 mm wide, centred at the model's origin, the outer (+x) one a
    /// centimetre behind the inner one.
    const CORNERS: [[f64; 3]; 2] = [[-0.015, 0.0, 0.005], [0.015, 0.0, -0.005]];

    /// An eye 30 mm wide, `aperture` × 30 mm open, centred at the model's origin, as `pose`
    /// shows it.
    fn eye(k: &Intrinsics, pose: &RigidTransform, aperture: f64) -> LidPoints {
        let p = |x: [f64; 3]| k.project(pose.apply(x));
        LidPoints {
            upper: p([0.0, 0.015 * aperture, 0.0]),
            lower: p([0.0, -0.015 * aperture, 0.0]),
            corners: CORNERS.map(p),
        }
    }

    #[test]
    fn the_aperture_does_not_change_as_the_head_turns() {
        let (k, frontal) = frontal();
        // The lids 9 mm apart over the corners' distance in space.
        let expected = 0.009 / 0.03f64.hypot(0.01);
        let o = opening(&k, &frontal, CORNERS, &eye(&k, &frontal, 0.3)).unwrap();
        assert!((o.aperture - expected).abs() < 1e-9, "{o:?}");
        // The lids are symmetric about the corners.
        assert!((o.upper - 0.5 * expected).abs() < 1e-9, "{o:?}");
        for (yaw, pitch) in [(0.6f64, 0.0f64), (0.0, 0.4), (-0.5, -0.3)] {
            let (cy, sy, cp, sp) = (yaw.cos(), yaw.sin(), pitch.cos(), pitch.sin());
            let turn = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
            let tilt = [[1.0, 0.0, 0.0], [0.0, cp, -sp], [0.0, sp, cp]];
            let m = |a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]| {
                std::array::from_fn(|i| {
                    std::array::from_fn(|j| (0..3).map(|l| a[i][l] * b[l][j]).sum())
                })
            };
            let pose = RigidTransform {
                rotation: m(&frontal.rotation, &m(&turn, &tilt)),
                translation: [0.02, -0.01, 0.5],
            };
            let lids = eye(&k, &pose, 0.3);
            let o = opening(&k, &pose, CORNERS, &lids).unwrap();
            // Perspective bends the small eye only slightly.
            assert!(
                (o.aperture - expected).abs() < 0.01,
                "yaw {yaw} pitch {pitch}: {o:?}"
            );
            assert!(
                (o.upper - 0.5 * expected).abs() < 0.01,
                "yaw {yaw} pitch {pitch}: {o:?}"
            );
            // The image ratio alone does change.
            let d = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
            let image = d(lids.upper, lids.lower) / d(lids.corners[0], lids.corners[1]);
            assert!(
                (image - 0.3).abs() > 0.015,
                "yaw {yaw} pitch {pitch}: {image}"
            );
        }
    }

    /// An eye `aperture` open, its lids symmetric about the corners head-on, as seen at `view`
    /// ([`upper_lid_seen`]'s inverse).
    fn seen(aperture: f64, view: [f64; 2]) -> LidOpening {
        let upper = 0.5 * aperture;
        LidOpening {
            aperture,
            upper: upper - (upper_lid_seen(upper, view) - upper),
        }
    }

    const HEAD_ON: [f64; 2] = [0.0, 0.0];

    #[test]
    fn a_closed_eye_blinks_an_open_one_does_not_and_a_wide_one_widens() {
        let mut lids = Eyelids::default();
        for i in 0..200 {
            // Open at 0.33 ± 3 %, a blink every 50 frames.
            let a = if i % 50 == 0 {
                0.08
            } else {
                0.33 * (1.0 + 0.03 * ((i % 3) as f64 - 1.0))
            };
            let r = lids.read(false, seen(a, HEAD_ON), HEAD_ON);
            if i > 20 && i % 50 != 0 {
                assert!(r.blink < 0.05 && r.wide == 0.0, "frame {i}: {r:?}");
            }
        }
        let closed = lids.read(false, seen(0.1, HEAD_ON), HEAD_ON);
        assert!(closed.blink > 0.95, "{closed:?}");
        let half = lids.read(false, seen(0.2, HEAD_ON), HEAD_ON);
        assert!(half.blink > 0.3 && half.blink < 0.7, "{half:?}");
        let wide = lids.read(false, seen(0.5, HEAD_ON), HEAD_ON);
        assert!(wide.wide > 0.9 && wide.blink == 0.0, "{wide:?}");
        // The other eye has its own calibration: nothing seen yet, so the floors hold.
        assert!(lids.read(true, seen(0.05, HEAD_ON), HEAD_ON).blink > 0.95);
    }

    #[test]
    fn a_squint_narrows_the_eye_without_closing_it() {
        let mut lids = Eyelids::default();
        for _ in 0..100 {
            lids.read(false, seen(0.33, HEAD_ON), HEAD_ON);
        }
        // 0.45 of the open aperture: the lower lid risen past the corners' line and the upper
        // lid where it was (a squint), or the upper lid come down (a blink).
        let squint = LidOpening {
            aperture: 0.45 * 0.33,
            upper: 0.5 * 0.33,
        };
        let blink = LidOpening {
            aperture: 0.45 * 0.33,
            upper: 0.0,
        };
        let r = lids.read(false, squint, HEAD_ON);
        assert!(r.blink < 0.25, "{r:?}");
        let r = lids.read(false, blink, HEAD_ON);
        assert!(r.blink > 0.85, "{r:?}");
        // The upper lid part way down caps the blink part way.
        let between = LidOpening {
            aperture: 0.45 * 0.33,
            upper: 0.5 * (UPPER_OPEN_EDGE + UPPER_CLOSED) * 0.5 * 0.33,
        };
        let r = lids.read(false, between, HEAD_ON);
        assert!((r.blink - 0.5).abs() < 0.05, "{r:?}");
    }

    #[test]
    fn a_nearly_closed_eye_seen_from_below_reads_more_closed() {
        let mut lids = Eyelids::default();
        for _ in 0..100 {
            lids.read(false, seen(0.33, HEAD_ON), HEAD_ON);
        }
        // 0.55 of the open aperture: a closed eye seen from 25° below, half closed head-on
        // and from above.
        let at = |lids: &mut Eyelids, pitch| {
            lids.read(false, seen(0.55 * 0.33, [0.0, pitch]), [0.0, pitch])
        };
        let below = at(&mut lids, -0.44);
        let head_on = at(&mut lids, 0.0);
        let above = at(&mut lids, 0.44);
        assert!(below.blink > 0.95, "{below:?}");
        assert!(head_on.blink > 0.5 && head_on.blink < 0.8, "{head_on:?}");
        assert_eq!(above.blink, head_on.blink);
        // An open eye stays open from any view, and the view past the renders' range counts
        // as their edge.
        for pitch in [-1.0, -0.44, 0.44, 1.0, f64::NAN] {
            let view = [0.3, pitch];
            assert_eq!(lids.read(false, seen(0.33, view), view).blink, 0.0);
        }
        assert_eq!(closed_aperture(-1.0), closed_aperture(-CLOSED_PITCH_RANGE));
        assert!(closed_aperture(-0.6) > closed_aperture(-0.44));
        assert_eq!(closed_aperture(f64::NAN), CLOSED_APERTURE);
        assert_eq!(closed_aperture(0.3), CLOSED_APERTURE);
    }

    #[test]
    fn a_clip_that_starts_with_closed_eyes_reads_them_closed() {
        let mut lids = Eyelids::default();
        for _ in 0..100 {
            let r = lids.read(false, seen(0.08, HEAD_ON), HEAD_ON);
            assert!(r.blink > 0.6, "{r:?}");
        }
    }
}
