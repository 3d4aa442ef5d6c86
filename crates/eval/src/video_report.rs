//! The real-clip stability report (`visage eval video`): the pipeline's landmarks against the
//! filters a user could put on the tracked landmarks instead — EMA, One-Euro, the
//! constant-velocity Kalman filter (causal, each swept) and a centred Gaussian (offline) — by
//! jitter, deviation and lag, over the face and per region, in image space.
//!
//! The comparison the report is built for: a pipeline output against the best baseline of its
//! kind at no larger deviation from the tracked landmarks (a filter that smooths more always
//! wins on jitter, so only the curve of jitter against deviation means anything).

use serde::Serialize;
use visage_face::FaceRegion;
use visage_temporal::{
    filter_track, gaussian_smooth, ConstantVelocity, Ema, FixedLagSmoother, OneEuro, TrackFigures,
    TrackFilter,
};

use visage_plot::{xy_chart_svg, XySeries};

/// A clip's tracks: frames that follow each other with a face (segments), every frame's 468
/// landmarks as `x, y` scalars (pixels).
#[derive(Clone, Debug, Default)]
pub struct ClipTracks {
    pub name: String,
    /// Seconds between frames.
    pub frame_interval_s: f64,
    /// The tracked landmarks, per segment and frame.
    pub tracked: Vec<Vec<Vec<f64>>>,
    /// The pipeline's outputs on the same frames.
    pub outputs: Vec<PipelineOutput>,
}

/// One way of running the pipeline on the clip.
#[derive(Clone, Debug, Default)]
pub struct PipelineOutput {
    pub name: String,
    /// Frames it waits for before giving a frame out (`None`: the whole clip, offline). It
    /// is measured against the causal baselines, or the offline ones when `None`.
    pub latency_frames: Option<usize>,
    /// The fused surface's landmarks projected into the frames, shaped as
    /// [`ClipTracks::tracked`].
    pub landmarks: Vec<Vec<Vec<f64>>>,
    /// The head's distance from the camera (metres) per segment and frame.
    pub distance_m: Vec<Vec<f64>>,
}

/// A method's figures: over the face and per region.
#[derive(Clone, Debug, Serialize)]
pub struct MethodFigures {
    /// `ema`, `one_euro`, `kalman`, `kalman_lag1`, `gaussian` or the pipeline's.
    pub family: String,
    /// The swept parameter(s), as text.
    pub parameter: String,
    pub causal: bool,
    #[serde(flatten)]
    pub face: TrackFigures,
    /// Jitter reduction against the tracked landmarks.
    pub reduction: f64,
    pub regions: Vec<RegionFigures>,
}

#[derive(Clone, Debug, Serialize)]
pub struct RegionFigures {
    pub region: &'static str,
    #[serde(flatten)]
    pub figures: TrackFigures,
}

/// A pipeline output against the best baseline of its kind at no larger deviation.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    pub output: String,
    pub reduction: f64,
    pub deviation_px: f64,
    pub lag_frames: f64,
    /// The best baseline's family and parameter, reduction and deviation.
    pub baseline: String,
    pub baseline_reduction: f64,
    pub baseline_deviation_px: f64,
    /// `reduction / baseline_reduction`.
    pub advantage: f64,
    /// The baselines' best reduction at exactly the output's deviation, interpolated on their
    /// upper envelope (a finer sweep would get about this), and the advantage over it.
    pub envelope_reduction: f64,
    pub envelope_advantage: f64,
    /// The same against baselines given the output's latency too (one frame: the
    /// constant-velocity smoother one frame late), at equal deviation.
    pub same_latency_advantage: f64,
    /// Mean deviation of the inner lips over the face's.
    pub inner_lip_ratio: f64,
    /// Second-difference jitter of the head's distance (mm), and the per-frame fit's.
    pub distance_jitter_mm: f64,
    pub per_frame_distance_jitter_mm: f64,
}

/// One clip's report.
#[derive(Clone, Debug, Serialize)]
pub struct ClipReport {
    pub clip: String,
    pub frames: usize,
    pub tracked_jitter_px: f64,
    pub methods: Vec<MethodFigures>,
    pub comparisons: Vec<Comparison>,
}

