//! One frame of a rig's animation: the 52 ARKit blendshape weights, the head's and each eye's
//! yaw, pitch and roll ([`BlendshapeFrame`]), with Live Link Face's names and signs; a whole
//! take ([`BlendshapeTrack`], `blendshapes.json` read back).
//!
//! # Rotations
//! Rotations are in radians. Older Unreal code (`AppleARKitFaceSupport`,
//! `ToBlendShapeMap`, UE 4.22) mapped degrees to `degrees / 180`, but the app's exports match
//! radians only: in `csv/facial.csv` a left eye with `EyeLookOutLeft` 0.34 has
//! `LeftEyeYaw` −0.267, i.e. 15° as radians but 48° as `degrees / 180` — a third of the
//! blendshape's range cannot be near the eye's largest rotation (~45–50°). Signs, from the same
//! exports: eye yaw < 0 when the gaze turns to the subject's left (`EyeLookOutLeft`,
//! `EyeLookInRight`), eye pitch < 0 looking up (`EyeLookUp…`); the head follows the eyes'
//! convention (its columns are 0 in every public sample: the app records the head only when
//! asked). So here, for the head relative to facing the camera and for each eye relative to
//! the head: **yaw > 0 turning to the subject's right, pitch > 0 looking down, roll > 0 tilting
//! the top toward the subject's right shoulder** (roll's sign is Unreal's `FRotator`
//! convention and could not be checked against a sample). [`live_link_angles`] converts a
//! rotation matrix to these angles.

use serde::{Deserialize, Serialize};

use crate::arkit::{ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT};

/// `BlendShapeCount` of a Live Link Face row: 52 blendshapes and 9 rotations.
pub const LIVE_LINK_VALUE_COUNT: usize = 61;

/// The Live Link Face CSV's blendshape columns: [`ARKIT_BLENDSHAPES`] capitalised, same order.
pub const LIVE_LINK_BLENDSHAPES: [&str; ARKIT_BLENDSHAPE_COUNT] = [
    "EyeBlinkLeft",
    "EyeLookDownLeft",
    "EyeLookInLeft",
    "EyeLookOutLeft",
    "EyeLookUpLeft",
    "EyeSquintLeft",
    "EyeWideLeft",
    "EyeBlinkRight",
    "EyeLookDownRight",
    "EyeLookInRight",
    "EyeLookOutRight",
    "EyeLookUpRight",
    "EyeSquintRight",
    "EyeWideRight",
    "JawForward",
    "JawRight",
    "JawLeft",
    "JawOpen",
    "MouthClose",
    "MouthFunnel",
    "MouthPucker",
    "MouthRight",
    "MouthLeft",
    "MouthSmileLeft",
    "MouthSmileRight",
    "MouthFrownLeft",
    "MouthFrownRight",
    "MouthDimpleLeft",
    "MouthDimpleRight",
    "MouthStretchLeft",
    "MouthStretchRight",
    "MouthRollLower",
    "MouthRollUpper",
    "MouthShrugLower",
    "MouthShrugUpper",
    "MouthPressLeft",
    "MouthPressRight",
    "MouthLowerDownLeft",
    "MouthLowerDownRight",
    "MouthUpperUpLeft",
    "MouthUpperUpRight",
    "BrowDownLeft",
    "BrowDownRight",
    "BrowInnerUp",
    "BrowOuterUpLeft",
    "BrowOuterUpRight",
    "CheekPuff",
    "CheekSquintLeft",
    "CheekSquintRight",
    "NoseSneerLeft",
    "NoseSneerRight",
    "TongueOut",
];

/// The Live Link Face CSV's 9 rotation columns after the blendshapes (radians).
pub const LIVE_LINK_ROTATIONS: [&str; 9] = [
    "HeadYaw",
    "HeadPitch",
    "HeadRoll",
    "LeftEyeYaw",
    "LeftEyePitch",
    "LeftEyeRoll",
    "RightEyeYaw",
    "RightEyePitch",
    "RightEyeRoll",
];

