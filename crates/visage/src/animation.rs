//! ARKit blendshape outputs for rigs: per frame, the 52 ARKit blendshape weights
//! (`ARFaceAnchor.BlendShapeLocation`), the head's and each eye's yaw, pitch and roll, written
//! as a Live Link Face CSV (`blendshapes.csv`, [`LiveLinkCsvWriter`]) and as compact JSON
//! (`blendshapes.json`, [`BlendshapesJsonWriter`]), both streamed under a temporary name and
//! renamed when finished, so a reader never sees half a file.
//!
//! # Live Link Face CSV
//! One header line, then one row per frame:
//! `Timecode,BlendShapeCount,EyeBlinkLeft,…,TongueOut,HeadYaw,HeadPitch,HeadRoll,LeftEyeYaw,
//! LeftEyePitch,LeftEyeRoll,RightEyeYaw,RightEyePitch,RightEyeRoll` — the 52 blendshapes in
//! Apple's names, capitalised ([`LIVE_LINK_BLENDSHAPES`]), then the 9 rotations
//! ([`LIVE_LINK_ROTATIONS`]); `BlendShapeCount` is 61, values have 10 decimals. The column
//! order is that of real Live Link Face exports (the public repository
//! `alexdjulin/LiveLinkFace-CSV-Retarget-For-Motionbuilder`, `anim/*.csv` and
//! `csv/facial.csv`), which Blender and Dart importers copy verbatim. It is *not* Unreal's
//! `EARFaceBlendShape` order used by the UDP stream (`JimWest/PyLiveLinkFace`'s enum): the CSV
//! has `JawRight,JawLeft` and `MouthRight,MouthLeft` where the enum has left first. Each value
//! is written under its own name, so either order reads back correctly by name.
//!
//! **Timecode** `HH:MM:SS:FF.fff`: `FF` is the frame within the second and `.fff` the
//! sub-frame, in thousandths of a frame — not milliseconds. Real exports show it: rows 1/30 s
//! apart at a 60 fps timecode rate read `13:13:04:31.652`, `…:33.651`, `…:35.651`, …,
//! `…:59.648`, `13:13:05:01.648` (the frame steps by 2 and wraps after 59, the fraction drifts
//! by a thousandth; as milliseconds it would step by 33). It is Unreal's `FQualifiedFrameTime`,
//! frame number plus sub-frame. [`live_link_timecode`] writes it from a timestamp `t` and the
//! timecode rate `fps`: the frame time `t · fps` rounded to a thousandth of a frame is split
//! into whole frames and the fraction, and the whole frames are counted in SMPTE non-drop-frame
//! style with `round(fps)` frames a second (29.97 and 30000/1001 count 30 a second, 59.94
//! counts 60, 23.976 counts 24; like Unreal's `FTimecode` for a non-integer rate, `ceil`). At
//! 29.97 the timecode thus runs 0.1 % behind the clock, as NTSC non-drop timecode does. Ours
//! starts at `00:00:00:00.000` on the first frame; the app stamps the time of day. The app's
//! own timecode rate is 60 even when it captures at 30 fps, and some importers assume 60:
//! pass 60 as the rate for those.
//!
//! **Rotations** are in radians. Older Unreal code (`AppleARKitFaceSupport`,
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
//!
//! # ICT-FaceKit → ARKit
//! ICT-FaceKit's 53 expressions ([`ICT_EXPRESSIONS`], the order of its `vertex_indices.json`)
//! are ARKit's shapes with sides named `_L`/`_R`, `browInnerUp` and `cheekPuff` split into
//! halves, and no `tongueOut`. `_L` is the subject's left, the same side as ARKit's `Left`
//! (ARKit's face frame has +x at "the face's own left"). Checked on the model files: the
//! vertices `eyeBlink_L`, `mouthSmile_L`, `browDown_L` move lie at x > 0 (weighted mean x
//! +3.3, +2.6, +4.2 cm; `_R` mirrored at x < 0), and in the ICT frame (nose tip at the largest
//! z, chin below the eyes: y up, the face looking along +z) +x is the subject's left, image
//! right; dlib landmark 45, the subject's left outer eye corner, is at x = +4.5 cm;
//! `mouthLeft` and `jawLeft` move the vertices toward +x. So `x_L` → `xLeft`, `x_R` → `xRight`.
//!
//! A split pair becomes the **mean** of its halves. The halves are mirror images with equal
//! norms (‖L‖² 46.9 vs 46.7 for `browInnerUp`), so for any weights `(l, r)` the least-squares
//! weight of the whole shape `L + R` on the displacement `l·L + r·R` is `(l + r) / 2` —
//! whatever their overlap. `max` would raise both brows fully for a one-sided raise; the mean
//! moves half as much over twice the area, the closest a symmetric shape gets. Symmetric
//! weights `(w, w)` give `w` either way.
//!
//! | ARKit (CSV order) | ICT-FaceKit | ARKit | ICT-FaceKit |
//! |---|---|---|---|
//! | eyeBlinkLeft | eyeBlink_L | mouthDimpleRight | mouthDimple_R |
//! | eyeLookDownLeft | eyeLookDown_L | mouthStretchLeft | mouthStretch_L |
//! | eyeLookInLeft | eyeLookIn_L | mouthStretchRight | mouthStretch_R |
//! | eyeLookOutLeft | eyeLookOut_L | mouthRollLower | mouthRollLower |
//! | eyeLookUpLeft | eyeLookUp_L | mouthRollUpper | mouthRollUpper |
//! | eyeSquintLeft | eyeSquint_L | mouthShrugLower | mouthShrugLower |
//! | eyeWideLeft | eyeWide_L | mouthShrugUpper | mouthShrugUpper |
//! | eyeBlinkRight | eyeBlink_R | mouthPressLeft | mouthPress_L |
//! | eyeLookDownRight | eyeLookDown_R | mouthPressRight | mouthPress_R |
//! | eyeLookInRight | eyeLookIn_R | mouthLowerDownLeft | mouthLowerDown_L |
//! | eyeLookOutRight | eyeLookOut_R | mouthLowerDownRight | mouthLowerDown_R |
//! | eyeLookUpRight | eyeLookUp_R | mouthUpperUpLeft | mouthUpperUp_L |
//! | eyeSquintRight | eyeSquint_R | mouthUpperUpRight | mouthUpperUp_R |
//! | eyeWideRight | eyeWide_R | browDownLeft | browDown_L |
//! | jawForward | jawForward | browDownRight | browDown_R |
//! | jawRight | jawRight | **browInnerUp** | **mean(browInnerUp_L, browInnerUp_R)** |
//! | jawLeft | jawLeft | browOuterUpLeft | browOuterUp_L |
//! | jawOpen | jawOpen | browOuterUpRight | browOuterUp_R |
//! | mouthClose | mouthClose | **cheekPuff** | **mean(cheekPuff_L, cheekPuff_R)** |
//! | mouthFunnel | mouthFunnel | cheekSquintLeft | cheekSquint_L |
//! | mouthPucker | mouthPucker | cheekSquintRight | cheekSquint_R |
//! | mouthRight | mouthRight | noseSneerLeft | noseSneer_L |
//! | mouthLeft | mouthLeft | noseSneerRight | noseSneer_R |
//! | mouthSmileLeft | mouthSmile_L | **tongueOut** | **none: 0** |
//! | mouthSmileRight | mouthSmile_R | | |
//! | mouthFrownLeft | mouthFrown_L | | |
//! | mouthFrownRight | mouthFrown_R | | |
//! | mouthDimpleLeft | mouthDimple_L | | |
//!
//! # blendshapes.json
//! `{"fps":30.0,"names":["eyeBlinkLeft",…],"frames":[{"index":0,"timestamp_s":0.0,
//! "weights":[…52],"head":[yaw,pitch,roll],"left_eye":[…],"right_eye":[…]},…]}` on one line:
//! [`BlendshapeTrack`] reads it back. `names` are Apple's camelCase names in the CSV's order,
//! `weights` follow `names`, angles as in the CSV (radians, the signs above), `fps` is `null`
//! when unknown.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::atomic_write::tmp_path;
use crate::Error;

