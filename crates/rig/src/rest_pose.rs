//! Expression weights relative to the person's resting face — what Live Link Face calls
//! calibrating the neutral pose, estimated from the clip instead of asked for.
//!
//! The model's neutral face is MediaPipe's mean face; a real person at rest differs from it in
//! ways the identity modes (learned from scans with neutral expressions) do not cover — eyes
//! more open, lips pressed — and the fit spends expression weights on them: 0.8 of `eyeWide`
//! on both sample clips at rest. An animator wants 0 at rest. So, per clip and causally:
//! - a one-sided shape's rest weight is its [`REST_QUANTILE`] over the frames so far (a face
//!   rests more often than not; the quantile is robust to the rest), and the output is
//!   `(w − rest) / (1 − rest)`, clamped to [0, 1];
//! - each eye's lid is one signed axis, not two independent shapes: the upper lid's height
//!   `h = a·eyeWide − b·eyeBlink` (a, b: how far the model's shapes move the lid landmark, in
//!   mm per unit weight) rests at its median; below rest is a blink (`−Δh / b`), above a wide
//!   eye (`Δh / a`). Without this, a blink of a wide-resting eye only lowers `eyeWide`.
//!
//! - the shapes that close the lips (`mouthPress`, `mouthClose`, `mouthShrug`, `mouthRoll`)
//!   rest at their median over the frames whose lips are closed ([`lips_closed`]) once there
//!   are [`MIN_CLOSED_FRAMES`] of them: ICT-FaceKit's neutral face holds the inner lips 4.5 mm
//!   apart, so a relaxed closed mouth needs about 0.7 of `mouthPress` — and a talking face's
//!   lips are apart more often than not, so the 10th percentile of those shapes is 0 and a
//!   closed mouth read as pressed lips; the range above a rest weight is stretched by at most
//!   `1 / MIN_RANGE`;
//! - gaze is relative to its median per eye: the eyeball model's centre and the eye's own
//!   optical axis (the angle kappa between the visual and the pupillary axis, ~5°) are not
//!   known per person, and in face capture the eyes rest on the camera.
//!
//! Quantiles come from per-shape histograms of [`crate::histogram::BINS`] bins over [0, 1] (lid heights over
//! their own range), so memory does not grow with the clip.

use visage_morphable::fit::LandmarkBasis;
use visage_morphable::FaceModel;

use crate::gaze::EyeGaze;
use crate::histogram::Histogram;

/// The quantile of a one-sided shape's weights taken as its rest value.
pub const REST_QUANTILE: f64 = 0.1;

/// The range above a shape's rest weight is stretched to [0, 1], but never by more than
/// `1 / MIN_RANGE`: a shape that rests near the top of its box (a closed mouth held by 0.8–1.0
/// of `mouthPress` on the sample clip `lp_d18`, whose fit cannot press harder than 1) would
/// otherwise turn the frame-to-frame noise at its bound into 0 or 1 (`mouthPressRight` sat at
/// 1.0 in 31 % of that clip's frames).
pub const MIN_RANGE: f64 = 0.5;

/// FaceMesh's upper-lid centre landmarks: the subject's right eye, then the left.
const UPPER_LID: [usize; 2] = [159, 386];

/// Frames with closed lips needed before the lip-closing shapes rest at their median over them.
pub const MIN_CLOSED_FRAMES: u32 = 5;

/// The lips are closed when the inner lips' gap is below this fraction of the distance between
/// the eyes' outer corners (about 1.8 mm on an adult face).
pub const CLOSED_LIP_GAP: f64 = 0.02;

/// Expression name prefixes of the shapes that close the lips.
const LIP_CLOSING: [&str; 4] = ["mouthPress", "mouthClose", "mouthShrug", "mouthRoll"];

/// Whether the tracked landmarks (468, pixels) show closed lips: the gap between the inner
/// lips' centres (13, 14) under [`CLOSED_LIP_GAP`] of the eye corners' distance (33, 263).
pub fn lips_closed(landmarks_px: &[[f64; 2]]) -> bool {
    if landmarks_px.len() < 468 {
        return false;
    }
    let d = |i: usize, j: usize| {
        let (p, q) = (landmarks_px[i], landmarks_px[j]);
        (p[0] - q[0]).hypot(p[1] - q[1])
    };
    let eyes = d(33, 263);
    eyes > 0.0 && d(13, 14) < CLOSED_LIP_GAP * eyes
}

