//! Which triangle of a fixed planar mesh holds an image point, and where in it: a uniform
//! bucket grid over the triangles' bounding boxes, built once per mesh.

/// Barycentric tolerance: points this far outside a triangle (in barycentric units) still
/// count as inside it, so points on shared edges are never lost to rounding.
const INSIDE_TOLERANCE: f64 = 1e-9;

/// A bucket grid over the triangles of a planar mesh (pixel coordinates).
pub struct PointLocator {
    points: Vec<[f64; 2]>,
    triangles: Vec<[u32; 3]>,
    origin: [f64; 2],
    cell: f64,
    columns: usize,
    rows: usize,
    /// Per cell `c`: triangles `entries[starts[c]..starts[c + 1]]`.
    starts: Vec<usize>,
    entries: Vec<u32>,
}

impl PointLocator {
    /// Indexes `triangles` over `points` with square cells of `cell` pixels (> 0).
    pub fn new(points: &[[f64; 2]], triangles: &[[u32; 3]], cell: f64) -> PointLocator {
        let cell = cell.max(1.0);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        if points.is_empty() {
            lo = [0.0; 2];
            hi = [0.0; 2];
        }
        let columns = ((hi[0] - lo[0]) / cell).floor() as usize + 1;
        let rows = ((hi[1] - lo[1]) / cell).floor() as usize + 1;
        let cells_of = |t: &[u32; 3]| {
            let corner = |f: fn(f64, f64) -> f64, a: usize| {
                t.iter()
                    .map(|&i| points[i as usize][a])
                    .fold(points[t[0] as usize][a], f)
            };
            let c0 = ((corner(f64::min, 0) - lo[0]) / cell).floor() as usize;
            let c1 = ((corner(f64::max, 0) - lo[0]) / cell).floor() as usize;
            let r0 = ((corner(f64::min, 1) - lo[1]) / cell).floor() as usize;
            let r1 = ((corner(f64::max, 1) - lo[1]) / cell).floor() as usize;
            (r0..=r1.min(rows - 1))
                .flat_map(move |r| (c0..=c1.min(columns - 1)).map(move |c| r * columns + c))
        };
        let mut counts = vec![0usize; columns * rows + 1];
        for t in triangles {
            for c in cells_of(t) {
                counts[c + 1] += 1;
            }
        }
        for c in 1..counts.len() {
            counts[c] += counts[c - 1];
        }
        let starts = counts;
        let mut fill = starts.clone();
        let mut entries = vec![0u32; *starts.last().unwrap_or(&0)];
        for (ti, t) in triangles.iter().enumerate() {
            for c in cells_of(t) {
                entries[fill[c]] = ti as u32;
                fill[c] += 1;
            }
        }
        PointLocator {
            points: points.to_vec(),
            triangles: triangles.to_vec(),
            origin: lo,
            cell,
            columns,
            rows,
            starts,
            entries,
        }
    }

    /// The triangle holding `p` and `p`'s barycentric coordinates in it (`Σ b = 1`, each ≥ 0
    /// up to rounding), or `None` outside the mesh.
    pub fn locate(&self, p: [f64; 2]) -> Option<(usize, [f64; 3])> {
        let c = ((p[0] - self.origin[0]) / self.cell).floor();
        let r = ((p[1] - self.origin[1]) / self.cell).floor();
        if !(c >= 0.0 && r >= 0.0 && (c as usize) < self.columns && (r as usize) < self.rows) {
            return None;
        }
        let cell = r as usize * self.columns + c as usize;
        self.entries[self.starts[cell]..self.starts[cell + 1]]
            .iter()
            .find_map(|&t| {
                let b = self.barycentric(t as usize, p)?;
                b.iter()
                    .all(|&x| x >= -INSIDE_TOLERANCE)
                    .then_some((t as usize, b))
            })
    }

    /// Interpolates a per-vertex field at `p` (`None` outside the mesh).
    pub fn interpolate(&self, field: &[[f64; 3]], p: [f64; 2]) -> Option<[f64; 3]> {
        let (t, b) = self.locate(p)?;
        let tri = self.triangles[t];
        Some(std::array::from_fn(|c| {
            (0..3).map(|j| b[j] * field[tri[j] as usize][c]).sum()
        }))
    }

    fn barycentric(&self, t: usize, p: [f64; 2]) -> Option<[f64; 3]> {
        let [a, b, c] = self.triangles[t].map(|i| self.points[i as usize]);
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if det == 0.0 {
            return None;
        }
        let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / det;
        let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / det;
        Some([1.0 - l1 - l2, l1, l2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10 × 10 pixel grid of squares split into two triangles each (either orientation).
    fn grid() -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let n = 11u32;
        let points = (0..n * n)
            .map(|i| [(i % n) as f64 * 3.0, (i / n) as f64 * 3.0])
            .collect();
        let mut triangles = Vec::new();
        for r in 0..n - 1 {
            for c in 0..n - 1 {
                let i = r * n + c;
                triangles.push([i, i + 1, i + n + 1]);
                triangles.push([i, i + n + 1, i + n]);
            }
        }
        (points, triangles)
    }

    #[test]
    fn interpolation_of_a_linear_field_is_exact_inside_and_none_outside() {
        let (points, triangles) = grid();
        let locator = PointLocator::new(&points, &triangles, 4.0);
        let field: Vec<[f64; 3]> = points
            .iter()
            .map(|p| [2.0 * p[0] - p[1], p[1] + 1.0, 0.5])
            .collect();
        for k in 0..200 {
            let p = [(k as f64 * 0.731) % 30.0, (k as f64 * 1.37) % 30.0];
            let v = locator.interpolate(&field, p).unwrap();
            assert!((v[0] - (2.0 * p[0] - p[1])).abs() < 1e-9);
            assert!((v[1] - (p[1] + 1.0)).abs() < 1e-9);
        }
        // Vertices and edges are found too.
        assert!(locator.locate([30.0, 30.0]).is_some());
        assert!(locator.locate([0.0, 15.0]).is_some());
        assert!(locator.locate([-0.5, 3.0]).is_none());
        assert!(locator.locate([12.0, 30.5]).is_none());
    }
}