/// Measures `track` (segments as in [`ClipTracks::tracked`]) against the tracked landmarks.
fn measure(
    family: &str,
    parameter: String,
    causal: bool,
    track: &[Vec<Vec<f64>>],
    tracked: &[Vec<Vec<f64>>],
    regions: &[(FaceRegion, Vec<usize>)],
) -> MethodFigures {
    let mut face = TrackFigures::default();
    let mut per_region: Vec<TrackFigures> =
        regions.iter().map(|_| TrackFigures::default()).collect();
    for (seg, reference) in track.iter().zip(tracked) {
        face.add_segment(seg, reference, 2, None);
        for ((_, points), figures) in regions.iter().zip(&mut per_region) {
            figures.add_segment(seg, reference, 2, Some(points));
        }
    }
    MethodFigures {
        family: family.into(),
        parameter,
        causal,
        reduction: face.reduction(),
        face,
        regions: regions
            .iter()
            .zip(per_region)
            .map(|((r, _), figures)| RegionFigures {
                region: r.name(),
                figures,
            })
            .collect(),
    }
}

/// Segments × frames × scalars.
type Track = Vec<Vec<Vec<f64>>>;

/// The baselines: every family over its sweep (family, parameter, causal, track).
fn baselines(clip: &ClipTracks) -> Vec<(&'static str, String, bool, Track)> {
    let dt = clip.frame_interval_s;
    let causal = |f: &mut dyn TrackFilter| -> Track {
        clip.tracked
            .iter()
            .map(|seg| filter_track(f, seg, dt))
            .collect()
    };
    let mut out = Vec::new();
    out.push(("tracked", "-".to_string(), true, clip.tracked.clone()));
    for alpha in (4..=19).rev().map(|i| i as f64 * 0.05) {
        out.push((
            "ema",
            format!("α {alpha:.2}"),
            true,
            causal(&mut Ema::new(alpha)),
        ));
    }
    for min_cutoff in [0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0] {
        for beta in [0.0, 0.001, 0.003, 0.01, 0.03, 0.1, 0.3] {
            out.push((
                "one_euro",
                format!("f_min {min_cutoff} Hz, β {beta}"),
                true,
                causal(&mut OneEuro::new(min_cutoff, beta)),
            ));
        }
    }
    for ratio in (0..=14).map(|i| 100.0 * 2f64.powf(i as f64 / 2.0)) {
        out.push((
            "kalman",
            format!("ratio {ratio:.0}"),
            true,
            causal(&mut ConstantVelocity::new(ratio)),
        ));
    }
    // The same model one frame later: what the pipeline's latency alone buys.
    for ratio in [400.0, 800.0, 1600.0, 3200.0, 6400.0] {
        let lagged = clip
            .tracked
            .iter()
            .map(|seg| {
                let mut s = FixedLagSmoother::new(ratio, 1);
                let mut out: Vec<Vec<f64>> = seg.iter().filter_map(|x| s.push(x, dt)).collect();
                out.extend(s.finish());
                out
            })
            .collect();
        out.push(("kalman_lag1", format!("ratio {ratio}"), false, lagged));
    }
    for sigma in (4..=30).map(|i| i as f64 * 0.1) {
        let smooth = clip
            .tracked
            .iter()
            .map(|seg| gaussian_smooth(seg, sigma))
            .collect();
        out.push(("gaussian", format!("σ {sigma:.1} frames"), false, smooth));
    }
    out
}

/// The upper envelope of `(deviation, reduction)` points: those with a better reduction than
/// every point of no larger deviation, by deviation.
fn upper_envelope(points: impl Iterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    let mut p: Vec<(f64, f64)> = points
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = f64::NEG_INFINITY;
    p.retain(|q| {
        let keep = q.1 > best;
        best = best.max(q.1);
        keep
    });
    p
}

/// The upper envelope of `(deviation, reduction)` points, linearly interpolated at
/// `deviation`.
fn envelope_at(points: impl Iterator<Item = (f64, f64)>, deviation: f64) -> f64 {
    let p = upper_envelope(points);
    match p.iter().position(|q| q.0 > deviation) {
        Some(0) => p[0].1.min(1.0),
        Some(i) => {
            let (a, b) = (p[i - 1], p[i]);
            a.1 + (b.1 - a.1) * (deviation - a.0) / (b.0 - a.0)
        }
        None => p.last().map_or(1.0, |q| q.1),
    }
}

