//! What the head's turn alone adds to each weight, and its removal.
//!
//! A neutral face turned away from the camera still reads some expression: the landmark
//! network's view-dependent bias that the fit's view correction leaves, the fitted identity's
//! small errors in depth, and the fit explaining a pose error by a shape (a head rolled a few
//! degrees too far reads as a jaw pushed sideways). On renders of neutral heads whose pose is
//! known, much of that leak is the same for every face at the same pose. The table holds, per
//! ARKit weight, the weight's change at each node of a grid over the head's read yaw,
//! pitch and roll (Live Link Face's angles, radians; interpolated trilinearly between nodes),
//! relative to the same head's median over its turn, learned from rigid renders of several
//! identities (`visage-eval`'s `pose_leak_table` example regenerates the file). Nothing in it
//! comes from an expression: it does not learn which shapes a performer moves together, so a
//! shape keeps its own reading and is never inferred from another one.
//!
//! A node's value starts from a kernel average of the rendered frames near it (a Gaussian in the
//! angles, [`LeakLearning::bandwidth`]) pulled toward a cubic polynomial in the angles fitted
//! to every frame by ridge regression, as if the polynomial were
//! [`LeakLearning::prior_frames`] more frames at the node: where renders are dense the local
//! average rules, where they are sparse the smooth fit does. The leak is not smooth over the
//! whole turn: at the corners of a turn (near 40° of yaw with 20° of pitch) it rises steeply,
//! and a cubic over the whole range took off about half of it there.
//!
//! A node holds more than the average: the kernel average plus [`LeakLearning::spread`] of the
//! kernel's standard deviations about it. The part of the leak that differs from face to face
//! (and from one visit of a view to the next) is as large as the shared part at the turn's
//! corners, so taking off the average left weights over 0.15 on every held-out face; two
//! standard deviations more take them under it and cost a real expression that much at the
//! view: head-on the table takes off 0.08 on average (0.02 without the spread), 0.32 of
//! `browDownRight`, 0.22–0.26 of `jawForward`, `eyeLookInRight` and the presses (see
//! `docs/performance.md`).
//!
//! [`PoseLeak::remove`] subtracts the table's value at the frame's read angles (clamped to
//! the range it was learned over) and clips to [0, 1]. The angles are the fit's, so the table
//! is learned against the fit's own pose estimate, errors included.

use visage_morphable::binary_reader::Reader;

use crate::arkit::{read_table_header, table_header, ARKIT_BLENDSHAPE_COUNT};

const EMBEDDED: &[u8] = include_bytes!("../data/pose_leak.bin");
const MAGIC: &[u8; 8] = b"VSGLEAK\0";
const VERSION: u32 = 2;
/// The largest leak taken off, either way: a table read past what it learned cannot wipe a
/// weight out.
const MAX_LEAK: f32 = 0.9;
/// The file's values are 16-bit integers in units of 1 / `VALUE_SCALE` (steps of 6e-5 over
/// ±2).
const VALUE_SCALE: f32 = 16384.0;
/// The most nodes along one axis a file may declare.
const MAX_NODES: usize = 1024;
/// `eyeBlinkLeft` and `eyeBlinkRight` in ARKit's order.
const LIDS: [usize; 2] = [0, 7];
/// Frames farther from a node than this many bandwidths do not count for it (their kernel
/// weight is below e⁻⁸).
const KERNEL_REACH: f64 = 4.0;

/// Terms of the prior's polynomial in the head's angles `[yaw, pitch, roll]` (radians):
/// every monomial of degree ≤ 3, by degree (1; y, p, r; y², y·p, y·r, p², p·r, r²; …).
pub const POSE_LEAK_TERMS: usize = 20;

/// The polynomial's terms at `angles`.
pub fn pose_leak_terms(angles: [f64; 3]) -> [f64; POSE_LEAK_TERMS] {
    let mut t = [0.0; POSE_LEAK_TERMS];
    t[0] = 1.0;
    t[1..4].copy_from_slice(&angles);
    let mut i = 4;
    for a in 0..3 {
        for b in a..3 {
            t[i] = angles[a] * angles[b];
            i += 1;
        }
    }
    for a in 0..3 {
        for b in a..3 {
            for c in b..3 {
                t[i] = angles[a] * angles[b] * angles[c];
                i += 1;
            }
        }
    }
    t
}

/// One frame of a rigid turn to learn the table from: the head's read `[yaw, pitch, roll]`
/// (radians) and the 52 weights read, each relative to its median over the same head's turn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeakSample {
    pub angles: [f64; 3],
    pub change: [f32; ARKIT_BLENDSHAPE_COUNT],
}

