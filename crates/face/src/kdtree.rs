//! A static 3-D k-d tree for nearest-neighbour queries, e.g. from FaceMesh landmarks to the
//! vertices of a reconstructed mesh (and back) in the later stages.
//!
//! Built once in `O(n log² n)` by median splits on the widest axis, stored as an implicit
//! balanced tree over a permutation of the points; queries are exact (branch-and-bound on the
//! squared distance to the splitting plane). Hand-written (≈100 lines) instead of `kiddo` to keep
//! the dependency tree small; the test checks it against brute force.

/// Points and the tree over them.
#[derive(Clone, Debug)]
pub struct KdTree {
    points: Vec<[f64; 3]>,
    /// Point indices in tree order: node `[lo, hi)` has its splitting point at `(lo + hi) / 2`.
    order: Vec<u32>,
    /// Split axis per tree position.
    axis: Vec<u8>,
}

impl KdTree {
    /// Builds the tree. Non-finite points are kept but never returned as nearest.
    pub fn new(points: Vec<[f64; 3]>) -> KdTree {
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        let mut axis = vec![0u8; points.len()];
        build(&points, &mut order, &mut axis, 0);
        KdTree {
            points,
            order,
            axis,
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the tree is empty.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The index of the point nearest to `q` and its squared distance; `None` if the tree is
    /// empty or `q` is not finite.
    pub fn nearest(&self, q: [f64; 3]) -> Option<(usize, f64)> {
        if self.points.is_empty() || q.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut best = (usize::MAX, f64::INFINITY);
        self.search(0, self.order.len(), q, &mut best);
        (best.0 != usize::MAX).then_some(best)
    }

    fn search(&self, lo: usize, hi: usize, q: [f64; 3], best: &mut (usize, f64)) {
        if lo >= hi {
            return;
        }
        let mid = (lo + hi) / 2;
        let i = self.order[mid] as usize;
        let p = self.points[i];
        let d2: f64 = (0..3).map(|a| (p[a] - q[a]).powi(2)).sum();
        if d2 < best.1 {
            *best = (i, d2);
        }
        let a = self.axis[mid] as usize;
        let diff = q[a] - p[a];
        let (near, far) = if diff < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1, q, best);
        if diff * diff < best.1 {
            self.search(far.0, far.1, q, best);
        }
    }
}

fn build(points: &[[f64; 3]], order: &mut [u32], axis: &mut [u8], _depth: usize) {
    if order.len() <= 1 {
        return;
    }
    // Widest axis of this cell.
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &i in order.iter() {
        for a in 0..3 {
            let v = points[i as usize][a];
            if v.is_finite() {
                lo[a] = lo[a].min(v);
                hi[a] = hi[a].max(v);
            }
        }
    }
    let ax = (0..3)
        .max_by(|&x, &y| (hi[x] - lo[x]).total_cmp(&(hi[y] - lo[y])))
        .unwrap_or(0);
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |&x, &y| {
        points[x as usize][ax].total_cmp(&points[y as usize][ax])
    });
    axis[mid] = ax as u8;
    let (left, right) = order.split_at_mut(mid);
    let (al, ar) = axis.split_at_mut(mid);
    build(points, left, al, _depth + 1);
    build(points, &mut right[1..], &mut ar[1..], _depth + 1);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_brute_force() {
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        for n in [0usize, 1, 2, 7, 468, 2000] {
            let pts: Vec<[f64; 3]> = (0..n).map(|_| [rnd(), rnd() * 2.0, rnd() * 0.1]).collect();
            let tree = KdTree::new(pts.clone());
            assert_eq!(tree.len(), n);
            for _ in 0..200 {
                let q = [rnd() * 1.2 - 0.1, rnd() * 2.4 - 0.2, rnd() * 0.3];
                let brute = pts
                    .iter()
                    .enumerate()
                    .map(|(i, p)| (i, (0..3).map(|a| (p[a] - q[a]).powi(2)).sum::<f64>()))
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                let got = tree.nearest(q);
                match (brute, got) {
                    (None, None) => {}
                    (Some(b), Some(g)) => {
                        assert!((b.1 - g.1).abs() < 1e-15, "n={n}: {b:?} vs {g:?}")
                    }
                    other => panic!("n={n}: {other:?}"),
                }
            }
        }
        assert!(KdTree::new(vec![[0.0; 3]])
            .nearest([f64::NAN, 0.0, 0.0])
            .is_none());
    }
}
