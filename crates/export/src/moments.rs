//! The moments of a take a user looks at first: every blink, every shot cut, and the frames
//! where the face does most — what the report's contact sheet shows, each with its source
//! frame beside the mesh.

use serde_json::Value;

use crate::capture::Capture;

/// Both lids at least this closed is a blink (the weight an animator reads as shut).
pub const BLINK_CLOSED: f32 = 0.6;

/// The most expressive frames shown besides the blinks and cuts.
pub const EXPRESSIVE_FRAMES: usize = 4;

/// Two moments of the same kind closer than this (seconds) are one.
const MIN_SPACING_S: f64 = 1.0;

/// Why a frame is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MomentKind {
    Blink,
    Cut,
    Expressive,
}

/// A frame worth a look: `frame` indexes [`Capture::frames`].
#[derive(Clone, Debug, PartialEq)]
pub struct Moment {
    pub frame: usize,
    pub kind: MomentKind,
    /// What is seen there, for the caption ("eyeBlinkLeft 0.93, eyeBlinkRight 0.91").
    pub note: String,
}

/// The take's moments in time order: each blink at its most closed frame, each cut's first
/// frame, and the [`EXPRESSIVE_FRAMES`] meshed frames whose expression weights (gaze and
/// blinks aside) sum highest, at least [`MIN_SPACING_S`] from each other and from the blinks
/// and cuts.
pub fn moments(capture: &Capture) -> Vec<Moment> {
    let mut out = Vec::new();
    if let Some(b) = &capture.blendshapes {
        let index = |name: &str| b.names.iter().position(|n| n == name);
        if let (Some(l), Some(r)) = (index("eyeBlinkLeft"), index("eyeBlinkRight")) {
            out.extend(blinks(capture, l, r));
        }
    }
    let cuts = capture.metrics["summary"]["cuts"].as_array();
    for cut in cuts.into_iter().flatten().filter_map(Value::as_u64) {
        if let Some(k) = capture.frames.iter().position(|f| f.index as u64 == cut) {
            out.push(Moment {
                frame: k,
                kind: MomentKind::Cut,
                note: "a shot cut: the tracker starts again".into(),
            });
        }
    }
    let taken: Vec<usize> = out.iter().map(|m| m.frame).collect();
    out.extend(expressive(capture, &taken));
    out.sort_by_key(|m| m.frame);
    out
}

/// Each run of frames with both lids at [`BLINK_CLOSED`] or more, at its most closed frame.
fn blinks(capture: &Capture, left: usize, right: usize) -> Vec<Moment> {
    let Some(b) = &capture.blendshapes else {
        return Vec::new();
    };
    let closure = |k: usize| -> Option<(f32, f32)> {
        let w = b.weights.get(k)?.as_ref()?;
        Some((*w.get(left)?, *w.get(right)?))
    };
    let mut out = Vec::new();
    let mut run: Option<(usize, f32)> = None;
    for k in 0..=capture.frames.len() {
        match closure(k).filter(|&(l, r)| l.min(r) >= BLINK_CLOSED) {
            Some((l, r)) => {
                if run.is_none_or(|(_, depth)| l + r > depth) {
                    run = Some((k, l + r));
                }
            }
            None => {
                if let Some((best, _)) = run.take() {
                    let (l, r) = closure(best).unwrap_or_default();
                    out.push(Moment {
                        frame: best,
                        kind: MomentKind::Blink,
                        note: format!("a blink: eyeBlinkLeft {l:.2}, eyeBlinkRight {r:.2}"),
                    });
                }
            }
        }
    }
    out
}