/// How [`PoseLeak::learn`] turns samples into a table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeakLearning {
    /// The largest yaw, pitch and roll (radians) the grid covers: the range of the turns
    /// rendered.
    pub max_angles: [f64; 3],
    /// The grid's spacing, radians (each axis gets the nearest spacing that divides its range).
    pub spacing: f64,
    /// The kernel's standard deviation in the angles, radians.
    pub bandwidth: f64,
    /// The cubic prior's weight at a node, in frames.
    pub prior_frames: f64,
    /// The ridge added to the cubic's normal equations (the terms are radians, scale ~1).
    pub ridge: f64,
    /// A node holds the kernel average plus this many of the kernel's standard deviations
    /// about it (the prior counted as its frames at the cubic's value): 0 takes off what an
    /// average face leaks at the view, more also what faces that leak more do. The lids'
    /// `eyeBlink*` keep the average (their leak is a share of the range above the weight, and
    /// more of it would open a blink read at a turn).
    pub spread: f64,
}

/// The table: per node of a grid over the head's angles, each ARKit weight's leak.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseLeak {
    max_angles: [f64; 3],
    nodes: [usize; 3],
    /// Node by node (roll fastest, then pitch, then yaw), the 52 weights' leaks.
    values: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]>,
}

impl PoseLeak {
    /// The table shipped with the crate.
    pub fn embedded() -> PoseLeak {
        match PoseLeak::parse(EMBEDDED) {
            Ok(t) => t,
            Err(e) => unreachable!("the embedded pose leak table is checked by a test: {e}"),
        }
    }

    /// Learns the table from `samples` (see the module's docs). `None` when the prior's
    /// normal equations are singular (no samples and no ridge) or the grid is not a grid
    /// (a range or the spacing not positive and finite).
    pub fn learn(samples: &[LeakSample], how: &LeakLearning) -> Option<PoseLeak> {
        let max = how.max_angles;
        if !(how.spacing.is_finite() && how.spacing > 0.0)
            || max.iter().any(|m| !(m.is_finite() && *m > 0.0))
        {
            return None;
        }
        let prior = cubic_fit(samples, how.ridge, max)?;
        let nodes = max.map(|m| ((2.0 * m / how.spacing).ceil() as usize + 1).clamp(2, MAX_NODES));
        let clamped: Vec<[f64; 3]> = samples.iter().map(|s| clamp(s.angles, max)).collect();
        let inv_two_var = 1.0 / (2.0 * how.bandwidth * how.bandwidth);
        let reach2 = (KERNEL_REACH * how.bandwidth).powi(2);
        let mut values = Vec::with_capacity(nodes.iter().product());
        for i in 0..nodes[0] {
            for j in 0..nodes[1] {
                for k in 0..nodes[2] {
                    let at = [i, j, k];
                    let node: [f64; 3] = std::array::from_fn(|a| {
                        -max[a] + 2.0 * max[a] * at[a] as f64 / (nodes[a] - 1) as f64
                    });
                    let t = pose_leak_terms(node);
                    let cubic = prior.map(|c| c.iter().zip(&t).map(|(c, t)| c * t).sum::<f64>());
                    let mut sum = cubic.map(|v| how.prior_frames * v);
                    let mut square = cubic.map(|v| how.prior_frames * v * v);
                    let mut weight = how.prior_frames;
                    for (a, s) in clamped.iter().zip(samples) {
                        let d2: f64 = (0..3).map(|c| (a[c] - node[c]).powi(2)).sum();
                        if d2 > reach2 {
                            continue;
                        }
                        let w = (-d2 * inv_two_var).exp();
                        weight += w;
                        for ((acc, sq), &c) in sum.iter_mut().zip(&mut square).zip(&s.change) {
                            let c = f64::from(c);
                            *acc += w * c;
                            *sq += w * c * c;
                        }
                    }
                    values.push(std::array::from_fn(|w| {
                        if weight <= 0.0 {
                            return 0.0;
                        }
                        let mean = sum[w] / weight;
                        let variance = (square[w] / weight - mean * mean).max(0.0);
                        let spread = if LIDS.contains(&w) { 0.0 } else { how.spread };
                        quantize((mean + spread * variance.sqrt()) as f32)
                    }));
                }
            }
        }
        Some(PoseLeak {
            max_angles: max,
            nodes,
            values,
        })
    }

    /// The largest yaw, pitch and roll (radians) the table was learned over.
    pub fn max_angles(&self) -> [f64; 3] {
        self.max_angles
    }