fn distance_jitter_mm(distance: &[Vec<f64>]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for seg in distance {
        for w in seg.windows(3) {
            sum += (w[2] - 2.0 * w[1] + w[0]).powi(2);
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        1e3 * (sum / n as f64).sqrt()
    }
}

/// Measures every baseline and pipeline output of a clip and compares each output with the
/// best baseline of its kind (causal outputs: EMA, One-Euro and Kalman; offline outputs: the
/// centred Gaussian) at no larger deviation. `per_frame` names the output whose distance is
/// the per-frame fit's (the pipeline without its temporal model).
pub fn evaluate_clip(clip: &ClipTracks, per_frame: &str) -> ClipReport {
    let regions: Vec<(FaceRegion, Vec<usize>)> = FaceRegion::ALL
        .iter()
        .map(|&r| (r, r.landmarks()))
        .collect();
    let mut methods: Vec<MethodFigures> = baselines(clip)
        .into_iter()
        .map(|(family, parameter, causal, track)| {
            measure(family, parameter, causal, &track, &clip.tracked, &regions)
        })
        .collect();
    let per_frame_z = clip
        .outputs
        .iter()
        .find(|o| o.name == per_frame)
        .map_or(0.0, |o| distance_jitter_mm(&o.distance_m));
    let mut comparisons = Vec::new();
    for o in &clip.outputs {
        let m = measure(
            &o.name,
            "-".into(),
            o.latency_frames.is_some(),
            &o.landmarks,
            &clip.tracked,
            &regions,
        );
        let kinds: &[&str] = match o.latency_frames {
            Some(_) => &["tracked", "ema", "one_euro", "kalman"],
            None => &["tracked", "gaussian"],
        };
        let same_latency: &[&str] = match o.latency_frames {
            Some(0) => kinds,
            Some(_) => &["tracked", "ema", "one_euro", "kalman", "kalman_lag1"],
            None => kinds,
        };
        let same = envelope_at(
            methods
                .iter()
                .filter(|b| same_latency.contains(&b.family.as_str()))
                .map(|b| (b.face.deviation, b.reduction)),
            m.face.deviation,
        );
        let best = methods
            .iter()
            .filter(|b| kinds.contains(&b.family.as_str()))
            .filter(|b| b.face.deviation <= m.face.deviation + 1e-12)
            .max_by(|a, b| a.reduction.total_cmp(&b.reduction));
        let inner = m
            .regions
            .iter()
            .find(|r| r.region == FaceRegion::InnerLips.name())
            .map_or(0.0, |r| r.figures.deviation);
        let envelope = envelope_at(
            methods
                .iter()
                .filter(|b| kinds.contains(&b.family.as_str()))
                .map(|b| (b.face.deviation, b.reduction)),
            m.face.deviation,
        );
        if let Some(best) = best {
            comparisons.push(Comparison {
                output: o.name.clone(),
                reduction: m.reduction,
                deviation_px: m.face.deviation,
                lag_frames: m.face.lag_frames,
                baseline: format!("{} ({})", best.family, best.parameter),
                baseline_reduction: best.reduction,
                baseline_deviation_px: best.face.deviation,
                advantage: m.reduction / best.reduction,
                envelope_reduction: envelope,
                envelope_advantage: m.reduction / envelope,
                same_latency_advantage: m.reduction / same,
                inner_lip_ratio: inner / m.face.deviation.max(1e-12),
                distance_jitter_mm: distance_jitter_mm(&o.distance_m),
                per_frame_distance_jitter_mm: per_frame_z,
            });
        }
        methods.push(m);
    }
    ClipReport {
        clip: clip.name.clone(),
        frames: clip.tracked.iter().map(Vec::len).sum(),
        tracked_jitter_px: methods.first().map_or(0.0, |m| m.face.jitter),
        methods,
        comparisons,
    }
}

/// The jitter reduction against deviation chart of a clip (SVG): one curve per baseline
/// family (over its sweep; One-Euro: the best reduction at each deviation), one dot per
/// pipeline output.
pub fn stability_chart_svg(report: &ClipReport) -> String {
    let mut series = Vec::new();
    for family in ["ema", "one_euro", "kalman", "kalman_lag1", "gaussian"] {
        let points = upper_envelope(
            report
                .methods
                .iter()
                .filter(|m| m.family == family)
                .map(|m| (m.face.deviation, m.reduction)),
        );
        series.push(XySeries {
            name: family.replace('_', " "),
            points,
            markers: false,
        });
    }
    for c in &report.comparisons {
        series.push(XySeries {
            name: c.output.clone(),
            points: vec![(c.deviation_px, c.reduction)],
            markers: true,
        });
    }
    xy_chart_svg(
        &format!("{}: jitter reduction against deviation", report.clip),
        "mean deviation from the tracked landmarks (px)",
        "jitter reduction (×)",
        &series,
    )
}

/// The comparisons of several clips as a text table, then each output's figures per region.
pub fn stability_table(reports: &[ClipReport]) -> String {
    let mut s = format!(
        "{:<10} {:<14} {:>7} {:>7} {:>6} {:>6} {:>11}  {}\n",
        "clip",
        "output",
        "jitter×",
        "dev px",
        "lag",
        "lips/µ",
        "z mm",
        "best baseline at ≤ dev (×, px) → advantage; envelope at = dev → advantage; same latency"
    );
    for r in reports {
        for c in &r.comparisons {
            s += &format!(
                "{:<10} {:<14} {:>7.2} {:>7.3} {:>6.2} {:>6.2} {:.3}/{:.3}  {} ({:.2}, {:.3}) → {:.2}×; {:.2} → {:.2}×; {:.2}×\n",
                r.clip,
                c.output,
                c.reduction,
                c.deviation_px,
                c.lag_frames,
                c.inner_lip_ratio,
                c.distance_jitter_mm,
                c.per_frame_distance_jitter_mm,
                c.baseline,
                c.baseline_reduction,
                c.baseline_deviation_px,
                c.advantage,
                c.envelope_reduction,
                c.envelope_advantage,
                c.same_latency_advantage
            );
        }
    }
    s += "\nper region: deviation px / lag frames / jitter reduction\n";
    for r in reports {
        for c in &r.comparisons {
            let Some(m) = r.methods.iter().find(|m| m.family == c.output) else {
                continue;
            };
            s += &format!("{:<10} {:<14}", r.clip, c.output);
            for g in &m.regions {
                s += &format!(
                    "  {} {:.3}/{:.2}/{:.2}",
                    g.region,
                    g.figures.deviation,
                    g.figures.lag_frames,
                    g.figures.reduction()
                );
            }
            s += "\n";
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_envelope_is_interpolated_between_its_points() {
        let pts = [(0.0, 1.0), (1.0, 2.0), (0.5, 1.2), (2.0, 3.0)];
        assert!((envelope_at(pts.into_iter(), 1.5) - 2.5).abs() < 1e-12);
        assert!((envelope_at(pts.into_iter(), 0.5) - 1.2).abs() < 1e-12);
        assert!((envelope_at(pts.into_iter(), 0.75) - 1.6).abs() < 1e-12);
        assert_eq!(envelope_at(pts.into_iter(), 5.0), 3.0);
    }

    /// A face that moves smoothly with white noise on every landmark.
    fn clip() -> ClipTracks {
        let frames = 90;
        let noise = |t: usize, i: usize| {
            (((t * 468 + i) as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5
        };
        let truth = |t: usize, i: usize| {
            [
                100.0 + (0.05 * t as f64).sin() * 20.0 + (i % 20) as f64,
                100.0 + (0.03 * t as f64).cos() * 10.0 + (i / 20) as f64,
            ]
        };
        let tracked: Vec<Vec<f64>> = (0..frames)
            .map(|t| {
                (0..468)
                    .flat_map(|i| {
                        let p = truth(t, i);
                        [p[0] + noise(t, i), p[1] + noise(t, 1000 + i)]
                    })
                    .collect()
            })
            .collect();
        let clean: Vec<Vec<f64>> = (0..frames)
            .map(|t| (0..468).flat_map(|i| truth(t, i)).collect())
            .collect();
        ClipTracks {
            name: "synthetic".into(),
            frame_interval_s: 1.0 / 30.0,
            tracked: vec![tracked.clone()],
            outputs: vec![
                PipelineOutput {
                    name: "as tracked".into(),
                    latency_frames: Some(0),
                    landmarks: vec![tracked],
                    distance_m: vec![vec![0.5; frames]],
                },
                PipelineOutput {
                    name: "noise-free".into(),
                    latency_frames: None,
                    landmarks: vec![clean],
                    distance_m: vec![vec![0.5; frames]],
                },
            ],
        }
    }

    #[test]
    fn outputs_are_compared_with_the_best_baseline_at_no_larger_deviation() {
        let report = evaluate_clip(&clip(), "as tracked");
        let as_tracked = &report.comparisons[0];
        // The tracked landmarks themselves: no reduction, no deviation, no advantage.
        assert!((as_tracked.reduction - 1.0).abs() < 1e-9);
        assert!(as_tracked.deviation_px < 1e-12 && (as_tracked.advantage - 1.0).abs() < 1e-9);
        // The noise-free track beats every Gaussian that deviates no more than it does.
        let clean = &report.comparisons[1];
        assert!(clean.reduction > 5.0, "{}", clean.reduction);
        assert!(clean.advantage > 1.0 && clean.baseline.starts_with("gaussian"));
        assert!(clean.baseline_deviation_px <= clean.deviation_px);
        assert!(
            clean.envelope_advantage > 1.0 && clean.envelope_reduction >= clean.baseline_reduction
        );
        assert!((as_tracked.envelope_advantage - 1.0).abs() < 1e-9);
        assert_eq!(
            report.methods.last().unwrap().regions.len(),
            FaceRegion::ALL.len()
        );
        let svg = stability_chart_svg(&report);
        assert!(svg.contains("noise-free") && svg.contains("one euro"));
        assert!(stability_table(&[report]).contains("noise-free"));
    }
}
