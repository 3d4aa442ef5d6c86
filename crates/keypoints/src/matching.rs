//! Brute-force descriptor matching with Lowe's ratio test (Lowe, IJCV 2004, §7.1) and a mutual
//! (cross) check, as OpenCV's `BFMatcher` with `NORM_L2` and `knnMatch(k = 2)` followed by the
//! usual `m.distance < ratio · n.distance` filter.
//!
//! Every query descriptor is compared with every train descriptor (O(#query · #train · 128)).
//! Squared distances are exact integers, computed as `‖q‖² + ‖t‖² − 2 q·t` with the bytes
//! widened to `i16` once, so that the inner product auto-vectorises to multiply-adds of pairs
//! of 16-bit lanes (`pmaddwd` on x86-64 without any target feature).

use serde::{Deserialize, Serialize};

use crate::{Descriptor, DESCRIPTOR_LEN};

/// Lowe's ratio: 0.8 rejected 90 % of the false matches and under 5 % of the correct ones in
/// his experiments (Lowe 2004, §7.1).
const DEFAULT_RATIO: f32 = 0.8;

/// Descriptors are compared in blocks of this many `i16` lanes: 16 lanes of `i32` partial sums
/// are what the auto-vectoriser turns into multiply-adds with independent accumulators (8 and
/// 32 lanes measured slower or equal, and tiling several descriptors at once defeated it).
const LANES: usize = 16;

/// How to match descriptors ([`match_descriptors`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MatchOptions {
    /// Lowe's ratio: a query is matched to its nearest train descriptor only if the nearest
    /// distance `d₁` and the second-nearest `d₂` satisfy `d₁ < ratio · d₂` (Lowe 2004, §7.1;
    /// default 0.8). Values in `(0, 1]` are meaningful; `ratio ≤ 0` (or NaN) rejects every
    /// match, `ratio > 1` accepts every nearest neighbour with `d₂ > 0` that beats it.
    pub ratio: f32,
    /// Also require that the query is the nearest of all queries to its matched train
    /// descriptor (OpenCV's `crossCheck`; default true). On equal distances the lowest query
    /// index counts as the nearest.
    pub mutual: bool,
}

impl Default for MatchOptions {
    /// Ratio 0.8, mutual check on.
    fn default() -> Self {
        MatchOptions {
            ratio: DEFAULT_RATIO,
            mutual: true,
        }
    }
}

/// A query descriptor paired with a train descriptor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Match {
    /// Index into the query descriptors.
    pub query: usize,
    /// Index into the train descriptors.
    pub train: usize,
    /// Euclidean (L2) distance between the two descriptors, taken as 128-vectors of byte values
    /// (0–255 each), as OpenCV's `NORM_L2` on `CV_8U` descriptors reports it.
    pub distance: f32,
}

/// A descriptor's bytes widened to `i16`, ready for [`dot`].
type Widened = [i16; DESCRIPTOR_LEN];

/// The nearest and second-nearest train descriptors of one query, squared distances.
#[derive(Clone, Copy)]
struct Neighbours {
    nearest: usize,
    nearest_sq: u32,
    second_sq: u32,
}

/// Matches each `query` descriptor to its nearest `train` descriptor, keeping the pairs that
/// pass Lowe's ratio test (Lowe 2004, §7.1) and, with [`MatchOptions::mutual`], the mutual
/// check; the result is sorted by [`Match::query`], at most one match per query.
///
/// Distances are Euclidean over the 128 byte values (OpenCV's `NORM_L2`), computed exactly in
/// integers; equal distances resolve to the lower index. The ratio test needs a second
/// neighbour, so with fewer than two train descriptors nothing is matched. A query with two
/// or more train descriptors at its nearest distance (a duplicate) fails the ratio test.
pub fn match_descriptors(
    query: &[Descriptor],
    train: &[Descriptor],
    options: &MatchOptions,
) -> Vec<Match> {
    if query.is_empty() || train.len() < 2 {
        return Vec::new();
    }
    let train_wide: Vec<Widened> = train.iter().map(widen).collect();
    let train_norms: Vec<u32> = train.iter().map(squared_norm).collect();

    // Per train descriptor: the nearest query so far, as (squared distance, query index).
    let mut train_nearest = vec![(u32::MAX, usize::MAX); train.len()];
    let mut neighbours = Vec::with_capacity(query.len());
    let mut dots = vec![0u32; train.len()];
    for (qi, q) in query.iter().enumerate() {
        let q_wide = widen(q);
        let q_norm = squared_norm(q);
        for (d, t) in dots.iter_mut().zip(&train_wide) {
            *d = dot(&q_wide, t);
        }
        let mut best = Neighbours {
            nearest: 0,
            nearest_sq: u32::MAX,
            second_sq: u32::MAX,
        };
        for (ti, ((&qt, &t_norm), nearest_query)) in dots
            .iter()
            .zip(&train_norms)
            .zip(&mut train_nearest)
            .enumerate()
        {
            // Exact: ‖q − t‖² = ‖q‖² + ‖t‖² − 2 q·t ≤ 128 · 255² fits comfortably in u32, and
            // 2 q·t ≤ ‖q‖² + ‖t‖² so the subtraction cannot wrap.
            let sq = q_norm + t_norm - 2 * qt;
            if sq < best.nearest_sq {
                best.second_sq = best.nearest_sq;
                best.nearest_sq = sq;
                best.nearest = ti;
            } else if sq < best.second_sq {
                best.second_sq = sq;
            }
            if sq < nearest_query.0 {
                *nearest_query = (sq, qi);
            }
        }
        neighbours.push(best);
    }

    neighbours
        .iter()
        .enumerate()
        .filter_map(|(qi, n)| {
            // Distances as OpenCV reports them: the f32 square root of the exact squared
            // distance (< 2²⁴, so the conversion is exact).
            let distance = (n.nearest_sq as f32).sqrt();
            let second = (n.second_sq as f32).sqrt();
            let passes_ratio = distance < options.ratio * second;
            let is_mutual = !options.mutual || train_nearest[n.nearest].1 == qi;
            (passes_ratio && is_mutual).then_some(Match {
                query: qi,
                train: n.nearest,
                distance,
            })
        })
        .collect()
}

