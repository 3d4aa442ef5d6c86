//! Sample points over the region with depth (paper §4, ERRATA 10).
//!
//! The image is cut into square cells of `spacing` pixels whose corners are pixel centres; a cell
//! belongs to the domain when at least [`MIN_CELL_COVERAGE`] of the pixel centres it contains
//! are in the mask. The samples are the corners of the domain's cells (a regular grid, which
//! includes the image corners and the boundary of the region), plus — where a reference depth
//! map shows detail the piecewise-linear mesh would miss — the centres of those cells.
//! The boundary of the union of cells becomes the constraint edges of the triangulation.
//! [`Samples::add_anchors`] adds caller-chosen points (keypoints, paper §3's "semantic
//! anchors") inside the domain.

use visage_camera::{DepthMap, Intrinsics};

use crate::{Mask, MeshError};

/// Fraction of a cell's pixel centres that must be in the mask for the cell to be meshed.
pub const MIN_CELL_COVERAGE: f64 = 0.5;

/// Default depth error (metres) above which a cell gets an extra sample at its centre.
pub const DEFAULT_REFINE_TOLERANCE_M: f64 = 0.001;

/// Closest an anchor may come to another sample or to the domain's boundary, as a fraction of
/// the grid spacing ([`Samples::add_anchors`]): nearer anchors are skipped, so no triangle gets
/// an edge shorter than a third of the spacing (the grid's own shortest edge is half of it, to
/// a refinement centre's diagonal neighbours ≈ 0.71).
pub const ANCHOR_MIN_SEPARATION: f64 = 1.0 / 3.0;

/// How to place sample points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplingOptions {
    /// Grid spacing in pixels (≥ 1).
    pub spacing: u32,
    /// See [`MIN_CELL_COVERAGE`].
    pub min_cell_coverage: f64,
    /// Curvature-driven refinement (ERRATA 10): a cell gets a sample at its centre when the
    /// reference depth there differs from the mean of its corners by more than this (metres).
    /// `None` disables refinement.
    pub refine_tolerance: Option<f64>,
}

impl Default for SamplingOptions {
    fn default() -> Self {
        SamplingOptions {
            spacing: 4,
            min_cell_coverage: MIN_CELL_COVERAGE,
            refine_tolerance: Some(DEFAULT_REFINE_TOLERANCE_M),
        }
    }
}

/// The cell grid: corner coordinates (pixels) and which cells belong to the domain.
#[derive(Clone, Debug, PartialEq)]
pub struct CellGrid {
    /// Column coordinates of the grid lines: 0, s, 2s, …, and `width − 1`.
    pub xs: Vec<f64>,
    /// Row coordinates of the grid lines: 0, s, 2s, …, and `height − 1`.
    pub ys: Vec<f64>,
    /// `(xs.len() − 1) × (ys.len() − 1)` flags, row-major: whether the cell is in the domain.
    pub inside: Vec<bool>,
}

impl CellGrid {
    fn cols(&self) -> usize {
        self.xs.len() - 1
    }

    /// Whether cell `(i, j)` is in the domain (`false` outside the grid).
    pub fn cell_inside(&self, i: i64, j: i64) -> bool {
        i >= 0
            && j >= 0
            && (i as usize) < self.cols()
            && (j as usize) < self.ys.len() - 1
            && self.inside[j as usize * self.cols() + i as usize]
    }

    /// Whether the point `(u, v)` (pixels) lies in a domain cell.
    pub fn contains(&self, u: f64, v: f64) -> bool {
        match (cell_of(&self.xs, u), cell_of(&self.ys, v)) {
            (Some(i), Some(j)) => self.cell_inside(i as i64, j as i64),
            _ => false,
        }
    }

    /// Area of the domain in square pixels.
    pub fn area(&self) -> f64 {
        let mut a = 0.0;
        for j in 0..self.ys.len() - 1 {
            for i in 0..self.cols() {
                if self.inside[j * self.cols() + i] {
                    a += (self.xs[i + 1] - self.xs[i]) * (self.ys[j + 1] - self.ys[j]);
                }
            }
        }
        a
    }
}

/// Index of the interval of sorted `lines` that contains `x`.
fn cell_of(lines: &[f64], x: f64) -> Option<usize> {
    if !(x >= lines[0] && x <= lines[lines.len() - 1]) {
        return None;
    }
    let i = lines.partition_point(|&l| l <= x);
    Some(i.saturating_sub(1).min(lines.len() - 2))
}

