//! How well read expression curves match played ones: per-curve error and correlation,
//! blinks caught and eyes closed that were open, the weights' motion while the face is at
//! rest and only the head moves (the rigid leak), the head's rotation error, and the fitted
//! identity's shape error. Frames are compared by index: the pipeline gives each frame's
//! weights for that frame, after its smoother's latency.

use visage_camera::RigidTransform;

/// A played weight at or above this is a closed eye (a blink to catch).
pub const BLINK_PLAYED: f32 = 0.8;
/// A read weight at or above this reads as a closed eye.
pub const BLINK_READ: f32 = 0.6;
/// A played weight below this is an open eye (a read closure there is false).
pub const OPEN_PLAYED: f32 = 0.2;
/// A frame is at rest when every played weight lies within this of its take's resting value
/// ([`rest_frames`]). On the range-of-motion take `alex_rom_3` 12 % of the frames are at rest
/// (0.1: 4 %, 0.2: 20 %).
pub const REST_TOLERANCE: f32 = 0.15;
/// The resting value of a played weight: this quantile of it over the take (the median: a
/// performance holds each shape for a minority of its frames, and real resting faces are not
/// at 0 — this take's lids rest at `eyeBlink` ≈ 0.2).
pub const REST_QUANTILE: f64 = 0.5;

/// Mean absolute difference; `None` for empty curves.
///
/// # Panics
/// Curves of different lengths.
#[track_caller]
pub fn mae(played: &[f32], read: &[f32]) -> Option<f64> {
    assert_eq!(played.len(), read.len(), "curves of different lengths");
    (!played.is_empty()).then(|| {
        played
            .iter()
            .zip(read)
            .map(|(a, b)| f64::from((a - b).abs()))
            .sum::<f64>()
            / played.len() as f64
    })
}

/// Pearson's correlation coefficient `r = cov(a, b) / (σ_a σ_b)`; `None` when either curve is
/// constant (or there are fewer than two frames): r is undefined there.
///
/// # Panics
/// Curves of different lengths.
#[track_caller]
pub fn pearson(a: &[f32], b: &[f32]) -> Option<f64> {
    assert_eq!(a.len(), b.len(), "curves of different lengths");
    let n = a.len() as f64;
    if a.len() < 2 {
        return None;
    }
    let mean = |x: &[f32]| x.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let (ma, mb) = (mean(a), mean(b));
    let (mut cov, mut va, mut vb) = (0.0, 0.0, 0.0);
    for (&x, &y) in a.iter().zip(b) {
        let (dx, dy) = (f64::from(x) - ma, f64::from(y) - mb);
        cov += dx * dy;
        va += dx * dx;
        vb += dy * dy;
    }
    // Relative to the curves' size: a curve constant to rounding is constant.
    let tiny = 1e-12 * n;
    (va > tiny && vb > tiny).then(|| cov / (va * vb).sqrt())
}

/// Blinks of one or more eyes: how many a reader caught, and how often it closed an open eye.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct BlinkCounts {
    /// Blinks played: maximal runs of frames with the played weight ≥ [`BLINK_PLAYED`].
    pub blinks: usize,
    /// Blinks in which the read weight reached [`BLINK_READ`] on some frame of the run.
    pub hits: usize,
    /// Frames with the played weight below [`OPEN_PLAYED`].
    pub open_frames: usize,
    /// Of those, frames whose read weight is ≥ [`BLINK_READ`].
    pub false_closures: usize,
}

impl BlinkCounts {
    /// Counts one eye's curves.
    ///
    /// # Panics
    /// Curves of different lengths.
    #[track_caller]
    pub fn of(played: &[f32], read: &[f32]) -> BlinkCounts {
        assert_eq!(played.len(), read.len(), "curves of different lengths");
        let mut c = BlinkCounts::default();
        let mut in_blink: Option<bool> = None; // Some(hit so far) inside a blink
        for (&p, &r) in played.iter().zip(read) {
            if p >= BLINK_PLAYED {
                let hit = in_blink.unwrap_or(false) || r >= BLINK_READ;
                if in_blink.is_none() {
                    c.blinks += 1;
                }
                in_blink = Some(hit);
            } else {
                if in_blink == Some(true) {
                    c.hits += 1;
                }
                in_blink = None;
            }
            if p < OPEN_PLAYED {
                c.open_frames += 1;
                c.false_closures += usize::from(r >= BLINK_READ);
            }
        }
        if in_blink == Some(true) {
            c.hits += 1;
        }
        c
    }

    /// Blinks caught / blinks played; `None` without blinks.
    pub fn hit_rate(&self) -> Option<f64> {
        (self.blinks > 0).then(|| self.hits as f64 / self.blinks as f64)
    }

    /// False closures / open frames; `None` without open frames.
    pub fn false_closure_rate(&self) -> Option<f64> {
        (self.open_frames > 0).then(|| self.false_closures as f64 / self.open_frames as f64)
    }
}

