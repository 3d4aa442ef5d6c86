//! The run report's charts: the design paper's per-frame figures (stage times, speed, the
//! curvature and roughness gains, landmark jitter, blendshape curves) drawn for one run from its
//! `metrics.json`, `landmarks.json` and blendshape curves.
//!
//! The files were written by this program but may come from another version or be edited, so
//! every value is read as optional: a frame without it is left out of that curve, and a chart
//! with no curve at all is left out of the report.

use std::collections::HashMap;

use serde_json::Value;
use visage_plot::{xy_chart_png, xy_chart_svg, XySeries};

use crate::{Capture, ExportError};

/// The stages `metrics.json` times, in pipeline order.
const STAGES: [&str; 6] = ["decode", "track", "fit", "depth", "fuse", "write"];
/// Window of the frame-rate curve: single frames' times swing with decoding and the detector;
/// a second of frames shows the trend.
const FPS_WINDOW_S: f64 = 1.0;
/// Blendshape curves drawn: more cannot be told apart in one chart.
const BLENDSHAPE_CURVES: usize = 8;
const TIME: &str = "time (s)";

/// One chart of the run report, written as `plots/NAME.svg` and `plots/NAME.png`.
pub struct Plot {
    /// The files' name without its extension, e.g. `stage_times`.
    pub name: &'static str,
    pub title: String,
    /// The chart as SVG, which scales to its container (the report embeds it).
    pub svg: String,
    y_label: &'static str,
    series: Vec<XySeries>,
}

impl Plot {
    /// The chart as a PNG: the SVG's drawing at 1280 × 800 pixels and the legend's column.
    ///
    /// # Errors
    /// [`ExportError::Internal`] if the PNG encoder fails (it writes into memory).
    pub fn png(&self) -> Result<Vec<u8>, ExportError> {
        xy_chart_png(&self.title, TIME, self.y_label, &self.series)
            .map_err(|e| ExportError::Internal(format!("PNG encoding: {e}")))
    }
}