/// How many ARKit blendshapes there are.
pub const ARKIT_BLENDSHAPE_COUNT: usize = 52;

/// `BlendShapeCount` of a Live Link Face row: 52 blendshapes and 9 rotations.
pub const LIVE_LINK_VALUE_COUNT: usize = 61;

/// The file [`LiveLinkCsvWriter::in_dir`] writes.
pub const BLENDSHAPES_CSV: &str = "blendshapes.csv";

/// The file [`BlendshapesJsonWriter::in_dir`] writes.
pub const BLENDSHAPES_JSON: &str = "blendshapes.json";

/// Apple's `ARFaceAnchor.BlendShapeLocation` names, in the Live Link Face CSV's column order.
pub const ARKIT_BLENDSHAPES: [&str; ARKIT_BLENDSHAPE_COUNT] = [
    "eyeBlinkLeft",
    "eyeLookDownLeft",
    "eyeLookInLeft",
    "eyeLookOutLeft",
    "eyeLookUpLeft",
    "eyeSquintLeft",
    "eyeWideLeft",
    "eyeBlinkRight",
    "eyeLookDownRight",
    "eyeLookInRight",
    "eyeLookOutRight",
    "eyeLookUpRight",
    "eyeSquintRight",
    "eyeWideRight",
    "jawForward",
    "jawRight",
    "jawLeft",
    "jawOpen",
    "mouthClose",
    "mouthFunnel",
    "mouthPucker",
    "mouthRight",
    "mouthLeft",
    "mouthSmileLeft",
    "mouthSmileRight",
    "mouthFrownLeft",
    "mouthFrownRight",
    "mouthDimpleLeft",
    "mouthDimpleRight",
    "mouthStretchLeft",
    "mouthStretchRight",
    "mouthRollLower",
    "mouthRollUpper",
    "mouthShrugLower",
    "mouthShrugUpper",
    "mouthPressLeft",
    "mouthPressRight",
    "mouthLowerDownLeft",
    "mouthLowerDownRight",
    "mouthUpperUpLeft",
    "mouthUpperUpRight",
    "browDownLeft",
    "browDownRight",
    "browInnerUp",
    "browOuterUpLeft",
    "browOuterUpRight",
    "cheekPuff",
    "cheekSquintLeft",
    "cheekSquintRight",
    "noseSneerLeft",
    "noseSneerRight",
    "tongueOut",
];

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

