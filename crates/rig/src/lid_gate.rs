//! While a lid covers the iris (a blink) the iris network still answers, and the iris it finds
//! drops with the lid: without a gate every blink reads as a glance down (on the sample clip
//! `lp_d13`, `eyeLookDown` rose to 0.45–0.56 at each of its four blinks). Each eye's aperture —
//! the upper to lower lid distance over the distance of the eye's corners, from the tracked
//! landmarks — is compared with its median so far; below [`HOLD_FRACTION`] of it the eye's gaze
//! is held at its last value from an open eye.

use crate::histogram::Histogram;

/// An eye whose aperture is below this fraction of its median holds its gaze.
pub const HOLD_FRACTION: f64 = 0.75;

/// FaceMesh landmarks of each eye (the subject's right, then left): upper and lower lid
/// centres, then the two corners.
const EYE_LANDMARKS: [[usize; 4]; 2] = [[159, 145, 33, 133], [386, 374, 362, 263]];

/// Apertures above this are out of the histogram's range (a wide-open eye is about 0.35).
const MAX_APERTURE: f64 = 1.0;

/// The gate of both eyes and the gaze each held last.
#[derive(Clone, Debug)]
pub struct LidGate<T> {
    apertures: [Histogram; 2],
    held: [Option<T>; 2],
}

impl<T: Copy> Default for LidGate<T> {
    fn default() -> Self {
        LidGate {
            apertures: std::array::from_fn(|_| Histogram::new(0.0, MAX_APERTURE)),
            held: [None, None],
        }
    }
}

impl<T: Copy> LidGate<T> {
    /// Records the eye's aperture in this frame (`left`: the subject's left eye) and says
    /// whether its iris is to be trusted.
    pub fn is_open(&mut self, left: bool, landmarks_px: &[[f64; 2]]) -> bool {
        let [up, down, a, b] = EYE_LANDMARKS[left as usize];
        if landmarks_px.len() <= up.max(down).max(a).max(b) {
            return true;
        }
        let d = |i: usize, j: usize| {
            let (p, q) = (landmarks_px[i], landmarks_px[j]);
            (p[0] - q[0]).hypot(p[1] - q[1])
        };
        let width = d(a, b);
        if width <= 0.0 {
            return true;
        }
        let aperture = d(up, down) / width;
        let hist = &mut self.apertures[left as usize];
        hist.push(aperture);
        aperture >= HOLD_FRACTION * hist.quantile(0.5)
    }

    /// Keeps `value` as the eye's gaze of an open eye.
    pub fn keep(&mut self, left: bool, value: T) {
        self.held[left as usize] = Some(value);
    }

    /// The eye's last gaze from an open eye.
    pub fn held(&self, left: bool) -> Option<T> {
        self.held[left as usize]
    }

    /// Forgets the held gazes (the face was lost); the apertures' medians stay.
    pub fn lose_track(&mut self) {
        self.held = [None, None];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 468 landmarks with each eye `width` wide and `aperture × width` open.
    fn face(aperture: f64) -> Vec<[f64; 2]> {
        let mut l = vec![[0.0; 2]; 468];
        for (eye, x0) in EYE_LANDMARKS.iter().zip([100.0, 200.0]) {
            let [up, down, a, b] = *eye;
            l[a] = [x0, 100.0];
            l[b] = [x0 + 30.0, 100.0];
            l[up] = [x0 + 15.0, 100.0 - 15.0 * aperture];
            l[down] = [x0 + 15.0, 100.0 + 15.0 * aperture];
        }
        l
    }

    #[test]
    fn a_blink_holds_the_gaze_and_an_open_eye_does_not() {
        let mut gate = LidGate::<f64>::default();
        for i in 0..50 {
            let open = face(0.3 + 0.01 * (i % 3) as f64);
            assert!(gate.is_open(false, &open) && gate.is_open(true, &open));
            gate.keep(false, i as f64);
        }
        let blink = face(0.12);
        assert!(!gate.is_open(false, &blink));
        assert!(!gate.is_open(true, &blink));
        assert_eq!(gate.held(false), Some(49.0));
        assert_eq!(gate.held(true), None);
        gate.lose_track();
        assert_eq!(gate.held(false), None);
    }
}
