//! Exact point-to-mesh distances with a uniform grid over the triangles.
//!
//! Triangles are binned into cubic cells of side `cell` by their bounding boxes. A query scans
//! the cells in growing Chebyshev rings around the query's cell; after ring r every unscanned
//! triangle is at least r·cell away, so the search stops once the best distance found is ≤ r·cell
//! — the answer is exact, not approximate. Closest point on a triangle: Ericson, *Real-Time
//! Collision Detection* (2005), §5.1.5.

use visage_camera::vec3::{add, distance2, dot, scale, sub};

type V3 = [f64; 3];

/// Squared distance from `p` to the triangle `(a, b, c)` (degenerate triangles included).
pub fn point_triangle_distance2(p: V3, a: V3, b: V3, c: V3) -> f64 {
    let w = closest_point_barycentric(p, a, b, c);
    let q: V3 = std::array::from_fn(|i| w[0] * a[i] + w[1] * b[i] + w[2] * c[i]);
    distance2(p, q)
}

/// Barycentric coordinates `(w_a, w_b, w_c)` (non-negative, summing to 1) of the point of the
/// triangle `(a, b, c)` closest to `p` (Ericson 2005, §5.1.5; a degenerate triangle gives the
/// closest point of its nearest edge).
pub fn closest_point_barycentric(p: V3, a: V3, b: V3, c: V3) -> [f64; 3] {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE {
        // Degenerate (collinear): the closest point of the nearest edge.
        let edge = |x: V3, y: V3| {
            let d = sub(y, x);
            let l2 = dot(d, d);
            let t = if l2 > 0.0 {
                (dot(sub(p, x), d) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = add(x, scale(d, t));
            (distance2(p, q), t)
        };
        let (ab_d, ab_t) = edge(a, b);
        let (bc_d, bc_t) = edge(b, c);
        let (ca_d, ca_t) = edge(c, a);
        return if ab_d <= bc_d && ab_d <= ca_d {
            [1.0 - ab_t, ab_t, 0.0]
        } else if bc_d <= ca_d {
            [0.0, 1.0 - bc_t, bc_t]
        } else {
            [ca_t, 0.0, 1.0 - ca_t]
        };
    }
    let (v, w) = (vb / denom, vc / denom);
    [1.0 - v - w, v, w]
}

/// A uniform grid over a triangle set, for exact nearest-distance queries.
#[derive(Clone, Debug)]
pub struct TriangleGrid<'a> {
    vertices: &'a [V3],
    triangles: Vec<[u32; 3]>,
    origin: V3,
    cell: f64,
    dims: [usize; 3],
    /// CSR: triangles of cell c are `items[start[c]..start[c + 1]]`.
    start: Vec<usize>,
    items: Vec<u32>,
}

impl<'a> TriangleGrid<'a> {
    /// Bins the triangles of (`vertices`, `triangles`) whose bounding box meets the box
    /// `[lo − margin, hi + margin]` into cells of side `cell` (metres). Queries are exact for
    /// points inside `[lo, hi]` whose nearest distance is ≤ `margin`; beyond that they return
    /// the nearest of the binned triangles (an upper bound, never less than `margin`).
    ///
    /// # Panics
    /// If `cell` is not positive or an index is out of range.
    #[track_caller]
    pub fn new(
        vertices: &'a [V3],
        triangles: &[[u32; 3]],
        lo: V3,
        hi: V3,
        margin: f64,
        cell: f64,
    ) -> Self {
        assert!(cell > 0.0);
        let lo = lo.map(|c| c - margin);
        let hi = hi.map(|c| c + margin);
        let kept: Vec<[u32; 3]> = triangles
            .iter()
            .filter(|t| {
                (0..3).all(|c| {
                    let (mn, mx) = t.iter().fold((f64::MAX, f64::MIN), |(mn, mx), &i| {
                        let x = vertices[i as usize][c];
                        (mn.min(x), mx.max(x))
                    });
                    mx >= lo[c] && mn <= hi[c]
                })
            })
            .copied()
            .collect();
        let dims: [usize; 3] =
            std::array::from_fn(|c| (((hi[c] - lo[c]) / cell).ceil() as usize).clamp(1, 1024));
        let index = |p: V3| -> [usize; 3] {
            std::array::from_fn(|c| {
                (((p[c] - lo[c]) / cell).floor().max(0.0) as usize).min(dims[c] - 1)
            })
        };
        let flat = |i: [usize; 3]| (i[2] * dims[1] + i[1]) * dims[0] + i[0];
        let ranges: Vec<([usize; 3], [usize; 3])> = kept
            .iter()
            .map(|t| {
                let (mut mn, mut mx) = ([usize::MAX; 3], [0; 3]);
                for &i in t {
                    let c = index(vertices[i as usize]);
                    for a in 0..3 {
                        mn[a] = mn[a].min(c[a]);
                        mx[a] = mx[a].max(c[a]);
                    }
                }
                (mn, mx)
            })
            .collect();
        let n_cells = dims[0] * dims[1] * dims[2];
        let mut count = vec![0usize; n_cells + 1];
        let for_cells = |(mn, mx): ([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
            for z in mn[2]..=mx[2] {
                for y in mn[1]..=mx[1] {
                    for x in mn[0]..=mx[0] {
                        f(flat([x, y, z]));
                    }
                }
            }
        };
        for &r in &ranges {
            for_cells(r, &mut |c| count[c + 1] += 1);
        }
        for c in 0..n_cells {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[n_cells]];
        for (t, &r) in ranges.iter().enumerate() {
            for_cells(r, &mut |c| {
                items[fill[c]] = t as u32;
                fill[c] += 1;
            });
        }
        TriangleGrid {
            vertices,
            triangles: kept,
            origin: lo,
            cell,
            dims,
            start: count,
            items,
        }
    }

    /// Number of triangles binned.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether no triangle was binned.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Distance from `p` to the nearest binned triangle (metres); `None` when nothing is binned.
    pub fn distance(&self, p: V3) -> Option<f64> {
        if self.triangles.is_empty() {
            return None;
        }
        let d = self.dims;
        let home: [i64; 3] = std::array::from_fn(|c| {
            (((p[c] - self.origin[c]) / self.cell).floor() as i64).clamp(0, d[c] as i64 - 1)
        });
        let mut best = f64::MAX;
        let max_ring = *d.iter().max().unwrap_or(&1) as i64;
        for r in 0..=max_ring {
            for z in home[2] - r..=home[2] + r {
                for y in home[1] - r..=home[1] + r {
                    for x in home[0] - r..=home[0] + r {
                        let on_shell = (x - home[0]).abs() == r
                            || (y - home[1]).abs() == r
                            || (z - home[2]).abs() == r;
                        if !on_shell
                            || x < 0
                            || y < 0
                            || z < 0
                            || x >= d[0] as i64
                            || y >= d[1] as i64
                            || z >= d[2] as i64
                        {
                            continue;
                        }
                        let c = (z as usize * d[1] + y as usize) * d[0] + x as usize;
                        for &t in &self.items[self.start[c]..self.start[c + 1]] {
                            let [a, b, cc] =
                                self.triangles[t as usize].map(|i| self.vertices[i as usize]);
                            best = best.min(point_triangle_distance2(p, a, b, cc));
                        }
                    }
                }
            }
            let reach = r as f64 * self.cell;
            if best <= reach * reach {
                break;
            }
        }
        Some(best.sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn triangle_distance_regions() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        assert!((point_triangle_distance2([0.2, 0.2, 0.5], a, b, c) - 0.25).abs() < 1e-15);
        assert!((point_triangle_distance2([-1.0, -1.0, 0.0], a, b, c) - 2.0).abs() < 1e-15);
        assert!((point_triangle_distance2([0.5, -2.0, 0.0], a, b, c) - 4.0).abs() < 1e-15);
        assert!((point_triangle_distance2([1.0, 1.0, 0.0], a, b, c) - 0.5).abs() < 1e-15);
        // Degenerate triangle: distance to the segment.
        assert!(
            (point_triangle_distance2([0.5, 1.0, 0.0], a, b, [2.0, 0.0, 0.0]) - 1.0).abs() < 1e-15
        );
    }

    /// The grid gives exactly the brute-force minimum over a random triangle soup.
    #[test]
    fn grid_matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let vertices: Vec<V3> = (0..300)
            .map(|_| std::array::from_fn(|_| rng.random_range(-0.1..0.1)))
            .collect();
        let triangles: Vec<[u32; 3]> = (0..100).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        // Shrink each triangle towards its first vertex (1–2 cm triangles).
        let mut small = vertices.clone();
        for t in &triangles {
            let a = vertices[t[0] as usize];
            for &i in &t[1..] {
                small[i as usize] =
                    std::array::from_fn(|c| a[c] + 0.1 * (vertices[i as usize][c] - a[c]));
            }
        }
        let grid = TriangleGrid::new(&small, &triangles, [-0.1; 3], [0.1; 3], 0.2, 0.01);
        assert_eq!(grid.len(), 100);
        for _ in 0..200 {
            let p: V3 = std::array::from_fn(|_| rng.random_range(-0.1..0.1));
            let brute = triangles
                .iter()
                .map(|t| {
                    point_triangle_distance2(
                        p,
                        small[t[0] as usize],
                        small[t[1] as usize],
                        small[t[2] as usize],
                    )
                })
                .fold(f64::MAX, f64::min)
                .sqrt();
            let got = grid.distance(p).unwrap();
            assert!((got - brute).abs() < 1e-12, "{got} vs {brute}");
        }
    }
}