    /// Each weight's leak at the head's `angles` (radians; clamped to [`Self::max_angles`]),
    /// interpolated trilinearly between the grid's nodes.
    pub fn leak(&self, angles: [f64; 3]) -> [f32; ARKIT_BLENDSHAPE_COUNT] {
        let a = clamp(angles, self.max_angles);
        let mut cell = [0usize; 3];
        let mut frac = [0.0f64; 3];
        for c in 0..3 {
            let n = self.nodes[c];
            let x = (a[c] + self.max_angles[c]) / (2.0 * self.max_angles[c]) * (n - 1) as f64;
            cell[c] = (x.floor() as usize).min(n - 2);
            frac[c] = x - cell[c] as f64;
        }
        let mut out = [0.0f64; ARKIT_BLENDSHAPE_COUNT];
        for corner in 0..8 {
            let mut w = 1.0;
            let mut index = 0;
            for c in 0..3 {
                let up = (corner >> (2 - c)) & 1;
                w *= if up == 1 { frac[c] } else { 1.0 - frac[c] };
                index = index * self.nodes[c] + cell[c] + up;
            }
            if w == 0.0 {
                continue;
            }
            for (o, &v) in out.iter_mut().zip(&self.values[index]) {
                *o += w * f64::from(v);
            }
        }
        out.map(|v| v as f32)
    }

    /// Takes the leak at the head's `angles` off `weights`, each result clipped to [0, 1]. A
    /// leak `l` ≥ 0 is subtracted, `w₀ = w − l`, except from the lids' `eyeBlink*`: they are
    /// measured by the lid's aperture, whose oblique view narrows an open eye but not a closed
    /// one, so their leak is a share of the range left above the weight, `w = w₀ + l·(1 − w₀)`,
    /// `w₀ = (w − l) / (1 − l)` (an eye read closed at a turn stays closed; subtracting lost
    /// blinks on the benchmark). A leak below 0 (the turn lowers the weight) is a share of the
    /// weight, `w = w₀·(1 + l)`, so a weight at 0 stays at 0.
    pub fn remove(&self, angles: [f32; 3], weights: &mut [f32; ARKIT_BLENDSHAPE_COUNT]) {
        let leak = self.leak(angles.map(f64::from));
        for (i, (w, l)) in weights.iter_mut().zip(leak).enumerate() {
            let l = l.clamp(-MAX_LEAK, MAX_LEAK);
            let w0 = if l < 0.0 {
                *w / (1.0 + l)
            } else if LIDS.contains(&i) {
                (*w - l) / (1.0 - l)
            } else {
                *w - l
            };
            *w = w0.clamp(0.0, 1.0);
        }
    }

    /// The file format: magic, version, weight count, the nodes along yaw, pitch and roll, the
    /// three angle limits (f32), then node by node the weights' leaks as 16-bit integers in
    /// units of 1 / 16384 (all little-endian).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = table_header(MAGIC, VERSION);
        for n in self.nodes {
            out.extend_from_slice(&(n as u32).to_le_bytes());
        }
        for v in self.max_angles {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
        for v in self.values.iter().flatten() {
            out.extend_from_slice(&((v * VALUE_SCALE).round() as i16).to_le_bytes());
        }
        out
    }

    /// Parses [`PoseLeak::to_bytes`]' format; the error says what is wrong.
    pub fn parse(bytes: &[u8]) -> Result<PoseLeak, String> {
        let mut r = Reader::new(bytes);
        read_table_header(&mut r, MAGIC, VERSION)?;
        let nodes = [r.u32()?, r.u32()?, r.u32()?].map(|n| n as usize);
        if nodes.iter().any(|n| !(2..=MAX_NODES).contains(n)) {
            return Err(format!(
                "grid of {nodes:?} nodes (2 to {MAX_NODES} per axis)"
            ));
        }
        let max_angles = [r.f32()?, r.f32()?, r.f32()?].map(f64::from);
        if max_angles.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(format!("angle limits {max_angles:?} are not positive"));
        }
        let count: usize = nodes.iter().product();
        let raw = r.take(count * ARKIT_BLENDSHAPE_COUNT * 2)?;
        let values = raw
            .chunks_exact(ARKIT_BLENDSHAPE_COUNT * 2)
            .map(|node| {
                std::array::from_fn(|w| {
                    f32::from(i16::from_le_bytes([node[2 * w], node[2 * w + 1]])) / VALUE_SCALE
                })
            })
            .collect();
        r.finish()?;
        Ok(PoseLeak {
            max_angles,
            nodes,
            values,
        })
    }
}