/// One frame's ARKit blendshapes, head pose and eye rotations, as written to
/// `blendshapes.csv` and `blendshapes.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlendshapeFrame {
    /// The input frame's index (a video's frame number, a folder's file number).
    pub index: usize,
    /// Seconds since the input's first frame: `Frame::timestamp_s`, or `index / fps` when the
    /// input has no timestamps.
    pub timestamp_s: f64,
    /// The 52 weights in [`ARKIT_BLENDSHAPES`]' order, each in [0, 1].
    #[serde(with = "weight_array")]
    pub weights: [f32; ARKIT_BLENDSHAPE_COUNT],
    /// The head's `[yaw, pitch, roll]` relative to facing the camera, radians (signs in the
    /// module's docs).
    pub head: [f32; 3],
    /// The left eye's `[yaw, pitch, roll]` relative to the head, radians.
    pub left_eye: [f32; 3],
    /// The right eye's `[yaw, pitch, roll]` relative to the head, radians.
    pub right_eye: [f32; 3],
}

impl BlendshapeFrame {
    /// Frame `index` at `timestamp_s` with every weight and angle 0.
    pub fn new(index: usize, timestamp_s: f64) -> BlendshapeFrame {
        BlendshapeFrame {
            index,
            timestamp_s,
            weights: [0.0; ARKIT_BLENDSHAPE_COUNT],
            head: [0.0; 3],
            left_eye: [0.0; 3],
            right_eye: [0.0; 3],
        }
    }

    /// The weight of the blendshape `name` (Apple's camelCase name), `None` for another name.
    pub fn weight(&self, name: &str) -> Option<f32> {
        ARKIT_BLENDSHAPES
            .iter()
            .position(|&n| n == name)
            .map(|i| self.weights[i])
    }

    /// The row's 61 values after `Timecode` and `BlendShapeCount`: the weights, then the head's
    /// and the eyes' angles in [`LIVE_LINK_ROTATIONS`]' order.
    pub fn live_link_values(&self) -> [f32; LIVE_LINK_VALUE_COUNT] {
        let mut v = [0.0; LIVE_LINK_VALUE_COUNT];
        v[..ARKIT_BLENDSHAPE_COUNT].copy_from_slice(&self.weights);
        v[52..55].copy_from_slice(&self.head);
        v[55..58].copy_from_slice(&self.left_eye);
        v[58..61].copy_from_slice(&self.right_eye);
        v
    }

    /// Why the frame cannot be written: a non-finite or negative time, a non-finite value.
    pub fn check(&self) -> Result<(), String> {
        if !(self.timestamp_s.is_finite() && self.timestamp_s >= 0.0) {
            return Err(format!(
                "frame {}: timestamp {} s is not a time since the first frame",
                self.index, self.timestamp_s
            ));
        }
        if let Some(i) = self.live_link_values().iter().position(|v| !v.is_finite()) {
            let name = LIVE_LINK_BLENDSHAPES
                .iter()
                .chain(&LIVE_LINK_ROTATIONS)
                .nth(i)
                .copied()
                .unwrap_or("?");
            return Err(format!("frame {}: {name} is not finite", self.index));
        }
        Ok(())
    }
}

/// Serde for the 52 weights as a JSON array.
mod weight_array {
    use serde::de::Error as _;
    use serde::{Deserialize, Deserializer, Serializer};

    use super::ARKIT_BLENDSHAPE_COUNT;

    pub fn serialize<S: Serializer>(
        w: &[f32; ARKIT_BLENDSHAPE_COUNT],
        s: S,
    ) -> Result<S::Ok, S::Error> {
        s.collect_seq(w)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<[f32; ARKIT_BLENDSHAPE_COUNT], D::Error> {
        let v = Vec::<f32>::deserialize(d)?;
        let n = v.len();
        v.try_into()
            .map_err(|_| D::Error::invalid_length(n, &"the 52 ARKit weights"))
    }
}

/// `blendshapes.json` as a whole: what the run folder's `BlendshapesJsonWriter` streams,
/// for reading it back.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlendshapeTrack {
    /// The input's frame rate, `None` when unknown.
    pub fps: Option<f64>,
    /// The blendshapes' names, [`ARKIT_BLENDSHAPES`].
    pub names: Vec<String>,
    /// The frames in input order.
    pub frames: Vec<BlendshapeFrame>,
}