/// The run's charts (the design paper's per-frame figures for this run), x = time in seconds.
/// `landmarks` is the run's `landmarks.json`; the jitter chart needs it.
pub fn run_plots(capture: &Capture, landmarks: Option<&Value>) -> Vec<Plot> {
    // Frames are matched by input index, the one key all of the run's files share.
    let times: HashMap<u64, f64> = capture
        .frames
        .iter()
        .map(|f| (f.index as u64, f.time_s))
        .collect();
    let frames: Vec<(f64, &Value)> = capture.metrics["frames"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|f| Some((time_of(f, &times)?, f)))
        .collect();
    let summary = &capture.metrics["summary"];
    // What the take's user reads first (the curves, the head), then the technical figures.
    [
        blendshapes(capture),
        head_motion(capture),
        stage_times(&frames),
        fps(&frames, summary),
        curvature(&frames),
        roughness(&frames),
        landmarks.and_then(|l| jitter(l, &times)),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// A frame's time: its own `time_s`, else the capture's time of its index.
fn time_of(frame: &Value, times: &HashMap<u64, f64>) -> Option<f64> {
    let t = frame["time_s"]
        .as_f64()
        .or_else(|| times.get(&frame["index"].as_u64()?).copied())?;
    t.is_finite().then_some(t)
}

/// The chart, unless no curve has a point.
fn chart(
    name: &'static str,
    title: String,
    y_label: &'static str,
    series: Vec<XySeries>,
) -> Option<Plot> {
    if series.iter().all(|s| s.points.is_empty()) {
        return None;
    }
    let svg = xy_chart_svg(&title, TIME, y_label, &series);
    Some(Plot {
        name,
        title,
        svg,
        y_label,
        series,
    })
}

fn curve(name: impl Into<String>, points: Vec<(f64, f64)>) -> XySeries {
    XySeries {
        name: name.into(),
        points,
        markers: false,
    }
}

/// `value` of each frame that has a finite one.
fn per_frame(frames: &[(f64, &Value)], value: impl Fn(&Value) -> Option<f64>) -> Vec<(f64, f64)> {
    frames
        .iter()
        .filter_map(|&(t, f)| value(f).filter(|v| v.is_finite()).map(|v| (t, v)))
        .collect()
}

/// A horizontal reference line at `y` over the time span of `points` (none without points).
fn level(name: String, y: f64, points: &[(f64, f64)]) -> Option<XySeries> {
    let t0 = points.iter().map(|p| p.0).reduce(f64::min)?;
    let t1 = points.iter().map(|p| p.0).reduce(f64::max)?;
    y.is_finite().then(|| curve(name, vec![(t0, y), (t1, y)]))
}

/// A frame's time in all stages together, ms: what it would cost if the stages ran one after
/// another (the stages it does not list are left out).
fn total_ms(frame: &Value) -> Option<f64> {
    let ms: Vec<f64> = STAGES
        .iter()
        .filter_map(|s| frame["ms"][*s].as_f64())
        .filter(|v| v.is_finite())
        .collect();
    (!ms.is_empty()).then(|| ms.iter().sum())
}

fn stage_times(frames: &[(f64, &Value)]) -> Option<Plot> {
    let mut series: Vec<XySeries> = STAGES
        .iter()
        .map(|s| curve(*s, per_frame(frames, |f| f["ms"][*s].as_f64())))
        .collect();
    series.push(curve("total", per_frame(frames, total_ms)));
    chart(
        "stage_times",
        "Time per frame by stage".into(),
        "ms",
        series,
    )
}

/// Frames per second over time: the stages run one after another (1000 / total ms over a
/// window), against the run's throughput, which is higher because the pipeline's threads work
/// on several frames at once.
fn fps(frames: &[(f64, &Value)], summary: &Value) -> Option<Plot> {
    let ms: Vec<(f64, f64)> = per_frame(frames, total_ms)
        .into_iter()
        .filter(|p| p.1 > 0.0)
        .collect();
    let rate = windowed_rate(&ms, FPS_WINDOW_S);
    let mut series = vec![curve("stages in series", rate.clone())];
    if let Some(fps) = summary["fps"].as_f64() {
        series.extend(level(format!("throughput {fps:.1} (threads)"), fps, &rate));
    }
    let title = match summary["cpu_use"].as_f64().filter(|c| c.is_finite()) {
        Some(c) => format!("Frames per second (CPU use {c:.2} cores on average)"),
        None => "Frames per second".into(),
    };
    chart("fps", title, "frames / s", series)
}

/// The frame rate around each frame: frames in the centred window over their time in it, ms.
/// Dividing sums, not averaging 1000 / ms, keeps a few fast frames from inflating the rate.
fn windowed_rate(ms: &[(f64, f64)], window_s: f64) -> Vec<(f64, f64)> {
    let mut ms = ms.to_vec();
    ms.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut prefix = vec![0.0];
    for p in &ms {
        prefix.push(prefix[prefix.len() - 1] + p.1);
    }
    let (mut lo, mut hi) = (0, 0);
    let mut rate = Vec::with_capacity(ms.len());
    for &(t, _) in &ms {
        while ms[lo].0 < t - window_s / 2.0 {
            lo += 1;
        }
        while hi < ms.len() && ms[hi].0 <= t + window_s / 2.0 {
            hi += 1;
        }
        rate.push((t, (hi - lo) as f64 * 1000.0 / (prefix[hi] - prefix[lo])));
    }
    rate
}

fn curvature(frames: &[(f64, &Value)]) -> Option<Plot> {
    let gain = per_frame(frames, |f| {
        f["curvature_improvement"]
            .as_f64()
            .or_else(|| Some(f["mean_abs_h_raw"].as_f64()? / f["mean_abs_h"].as_f64()?))
    });
    let mut series = vec![curve("raw / fused", gain.clone())];
    series.extend(level("1 = no change".into(), 1.0, &gain));
    let title = "Mean-curvature improvement (mean |H| raw / fused)".into();
    chart("curvature", title, "ratio", series)
}

fn roughness(frames: &[(f64, &Value)]) -> Option<Plot> {
    let series = vec![
        curve("raw", per_frame(frames, |f| f["roughness_raw"].as_f64())),
        curve("fused", per_frame(frames, |f| f["roughness"].as_f64())),
    ];
    chart(
        "roughness",
        "Roughness, raw vs fused".into(),
        "roughness",
        series,
    )
}

/// Per-frame image-space jitter of the first face's landmarks, tracked vs fused (the fused
/// surface's landmarks projected): a frame needs both its neighbours in `landmarks.json` with
/// both sets, so a lost face or an unmeshed frame breaks the run, as in the run's summary.
fn jitter(landmarks: &Value, times: &HashMap<u64, f64>) -> Option<Plot> {
    let tracks: Vec<Option<LandmarkFrame>> = landmarks["frames"]
        .as_array()?
        .iter()
        .map(|f| {
            let face = &f["faces"][0];
            let fused = pixels(&face["fused_landmarks"])?;
            Some((time_of(f, times)?, pixels(&face["landmarks"])?, fused))
        })
        .collect();
    let (mut tracked, mut fused) = (Vec::new(), Vec::new());
    for w in tracks.windows(3) {
        let [Some(a), Some(b), Some(c)] = w else {
            continue;
        };
        if let Some(j) = second_difference_rms([&a.1, &b.1, &c.1]) {
            tracked.push((b.0, j));
        }
        if let Some(j) = second_difference_rms([&a.2, &b.2, &c.2]) {
            fused.push((b.0, j));
        }
    }
    let series = vec![curve("tracked", tracked), curve("fused", fused)];
    let title = "Landmark jitter (RMS second difference)".into();
    chart("jitter", title, "px", series)
}

/// A frame's time and its tracked and fused landmark pixels.
type LandmarkFrame = (f64, Vec<[f64; 2]>, Vec<[f64; 2]>);

/// `[x, y]` of each point of a JSON list of points; NaN where a value is missing (`null`).
fn pixels(v: &Value) -> Option<Vec<[f64; 2]>> {
    let list = v.as_array().filter(|l| !l.is_empty())?;
    let c = |p: &Value, i: usize| p[i].as_f64().unwrap_or(f64::NAN);
    Some(list.iter().map(|p| [c(p, 0), c(p, 1)]).collect())
}

/// RMS over the points of |x₋ − 2x + x₊|: zero for motion at constant velocity, so it measures
/// the frame-to-frame shake a viewer sees, not the motion. Points missing in any frame are
/// skipped; `None` when none is left.
fn second_difference_rms(frames: [&[[f64; 2]]; 3]) -> Option<f64> {
    let [a, b, c] = frames;
    let (mut sum, mut count) = (0.0, 0usize);
    for ((p, q), r) in a.iter().zip(b).zip(c) {
        let d = [p[0] - 2.0 * q[0] + r[0], p[1] - 2.0 * q[1] + r[1]];
        if d.iter().all(|v| v.is_finite()) {
            sum += d[0] * d[0] + d[1] * d[1];
            count += 1;
        }
    }
    (count > 0).then(|| (sum / count as f64).sqrt())
}

/// The blendshapes by how much they move over the clip, most first: the mean of |Δw| from
/// frame to frame, so a shape that sits near a bound (a weight pinned at 1 with a few drops
/// has a large range) does not push out the jaw, the blinks and the smiles that carry the take.
/// Each with its (time, weight) points.
pub(crate) fn shapes_by_motion(capture: &Capture) -> Vec<(f64, XySeries)> {
    let Some(b) = capture.blendshapes.as_ref() else {
        return Vec::new();
    };
    let mut curves: Vec<(f64, XySeries)> = (0..b.names.len())
        .map(|i| {
            let points: Vec<(f64, f64)> = (capture.frames.iter().zip(&b.weights))
                .filter_map(|(f, w)| Some((f.time_s, *w.as_ref()?.get(i)? as f64)))
                .filter(|(t, v)| t.is_finite() && v.is_finite())
                .collect();
            let motion = points
                .windows(2)
                .map(|w| (w[1].1 - w[0].1).abs())
                .sum::<f64>()
                / points.len().max(2) as f64;
            (motion, curve(b.names[i].clone(), points))
        })
        .filter(|(motion, _)| motion.is_finite())
        .collect();
    curves.sort_by(|a, b| b.0.total_cmp(&a.0));
    curves
}

/// The [`BLENDSHAPE_CURVES`] blendshapes that move most ([`shapes_by_motion`]).
fn blendshapes(capture: &Capture) -> Option<Plot> {
    capture.blendshapes.as_ref()?;
    let series = shapes_by_motion(capture)
        .into_iter()
        .take(BLENDSHAPE_CURVES)
        .map(|c| c.1)
        .collect();
    let title = format!("ARKit blendshapes: the {BLENDSHAPE_CURVES} that move most");
    chart("blendshapes", title, "weight", series)
}

/// The head's yaw, pitch and roll over the take, in degrees.
fn head_motion(capture: &Capture) -> Option<Plot> {
    let b = capture.blendshapes.as_ref()?;
    let series: Vec<XySeries> = ["yaw", "pitch", "roll"]
        .iter()
        .enumerate()
        .map(|(axis, name)| {
            let points = (capture.frames.iter().zip(&b.head))
                .filter_map(|(f, h)| Some((f.time_s, h.as_ref()?[axis].to_degrees() as f64)))
                .collect();
            curve(*name, points)
        })
        .collect();
    chart("head", "Head motion".into(), "degrees", series)
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;
    use crate::capture::synthetic as capture;
    use crate::Blendshapes;

    #[test]
    fn a_full_run_has_every_chart() {
        let n = 40;
        let frames: Vec<Value> = (0..n)
            .map(|i| {
                let ms = json!({"decode": 1.0, "track": 5.0, "fit": 8.0 + (i % 3) as f64,
                    "depth": 0.0, "fuse": 1.0, "write": 0.5});
                json!({"index": i, "time_s": i as f64 / 30.0, "status": "solved", "ms": ms,
                    "curvature_improvement": 1.1, "roughness_raw": 0.07, "roughness": 0.06})
            })
            .collect();
        let metrics = json!({"frames": frames, "summary": {"fps": 90.0, "cpu_use": 1.5}});
        let landmarks = json!({"frames": (0..n).map(|i| {
            let x = 100.0 + i as f64 + [0.5, -0.5][i % 2];
            json!({"index": i, "faces": [{"landmarks": vec![[x, 50.0, 0.0]; 468],
                "fused_landmarks": vec![[x, 50.0]; 468]}]})
        }).collect::<Vec<_>>()});
        let names: Vec<String> = (0..10).map(|i| format!("shape{i}")).collect();
        // shape0 never moves; shape1 sits at 1 with one drop (the largest range, little
        // motion); shapes 2–9 move every frame, by more the higher their number.
        let weights = (0..n)
            .map(|k| {
                Some(
                    (0..10)
                        .map(|i| match i {
                            0 => 0.0,
                            1 => (k != 20) as u8 as f32,
                            _ => (k % 2) as f32 * i as f32 / 10.0,
                        })
                        .collect(),
                )
            })
            .collect();
        let head = (0..n).map(|k| Some([0.01 * k as f32, 0.2, 0.0])).collect();
        let c = capture(
            n,
            metrics,
            Some(Blendshapes {
                names,
                weights,
                head,
            }),
        );
        let plots = run_plots(&c, Some(&landmarks));
        let names: Vec<&str> = plots.iter().map(|p| p.name).collect();
        assert_eq!(
            names,
            [
                "blendshapes",
                "head",
                "stage_times",
                "fps",
                "curvature",
                "roughness",
                "jitter",
            ]
        );
        assert!(plots.iter().all(|p| p.svg.starts_with("<svg")));
        assert!(plots[3].title.contains("1.50 cores"));
        // The 8 shapes that move most are shape2..shape9, not the pinned shape1.
        let shapes = &plots[0].svg;
        let named = |name: &str| shapes.lines().any(|l| l.trim() == name);
        assert!(named("shape9") && named("shape2"));
        assert!(!named("shape0") && !named("shape1"));
    }

    #[test]
    fn jitter_is_zero_at_constant_velocity_and_positive_when_alternating() {
        let track = |x: [f64; 3]| x.map(|x| vec![[x, 2.0 * x], [f64::NAN, 0.0]]);
        let [a, b, c] = track([1.0, 2.0, 3.0]);
        assert_eq!(second_difference_rms([&a, &b, &c]), Some(0.0));
        let [a, b, c] = track([0.0, 1.0, 0.0]);
        let j = second_difference_rms([&a, &b, &c]).unwrap();
        assert!((j - 20f64.sqrt()).abs() < 1e-12, "{j}");
        let none = vec![[f64::NAN; 2]];
        assert_eq!(second_difference_rms([&none, &none, &none]), None);
    }

    #[test]
    fn odd_or_missing_values_do_not_panic() {
        let metrics = json!({
            "frames": [{"index": 0}, {"index": 1, "ms": "fast", "time_s": null}, 5,
                {"index": 2, "ms": {"track": null, "fit": 0.0}, "roughness": "x"},
                {"time_s": 0.1, "ms": {"fit": 3.0}, "curvature_improvement": 2.0}],
            "summary": "none"
        });
        let landmarks = json!({"frames": [{"index": 0, "faces": "none"}, 3,
            {"index": 1, "faces": [{"landmarks": [[1, "a"]], "fused_landmarks": null}]},
            {"index": 2, "faces": [{"landmarks": [[1, 2]], "fused_landmarks": [[null, 2]]}]}]});
        let shapes = Blendshapes {
            names: vec!["a".into(), "b".into()],
            weights: vec![Some(vec![]), None, Some(vec![f32::NAN, 1.0])],
            head: vec![None, Some([f32::NAN, 0.0, 1.0]), None],
        };
        let c = capture(3, metrics, Some(shapes));
        let plots = run_plots(&c, Some(&landmarks));
        assert!(plots.iter().all(|p| p.svg.starts_with("<svg")));
        assert!(plots.iter().all(|p| p.name != "jitter"));
        assert!(run_plots(&capture(0, Value::Null, None), Some(&Value::Null)).is_empty());
    }
}
