//! What the mouth's shapes alone add to the upper face's weights, and its removal.
//!
//! MediaPipe's landmark network moves landmarks that the mouth's motion leaves still on a real
//! face model: rendered ICT-FaceKit heads that only talk (the upper face's ARKit curves held at
//! 0) read `noseSneer`, `browDown` and `cheekSquint` that rise and fall with the mouth's
//! shapes, because the network's nose, brow and cheek landmarks move with the jaw and lips.
//! The fit's region-local evidence keeps the lips' landmarks out of the upper face's shapes,
//! but not the nose's and cheeks' own motion. On real speech that makes the sneer follow the
//! lip gap.
//!
//! The table holds, per weight of the upper face ([`is_upper_face`]: the brows, the eyes'
//! squint and wide, the cheeks' squint, the sneer), a non-negative coefficient on each of the
//! mouth's and jaw's weights ([`is_mouth`]), learned by least squares with a free constant
//! from renders of several identities talking through a performance's mouth under the
//! benchmark's head motion (`visage-eval`'s `mouth_leak_table` example regenerates the file),
//! the weights read with the pose leak already taken off. [`MouthLeak::remove`] subtracts the
//! mouth's weights times their coefficients, clipped to [0, 1]. Nothing else is touched: the
//! mouth's own weights, the lids' blinks (the eye network's), the gaze.
//!
//! Like the pose leak, nothing in it comes from what a performer does: the renders play no
//! upper-face shape at all, so what the table learns is the network's own cross-talk, and a
//! real sneer or squint made while talking keeps what is above it.

use faer::Mat;
use visage_morphable::binary_reader::Reader;
use visage_morphable::fit::bounded_least_squares::BoxQp;

use crate::arkit::{read_table_header, table_header, ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT};

const EMBEDDED: &[u8] = include_bytes!("../data/mouth_leak.bin");
const MAGIC: &[u8; 8] = b"VSGMLEAK";
const VERSION: u32 = 1;
/// The largest coefficient learned: a mouth's weight cannot take off more than itself.
const MAX_COEFFICIENT: f64 = 1.0;

/// Whether ARKit weight `index` is one of the upper face's that the table corrects: the brows,
/// `eyeSquint*`, `eyeWide*`, `cheekSquint*` and `noseSneer*`.
pub fn is_upper_face(index: usize) -> bool {
    ARKIT_BLENDSHAPES.get(index).is_some_and(|n| {
        ["brow", "eyeSquint", "eyeWide", "cheekSquint", "noseSneer"]
            .iter()
            .any(|p| n.starts_with(p))
    })
}

/// Whether ARKit weight `index` is one of the mouth's or jaw's (`jaw*`, `mouth*`, `cheekPuff`;
/// not `tongueOut`, which the fit does not read).
pub fn is_mouth(index: usize) -> bool {
    ARKIT_BLENDSHAPES
        .get(index)
        .is_some_and(|n| n.starts_with("jaw") || n.starts_with("mouth") || *n == "cheekPuff")
}

/// The table: per weight, its coefficients on the 52 weights (non-zero only for an upper-face
/// weight on a mouth weight).
#[derive(Clone, Debug, PartialEq)]
pub struct MouthLeak {
    coefficients: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]>,
}

impl MouthLeak {
    /// The table shipped with the crate.
    pub fn embedded() -> MouthLeak {
        match MouthLeak::parse(EMBEDDED) {
            Ok(t) => t,
            Err(e) => unreachable!("the embedded mouth leak table is checked by a test: {e}"),
        }
    }