/// The bytes of `d` as `i16`.
fn widen(d: &Descriptor) -> Widened {
    d.map(i16::from)
}

/// `‖d‖²` over the byte values.
fn squared_norm(d: &Descriptor) -> u32 {
    d.iter().map(|&v| u32::from(v) * u32::from(v)).sum()
}

/// `a · b` of two widened descriptors, exact (each product ≤ 255², the sum ≤ 128 · 255²).
///
/// Written as [`LANES`] independent `i32` partial sums of `i16 × i16` products so that it
/// auto-vectorises to pairwise multiply-adds.
#[inline(always)]
fn dot(a: &Widened, b: &Widened) -> u32 {
    let mut acc = [0i32; LANES];
    for (ca, cb) in a.chunks_exact(LANES).zip(b.chunks_exact(LANES)) {
        for ((s, &x), &y) in acc.iter_mut().zip(ca).zip(cb) {
            *s += i32::from(x) * i32::from(y);
        }
    }
    // Every product is non-negative (the lanes hold bytes), so the sum is too.
    acc.iter().sum::<i32>().unsigned_abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::seq::SliceRandom;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_descriptors(rng: &mut ChaCha8Rng, n: usize) -> Vec<Descriptor> {
        (0..n)
            .map(|_| std::array::from_fn(|_| rng.random()))
            .collect()
    }

    /// `d` with each byte moved by up to ±`amplitude`, saturating.
    fn perturbed(rng: &mut ChaCha8Rng, d: &Descriptor, amplitude: i16) -> Descriptor {
        d.map(|v| {
            let moved = i16::from(v) + rng.random_range(-amplitude..=amplitude);
            u8::try_from(moved.clamp(0, 255)).unwrap_or(0)
        })
    }

    fn naive_distance(a: &Descriptor, b: &Descriptor) -> f64 {
        a.iter()
            .zip(b)
            .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// The matcher written the obvious way, in f64.
    fn naive_matches(
        query: &[Descriptor],
        train: &[Descriptor],
        options: &MatchOptions,
    ) -> Vec<(usize, usize)> {
        let nearest = |d: &Descriptor, set: &[Descriptor]| -> (usize, f64, f64) {
            let mut dist: Vec<(f64, usize)> = set
                .iter()
                .enumerate()
                .map(|(i, s)| (naive_distance(d, s), i))
                .collect();
            dist.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            (dist[0].1, dist[0].0, dist.get(1).map_or(f64::NAN, |s| s.0))
        };
        query
            .iter()
            .enumerate()
            .filter_map(|(qi, q)| {
                let (ti, d1, d2) = nearest(q, train);
                let ratio_ok = d1 < f64::from(options.ratio) * d2;
                let mutual_ok = !options.mutual || nearest(&train[ti], query).0 == qi;
                (ratio_ok && mutual_ok).then_some((qi, ti))
            })
            .collect()
    }

    #[test]
    fn identical_sets_match_one_to_one() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let set = random_descriptors(&mut rng, 60);
        let matches = match_descriptors(&set, &set, &MatchOptions::default());
        assert_eq!(matches.len(), set.len());
        for (i, m) in matches.iter().enumerate() {
            assert_eq!((m.query, m.train), (i, i));
            assert_eq!(m.distance, 0.0);
        }
    }

    #[test]
    fn perturbed_copy_matches_the_right_indices() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let query = random_descriptors(&mut rng, 200);
        let mut permutation: Vec<usize> = (0..query.len()).collect();
        permutation.shuffle(&mut rng);
        let mut train = vec![[0u8; DESCRIPTOR_LEN]; query.len()];
        for (qi, &ti) in permutation.iter().enumerate() {
            train[ti] = perturbed(&mut rng, &query[qi], 12);
        }
        let matches = match_descriptors(&query, &train, &MatchOptions::default());
        assert_eq!(matches.len(), query.len());
        for m in &matches {
            assert_eq!(m.train, permutation[m.query]);
            let expected = naive_distance(&query[m.query], &train[m.train]);
            assert!((f64::from(m.distance) - expected).abs() < 1e-3 * expected.max(1.0));
            assert!(m.distance > 0.0);
        }
    }

    #[test]
    fn ambiguous_duplicates_are_rejected_by_the_ratio_test() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut train = random_descriptors(&mut rng, 20);
        train[7] = train[3];
        let query = vec![train[3], train[5]];
        let matches = match_descriptors(&query, &train, &MatchOptions::default());
        // train[3] has an exact twin (d₁ = d₂ = 0): ambiguous; train[5] is unique.
        assert_eq!(matches.len(), 1);
        assert_eq!((matches[0].query, matches[0].train), (1, 5));
    }

    #[test]
    fn ratio_threshold_separates_near_ties() {
        // Nearest at distance 9 (one byte off by 9), second at 10: ratio 0.9.
        let base = [100u8; DESCRIPTOR_LEN];
        let mut near = base;
        near[0] = 109;
        let mut second = base;
        second[1] = 110;
        let train = vec![near, second];
        let query = vec![base];
        let strict = match_descriptors(&query, &train, &MatchOptions::default());
        assert!(strict.is_empty());
        let loose = MatchOptions {
            ratio: 0.95,
            ..MatchOptions::default()
        };
        let matches = match_descriptors(&query, &train, &loose);
        assert_eq!(matches.len(), 1);
        assert_eq!(matches[0].train, 0);
        assert_eq!(matches[0].distance, 9.0);
    }

    #[test]
    fn mutual_check_removes_a_many_to_one_match() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let train = random_descriptors(&mut rng, 10);
        // Both queries are nearest to train[2]; query 1 is closer to it.
        let query = vec![
            perturbed(&mut rng, &train[2], 20),
            perturbed(&mut rng, &train[2], 4),
        ];
        let one_way = MatchOptions {
            mutual: false,
            ..MatchOptions::default()
        };
        let matches = match_descriptors(&query, &train, &one_way);
        assert_eq!(
            matches
                .iter()
                .map(|m| (m.query, m.train))
                .collect::<Vec<_>>(),
            vec![(0, 2), (1, 2)]
        );
        let matches = match_descriptors(&query, &train, &MatchOptions::default());
        assert_eq!(
            matches
                .iter()
                .map(|m| (m.query, m.train))
                .collect::<Vec<_>>(),
            vec![(1, 2)]
        );
    }

    #[test]
    fn empty_inputs_give_empty_output() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let set = random_descriptors(&mut rng, 5);
        let options = MatchOptions::default();
        assert!(match_descriptors(&[], &set, &options).is_empty());
        assert!(match_descriptors(&set, &[], &options).is_empty());
        assert!(match_descriptors(&[], &[], &options).is_empty());
    }

    #[test]
    fn a_single_train_descriptor_matches_nothing() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let set = random_descriptors(&mut rng, 3);
        assert!(match_descriptors(&set, &set[..1], &MatchOptions::default()).is_empty());
    }

    #[test]
    fn agrees_with_a_naive_matcher() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        // Half the queries have a perturbed twin in train, of varying closeness; the rest are
        // unrelated, so the ratio test and the mutual check both have work to do.
        let train = random_descriptors(&mut rng, 150);
        let mut query = random_descriptors(&mut rng, 60);
        for (i, t) in train.iter().take(60).enumerate() {
            let amplitude = i16::try_from(10 + 4 * i).unwrap_or(i16::MAX);
            query.push(perturbed(&mut rng, t, amplitude));
        }
        query.push(query[65]);
        for options in [
            MatchOptions::default(),
            MatchOptions {
                mutual: false,
                ..MatchOptions::default()
            },
            MatchOptions {
                ratio: 0.95,
                mutual: false,
            },
        ] {
            let got: Vec<(usize, usize)> = match_descriptors(&query, &train, &options)
                .iter()
                .map(|m| (m.query, m.train))
                .collect();
            let expected = naive_matches(&query, &train, &options);
            assert_eq!(got, expected, "{options:?}");
            assert!(!got.is_empty() && got.len() < query.len(), "{options:?}");
        }
    }

    /// 1000 × 1000 descriptors, each query with a perturbed twin; prints the time taken (run
    /// with `--release -- --nocapture` for a meaningful number).
    #[test]
    fn thousand_by_thousand_all_twins_found() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let query = random_descriptors(&mut rng, 1000);
        let mut permutation: Vec<usize> = (0..query.len()).collect();
        permutation.shuffle(&mut rng);
        let mut train = vec![[0u8; DESCRIPTOR_LEN]; query.len()];
        for (qi, &ti) in permutation.iter().enumerate() {
            train[ti] = perturbed(&mut rng, &query[qi], 20);
        }
        let start = std::time::Instant::now();
        let matches = match_descriptors(&query, &train, &MatchOptions::default());
        let elapsed = start.elapsed();
        println!("match_descriptors 1000 × 1000: {elapsed:?}");
        assert_eq!(matches.len(), query.len());
        assert!(matches.iter().all(|m| m.train == permutation[m.query]));
    }
}