/// Sample points, the boundary constraint edges between them, and the grid they came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Samples {
    /// Pixel positions `(u, v)`, no duplicates.
    pub points: Vec<[f64; 2]>,
    /// Boundary edges of the domain as pairs of point indices.
    pub constraint_edges: Vec<[u32; 2]>,
    /// The cell grid (used to tell inside from outside triangles).
    pub grid: CellGrid,
}

impl Samples {
    /// Adds `anchors` (pixel positions `(u, v)`, e.g. keypoints) as sample points, in order,
    /// and returns how many were added. An anchor is kept when
    /// - it is finite and the pixel nearest to it is set in `mask`,
    /// - the square of half-side `ANCHOR_MIN_SEPARATION · spacing` around it lies in domain
    ///   cells (it stays that far from the boundary, so it never lands on a constraint edge), and
    /// - no sample already present (grid corner, refinement centre or an earlier anchor) is
    ///   nearer than [`ANCHOR_MIN_SEPARATION`]` · spacing`.
    ///
    /// The constraint edges and the grid are unchanged; `spacing` is the grid spacing the
    /// samples were placed with ([`SamplingOptions::spacing`]).
    pub fn add_anchors(&mut self, mask: &Mask, anchors: &[[f64; 2]], spacing: u32) -> usize {
        let min = ANCHOR_MIN_SEPARATION * f64::from(spacing.max(1));
        // Buckets of side `min`: a sample nearer than `min` lies in the 3 × 3 around an anchor's.
        let bucket = |p: [f64; 2]| ((p[0] / min).floor() as i64, (p[1] / min).floor() as i64);
        let mut buckets: std::collections::HashMap<(i64, i64), Vec<u32>> =
            std::collections::HashMap::new();
        for (i, &p) in self.points.iter().enumerate() {
            buckets.entry(bucket(p)).or_default().push(i as u32);
        }
        let mut added = 0;
        for &a in anchors {
            let in_mask = a[0].is_finite()
                && a[1].is_finite()
                && mask.get(a[0].round() as i64, a[1].round() as i64);
            if !in_mask {
                continue;
            }
            let clear_of_boundary = [[-min, -min], [min, -min], [-min, min], [min, min]]
                .iter()
                .all(|d| self.grid.contains(a[0] + d[0], a[1] + d[1]));
            if !clear_of_boundary {
                continue;
            }
            let (bi, bj) = bucket(a);
            let crowded = (bj - 1..=bj + 1).any(|j| {
                (bi - 1..=bi + 1).any(|i| {
                    buckets.get(&(i, j)).is_some_and(|b| {
                        b.iter().any(|&k| {
                            let p = self.points[k as usize];
                            (p[0] - a[0]).hypot(p[1] - a[1]) < min
                        })
                    })
                })
            });
            if crowded {
                continue;
            }
            buckets
                .entry((bi, bj))
                .or_default()
                .push(self.points.len() as u32);
            self.points.push(a);
            added += 1;
        }
        added
    }
}

fn grid_lines(size: u32, spacing: u32) -> Vec<f64> {
    let last = size - 1;
    let mut lines: Vec<f64> = (0..=last)
        .step_by(spacing as usize)
        .map(f64::from)
        .collect();
    if lines.last() != Some(&(last as f64)) {
        lines.push(last as f64);
    }
    lines
}

