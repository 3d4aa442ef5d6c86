//! What the head's turn alone adds to each weight, and its removal.
//!
//! A neutral face turned away from the camera still reads some expression: the landmark
//! network's view-dependent bias that the fit's view correction leaves, the fitted identity's
//! small errors in depth, and the fit explaining a pose error by a shape (a head rolled a few
//! degrees too far reads as a jaw pushed sideways). On renders of neutral heads whose pose is
//! known, that leak is largely the same for every face at the same pose. The table holds, per
//! ARKit weight, a cubic polynomial in the head's read yaw, pitch and roll (Live Link Face's
//! angles, radians): the weight's mean change at that pose relative to the same head's median
//! over its turn, learned by ridge regression from rigid renders of several identities
//! (`visage-eval`'s `pose_leak_table` example regenerates the file). Nothing in it comes from an
//! expression: it does not learn which shapes a performer moves together, so a shape keeps its
//! own reading and is never inferred from another one.
//!
//! [`PoseLeak::remove`] subtracts the table's value at the frame's read angles (clamped to
//! the range it was learned over) and clips to [0, 1]. The angles are the fit's, so the table
//! is learned against the fit's own pose estimate, errors included.

use visage_morphable::binary_reader::Reader;

use crate::arkit::ARKIT_BLENDSHAPE_COUNT;

const EMBEDDED: &[u8] = include_bytes!("../data/pose_leak.bin");
const MAGIC: &[u8; 8] = b"VSGLEAK\0";
const VERSION: u32 = 1;
/// The largest leak taken off, either way: a table read past what it learned cannot wipe a
/// weight out.
const MAX_LEAK: f32 = 0.9;
/// `eyeBlinkLeft` and `eyeBlinkRight` in ARKit's order.
const LIDS: [usize; 2] = [0, 7];

/// Terms of the polynomial in the head's angles `[yaw, pitch, roll]` (radians): every
/// monomial of degree ≤ 3, by degree (1; y, p, r; y², y·p, y·r, p², p·r, r²; …).
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

/// The table: per ARKit weight, the coefficients of its leak on [`pose_leak_terms`], and the
/// largest yaw, pitch and roll (radians) it was learned over.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseLeak {
    coefficients: [[f32; POSE_LEAK_TERMS]; ARKIT_BLENDSHAPE_COUNT],
    max_angles: [f64; 3],
}

impl PoseLeak {
    /// The table shipped with the crate.
    pub fn embedded() -> PoseLeak {
        match PoseLeak::parse(EMBEDDED) {
            Ok(t) => t,
            Err(e) => unreachable!("the embedded pose leak table is checked by a test: {e}"),
        }
    }