/// ICT-FaceKit's expression names, in the order of its `vertex_indices.json` (`expressions`).
pub const ICT_EXPRESSIONS: [&str; 53] = [
    "browDown_L",
    "browDown_R",
    "browInnerUp_L",
    "browInnerUp_R",
    "browOuterUp_L",
    "browOuterUp_R",
    "cheekPuff_L",
    "cheekPuff_R",
    "cheekSquint_L",
    "cheekSquint_R",
    "eyeBlink_L",
    "eyeBlink_R",
    "eyeLookDown_L",
    "eyeLookDown_R",
    "eyeLookIn_L",
    "eyeLookIn_R",
    "eyeLookOut_L",
    "eyeLookOut_R",
    "eyeLookUp_L",
    "eyeLookUp_R",
    "eyeSquint_L",
    "eyeSquint_R",
    "eyeWide_L",
    "eyeWide_R",
    "jawForward",
    "jawLeft",
    "jawOpen",
    "jawRight",
    "mouthClose",
    "mouthDimple_L",
    "mouthDimple_R",
    "mouthFrown_L",
    "mouthFrown_R",
    "mouthFunnel",
    "mouthLeft",
    "mouthLowerDown_L",
    "mouthLowerDown_R",
    "mouthPress_L",
    "mouthPress_R",
    "mouthPucker",
    "mouthRight",
    "mouthRollLower",
    "mouthRollUpper",
    "mouthShrugLower",
    "mouthShrugUpper",
    "mouthSmile_L",
    "mouthSmile_R",
    "mouthStretch_L",
    "mouthStretch_R",
    "mouthUpperUp_L",
    "mouthUpperUp_R",
    "noseSneer_L",
    "noseSneer_R",
];

/// Where one ARKit weight comes from among ICT-FaceKit's expressions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IctSource {
    /// The ICT expression of the same meaning.
    Shape(&'static str),
    /// The mean of ICT's left and right halves of a symmetric ARKit shape.
    MeanOf(&'static str, &'static str),
    /// No ICT counterpart: the weight is 0.
    Zero,
}

/// The source of each ARKit weight, in [`ARKIT_BLENDSHAPES`]' order (the module's table).
pub const ICT_TO_ARKIT: [IctSource; ARKIT_BLENDSHAPE_COUNT] = {
    use IctSource::{MeanOf, Shape, Zero};
    [
        Shape("eyeBlink_L"),
        Shape("eyeLookDown_L"),
        Shape("eyeLookIn_L"),
        Shape("eyeLookOut_L"),
        Shape("eyeLookUp_L"),
        Shape("eyeSquint_L"),
        Shape("eyeWide_L"),
        Shape("eyeBlink_R"),
        Shape("eyeLookDown_R"),
        Shape("eyeLookIn_R"),
        Shape("eyeLookOut_R"),
        Shape("eyeLookUp_R"),
        Shape("eyeSquint_R"),
        Shape("eyeWide_R"),
        Shape("jawForward"),
        Shape("jawRight"),
        Shape("jawLeft"),
        Shape("jawOpen"),
        Shape("mouthClose"),
        Shape("mouthFunnel"),
        Shape("mouthPucker"),
        Shape("mouthRight"),
        Shape("mouthLeft"),
        Shape("mouthSmile_L"),
        Shape("mouthSmile_R"),
        Shape("mouthFrown_L"),
        Shape("mouthFrown_R"),
        Shape("mouthDimple_L"),
        Shape("mouthDimple_R"),
        Shape("mouthStretch_L"),
        Shape("mouthStretch_R"),
        Shape("mouthRollLower"),
        Shape("mouthRollUpper"),
        Shape("mouthShrugLower"),
        Shape("mouthShrugUpper"),
        Shape("mouthPress_L"),
        Shape("mouthPress_R"),
        Shape("mouthLowerDown_L"),
        Shape("mouthLowerDown_R"),
        Shape("mouthUpperUp_L"),
        Shape("mouthUpperUp_R"),
        Shape("browDown_L"),
        Shape("browDown_R"),
        MeanOf("browInnerUp_L", "browInnerUp_R"),
        Shape("browOuterUp_L"),
        Shape("browOuterUp_R"),
        MeanOf("cheekPuff_L", "cheekPuff_R"),
        Shape("cheekSquint_L"),
        Shape("cheekSquint_R"),
        Shape("noseSneer_L"),
        Shape("noseSneer_R"),
        Zero,
    ]
};

/// One ARKit weight's source as positions in a fit's weight vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    Zero,
    One(Option<usize>),
    Mean(Option<usize>, Option<usize>),
}

/// ICT-FaceKit weights → the 52 ARKit weights ([`ICT_TO_ARKIT`]), for a fit whose expressions
/// are named `ict_names` in its own order. Build it once, apply it per frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IctToArkit {
    slots: [Slot; ARKIT_BLENDSHAPE_COUNT],
}