/// Places the sample points over the pixels set in `mask`.
///
/// `reference` (a depth map of the same size, e.g. the mean of the sequence) drives the
/// curvature refinement when `options.refine_tolerance` is set; the intrinsics convert its
/// values to ray distances.
pub fn sample_domain(
    mask: &Mask,
    reference: Option<(&DepthMap, &Intrinsics)>,
    options: &SamplingOptions,
) -> Result<Samples, MeshError> {
    if options.spacing == 0 {
        return Err(MeshError::InvalidSpacing {
            spacing: options.spacing,
        });
    }
    if mask.width < 2 || mask.height < 2 {
        return Err(MeshError::ImageTooSmall {
            width: mask.width,
            height: mask.height,
        });
    }
    let xs = grid_lines(mask.width, options.spacing);
    let ys = grid_lines(mask.height, options.spacing);
    let (cols, rows) = (xs.len() - 1, ys.len() - 1);
    let mut inside = vec![false; cols * rows];
    for j in 0..rows {
        for i in 0..cols {
            let (u0, u1) = (xs[i] as i64, xs[i + 1] as i64);
            let (v0, v1) = (ys[j] as i64, ys[j + 1] as i64);
            let total = ((u1 - u0 + 1) * (v1 - v0 + 1)) as f64;
            let mut set = 0usize;
            for v in v0..=v1 {
                for u in u0..=u1 {
                    set += mask.get(u, v) as usize;
                }
            }
            inside[j * cols + i] = set as f64 >= options.min_cell_coverage * total;
        }
    }
    let grid = CellGrid { xs, ys, inside };
    if !grid.inside.iter().any(|&b| b) {
        return Err(MeshError::EmptyDomain {
            valid: mask.count(),
            total: mask.data.len(),
        });
    }

    // Grid corners used by at least one domain cell.
    let mut index = vec![u32::MAX; (cols + 1) * (rows + 1)];
    let mut points = Vec::new();
    for gj in 0..=rows {
        for gi in 0..=cols {
            let (i, j) = (gi as i64, gj as i64);
            let used = grid.cell_inside(i - 1, j - 1)
                || grid.cell_inside(i, j - 1)
                || grid.cell_inside(i - 1, j)
                || grid.cell_inside(i, j);
            if used {
                index[gj * (cols + 1) + gi] = points.len() as u32;
                points.push([grid.xs[gi], grid.ys[gj]]);
            }
        }
    }
    let at = |gi: usize, gj: usize| index[gj * (cols + 1) + gi];

    // Boundary edges: cell sides with a domain cell on exactly one side.
    let mut constraint_edges = Vec::new();
    for gj in 0..=rows {
        for gi in 0..cols {
            let (i, j) = (gi as i64, gj as i64);
            if grid.cell_inside(i, j - 1) != grid.cell_inside(i, j) {
                constraint_edges.push([at(gi, gj), at(gi + 1, gj)]);
            }
        }
    }
    for gj in 0..rows {
        for gi in 0..=cols {
            let (i, j) = (gi as i64, gj as i64);
            if grid.cell_inside(i - 1, j) != grid.cell_inside(i, j) {
                constraint_edges.push([at(gi, gj), at(gi, gj + 1)]);
            }
        }
    }

    if let (Some(tol), Some((depth, k))) = (options.refine_tolerance, reference) {
        for j in 0..rows {
            for i in 0..cols {
                if !grid.inside[j * cols + i] {
                    continue;
                }
                let (u0, u1, v0, v1) = (grid.xs[i], grid.xs[i + 1], grid.ys[j], grid.ys[j + 1]);
                if u1 - u0 < 2.0 || v1 - v0 < 2.0 {
                    continue; // no room for a centre sample distinct from the corners
                }
                let centre = [0.5 * (u0 + u1), 0.5 * (v0 + v1)];
                let corners = [[u0, v0], [u1, v0], [u0, v1], [u1, v1]]
                    .map(|[u, v]| depth.sample_ray_distance(k, u, v));
                let Some(dc) = depth.sample_ray_distance(k, centre[0], centre[1]) else {
                    continue;
                };
                if corners.iter().all(Option::is_some) {
                    let mean = corners.iter().flatten().sum::<f64>() / 4.0;
                    if (dc - mean).abs() > tol {
                        points.push(centre);
                    }
                }
            }
        }
    }
    Ok(Samples {
        points,
        constraint_edges,
        grid,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_mask_gives_the_whole_grid_and_its_outline() {
        let mask = Mask::filled(9, 7, true);
        let opts = SamplingOptions {
            spacing: 4,
            ..Default::default()
        };
        let s = sample_domain(&mask, None, &opts).unwrap();
        assert_eq!(s.grid.xs, vec![0.0, 4.0, 8.0]);
        assert_eq!(s.grid.ys, vec![0.0, 4.0, 6.0]);
        assert_eq!(s.points.len(), 9);
        assert_eq!(s.constraint_edges.len(), 8);
        assert!((s.grid.area() - 48.0).abs() < 1e-12);
        assert!(s.points.contains(&[8.0, 6.0]) && s.points.contains(&[0.0, 0.0]));
    }

    #[test]
    fn disc_mask_has_a_closed_boundary() {
        let mut mask = Mask::filled(64, 64, false);
        for v in 0..64 {
            for u in 0..64 {
                let (x, y) = (u as f64 - 31.5, v as f64 - 31.5);
                mask.data[v * 64 + u] = x * x + y * y < 25.0 * 25.0;
            }
        }
        let s = sample_domain(&mask, None, &SamplingOptions::default()).unwrap();
        // Every boundary vertex has an even number of boundary edges (closed curves).
        let mut degree = vec![0; s.points.len()];
        for e in &s.constraint_edges {
            degree[e[0] as usize] += 1;
            degree[e[1] as usize] += 1;
        }
        assert!(degree.iter().all(|d| d % 2 == 0));
        assert!(degree.iter().any(|&d| d > 0));
        let disc = std::f64::consts::PI * 25.0 * 25.0;
        assert!((s.grid.area() - disc).abs() < 0.1 * disc);
    }

    #[test]
    fn empty_mask_and_zero_spacing_are_errors() {
        let mask = Mask::filled(8, 8, false);
        assert!(matches!(
            sample_domain(&mask, None, &SamplingOptions::default()),
            Err(MeshError::EmptyDomain { .. })
        ));
        let opts = SamplingOptions {
            spacing: 0,
            ..Default::default()
        };
        assert!(sample_domain(&Mask::filled(8, 8, true), None, &opts).is_err());
    }

    #[test]
    fn refinement_adds_centres_only_where_depth_bends() {
        let k = Intrinsics::from_fov(65, 65, 60.0).unwrap();
        let mut depth = DepthMap::empty(65, 65, visage_camera::DepthKind::Ray);
        for v in 0..65 {
            for u in 0..65 {
                // a plane on the left half, a sharp bump on the right
                let bump = if u > 40 {
                    0.05 * ((u as f64 - 40.0) / 24.0).powi(2)
                } else {
                    0.0
                };
                depth.data[v * 65 + u] = (1.0 + bump) as f32;
            }
        }
        let mask = Mask::from_valid_depth(&depth);
        let opts = SamplingOptions {
            spacing: 8,
            ..Default::default()
        };
        let s = sample_domain(&mask, Some((&depth, &k)), &opts).unwrap();
        let centres: Vec<_> = s.points[81..].to_vec();
        assert!(!centres.is_empty());
        assert!(centres.iter().all(|p| p[0] > 40.0), "{centres:?}");
    }

    #[test]
    fn anchors_inside_the_domain_become_vertices_and_the_rest_are_skipped() {
        // The left half of a 33 × 33 image is in the domain (cells of 8 px up to u = 16).
        let mut mask = Mask::filled(33, 33, false);
        for v in 0..33 {
            for u in 0..=16 {
                mask.data[v * 33 + u] = true;
            }
        }
        let opts = SamplingOptions {
            spacing: 8,
            ..Default::default()
        };
        let plain = sample_domain(&mask, None, &opts).unwrap();
        let mut s = plain.clone();
        let anchors = [
            [5.3, 11.7],  // inside, clear of every corner: kept
            [12.0, 27.5], // inside: kept
            [25.0, 12.0], // outside the mask: skipped
            [8.5, 8.4],   // 0.64 px from the corner (8, 8): too close
            [6.0, 12.5],  // 1.06 px from the first anchor: too close
            [15.5, 20.0], // 0.5 px from the boundary u = 16: skipped
            [f64::NAN, 4.0],
        ];
        assert_eq!(s.add_anchors(&mask, &anchors, opts.spacing), 2);
        assert_eq!(s.points.len(), plain.points.len() + 2);
        assert_eq!(&s.points[plain.points.len()..], &[anchors[0], anchors[1]]);
        assert_eq!(s.constraint_edges, plain.constraint_edges);

        let mesh = crate::PlanarMesh::triangulate(&s).unwrap();
        let anchored: Vec<u32> = (plain.points.len() as u32..s.points.len() as u32).collect();
        for i in &anchored {
            assert!(mesh.triangles.iter().any(|t| t.contains(i)), "vertex {i}");
        }
        let plain_mesh = crate::PlanarMesh::triangulate(&plain).unwrap();
        assert!((mesh.area() - plain_mesh.area()).abs() < 1e-9);
        // No anchors: the samples are untouched.
        let mut same = plain.clone();
        assert_eq!(same.add_anchors(&mask, &[], opts.spacing), 0);
        assert_eq!(same, plain);
    }
}