/// Each played weight's resting value: its [`REST_QUANTILE`] over the frames. `played[f]` is
/// frame f's weights.
pub fn resting_values<const N: usize>(played: &[[f32; N]]) -> [f32; N] {
    std::array::from_fn(|w| {
        let mut v: Vec<f32> = played.iter().map(|p| p[w]).collect();
        v.sort_by(f32::total_cmp);
        quantile_sorted(&v, REST_QUANTILE)
    })
}

/// The played weights relative to the performer's resting face, as the pipeline reads a face
/// (weights relative to the person's rest): `(w − rest) / (1 − rest)` clamped to [0, 1], with
/// `rest` the weight's [`resting_values`]. A recorded take rests away from 0 where the
/// performer's face differs from ARKit's neutral (`browDown` ≈ 0.46 on `jmtechart_MySlate_3`)
/// — the performer's identity as ARKit reads it, which no reading relative to the rest
/// returns.
pub fn from_rest<const N: usize>(played: &[[f32; N]]) -> Vec<[f32; N]> {
    let rest = resting_values(played);
    played
        .iter()
        .map(|p| {
            std::array::from_fn(|w| {
                let span = (1.0 - rest[w]).max(f32::EPSILON);
                ((p[w] - rest[w]) / span).clamp(0.0, 1.0)
            })
        })
        .collect()
}

/// The frames at rest: every played weight within [`REST_TOLERANCE`] of its resting value
/// ([`resting_values`]). `played[f]` is frame f's weights.
pub fn rest_frames<const N: usize>(played: &[[f32; N]]) -> Vec<usize> {
    let rest = resting_values(played);
    (0..played.len())
        .filter(|&f| (0..N).all(|w| (played[f][w] - rest[w]).abs() <= REST_TOLERANCE))
        .collect()
}

/// The rigid leak over `frames` (frames at rest while the head moves): for every weight w, the
/// read-minus-played difference's distance from its median over those frames,
/// `|(read_w − played_w)(f) − median_f(read_w − played_w)|`, pooled over weights and frames.
/// Subtracting the played value removes what the face itself did; subtracting the median
/// removes a constant offset (a resting face read slightly off), which is not motion. Returns
/// the pooled samples, sorted.
pub fn rigid_leak<const N: usize>(
    played: &[[f32; N]],
    read: &[[f32; N]],
    frames: &[usize],
) -> Vec<f32> {
    let mut pooled = Vec::with_capacity(frames.len() * N);
    for w in 0..N {
        let mut diff: Vec<f32> = frames.iter().map(|&f| read[f][w] - played[f][w]).collect();
        let mut sorted = diff.clone();
        sorted.sort_by(f32::total_cmp);
        if sorted.is_empty() {
            continue;
        }
        let median = quantile_sorted(&sorted, 0.5);
        for d in &mut diff {
            *d = (*d - median).abs();
        }
        pooled.extend(diff);
    }
    pooled.sort_by(f32::total_cmp);
    pooled
}