/// `[yaw, pitch, roll]` in radians, with Live Link Face's signs (the module's docs), of the
/// rotation `r` (row-major, applied to column vectors) in the face frame — x to the subject's
/// left, y up, z out of the face (ICT-FaceKit's and ARKit's face frame) — relative to the rest
/// pose: the head relative to facing the camera, or an eye relative to looking straight ahead.
/// `r = R_y(−yaw) · R_x(pitch) · R_z(roll)`: the yaw about the head's up axis, then the pitch
/// about its turned left axis, then the roll about the face's normal.
///
/// For a head pose `R_cam` in camera coordinates (x right, y down, z forward) that maps the
/// ICT frame into the camera's, the rotation from facing the camera is
/// `r = diag(1, −1, −1) · R_cam`.
pub fn live_link_angles(r: &[[f64; 3]; 3]) -> [f32; 3] {
    let pitch = (-r[1][2]).clamp(-1.0, 1.0).asin();
    let yaw = r[0][2].atan2(r[2][2]);
    let roll = r[1][0].atan2(r[1][1]);
    // `+ 0.0`: no −0 in the files.
    [
        (-yaw + 0.0) as f32,
        (pitch + 0.0) as f32,
        (roll + 0.0) as f32,
    ]
}

/// The rotation of Live Link Face angles `[yaw, pitch, roll]` (radians, the module's signs):
/// `R_y(−yaw) · R_x(pitch) · R_z(roll)` (row-major, applied to column vectors, in the face
/// frame of [`live_link_angles`], of which it is the inverse for |pitch| < 90°).
pub fn live_link_rotation(angles: [f64; 3]) -> [[f64; 3]; 3] {
    let [yaw, pitch, roll] = angles;
    let (sy, cy) = (-yaw).sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sr, cr) = roll.sin_cos();
    let r_y = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
    let r_x = [[1.0, 0.0, 0.0], [0.0, cp, -sp], [0.0, sp, cp]];
    let r_z = [[cr, -sr, 0.0], [sr, cr, 0.0], [0.0, 0.0, 1.0]];
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
    };
    mul(mul(r_y, r_x), r_z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `R_y(a)`, `R_x(b)`, `R_z(c)` and products, row-major.
    fn rot(axis: usize, angle: f64) -> [[f64; 3]; 3] {
        let (s, c) = angle.sin_cos();
        match axis {
            0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
            1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
            _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
        }
    }

    fn mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
    }

    fn apply(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| (0..3).map(|k| r[i][k] * v[k]).sum())
    }

    #[test]
    fn live_link_rotation_inverts_the_angles() {
        for angles in [[0.3, -0.2, 0.1], [-0.7, 0.4, -0.25], [0.0, 0.0, 0.0]] {
            let r = live_link_rotation(angles);
            let expected = mul(
                &mul(&rot(1, -angles[0]), &rot(0, angles[1])),
                &rot(2, angles[2]),
            );
            assert_eq!(r, expected);
            let back = live_link_angles(&r);
            for (a, b) in back.iter().zip(angles) {
                assert!((f64::from(*a) - b).abs() < 1e-6, "{back:?} vs {angles:?}");
            }
        }
    }

    #[test]
    fn angles_have_live_link_faces_signs() {
        let forward = [0.0, 0.0, 1.0];
        // Turning to the subject's right (toward −x): yaw > 0.
        let r = rot(1, -0.3);
        assert!(apply(&r, forward)[0] < 0.0);
        let [yaw, pitch, roll] = live_link_angles(&r);
        assert!((yaw - 0.3).abs() < 1e-6 && pitch.abs() < 1e-6 && roll.abs() < 1e-6);
        // Looking down (forward toward −y): pitch > 0.
        let r = rot(0, 0.2);
        assert!(apply(&r, forward)[1] < 0.0);
        let [yaw, pitch, roll] = live_link_angles(&r);
        assert!(yaw.abs() < 1e-6 && (pitch - 0.2).abs() < 1e-6 && roll.abs() < 1e-6);
        // Top of the head toward the subject's right shoulder (up toward −x): roll > 0.
        let r = rot(2, 0.1);
        assert!(apply(&r, [0.0, 1.0, 0.0])[0] < 0.0);
        let [_, _, roll] = live_link_angles(&r);
        assert!((roll - 0.1).abs() < 1e-6);
        // A combination comes back apart.
        let r = mul(&mul(&rot(1, -0.4), &rot(0, -0.25)), &rot(2, 0.15));
        let a = live_link_angles(&r);
        for (got, want) in a.iter().zip([0.4, -0.25, 0.15]) {
            assert!((got - want).abs() < 1e-6, "{a:?}");
        }
        // A face looking straight at the camera: zero.
        let cam = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
        let flip = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
        assert_eq!(live_link_angles(&mul(&flip, &cam)), [0.0, 0.0, 0.0]);
    }
}