impl IctToArkit {
    /// The mapping for expressions named `ict_names` (e.g. `IctModel::expression_names`; a
    /// subset of [`ICT_EXPRESSIONS`] in any order). An ICT expression missing from the names
    /// counts as weight 0; names that are not ICT expressions are ignored.
    pub fn new<S: AsRef<str>>(ict_names: &[S]) -> IctToArkit {
        let find = |name: &str| ict_names.iter().position(|n| n.as_ref() == name);
        IctToArkit {
            slots: ICT_TO_ARKIT.map(|source| match source {
                IctSource::Shape(a) => Slot::One(find(a)),
                IctSource::MeanOf(a, b) => Slot::Mean(find(a), find(b)),
                IctSource::Zero => Slot::Zero,
            }),
        }
    }

    /// The mapping for all 53 expressions in [`ICT_EXPRESSIONS`]' order.
    pub fn all() -> IctToArkit {
        IctToArkit::new(&ICT_EXPRESSIONS)
    }

    /// The ARKit weights, in [`ARKIT_BLENDSHAPES`]' order, for the ICT weights
    /// `ict_weights[i]` of `ict_names[i]`. Each ICT weight is clamped to [0, 1] first (NaN and
    /// entries past the slice's end read as 0); a split pair gives the mean of its halves.
    pub fn weights(&self, ict_weights: &[f64]) -> [f32; ARKIT_BLENDSHAPE_COUNT] {
        let w = |i: Option<usize>| {
            let v = i.and_then(|i| ict_weights.get(i)).copied().unwrap_or(0.0);
            if v.is_nan() {
                0.0
            } else {
                v.clamp(0.0, 1.0)
            }
        };
        self.slots.map(|slot| match slot {
            Slot::Zero => 0.0,
            Slot::One(i) => w(i) as f32,
            Slot::Mean(a, b) => (0.5 * (w(a) + w(b))) as f32,
        })
    }
}

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
    fn check(&self) -> Result<(), String> {
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

/// `blendshapes.json` as a whole (the module's docs): what [`BlendshapesJsonWriter`] streams,
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

/// The Live Link Face timecode `HH:MM:SS:FF.fff` of `timestamp_s` at the timecode rate `fps`:
/// `FF` the frame within the second, `.fff` thousandths of a frame (see the module's docs).
/// Negative times read as 0.
pub fn live_link_timecode(timestamp_s: f64, fps: f64) -> String {
    let per_second = timecode_frames_per_second(fps);
    let thousandths = (timestamp_s.max(0.0) * fps * 1000.0).round() as u64;
    let (frames, sub) = (thousandths / 1000, thousandths % 1000);
    let (seconds, frame) = (frames / per_second, frames % per_second);
    let (h, m, s) = (seconds / 3600, seconds / 60 % 60, seconds % 60);
    format!("{h:02}:{m:02}:{s:02}:{frame:02}.{sub:03}")
}

/// Frames counted per timecode second: `fps` when it is a whole number, else `ceil(fps)`.
fn timecode_frames_per_second(fps: f64) -> u64 {
    let whole = fps.round();
    let n = if (fps - whole).abs() < 1e-6 {
        whole
    } else {
        fps.ceil()
    };
    (n as u64).max(1)
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

/// Creates `tmp` (a sibling of the final file) for writing.
fn create_tmp(path: &Path) -> Result<(PathBuf, BufWriter<File>), Error> {
    let tmp = tmp_path(path);
    let file = File::create(&tmp).map_err(|source| Error::Write {
        path: tmp.clone(),
        source,
    })?;
    Ok((tmp, BufWriter::new(file)))
}

/// Opens `path`'s existing temporary sibling for appending.
fn open_tmp_for_append(path: &Path) -> Result<(PathBuf, BufWriter<File>), Error> {
    let tmp = tmp_path(path);
    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(&tmp)
        .map_err(|source| Error::Write {
            path: tmp.clone(),
            source,
        })?;
    Ok((tmp, BufWriter::new(file)))
}

/// Writes `tail`, flushes `out` to `tmp` and renames it to `path`; on failure `tmp` stays
/// (with what it holds).
fn finish_tmp(
    mut out: BufWriter<File>,
    tail: &[u8],
    tmp: &Path,
    path: &Path,
) -> Result<PathBuf, Error> {
    let result = out
        .write_all(tail)
        .and_then(|()| out.into_inner().map_err(|e| e.into_error()))
        .map_err(|source| Error::Write {
            path: tmp.to_owned(),
            source,
        })
        .and_then(|file| {
            drop(file);
            std::fs::rename(tmp, path).map_err(|source| Error::Write {
                path: path.to_owned(),
                source,
            })
        });
    result.map(|()| path.to_owned())
}

fn check_fps(fps: f64) -> Result<(), Error> {
    if fps.is_finite() && fps > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidOption {
            name: "fps",
            value: fps.to_string(),
            reason: "must be a positive number of frames per second",
        })
    }
}

fn invalid_frame(path: &Path, reason: String) -> Error {
    Error::Write {
        path: path.to_owned(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, reason),
    }
}

/// Streams frames to a Live Link Face CSV (the module's docs): rows go to `<name>.tmp`, which
/// [`finish`](Self::finish) renames to the final name; dropped unfinished (or when finishing
/// fails), the rows so far stay under the temporary name, where `visage run --resume` finds
/// them.
pub struct LiveLinkCsvWriter {
    path: PathBuf,
    tmp: PathBuf,
    out: Option<BufWriter<File>>,
    fps: f64,
    rows: usize,
}