/// One eye's lid axis: the expression indices and how far they move the upper lid (metres
/// per unit weight, positive).
#[derive(Clone, Copy, Debug)]
struct Lid {
    wide: usize,
    blink: usize,
    up: f64,
    down: f64,
}

/// The clip's rest pose so far and the mapping of raw weights to weights relative to it.
#[derive(Clone, Debug)]
pub struct RestPose {
    shapes: Vec<Histogram>,
    /// Per expression: for the lip-closing shapes, their weights in closed-lip frames.
    closed_lips: Vec<Option<Histogram>>,
    lids: Vec<(Lid, Histogram)>,
    /// Per eye (the subject's right, then left): yaw and pitch.
    gaze: [[Histogram; 2]; 2],
}

/// The range of gaze angles the histograms cover (radians).
const GAZE_RANGE: f64 = 1.0;

impl RestPose {
    /// A rest pose for `model`'s expressions, with no frame seen yet.
    pub fn new(model: &FaceModel) -> RestPose {
        let basis = LandmarkBasis::new(model);
        let n_id = basis.identity_count;
        // Vertical (model y) motion of a lid landmark per unit of an expression.
        let lift = |landmark: usize, e: usize| basis.row(3 * landmark + 1)[n_id + e];
        let lids = [("_R", UPPER_LID[0]), ("_L", UPPER_LID[1])]
            .into_iter()
            .filter_map(|(side, landmark)| {
                let wide = model.expression_index(&format!("eyeWide{side}"))?;
                let blink = model.expression_index(&format!("eyeBlink{side}"))?;
                let (up, down) = (lift(landmark, wide), -lift(landmark, blink));
                (up > 0.0 && down > 0.0).then(|| {
                    let lid = Lid {
                        wide,
                        blink,
                        up,
                        down,
                    };
                    (lid, Histogram::new(-down, up))
                })
            })
            .collect();
        RestPose {
            shapes: (0..model.expressions.len())
                .map(|_| Histogram::new(0.0, 1.0))
                .collect(),
            closed_lips: model
                .expression_names
                .iter()
                .map(|name| {
                    LIP_CLOSING
                        .iter()
                        .any(|p| name.starts_with(p))
                        .then(|| Histogram::new(0.0, 1.0))
                })
                .collect(),
            lids,
            gaze: std::array::from_fn(|_| {
                std::array::from_fn(|_| Histogram::new(-GAZE_RANGE, GAZE_RANGE))
            }),
        }
    }

    /// Adds an eye's gaze (`left`: the subject's left eye) and returns it relative to the
    /// eye's median gaze so far.
    pub fn calibrate_gaze(&mut self, left: bool, gaze: EyeGaze) -> EyeGaze {
        let [yaw, pitch] = &mut self.gaze[left as usize];
        yaw.push(gaze.yaw);
        pitch.push(gaze.pitch);
        EyeGaze {
            yaw: gaze.yaw - yaw.quantile(0.5),
            pitch: gaze.pitch - pitch.quantile(0.5),
        }
    }