/// The cubic prior: per weight, the ridge-regression coefficients on [`pose_leak_terms`].
fn cubic_fit(
    samples: &[LeakSample],
    ridge: f64,
    max: [f64; 3],
) -> Option<[[f64; POSE_LEAK_TERMS]; ARKIT_BLENDSHAPE_COUNT]> {
    let mut normal = faer::Mat::<f64>::zeros(POSE_LEAK_TERMS, POSE_LEAK_TERMS);
    let mut rhs = faer::Mat::<f64>::zeros(POSE_LEAK_TERMS, ARKIT_BLENDSHAPE_COUNT);
    for s in samples {
        let t = pose_leak_terms(clamp(s.angles, max));
        for i in 0..POSE_LEAK_TERMS {
            for j in 0..POSE_LEAK_TERMS {
                normal[(i, j)] += t[i] * t[j];
            }
            for (w, &c) in s.change.iter().enumerate() {
                rhs[(i, w)] += t[i] * f64::from(c);
            }
        }
    }
    for i in 0..POSE_LEAK_TERMS {
        normal[(i, i)] += ridge;
    }
    let llt = normal.llt(faer::Side::Lower).ok()?;
    let x = faer::linalg::solvers::Solve::solve(&llt, &rhs);
    Some(std::array::from_fn(|w| std::array::from_fn(|t| x[(t, w)])))
}

/// `v` on the file's 16-bit grid of values (so a learned table and its file are the same).
fn quantize(v: f32) -> f32 {
    (v.clamp(-1.99, 1.99) * VALUE_SCALE).round() / VALUE_SCALE
}