/// The `q`-quantile of sorted values (nearest rank, `⌈q n⌉`-th); 0 when empty.
pub fn quantile_sorted(sorted: &[f32], q: f64) -> f32 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = (q * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// The geodesic angle between two rotations, `acos((tr(Aᵀ B) − 1) / 2)`, degrees.
pub fn rotation_angle_deg(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> f64 {
    let trace: f64 = (0..3)
        .map(|i| (0..3).map(|k| a[k][i] * b[k][i]).sum::<f64>())
        .sum();
    ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees()
}

/// Root mean square; `None` when empty.
pub fn rms(values: &[f64]) -> Option<f64> {
    (!values.is_empty())
        .then(|| (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt())
}

/// The RMS distance between two shapes of corresponding points after the rigid motion that
/// best moves `a` onto `b` (Horn's, no scale: a face fitted too small or too large counts as
/// error); `None` for empty shapes. Same units as the points.
///
/// # Panics
/// Shapes of different sizes.
#[track_caller]
pub fn aligned_rms(a: &[[f64; 3]], b: &[[f64; 3]]) -> Option<f64> {
    assert_eq!(a.len(), b.len(), "shapes of different sizes");
    let t = RigidTransform::fit(a.iter().zip(b).map(|(&p, &q)| (p, q, 1.0)))?;
    let d: Vec<f64> = a
        .iter()
        .zip(b)
        .map(|(&p, &q)| visage_camera::vec3::distance(t.apply(p), q))
        .collect();
    rms(&d)
}

/// The sum of two counts (two eyes, two takes).
impl std::ops::Add for BlinkCounts {
    type Output = BlinkCounts;

    fn add(self, other: BlinkCounts) -> BlinkCounts {
        BlinkCounts {
            blinks: self.blinks + other.blinks,
            hits: self.hits + other.hits,
            open_frames: self.open_frames + other.open_frames,
            false_closures: self.false_closures + other.false_closures,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pearson_and_mae_on_hand_made_curves() {
        let a = [0.0, 0.5, 1.0, 0.5, 0.0];
        let twice = a.map(|v| 0.2 + 0.5 * v);
        assert!((pearson(&a, &twice).unwrap() - 1.0).abs() < 1e-12);
        let flipped = a.map(|v| 1.0 - v);
        assert!((pearson(&a, &flipped).unwrap() + 1.0).abs() < 1e-12);
        assert_eq!(
            pearson(&a, &[0.3; 5]),
            None,
            "a constant read curve has no r"
        );
        // Uncorrelated: a symmetric bump against an odd ramp.
        let ramp = [-1.0, -0.5, 0.0, 0.5, 1.0];
        assert!(pearson(&a, &ramp).unwrap().abs() < 1e-12);
        assert!((mae(&a, &twice).unwrap() - 0.16).abs() < 1e-6);
        assert_eq!(mae(&[], &[]), None);
    }

    #[test]
    fn blinks_are_caught_per_run_and_false_closures_per_open_frame() {
        // Two blinks: the first read (0.7 on one frame), the second missed (0.5 peak).
        let played = [0.0, 0.9, 1.0, 0.1, 0.0, 0.85, 0.9, 0.0, 0.0, 0.1];
        let read = [0.0, 0.3, 0.7, 0.2, 0.0, 0.5, 0.4, 0.0, 0.65, 0.0];
        let c = BlinkCounts::of(&played, &read);
        assert_eq!(c.blinks, 2);
        assert_eq!(c.hits, 1);
        assert_eq!(c.hit_rate(), Some(0.5));
        // Open frames: 0, 3, 4, 7, 8, 9; frame 8 closed by the reader.
        assert_eq!(c.open_frames, 6);
        assert_eq!(c.false_closures, 1);
        assert!((c.false_closure_rate().unwrap() - 1.0 / 6.0).abs() < 1e-12);
        // A blink still on at the end counts.
        let c = BlinkCounts::of(&[0.0, 0.9], &[0.0, 0.9]);
        assert_eq!((c.blinks, c.hits), (1, 1));
        assert_eq!(BlinkCounts::default().hit_rate(), None);
    }

    #[test]
    fn the_rigid_leak_ignores_offsets_and_played_motion() {
        // Two weights over six frames at rest; the reader adds a constant 0.2 to weight 0 (no
        // leak) and a wobble of ±0.05 on weight 1 (the leak).
        let played: Vec<[f32; 2]> = (0..6).map(|f| [0.02 * f as f32, 0.0]).collect();
        let read: Vec<[f32; 2]> = played
            .iter()
            .enumerate()
            .map(|(f, p)| [p[0] + 0.2, if f % 2 == 0 { 0.05 } else { -0.05 }])
            .collect();
        let frames: Vec<usize> = (0..6).collect();
        let leak = rigid_leak(&played, &read, &frames);
        assert_eq!(leak.len(), 12);
        assert!(leak[..6].iter().all(|&v| v < 1e-6), "{leak:?}");
        assert!(
            (quantile_sorted(&leak, 0.99) - 0.1).abs() < 1e-6,
            "{leak:?}"
        );
        // Rest frames: weight 0 moves to 0.5 on frame 3 only.
        let mut moving = played.clone();
        moving[3][0] = 0.5;
        assert_eq!(rest_frames(&moving), vec![0, 1, 2, 4, 5]);
    }

    #[test]
    fn played_weights_from_the_rest_of_the_take() {
        // Weight 0 rests at 0.4 and peaks at 1; weight 1 rests at 0 and dips nowhere.
        let played = [[0.4, 0.0], [0.4, 0.5], [0.7, 0.0], [1.0, 0.0], [0.2, 0.0]];
        assert_eq!(resting_values(&played), [0.4, 0.0]);
        let relative = from_rest(&played);
        let expect = [[0.0, 0.0], [0.0, 0.5], [0.5, 0.0], [1.0, 0.0], [0.0, 0.0]];
        for (r, e) in relative.iter().zip(&expect) {
            assert!(
                (r[0] - e[0]).abs() < 1e-6 && (r[1] - e[1]).abs() < 1e-6,
                "{r:?} {e:?}"
            );
        }
    }

    #[test]
    fn rotation_angles_and_aligned_shapes() {
        let rz = |a: f64| {
            let (s, c) = a.sin_cos();
            [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
        };
        assert!((rotation_angle_deg(&rz(0.1), &rz(0.4)) - 0.3f64.to_degrees()).abs() < 1e-9);
        assert!(rotation_angle_deg(&rz(0.2), &rz(0.2)) < 1e-6);
        // A shape moved rigidly aligns exactly; one scaled by 1.1 does not.
        let a: Vec<[f64; 3]> = (0..20)
            .map(|i| {
                let t = i as f64;
                [t.sin(), (1.7 * t).cos(), 0.1 * t]
            })
            .collect();
        let r = rz(0.7);
        let moved: Vec<[f64; 3]> = a
            .iter()
            .map(|p| std::array::from_fn(|i| (0..3).map(|k| r[i][k] * p[k]).sum::<f64>() + 0.3))
            .collect();
        assert!(aligned_rms(&a, &moved).unwrap() < 1e-9);
        let scaled: Vec<[f64; 3]> = a.iter().map(|p| p.map(|c| 1.1 * c)).collect();
        assert!(aligned_rms(&a, &scaled).unwrap() > 0.01);
    }
}