impl LiveLinkCsvWriter {
    /// Starts `dir/blendshapes.csv` with the timecode rate `fps` (see [`Self::create`]).
    pub fn in_dir(dir: &Path, fps: f64) -> Result<LiveLinkCsvWriter, Error> {
        LiveLinkCsvWriter::create(&dir.join(BLENDSHAPES_CSV), fps)
    }

    /// Starts the CSV `path` and writes its header; `fps` is the timecode rate, normally the
    /// input's frame rate (the rate the timestamps came from).
    ///
    /// # Errors
    /// `fps` not positive and finite; the temporary file cannot be written.
    pub fn create(path: &Path, fps: f64) -> Result<LiveLinkCsvWriter, Error> {
        check_fps(fps)?;
        let (tmp, mut out) = create_tmp(path)?;
        let header = ["Timecode", "BlendShapeCount"]
            .iter()
            .chain(&LIVE_LINK_BLENDSHAPES)
            .chain(&LIVE_LINK_ROTATIONS)
            .copied()
            .collect::<Vec<_>>()
            .join(",");
        let result = writeln!(out, "{header}");
        let writer = LiveLinkCsvWriter {
            path: path.to_owned(),
            tmp,
            out: Some(out),
            fps,
            rows: 0,
        };
        result.map_err(|source| writer.io_error(source))?;
        Ok(writer)
    }

    /// Continues `dir/blendshapes.csv`'s temporary file, which holds its header and `rows`
    /// rows (a resumed run; [`crate::prepare_resume`] cut it there).
    ///
    /// # Errors
    /// `fps` not positive and finite; the temporary file cannot be opened.
    pub fn append_in_dir(dir: &Path, fps: f64, rows: usize) -> Result<LiveLinkCsvWriter, Error> {
        check_fps(fps)?;
        let path = dir.join(BLENDSHAPES_CSV);
        let (tmp, out) = open_tmp_for_append(&path)?;
        Ok(LiveLinkCsvWriter {
            path,
            tmp,
            out: Some(out),
            fps,
            rows,
        })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Hands the rows so far to the operating system.
    ///
    /// # Errors
    /// The temporary file cannot be written.
    pub fn flush(&mut self) -> Result<(), Error> {
        let result = self.out.as_mut().map_or(Ok(()), Write::flush);
        result.map_err(|source| self.io_error(source))
    }

    /// Appends `frame`'s row.
    ///
    /// # Errors
    /// A negative or non-finite timestamp or a non-finite value; the file cannot be written.
    pub fn write(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        frame
            .check()
            .map_err(|reason| invalid_frame(&self.path, reason))?;
        let mut row = live_link_timecode(frame.timestamp_s, self.fps);
        row.push_str(&format!(",{LIVE_LINK_VALUE_COUNT}"));
        for v in frame.live_link_values() {
            // `+ 0.0` writes −0 as 0.
            row.push_str(&format!(",{:.10}", v + 0.0));
        }
        row.push('\n');
        let result = match self.out.as_mut() {
            Some(out) => out.write_all(row.as_bytes()),
            None => Ok(()),
        };
        result.map_err(|source| self.io_error(source))?;
        self.rows += 1;
        Ok(())
    }

    /// Completes the file and moves it to its final name, which it returns.
    pub fn finish(mut self) -> Result<PathBuf, Error> {
        match self.out.take() {
            Some(out) => finish_tmp(out, b"", &self.tmp, &self.path),
            None => Ok(self.path.clone()),
        }
    }

    fn io_error(&self, source: std::io::Error) -> Error {
        Error::Write {
            path: self.tmp.clone(),
            source,
        }
    }
}

/// Streams frames to `blendshapes.json` (the module's docs), compact, under `<name>.tmp` until
/// [`finish`](Self::finish); dropped unfinished, the frames so far stay under the temporary
/// name.
pub struct BlendshapesJsonWriter {
    path: PathBuf,
    tmp: PathBuf,
    out: Option<BufWriter<File>>,
    frames: usize,
}

impl BlendshapesJsonWriter {
    /// Starts `dir/blendshapes.json` (see [`Self::create`]).
    pub fn in_dir(dir: &Path, fps: Option<f64>) -> Result<BlendshapesJsonWriter, Error> {
        BlendshapesJsonWriter::create(&dir.join(BLENDSHAPES_JSON), fps)
    }

    /// Starts the JSON file `path` for an input at `fps` frames per second (`None`: unknown).
    ///
    /// # Errors
    /// `fps` given but not positive and finite; the temporary file cannot be written.
    pub fn create(path: &Path, fps: Option<f64>) -> Result<BlendshapesJsonWriter, Error> {
        if let Some(fps) = fps {
            check_fps(fps)?;
        }
        let (tmp, mut out) = create_tmp(path)?;
        let head = serde_json::to_string(&fps)
            .and_then(|fps| Ok((fps, serde_json::to_string(&ARKIT_BLENDSHAPES[..])?)))
            .map_err(std::io::Error::from)
            .and_then(|(fps, names)| write!(out, "{{\"fps\":{fps},\"names\":{names},\"frames\":["));
        let writer = BlendshapesJsonWriter {
            path: path.to_owned(),
            tmp,
            out: Some(out),
            frames: 0,
        };
        head.map_err(|source| writer.io_error(source))?;
        Ok(writer)
    }