    /// Adds a frame's raw weights to the estimate and rewrites them relative to the rest pose;
    /// `lips_closed`: whether the frame's lips are closed ([`lips_closed`]).
    pub fn calibrate(&mut self, weights: &mut [f64], lips_closed: bool) {
        let mut lid_values = Vec::with_capacity(self.lids.len());
        for (lid, hist) in &mut self.lids {
            let h = lid.up * weights[lid.wide] - lid.down * weights[lid.blink];
            hist.push(h);
            lid_values.push((*lid, h - hist.quantile(0.5)));
        }
        for ((w, hist), closed) in weights
            .iter_mut()
            .zip(&mut self.shapes)
            .zip(&mut self.closed_lips)
        {
            hist.push(*w);
            let mut rest = hist.quantile(REST_QUANTILE);
            if let Some(closed) = closed {
                if lips_closed {
                    closed.push(*w);
                }
                if closed.total() >= MIN_CLOSED_FRAMES {
                    rest = closed.quantile(0.5);
                }
            }
            *w = ((*w - rest) / (1.0 - rest).max(MIN_RANGE)).clamp(0.0, 1.0);
        }
        for (lid, delta) in lid_values {
            weights[lid.wide] = (delta / lid.up).clamp(0.0, 1.0);
            weights[lid.blink] = (-delta / lid.down).clamp(0.0, 1.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_resting_offset_is_removed_and_a_blink_of_a_wide_resting_eye_shows() {
        let model = FaceModel::embedded();
        let mut rest = RestPose::new(&model);
        let (wide, blink) = (
            model.expression_index("eyeWide_R").unwrap(),
            model.expression_index("eyeBlink_R").unwrap(),
        );
        let jaw = model.expression_index("jawOpen").unwrap();
        let n = model.expressions.len();
        // A face that rests with eyeWide 0.8 and talks (jawOpen 0.2 at rest, up to 0.7).
        let frame = |w_wide: f64, w_blink: f64, w_jaw: f64| {
            let mut w = vec![0.0; n];
            w[wide] = w_wide;
            w[blink] = w_blink;
            w[jaw] = w_jaw;
            w
        };
        for i in 0..100 {
            let mut w = frame(0.8, 0.0, 0.2 + 0.5 * ((i % 10) as f64 / 10.0));
            rest.calibrate(&mut w, false);
        }
        let mut at_rest = frame(0.8, 0.0, 0.2);
        rest.calibrate(&mut at_rest, false);
        assert!(at_rest.iter().all(|&w| w < 0.02), "{at_rest:?}");
        // The lid drops: eyeWide falls to 0 and eyeBlink rises a little.
        let mut blink_frame = frame(0.0, 0.2, 0.2);
        rest.calibrate(&mut blink_frame, false);
        assert!(blink_frame[blink] > 0.4, "{}", blink_frame[blink]);
        assert_eq!(blink_frame[wide], 0.0);
        let mut open = frame(0.8, 0.0, 0.7);
        rest.calibrate(&mut open, false);
        assert!(open[jaw] > 0.55, "{}", open[jaw]);
    }

    /// A face whose closed lips need 0.7 of mouthPress on the model, talking with its lips
    /// apart 70 % of the time: its closed mouth reads 0, pressing harder still shows.
    #[test]
    fn a_closed_mouth_is_not_read_as_pressed_lips() {
        let model = FaceModel::embedded();
        let mut rest = RestPose::new(&model);
        let press = model.expression_index("mouthPress_L").unwrap();
        let n = model.expressions.len();
        let frame = |w: f64| {
            let mut v = vec![0.0; n];
            v[press] = w;
            v
        };
        for i in 0..100 {
            let closed = i % 10 < 3;
            let mut w = frame(if closed { 0.7 } else { 0.0 });
            rest.calibrate(&mut w, closed);
        }
        let mut at_rest = frame(0.7);
        rest.calibrate(&mut at_rest, true);
        assert!(at_rest[press] < 0.02, "{}", at_rest[press]);
        // Pressing harder still shows, stretched by at most 1 / MIN_RANGE.
        let mut pressed = frame(0.95);
        rest.calibrate(&mut pressed, true);
        let expected = (0.95 - 0.7) / MIN_RANGE;
        assert!(
            (pressed[press] - expected).abs() < 0.02,
            "{}",
            pressed[press]
        );
    }

    #[test]
    fn closed_lips_are_told_from_open_ones() {
        let mut l = vec![[0.0; 2]; 468];
        l[33] = [100.0, 100.0];
        l[263] = [190.0, 100.0];
        l[13] = [145.0, 150.0];
        l[14] = [145.0, 151.0];
        assert!(lips_closed(&l));
        l[14] = [145.0, 160.0];
        assert!(!lips_closed(&l));
        assert!(!lips_closed(&l[..100]));
    }
}