    /// Learns the table from `samples` by ridge regression (`ridge` times the identity added
    /// to the normal equations; the terms are radians, so their scale is ~1), the same for
    /// every weight; `max_angles` is the range of the turns rendered. `None` when the normal
    /// equations are singular (no samples and no ridge).
    pub fn learn(samples: &[LeakSample], ridge: f64, max_angles: [f64; 3]) -> Option<PoseLeak> {
        let mut normal = faer::Mat::<f64>::zeros(POSE_LEAK_TERMS, POSE_LEAK_TERMS);
        let mut rhs = faer::Mat::<f64>::zeros(POSE_LEAK_TERMS, ARKIT_BLENDSHAPE_COUNT);
        for s in samples {
            let t = pose_leak_terms(clamp(s.angles, max_angles));
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
        Some(PoseLeak {
            coefficients: std::array::from_fn(|w| std::array::from_fn(|t| x[(t, w)] as f32)),
            max_angles,
        })
    }

    /// The largest yaw, pitch and roll (radians) the table was learned over.
    pub fn max_angles(&self) -> [f64; 3] {
        self.max_angles
    }

    /// Each weight's leak at the head's `angles` (radians; clamped to [`Self::max_angles`]).
    pub fn leak(&self, angles: [f64; 3]) -> [f32; ARKIT_BLENDSHAPE_COUNT] {
        let t = pose_leak_terms(clamp(angles, self.max_angles));
        self.coefficients.map(|c| {
            c.iter()
                .zip(&t)
                .map(|(&c, t)| f64::from(c) * t)
                .sum::<f64>() as f32
        })
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

    /// The file format: magic, version, weight count, term count, the three angle limits and
    /// the coefficients (little-endian f32, weight by weight in ARKit's order).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(32 + ARKIT_BLENDSHAPE_COUNT * 4 * POSE_LEAK_TERMS);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(ARKIT_BLENDSHAPE_COUNT as u32).to_le_bytes());
        out.extend_from_slice(&(POSE_LEAK_TERMS as u32).to_le_bytes());
        for v in self.max_angles {
            out.extend_from_slice(&(v as f32).to_le_bytes());
        }
        for c in self.coefficients.iter().flatten() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out
    }

    /// Parses [`PoseLeak::to_bytes`]' format; the error says what is wrong.
    pub fn parse(bytes: &[u8]) -> Result<PoseLeak, String> {
        let mut r = Reader::new(bytes);
        r.header(MAGIC, VERSION)?;
        let weights = r.u32()? as usize;
        let terms = r.u32()? as usize;
        if weights != ARKIT_BLENDSHAPE_COUNT || terms != POSE_LEAK_TERMS {
            return Err(format!(
                "{weights} weights × {terms} terms, expected {ARKIT_BLENDSHAPE_COUNT} × \
                 {POSE_LEAK_TERMS}"
            ));
        }
        let max_angles = [r.f32()?, r.f32()?, r.f32()?].map(f64::from);
        if max_angles.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(format!("angle limits {max_angles:?} are not positive"));
        }
        let mut coefficients = [[0.0; POSE_LEAK_TERMS]; ARKIT_BLENDSHAPE_COUNT];
        for v in coefficients.iter_mut().flatten() {
            *v = r.f32()?;
            if !v.is_finite() {
                return Err("a coefficient is not finite".into());
            }
        }
        r.finish()?;
        Ok(PoseLeak {
            coefficients,
            max_angles,
        })
    }
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
        // Learned over a turn of tens of degrees, and small where the face looks ahead.
        assert!(t.max_angles().iter().all(|&a| a > 0.1 && a < 1.2), "{t:?}");
        assert!(t.leak([0.0; 3]).iter().all(|l| l.abs() < 0.1), "{t:?}");
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
        for i in -6..=6 {
            for j in -4..=4 {
                for k in -2..=2 {
                    let angles = [i as f64 * 0.1, j as f64 * 0.1, k as f64 * 0.1];
                    samples.push(LeakSample {
                        angles,
                        change: truth(angles),
                    });
                }
            }
        }
        let max = [0.6, 0.4, 0.2];
        let t = PoseLeak::learn(&samples, 1e-9, max).unwrap();
        let a = [0.45, -0.25, 0.15];
        let leak = t.leak(a);
        let expected = truth(a);
        for w in 0..ARKIT_BLENDSHAPE_COUNT {
            assert!((leak[w] - expected[w]).abs() < 1e-4, "{w}: {leak:?}");
        }
        // A shape's leak is subtracted (clipping at 0); outside the learned range the table
        // holds its edge.
        let mut weights = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
        weights[3] = 0.6;
        weights[7] = 0.01;
        let angles = a.map(|v| v as f32);
        t.remove(angles, &mut weights);
        assert!(
            (weights[3] - (0.6 - expected[3])).abs() < 1e-4,
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
            let one = PoseLeak::learn(
                &[LeakSample {
                    angles: [0.0; 3],
                    change: c,
                }],
                1e-12,
                max,
            )
            .unwrap();
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
        let empty = PoseLeak::learn(&[], 1.0, max).unwrap();
        assert!(empty.leak(a).iter().all(|&l| l == 0.0));
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
