//! ARKit's 52 blendshapes (`ARFaceAnchor.BlendShapeLocation`) and where each one's weight comes
//! from among ICT-FaceKit's expressions.
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

/// How many ARKit blendshapes there are.
pub const ARKIT_BLENDSHAPE_COUNT: usize = 52;

/// The start of a rig table's file (`PoseLeak`'s, `MouthLeak`'s): `magic`, `version` and the
/// weight count, ARKit's 52 (all little-endian).
pub(crate) fn table_header(magic: &[u8; 8], version: u32) -> Vec<u8> {
    let mut out = magic.to_vec();
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&(ARKIT_BLENDSHAPE_COUNT as u32).to_le_bytes());
    out
}

/// Reads [`table_header`]'s fields; the error says which is wrong.
pub(crate) fn read_table_header(
    r: &mut visage_morphable::binary_reader::Reader,
    magic: &[u8; 8],
    version: u32,
) -> Result<(), String> {
    r.header(magic, version)?;
    let weights = r.u32()? as usize;
    if weights != ARKIT_BLENDSHAPE_COUNT {
        return Err(format!(
            "{weights} weights, expected {ARKIT_BLENDSHAPE_COUNT}"
        ));
    }
    Ok(())
}

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

/// The 52 ARKit weights → ICT-FaceKit weights: the inverse of [`IctToArkit`], to drive the
/// ICT model with a recorded ARKit performance (a Live Link Face take). Each ICT expression
/// takes the weight of the ARKit shape it makes ([`ICT_TO_ARKIT`]); both halves of a split
/// pair (`browInnerUp`, `cheekPuff`) take the whole shape's weight, so that
/// `IctToArkit::weights(ArkitToIct::weights(a)) = a` for every `a` in [0, 1]⁵² whose
/// `tongueOut` is 0 (ICT has no tongue shape). Build it once, apply it per frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArkitToIct {
    /// For each ICT expression of the target order, its ARKit weight's index.
    sources: Vec<Option<usize>>,
}

impl ArkitToIct {
    /// The mapping into expressions named `ict_names` (e.g. `IctModel::expression_names`), in
    /// that order; a name that is not an ICT expression gets weight 0.
    pub fn new<S: AsRef<str>>(ict_names: &[S]) -> ArkitToIct {
        let source = |name: &str| {
            ICT_TO_ARKIT.iter().position(|s| match *s {
                IctSource::Shape(a) => a == name,
                IctSource::MeanOf(a, b) => a == name || b == name,
                IctSource::Zero => false,
            })
        };
        ArkitToIct {
            sources: ict_names.iter().map(|n| source(n.as_ref())).collect(),
        }
    }

    /// The ICT weights, one per name given to [`ArkitToIct::new`], for ARKit weights `arkit`
    /// in [`ARKIT_BLENDSHAPES`]' order, each clamped to [0, 1] (NaN reads as 0).
    pub fn weights(&self, arkit: &[f32; ARKIT_BLENDSHAPE_COUNT]) -> Vec<f64> {
        self.sources
            .iter()
            .map(|s| {
                let v = s.map_or(0.0, |i| f64::from(arkit[i]));
                if v.is_nan() {
                    0.0
                } else {
                    v.clamp(0.0, 1.0)
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LIVE_LINK_BLENDSHAPES;

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
    fn arkit_to_ict_round_trips_and_keeps_the_sides() {
        let to_ict = ArkitToIct::new(&ICT_EXPRESSIONS);
        let to_arkit = IctToArkit::all();
        let mut a = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
        for (i, w) in a.iter_mut().enumerate().take(ARKIT_BLENDSHAPE_COUNT - 1) {
            // Distinct values in [0, 1], exact in f32 and f64.
            *w = (i as f32 + 1.0) / 64.0;
        }
        let ict = to_ict.weights(&a);
        assert_eq!(ict.len(), ICT_EXPRESSIONS.len());
        assert_eq!(to_arkit.weights(&ict), a);
        let arkit = |name: &str| ARKIT_BLENDSHAPES.iter().position(|&n| n == name).unwrap();
        let ict_at = |name: &str| ICT_EXPRESSIONS.iter().position(|&n| n == name).unwrap();
        // ARKit's Left is ICT's _L (the subject's left); a split pair gives both halves.
        assert_eq!(
            ict[ict_at("eyeBlink_L")],
            f64::from(a[arkit("eyeBlinkLeft")])
        );
        assert_eq!(
            ict[ict_at("mouthSmile_R")],
            f64::from(a[arkit("mouthSmileRight")])
        );
        assert_eq!(
            ict[ict_at("browInnerUp_L")],
            f64::from(a[arkit("browInnerUp")])
        );
        assert_eq!(
            ict[ict_at("browInnerUp_R")],
            f64::from(a[arkit("browInnerUp")])
        );
        // Out-of-range weights are clamped; another order and unknown names are honoured.
        let mut b = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
        b[arkit("jawOpen")] = 1.5;
        b[arkit("cheekPuff")] = -1.0;
        b[arkit("tongueOut")] = 1.0;
        let subset = ArkitToIct::new(&["cheekPuff_R", "jawOpen", "tongue"]);
        assert_eq!(subset.weights(&b), vec![0.0, 1.0, 0.0]);
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
}