fn clamp(angles: [f64; 3], max: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| angles[i].clamp(-max[i], max[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_table_parses_and_round_trips() {
        let t = PoseLeak::embedded();
        assert_eq!(PoseLeak::parse(&t.to_bytes()), Ok(t.clone()));
        // Learned over a turn of tens of degrees, and small where the face looks ahead (0.08
        // on average there; the largest, browDownRight, 0.32).
        assert!(t.max_angles().iter().all(|&a| a > 0.1 && a < 1.2), "{t:?}");
        let ahead = t.leak([0.0; 3]);
        assert!(ahead.iter().all(|l| l.abs() < 0.35), "{ahead:?}");
        assert!(
            ahead.iter().sum::<f32>() / (ahead.len() as f32) < 0.1,
            "{ahead:?}"
        );
    }

    fn learning(ridge: f64) -> LeakLearning {
        LeakLearning {
            max_angles: [0.6, 0.4, 0.2],
            spacing: 0.1,
            bandwidth: 0.03,
            prior_frames: 1.0,
            ridge,
            spread: 0.0,
        }
    }

    #[test]
    fn a_leak_that_follows_the_pose_is_learned_and_removed() {
        // Weight 3 leaks 0.5·yaw² + 0.2·pitch·roll, weight 7 a constant 0.05; others none.
        let truth = |a: [f64; 3]| {
            let mut c = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
            c[3] = (0.5 * a[0] * a[0] + 0.2 * a[1] * a[2]) as f32;
            c[7] = 0.05;
            c
        };
        let mut samples = Vec::new();
        for i in -15..=15 {
            for j in -10..=10 {
                for k in -5..=5 {
                    let angles = [i as f64 * 0.04, j as f64 * 0.04, k as f64 * 0.04];
                    samples.push(LeakSample {
                        angles,
                        change: truth(angles),
                    });
                }
            }
        }
        let t = PoseLeak::learn(&samples, &learning(1e-9)).unwrap();
        assert_eq!(t.nodes, [13, 9, 5]);
        let a = [0.45, -0.25, 0.15];
        let leak = t.leak(a);
        let expected = truth(a);
        for w in 0..ARKIT_BLENDSHAPE_COUNT {
            assert!((leak[w] - expected[w]).abs() < 5e-3, "{w}: {leak:?}");
        }
        // A shape's leak is subtracted (clipping at 0); outside the learned range the table
        // holds its edge.
        let mut weights = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
        weights[3] = 0.6;
        weights[7] = 0.01;
        let angles = a.map(|v| v as f32);
        t.remove(angles, &mut weights);
        assert!(
            (weights[3] - (0.6 - leak[3])).abs() < 1e-6,
            "{}",
            weights[3]
        );
        assert_eq!(weights[7], 0.0);
        assert_eq!(t.leak([2.0, 0.0, 0.0]), t.leak([0.6, 0.0, 0.0]));
        assert_eq!(
            LIDS.map(|i| crate::ARKIT_BLENDSHAPES[i]),
            ["eyeBlinkLeft", "eyeBlinkRight"]
        );
        // A lid's leak is a share of the range above it: closed stays closed, at the leak
        // opens fully, between is scaled back.
        let lid = |w: f32, l: f32| {
            let mut c = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
            c[LIDS[0]] = l;
            let sample = LeakSample {
                angles: [0.0; 3],
                change: c,
            };
            let one = PoseLeak::learn(&[sample], &learning(1e-12)).unwrap();
            let mut weights = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
            weights[LIDS[0]] = w;
            one.remove([0.0; 3], &mut weights);
            weights[LIDS[0]]
        };
        assert!((lid(1.0, 0.2) - 1.0).abs() < 1e-4);
        assert!(lid(0.2, 0.2).abs() < 1e-4);
        assert!((lid(0.6, 0.2) - 0.5).abs() < 1e-4);
        // A negative leak scales up: 0 stays 0.
        assert!(lid(0.0, -0.2).abs() < 1e-6);
        assert!((lid(0.4, -0.2) - 0.5).abs() < 1e-4);
        // Without samples only the ridge is left: no leak at all.
        let empty = PoseLeak::learn(&[], &learning(1.0)).unwrap();
        assert!(empty.leak(a).iter().all(|&l| l == 0.0));
        // Nor a grid without a spacing.
        let mut no_grid = learning(1.0);
        no_grid.spacing = 0.0;
        assert!(PoseLeak::learn(&samples, &no_grid).is_none());
    }

    /// Samples every 0.02 rad of yaw (±0.6) and pitch (±0.4), no roll: one per change `faces`
    /// gives at the angles.
    fn over_yaw_and_pitch(
        faces: impl Fn([f64; 3]) -> Vec<[f32; ARKIT_BLENDSHAPE_COUNT]>,
    ) -> Vec<LeakSample> {
        let mut samples = Vec::new();
        for i in -30..=30 {
            for j in -20..=20 {
                let angles = [i as f64 * 0.02, j as f64 * 0.02, 0.0];
                samples.extend(
                    faces(angles)
                        .into_iter()
                        .map(|change| LeakSample { angles, change }),
                );
            }
        }
        samples
    }

    #[test]
    fn a_steep_corner_is_kept_where_a_cubic_would_smooth_it() {
        // Weight 16 leaks 0.6 only where yaw < −0.5 and pitch < −0.25 (a turn's corner).
        let samples = over_yaw_and_pitch(|angles| {
            let mut change = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
            if angles[0] < -0.5 && angles[1] < -0.25 {
                change[16] = 0.6;
            }
            vec![change]
        });
        let t = PoseLeak::learn(&samples, &learning(1.0)).unwrap();
        assert!(
            t.leak([-0.58, -0.35, 0.0])[16] > 0.45,
            "{:?}",
            t.leak([-0.58, -0.35, 0.0])
        );
        assert!(t.leak([0.0, 0.0, 0.0])[16].abs() < 0.02);
    }

    #[test]
    fn a_spread_takes_off_what_faces_that_leak_more_do() {
        // At every view half the faces leak 0.2 of weight 5 (and of a lid) and half none: the
        // average face leaks 0.1, one standard deviation above it 0.2.
        let samples = over_yaw_and_pitch(|_| {
            (0..2)
                .map(|face| {
                    let mut change = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
                    change[5] = 0.2 * face as f32;
                    change[LIDS[0]] = 0.2 * face as f32;
                    change
                })
                .collect()
        });
        let mut how = learning(1.0);
        let average = PoseLeak::learn(&samples, &how).unwrap();
        how.spread = 1.0;
        let above = PoseLeak::learn(&samples, &how).unwrap();
        let a = [0.1, -0.1, 0.0];
        assert!(
            (average.leak(a)[5] - 0.1).abs() < 2e-3,
            "{:?}",
            average.leak(a)
        );
        assert!((above.leak(a)[5] - 0.2).abs() < 2e-3, "{:?}", above.leak(a));
        // A weight that no face leaks keeps no spread; a lid keeps the average.
        assert!(above.leak(a)[6].abs() < 1e-4);
        assert!((above.leak(a)[LIDS[0]] - 0.1).abs() < 2e-3);
    }

    #[test]
    fn a_damaged_file_is_refused_with_the_reason() {
        let bytes = PoseLeak::embedded().to_bytes();
        assert!(PoseLeak::parse(&bytes[..bytes.len() - 2])
            .unwrap_err()
            .contains("truncated"));
        let mut bad = bytes.clone();
        bad[0] = b'X';
        assert_eq!(PoseLeak::parse(&bad).unwrap_err(), "bad magic");
    }
}
