//! While a lid covers the iris (a blink) the iris network still answers, and the iris it finds
//! drops with the lid: without a gate every blink reads as a glance down (on the sample clip
//! `lp_d13`, `eyeLookDown` rose to 0.45–0.56 at each of its four blinks). An eye whose lids
//! ([`crate::Eyelids`]) read a blink of [`HOLD_BLINK`] or more, or did in the frame before (the
//! lid is still lifting off the iris), holds its gaze at its last value from an open eye.

/// The eyes hold their gaze while either eye's `eyeBlink` reaches this: the lid has dropped by
/// a tenth of the open aperture, onto the iris's upper rim, and the iris the network finds
/// starts to follow it down (on the sample clip `lp_d18`, 0.3 let a 7° glance through at the
/// start of a blink).
pub const HOLD_BLINK: f64 = 0.15;

/// The gate of both eyes and the gaze each held last.
#[derive(Clone, Debug)]
pub struct LidGate<T> {
    held: [Option<T>; 2],
    /// Whether the eye was covered in the frame before.
    covered: [bool; 2],
}

impl<T: Copy> Default for LidGate<T> {
    fn default() -> Self {
        LidGate {
            held: [None, None],
            covered: [false; 2],
        }
    }
}

impl<T: Copy> LidGate<T> {
    /// Records the eye's blink weight in this frame (`left`: the subject's left eye) and says
    /// whether its iris is to be trusted.
    pub fn is_open(&mut self, left: bool, blink: f64) -> bool {
        let covered = blink >= HOLD_BLINK;
        let was = std::mem::replace(&mut self.covered[left as usize], covered);
        !covered && !was
    }

    /// Keeps `value` as the eye's gaze of an open eye.
    pub fn keep(&mut self, left: bool, value: T) {
        self.held[left as usize] = Some(value);
    }

    /// The eye's last gaze from an open eye.
    pub fn held(&self, left: bool) -> Option<T> {
        self.held[left as usize]
    }

    /// Forgets the held gazes (the face was lost).
    pub fn lose_track(&mut self) {
        self.held = [None, None];
        self.covered = [false; 2];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_blink_holds_the_gaze_until_the_frame_after_it_and_an_open_eye_does_not() {
        let mut gate = LidGate::<f64>::default();
        for i in 0..50 {
            assert!(gate.is_open(false, 0.05) && gate.is_open(true, 0.1));
            gate.keep(false, i as f64);
        }
        assert!(!gate.is_open(false, 0.9));
        assert!(!gate.is_open(true, 0.3));
        assert_eq!(gate.held(false), Some(49.0));
        assert_eq!(gate.held(true), None);
        // The lid lifts: held one more frame.
        assert!(!gate.is_open(false, 0.1));
        assert!(gate.is_open(false, 0.1));
        gate.lose_track();
        assert_eq!(gate.held(false), None);
    }
}