/// The frames where the face does most, apart in time from each other and from the frames
/// already `taken`, with their three largest weights.
fn expressive(capture: &Capture, taken: &[usize]) -> Vec<Moment> {
    let Some(b) = &capture.blendshapes else {
        return Vec::new();
    };
    let counted: Vec<bool> = b
        .names
        .iter()
        .map(|n| !n.starts_with("eyeLook") && !n.starts_with("eyeBlink"))
        .collect();
    let mut scored: Vec<(f32, usize)> = capture
        .meshed()
        .filter_map(|(k, _)| {
            let w = b.weights.get(k)?.as_ref()?;
            let sum = w.iter().zip(&counted).filter(|(_, &c)| c).map(|(v, _)| v);
            Some((sum.sum::<f32>(), k))
        })
        .filter(|(s, _)| s.is_finite() && *s > 0.0)
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut picked: Vec<usize> = Vec::new();
    for (_, k) in scored {
        if picked.len() == EXPRESSIVE_FRAMES {
            break;
        }
        let t = capture.frames[k].time_s;
        let apart = |p: &usize| (capture.frames[*p].time_s - t).abs() >= MIN_SPACING_S;
        if picked.iter().all(apart) && taken.iter().all(apart) {
            picked.push(k);
        }
    }
    picked
        .into_iter()
        .filter_map(|k| {
            let w = b.weights[k].as_ref()?;
            let mut top: Vec<(f32, &str)> = w
                .iter()
                .zip(&b.names)
                .zip(&counted)
                .filter(|(_, &c)| c)
                .map(|((&v, n), _)| (v, n.as_str()))
                .collect();
            top.sort_by(|a, b| b.0.total_cmp(&a.0));
            let names: Vec<String> = top
                .iter()
                .take(3)
                .map(|(v, n)| format!("{n} {v:.2}"))
                .collect();
            Some(Moment {
                frame: k,
                kind: MomentKind::Expressive,
                note: names.join(", "),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;
    use crate::capture::synthetic;
    use crate::Blendshapes;

    #[test]
    fn each_blink_cut_and_strong_expression_is_one_moment() {
        let n = 300;
        let names: Vec<String> = ["eyeBlinkLeft", "eyeBlinkRight", "jawOpen", "eyeLookInLeft"]
            .map(String::from)
            .to_vec();
        let weights = (0..n)
            .map(|k| {
                // Blinks over frames 94–98 (deepest at 96) and 185–188, one eye alone
                // closing at 40 (not a blink); the jaw opens most at 150 and less at 250; the
                // gaze, which does not count as expression, is large at 20.
                let blink = match k {
                    94..=98 => 1.0 - (k as f32 - 96.0).abs() * 0.1,
                    185..=188 => 0.9,
                    _ => 0.0,
                };
                let left = if k == 40 { 1.0 } else { blink };
                let jaw = 0.9 * (-((k as f32 - 150.0) / 10.0).powi(2)).exp()
                    + 0.5 * (-((k as f32 - 250.0) / 10.0).powi(2)).exp();
                let gaze = if k == 20 { 1.0 } else { 0.0 };
                Some(vec![left, blink, jaw, gaze])
            })
            .collect();
        let metrics = json!({"summary": {"cuts": [200]}});
        let shapes = Blendshapes {
            names,
            weights,
            head: vec![None; n],
        };
        let capture = synthetic(n, metrics, Some(shapes));
        let found: Vec<(usize, MomentKind)> = moments(&capture)
            .iter()
            .map(|m| (m.frame, m.kind))
            .collect();
        use MomentKind::*;
        let blinks_and_cuts: Vec<_> = found.iter().filter(|m| m.1 != Expressive).collect();
        assert_eq!(blinks_and_cuts, [&(96, Blink), &(185, Blink), &(200, Cut)]);
        let expressive: Vec<usize> = found
            .iter()
            .filter(|m| m.1 == Expressive)
            .map(|m| m.0)
            .collect();
        assert!(
            expressive.contains(&150) && expressive.contains(&250),
            "{found:?}"
        );
        // At least a second from each other and from the blinks and the cut.
        for e in &expressive {
            for other in found.iter().filter(|m| m.0 != *e) {
                assert!(e.abs_diff(other.0) >= 30, "{found:?}");
            }
        }
    }
}