    /// Learns the table from frames read where no upper-face shape was played: per upper-face
    /// weight, `min ‖(y − ȳ) − (X − X̄) c‖² + ridge · n · ‖c‖²` over `0 ≤ c ≤ 1`, `X` the mouth's
    /// weights and `y` the upper-face weight over the `n` frames (centring frees the constant:
    /// a standing offset is the rest pose's or the pose leak's, not the mouth's). `None`
    /// without frames.
    pub fn learn(read: &[[f32; ARKIT_BLENDSHAPE_COUNT]], ridge: f64) -> Option<MouthLeak> {
        if read.is_empty() {
            return None;
        }
        let n = read.len() as f64;
        let sources: Vec<usize> = (0..ARKIT_BLENDSHAPE_COUNT)
            .filter(|&i| is_mouth(i))
            .collect();
        let mean: [f64; ARKIT_BLENDSHAPE_COUNT] =
            std::array::from_fn(|w| read.iter().map(|r| f64::from(r[w])).sum::<f64>() / n);
        let centred = |r: &[f32; ARKIT_BLENDSHAPE_COUNT], w: usize| f64::from(r[w]) - mean[w];
        let m = sources.len();
        let mut normal = Mat::<f64>::zeros(m, m);
        for r in read {
            for (a, &i) in sources.iter().enumerate() {
                let xi = centred(r, i);
                for (b, &j) in sources.iter().enumerate() {
                    normal[(a, b)] += xi * centred(r, j);
                }
            }
        }
        for a in 0..m {
            normal[(a, a)] += ridge * n;
        }
        let mut coefficients = vec![[0.0f32; ARKIT_BLENDSHAPE_COUNT]; ARKIT_BLENDSHAPE_COUNT];
        for (u, row) in coefficients.iter_mut().enumerate() {
            if !is_upper_face(u) {
                continue;
            }
            let rhs: Vec<f64> = sources
                .iter()
                .map(|&i| read.iter().map(|r| centred(r, i) * centred(r, u)).sum())
                .collect();
            let mut c = vec![0.0; m];
            BoxQp::new(m).solve(normal.as_ref(), &rhs, 0.0, MAX_COEFFICIENT, &mut c);
            for (&i, &v) in sources.iter().zip(&c) {
                row[i] = v as f32;
            }
        }
        Some(MouthLeak { coefficients })
    }

    /// The coefficient of mouth weight `source` in upper-face weight `target` (ARKit indices).
    pub fn coefficient(&self, target: usize, source: usize) -> f32 {
        self.coefficients[target][source]
    }

    /// Takes the mouth's leak off the upper face's weights: `w_u − Σ c_um w_m` (the mouth's
    /// weights as given), clipped to [0, 1].
    pub fn remove(&self, weights: &mut [f32; ARKIT_BLENDSHAPE_COUNT]) {
        let read = *weights;
        for (w, row) in weights.iter_mut().zip(&self.coefficients) {
            let leak: f32 = row.iter().zip(&read).map(|(c, m)| c * m).sum();
            if leak != 0.0 {
                *w = (*w - leak).clamp(0.0, 1.0);
            }
        }
    }