    /// Continues `dir/blendshapes.json`'s temporary file, which holds its head and `frames`
    /// frames (a resumed run; [`crate::prepare_resume`] cut it there).
    ///
    /// # Errors
    /// The temporary file cannot be opened.
    pub fn append_in_dir(dir: &Path, frames: usize) -> Result<BlendshapesJsonWriter, Error> {
        let path = dir.join(BLENDSHAPES_JSON);
        let (tmp, out) = open_tmp_for_append(&path)?;
        Ok(BlendshapesJsonWriter {
            path,
            tmp,
            out: Some(out),
            frames,
        })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Hands the frames so far to the operating system.
    ///
    /// # Errors
    /// The temporary file cannot be written.
    pub fn flush(&mut self) -> Result<(), Error> {
        let result = self.out.as_mut().map_or(Ok(()), Write::flush);
        result.map_err(|source| self.io_error(source))
    }

    /// Appends `frame`.
    ///
    /// # Errors
    /// A negative or non-finite timestamp or a non-finite value; the file cannot be written.
    pub fn write(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        frame
            .check()
            .map_err(|reason| invalid_frame(&self.path, reason))?;
        let mut text = if self.frames == 0 {
            String::new()
        } else {
            ",".to_owned()
        };
        text.push_str(
            &serde_json::to_string(frame).map_err(|e| self.io_error(std::io::Error::from(e)))?,
        );
        let result = match self.out.as_mut() {
            Some(out) => out.write_all(text.as_bytes()),
            None => Ok(()),
        };
        result.map_err(|source| self.io_error(source))?;
        self.frames += 1;
        Ok(())
    }

    /// Closes the JSON document and moves the file to its final name, which it returns.
    pub fn finish(mut self) -> Result<PathBuf, Error> {
        match self.out.take() {
            Some(out) => finish_tmp(out, b"]}\n", &self.tmp, &self.path),
            None => Ok(self.path.clone()),
        }
    }

    fn io_error(&self, source: std::io::Error) -> Error {
        Error::Write {
            path: self.tmp.clone(),
            source,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Live Link Face CSV header, copied from a real export.
    const LIVE_LINK_HEADER: &str = "Timecode,BlendShapeCount,EyeBlinkLeft,EyeLookDownLeft,\
        EyeLookInLeft,EyeLookOutLeft,EyeLookUpLeft,EyeSquintLeft,EyeWideLeft,EyeBlinkRight,\
        EyeLookDownRight,EyeLookInRight,EyeLookOutRight,EyeLookUpRight,EyeSquintRight,\
        EyeWideRight,JawForward,JawRight,JawLeft,JawOpen,MouthClose,MouthFunnel,MouthPucker,\
        MouthRight,MouthLeft,MouthSmileLeft,MouthSmileRight,MouthFrownLeft,MouthFrownRight,\
        MouthDimpleLeft,MouthDimpleRight,MouthStretchLeft,MouthStretchRight,MouthRollLower,\
        MouthRollUpper,MouthShrugLower,MouthShrugUpper,MouthPressLeft,MouthPressRight,\
        MouthLowerDownLeft,MouthLowerDownRight,MouthUpperUpLeft,MouthUpperUpRight,BrowDownLeft,\
        BrowDownRight,BrowInnerUp,BrowOuterUpLeft,BrowOuterUpRight,CheekPuff,CheekSquintLeft,\
        CheekSquintRight,NoseSneerLeft,NoseSneerRight,TongueOut,HeadYaw,HeadPitch,HeadRoll,\
        LeftEyeYaw,LeftEyePitch,LeftEyeRoll,RightEyeYaw,RightEyePitch,RightEyeRoll";

    fn sample_frame(index: usize, timestamp_s: f64) -> BlendshapeFrame {
        let mut f = BlendshapeFrame::new(index, timestamp_s);
        for (i, w) in f.weights.iter_mut().enumerate() {
            *w = (i as f32 * 0.37 + index as f32 * 0.11).fract();
        }
        f.head = [0.1, -0.2, 0.05];
        f.left_eye = [-0.25, 0.125, 0.0];
        f.right_eye = [-0.2, 0.125, -0.01];
        f
    }

    #[test]
    fn csv_header_is_live_link_faces() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = LiveLinkCsvWriter::in_dir(dir.path(), 30.0).unwrap();
        let csv = dir.path().join(BLENDSHAPES_CSV);
        assert!(!csv.exists(), "nothing under the final name before finish");
        w.write(&sample_frame(0, 0.0)).unwrap();
        w.write(&sample_frame(1, 1.0 / 30.0)).unwrap();
        assert_eq!(w.finish().unwrap(), csv);
        assert!(!tmp_path(&csv).exists());
        let text = std::fs::read_to_string(&csv).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let expected: String = LIVE_LINK_HEADER.split_whitespace().collect();
        assert_eq!(lines[0], expected);
        assert_eq!(lines[0].split(',').count(), 2 + LIVE_LINK_VALUE_COUNT);
        assert_eq!(lines.len(), 3);
        let row: Vec<&str> = lines[2].split(',').collect();
        assert_eq!(row.len(), 2 + LIVE_LINK_VALUE_COUNT);
        assert_eq!(&row[..2], ["00:00:00:01.000", "61"]);
        let frame = sample_frame(1, 1.0 / 30.0);
        let values: Vec<f32> = row[2..].iter().map(|v| v.parse().unwrap()).collect();
        for (got, want) in values.iter().zip(frame.live_link_values()) {
            assert!((got - want).abs() <= 1e-9, "{got} vs {want}");
        }
        // By name: the weights follow the header.
        let jaw_left = lines[0].split(',').position(|c| c == "JawLeft").unwrap();
        assert_eq!(
            row[jaw_left].parse::<f32>().unwrap(),
            frame.weight("jawLeft").unwrap()
        );
        assert_eq!(row[2 + 52], "0.1000000015"); // HeadYaw, f32 0.1 to 10 decimals
    }

    #[test]
    fn unfinished_writers_leave_their_frames_under_the_temporary_name() {
        let dir = tempfile::tempdir().unwrap();
        let mut csv = LiveLinkCsvWriter::in_dir(dir.path(), 30.0).unwrap();
        let mut json = BlendshapesJsonWriter::in_dir(dir.path(), Some(30.0)).unwrap();
        csv.write(&sample_frame(0, 0.0)).unwrap();
        json.write(&sample_frame(0, 0.0)).unwrap();
        let mut bad = sample_frame(1, 0.1);
        bad.head[1] = f32::NAN;
        let err = csv.write(&bad).unwrap_err();
        assert!(matches!(err, Error::Write { .. }), "{err}");
        assert!(json.write(&bad).is_err());
        assert!(csv.write(&sample_frame(2, f64::NAN)).is_err());
        drop((csv, json));
        // Nothing under a final name; the frames written so far under the temporary ones,
        // where a resumed run continues them.
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["blendshapes.csv.tmp", "blendshapes.json.tmp"]);
        let csv_rows = std::fs::read_to_string(dir.path().join("blendshapes.csv.tmp")).unwrap();
        assert_eq!(csv_rows.lines().count(), 2, "the header and frame 0");
        assert!(LiveLinkCsvWriter::in_dir(dir.path(), 0.0).is_err());
        assert!(BlendshapesJsonWriter::in_dir(dir.path(), Some(f64::NAN)).is_err());
        let missing = dir.path().join("no/such/dir");
        assert!(matches!(
            LiveLinkCsvWriter::in_dir(&missing, 30.0),
            Err(Error::Write { .. })
        ));
    }

    #[test]
    fn timecodes_count_frames_and_thousandths_of_a_frame() {
        // 30 fps.
        assert_eq!(live_link_timecode(0.0, 30.0), "00:00:00:00.000");
        assert_eq!(live_link_timecode(29.0 / 30.0, 30.0), "00:00:00:29.000");
        assert_eq!(live_link_timecode(31.0 / 30.0, 30.0), "00:00:01:01.000");
        assert_eq!(live_link_timecode(0.05, 30.0), "00:00:00:01.500");
        assert_eq!(live_link_timecode(3661.5, 30.0), "01:01:01:15.000");
        assert_eq!(live_link_timecode(-1.0, 30.0), "00:00:00:00.000");
        // 29.97 (NTSC): 30 frames a timecode second, non-drop-frame.
        let ntsc = 30000.0 / 1001.0;
        for (n, tc) in [
            (29, "00:00:00:29.000"),
            (30, "00:00:01:00.000"),
            (1799, "00:00:59:29.000"),
            (1800, "00:01:00:00.000"),
            (107_892, "00:59:56:12.000"),
        ] {
            assert_eq!(live_link_timecode(n as f64 / ntsc, ntsc), tc, "frame {n}");
            assert_eq!(live_link_timecode(n as f64 / 29.97, 29.97), tc, "frame {n}");
        }
        assert_eq!(
            live_link_timecode(10.25 / ntsc, ntsc),
            "00:00:00:10.250",
            "a quarter frame"
        );
        // 60 fps, as Live Link Face stamps its takes.
        assert_eq!(live_link_timecode(0.5, 60.0), "00:00:00:30.000");
        assert_eq!(
            live_link_timecode(1.0 + 59.0 / 60.0, 60.0),
            "00:00:01:59.000"
        );
        assert_eq!(live_link_timecode(2.0, 60.0), "00:00:02:00.000");
        assert_eq!(
            live_link_timecode((31.652 + 60.0 * 4.0) / 60.0, 60.0),
            "00:00:04:31.652"
        );
    }

    #[test]
    fn ict_to_arkit_uses_every_ict_expression_once() {
        let mut used = Vec::new();
        for source in ICT_TO_ARKIT {
            match source {
                IctSource::Shape(a) => used.push(a),
                IctSource::MeanOf(a, b) => used.extend([a, b]),
                IctSource::Zero => {}
            }
        }
        let mut sorted_used = used.clone();
        sorted_used.sort_unstable();
        let mut all = ICT_EXPRESSIONS.to_vec();
        all.sort_unstable();
        assert_eq!(sorted_used, all, "each ICT expression exactly once");
        // Names: `x_L` → `xLeft`, `x_R` → `xRight`, the rest unchanged.
        for (arkit, source) in ARKIT_BLENDSHAPES.iter().zip(ICT_TO_ARKIT) {
            let expected = |ict: &str| {
                ict.strip_suffix("_L")
                    .map(|s| format!("{s}Left"))
                    .or_else(|| ict.strip_suffix("_R").map(|s| format!("{s}Right")))
                    .unwrap_or_else(|| ict.to_owned())
            };
            match source {
                IctSource::Shape(ict) => assert_eq!(&expected(ict), arkit),
                IctSource::MeanOf(l, r) => {
                    assert_eq!(expected(l), format!("{arkit}Left"));
                    assert_eq!(expected(r), format!("{arkit}Right"));
                }
                IctSource::Zero => assert_eq!(*arkit, "tongueOut"),
            }
        }
        // PascalCase is the camelCase capitalised.
        for (camel, pascal) in ARKIT_BLENDSHAPES.iter().zip(LIVE_LINK_BLENDSHAPES) {
            assert_eq!(camel[..1].to_uppercase() + &camel[1..], pascal);
        }
    }

    #[test]
    fn ict_weights_map_to_arkit_with_pairs_averaged_and_no_tongue() {
        let map = IctToArkit::all();
        let ict = |name: &str| ICT_EXPRESSIONS.iter().position(|&n| n == name).unwrap();
        let arkit = |name: &str| ARKIT_BLENDSHAPES.iter().position(|&n| n == name).unwrap();
        let mut w = vec![0.0; ICT_EXPRESSIONS.len()];
        w[ict("eyeBlink_L")] = 0.8;
        w[ict("mouthSmile_R")] = 0.3;
        w[ict("jawLeft")] = 0.6;
        w[ict("browInnerUp_L")] = 1.0;
        w[ict("browInnerUp_R")] = 0.5;
        w[ict("cheekPuff_L")] = 0.4;
        w[ict("noseSneer_R")] = 1.7; // clamped
        w[ict("jawOpen")] = -0.2; // clamped
        let a = map.weights(&w);
        assert_eq!(a[arkit("eyeBlinkLeft")], 0.8);
        assert_eq!(a[arkit("eyeBlinkRight")], 0.0);
        assert_eq!(a[arkit("mouthSmileRight")], 0.3);
        assert_eq!(a[arkit("jawLeft")], 0.6);
        assert_eq!(a[arkit("jawRight")], 0.0);
        assert_eq!(a[arkit("browInnerUp")], 0.75);
        assert_eq!(a[arkit("cheekPuff")], 0.2);
        assert_eq!(a[arkit("noseSneerRight")], 1.0);
        assert_eq!(a[arkit("jawOpen")], 0.0);
        assert_eq!(a[arkit("tongueOut")], 0.0);
        assert_eq!(a.iter().filter(|&&v| v != 0.0).count(), 6);
        // All ones: every ARKit weight 1 but the tongue.
        let ones = map.weights(&[1.0; 53]);
        assert!(ones[..51].iter().all(|&v| v == 1.0) && ones[51] == 0.0);
        // A fit with a subset of expressions, in its own order; missing ones read as 0.
        let subset = IctToArkit::new(&["jawOpen", "browInnerUp_R", "notAnExpression"]);
        let a = subset.weights(&[0.9, 0.6, 1.0]);
        assert_eq!(a[arkit("jawOpen")], 0.9);
        assert_eq!(a[arkit("browInnerUp")], 0.3);
        assert_eq!(a.iter().filter(|&&v| v != 0.0).count(), 2);
    }

    #[test]
    #[cfg_attr(not(shared_data), ignore = "needs ../shared")]
    fn ict_expression_names_match_the_model_files() {
        let path = visage_testdata::require(
            visage_testdata::shared_dir().join("data/ict-facekit/FaceXModel/vertex_indices.json"),
        );
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let names: Vec<&str> = v["expressions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap())
            .collect();
        assert_eq!(names, ICT_EXPRESSIONS);
    }

    #[test]
    fn json_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let frames: Vec<_> = (0..4)
            .map(|i| sample_frame(i * 2, i as f64 * 2.0 / 29.97))
            .collect();
        let mut w = BlendshapesJsonWriter::in_dir(dir.path(), Some(29.97)).unwrap();
        for f in &frames {
            w.write(f).unwrap();
        }
        assert_eq!(w.frames(), 4);
        let path = w.finish().unwrap();
        assert_eq!(path, dir.path().join(BLENDSHAPES_JSON));
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 1, "compact");
        let track: BlendshapeTrack = serde_json::from_str(&text).unwrap();
        assert_eq!(track.fps, Some(29.97));
        assert_eq!(track.names, ARKIT_BLENDSHAPES);
        assert_eq!(track.frames, frames);
        // What the writer streams is what serde writes for the whole track.
        assert_eq!(text.trim_end(), serde_json::to_string(&track).unwrap());
        // No frames, no frame rate.
        let empty = BlendshapesJsonWriter::create(&dir.path().join("empty.json"), None).unwrap();
        let text = std::fs::read_to_string(empty.finish().unwrap()).unwrap();
        let track: BlendshapeTrack = serde_json::from_str(&text).unwrap();
        assert_eq!((track.fps, track.frames.len()), (None, 0));
        // The weights must be 52.
        let short = text.replace("\"frames\":[]", "\"frames\":[{\"index\":0,\"timestamp_s\":0.0,\"weights\":[0.5],\"head\":[0,0,0],\"left_eye\":[0,0,0],\"right_eye\":[0,0,0]}]");
        assert!(serde_json::from_str::<BlendshapeTrack>(&short).is_err());
    }

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