    /// The file format: magic, version, weight count, then per weight its coefficients on
    /// every weight as f32 (all little-endian).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = table_header(MAGIC, VERSION);
        for v in self.coefficients.iter().flatten() {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// Parses [`MouthLeak::to_bytes`]' format; the error says what is wrong. A coefficient
    /// outside [0, 1], or anywhere but an upper-face weight's row and a mouth weight's column,
    /// is refused.
    pub fn parse(bytes: &[u8]) -> Result<MouthLeak, String> {
        let mut r = Reader::new(bytes);
        read_table_header(&mut r, MAGIC, VERSION)?;
        let mut coefficients = vec![[0.0f32; ARKIT_BLENDSHAPE_COUNT]; ARKIT_BLENDSHAPE_COUNT];
        for (u, row) in coefficients.iter_mut().enumerate() {
            for (m, c) in row.iter_mut().enumerate() {
                *c = r.f32()?;
                let allowed = is_upper_face(u) && is_mouth(m);
                if !(0.0..=MAX_COEFFICIENT as f32).contains(c) || (!allowed && *c != 0.0) {
                    return Err(format!(
                        "coefficient {c} of {} on {}",
                        ARKIT_BLENDSHAPES[m], ARKIT_BLENDSHAPES[u]
                    ));
                }
            }
        }
        r.finish()?;
        Ok(MouthLeak { coefficients })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn index(name: &str) -> usize {
        ARKIT_BLENDSHAPES.iter().position(|n| *n == name).unwrap()
    }

    #[test]
    fn the_embedded_table_parses_and_round_trips() {
        let t = MouthLeak::embedded();
        assert_eq!(MouthLeak::parse(&t.to_bytes()).unwrap(), t);
        assert!(MouthLeak::parse(&t.to_bytes()[..100]).is_err());
        let mut bad = t.to_bytes();
        // The first coefficient: eyeBlinkLeft on itself, which the table never corrects.
        bad[16..20].copy_from_slice(&0.5f32.to_le_bytes());
        assert!(MouthLeak::parse(&bad).unwrap_err().contains("eyeBlinkLeft"));
    }

    #[test]
    fn a_leak_that_follows_the_jaw_is_learned_and_removed() {
        let (jaw, funnel, sneer, blink) = (
            index("jawOpen"),
            index("mouthFunnel"),
            index("noseSneerLeft"),
            index("eyeBlinkLeft"),
        );
        // The sneer reads 0.3 of the jaw plus a standing 0.05; the funnel moves on its own,
        // and the blink follows the jaw too (the lids are not the table's).
        let read: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]> = (0..400)
            .map(|i| {
                let t = i as f32 * 0.05;
                let mut w = [0.0; ARKIT_BLENDSHAPE_COUNT];
                w[jaw] = 0.5 + 0.5 * t.sin();
                w[funnel] = 0.5 + 0.5 * (1.7 * t).cos();
                w[sneer] = 0.05 + 0.3 * w[jaw];
                w[blink] = 0.2 * w[jaw];
                w
            })
            .collect();
        let t = MouthLeak::learn(&read, 1e-6).unwrap();
        assert!((t.coefficient(sneer, jaw) - 0.3).abs() < 0.01);
        assert!(t.coefficient(sneer, funnel).abs() < 0.01);
        assert_eq!(t.coefficient(blink, jaw), 0.0);
        let mut w = read[10];
        t.remove(&mut w);
        assert!((w[sneer] - 0.05).abs() < 0.01, "{}", w[sneer]);
        assert_eq!((w[jaw], w[blink]), (read[10][jaw], read[10][blink]));
        // A sneer made on top keeps what is above the leak.
        let mut w = read[10];
        w[sneer] += 0.4;
        t.remove(&mut w);
        assert!((w[sneer] - 0.45).abs() < 0.01, "{}", w[sneer]);
    }

    #[test]
    fn a_mouth_that_lowers_an_upper_weight_is_not_added_back() {
        let (jaw, brow) = (index("jawOpen"), index("browDownLeft"));
        let read: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]> = (0..100)
            .map(|i| {
                let mut w = [0.0; ARKIT_BLENDSHAPE_COUNT];
                w[jaw] = (i % 10) as f32 / 10.0;
                w[brow] = 0.5 - 0.2 * w[jaw];
                w
            })
            .collect();
        let t = MouthLeak::learn(&read, 1e-6).unwrap();
        assert_eq!(t.coefficient(brow, jaw), 0.0);
        assert!(MouthLeak::learn(&[], 1e-6).is_none());
    }

    #[test]
    fn the_groups_are_the_upper_face_and_the_mouth() {
        let upper: Vec<&str> = (0..ARKIT_BLENDSHAPE_COUNT)
            .filter(|&i| is_upper_face(i))
            .map(|i| ARKIT_BLENDSHAPES[i])
            .collect();
        assert_eq!(upper.len(), 13, "{upper:?}");
        assert!(!upper
            .iter()
            .any(|n| n.starts_with("eyeBlink") || n.starts_with("eyeLook")));
        let mouth = (0..ARKIT_BLENDSHAPE_COUNT).filter(|&i| is_mouth(i)).count();
        assert_eq!(mouth, 28);
        assert!(!(0..ARKIT_BLENDSHAPE_COUNT).any(|i| is_upper_face(i) && is_mouth(i)));
    }
}
