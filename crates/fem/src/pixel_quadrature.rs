//! The data term ∫_Ω |S − D_k ρ_k|² dx integrated with one quadrature point per pixel centre
//! (paper Eq. (2.2); ERRATA 2).
//!
//! The depth `D_k` is only known at pixel centres, so the data term is evaluated there:
//! `E_data = Σ_p w |S(p) − D_k(p) ρ(p)|²` with `w` the pixel's area in domain units. Its Hessian
//! is the data mass matrix `M_D = Σ_p w φ_i(p) φ_j(p)` — the pixel-quadrature version of the
//! consistent mass matrix M, constant for the sequence because every pixel always contributes
//! — and its gradient gives the right-hand side `b_i = Σ_p w φ_i(p) D_k(p) ρ(p)` (3 columns).
//! Unlike a vertex-sampled data term, every pixel's measurement is used, so noise averages
//! over the whole support of each basis function.
//!
//! Pixels without valid depth (0, NaN, beyond `max_depth`) take the value of a caller-given
//! fill field instead (the previous solution in streaming mode), so a hole neither changes the
//! matrix nor pulls the surface toward the camera.

use faer::sparse::Triplet;
use faer::{MatMut, MatRef};
use visage_camera::{DepthMap, Intrinsics};

use crate::domain::pixel_area;
use crate::sparse::{from_triplets, SparseMatrix};
use crate::FemError;

/// Tolerance on barycentric coordinates when testing whether a pixel centre is in a triangle.
const INSIDE_TOLERANCE: f64 = 1e-9;

/// Pixel-centre quadrature of a planar mesh: for every covered pixel, its triangle and
/// barycentric coordinates, and its unit ray.
#[derive(Clone, Debug)]
pub struct PixelQuadrature {
    width: u32,
    height: u32,
    pixels: Vec<u32>,
    corners: Vec<[u32; 3]>,
    bary: Vec<[f64; 3]>,
    rays: Vec<[f64; 3]>,
    weight: f64,
    vertex_count: usize,
}

impl PixelQuadrature {
    /// Locates every pixel centre of a `k.width × k.height` image in the mesh given by
    /// `points_px` (pixel positions) and `triangles`. A pixel on a shared edge belongs to the
    /// first triangle that contains it (P1 functions agree there, so the choice is immaterial).
    pub fn new(points_px: &[[f64; 2]], triangles: &[[u32; 3]], k: &Intrinsics) -> Self {
        let (w, h) = (k.width as i64, k.height as i64);
        let mut owner = vec![u32::MAX; (w * h) as usize];
        let mut bary_of = vec![[0.0; 3]; (w * h) as usize];
        for (t, tri) in triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|i| points_px[i as usize]);
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            if det == 0.0 {
                continue;
            }
            let (lo_u, hi_u) = (a[0].min(b[0]).min(c[0]), a[0].max(b[0]).max(c[0]));
            let (lo_v, hi_v) = (a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]));
            for v in (lo_v.ceil() as i64).max(0)..=(hi_v.floor() as i64).min(h - 1) {
                for u in (lo_u.ceil() as i64).max(0)..=(hi_u.floor() as i64).min(w - 1) {
                    let idx = (v * w + u) as usize;
                    if owner[idx] != u32::MAX {
                        continue;
                    }
                    let (x, y) = (u as f64, v as f64);
                    let l1 = ((x - a[0]) * (c[1] - a[1]) - (y - a[1]) * (c[0] - a[0])) / det;
                    let l2 = ((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])) / det;
                    let l0 = 1.0 - l1 - l2;
                    if l0 >= -INSIDE_TOLERANCE && l1 >= -INSIDE_TOLERANCE && l2 >= -INSIDE_TOLERANCE
                    {
                        owner[idx] = t as u32;
                        bary_of[idx] = [l0, l1, l2];
                    }
                }
            }
        }
        let mut q = PixelQuadrature {
            width: k.width,
            height: k.height,
            pixels: Vec::new(),
            corners: Vec::new(),
            bary: Vec::new(),
            rays: Vec::new(),
            weight: pixel_area(k),
            vertex_count: points_px.len(),
        };
        for (idx, &t) in owner.iter().enumerate() {
            if t == u32::MAX {
                continue;
            }
            let (u, v) = ((idx as i64 % w) as f64, (idx as i64 / w) as f64);
            q.pixels.push(idx as u32);
            q.corners.push(triangles[t as usize]);
            q.bary.push(bary_of[idx]);
            q.rays.push(k.ray(u, v));
        }
        q
    }

    /// Number of quadrature points (covered pixels).
    pub fn len(&self) -> usize {
        self.pixels.len()
    }

    /// Whether no pixel is covered.
    pub fn is_empty(&self) -> bool {
        self.pixels.is_empty()
    }

    /// The data mass matrix `M_D = Σ_p w φ_i(p) φ_j(p)` (#V × #V, symmetric positive
    /// semi-definite; definite when every vertex's support contains a pixel centre).
    pub fn mass_matrix(&self) -> Result<SparseMatrix, FemError> {
        let mut triplets = Vec::with_capacity(9 * self.len());
        for (t, l) in self.corners.iter().zip(&self.bary) {
            for a in 0..3 {
                for b in 0..3 {
                    triplets.push(Triplet::new(
                        t[a] as usize,
                        t[b] as usize,
                        self.weight * l[a] * l[b],
                    ));
                }
            }
        }
        from_triplets(self.vertex_count, &triplets)
    }

    /// Right-hand side `b_i = Σ_p w φ_i(p) X(p)` (#V × 3) of one frame, with `X(p) = D(p) ρ(p)`
    /// where the depth is valid and at most `max_depth` metres, else the P1 interpolant of
    /// `fill` (#V × 3). Returns the number of pixels with valid depth. Allocates nothing.
    ///
    /// # Panics
    /// If `depth` is not `width × height` or `fill`/`b` are not #V × 3.
    #[track_caller]
    pub fn assemble_rhs(
        &self,
        depth: &DepthMap,
        max_depth: f64,
        fill: MatRef<'_, f64>,
        mut b: MatMut<'_, f64>,
    ) -> usize {
        assert!(depth.width == self.width && depth.height == self.height);
        assert!(fill.nrows() == self.vertex_count && b.nrows() == self.vertex_count);
        assert!(fill.ncols() == 3 && b.ncols() == 3);
        b.fill(0.0);
        let mut valid = 0;
        for (((&idx, t), l), ray) in self
            .pixels
            .iter()
            .zip(&self.corners)
            .zip(&self.bary)
            .zip(&self.rays)
        {
            let d = depth.data[idx as usize];
            let x = if DepthMap::is_valid(d) && (d as f64) <= max_depth {
                valid += 1;
                let dist = depth.kind.to_ray_distance(d as f64, *ray);
                [dist * ray[0], dist * ray[1], dist * ray[2]]
            } else {
                let mut x = [0.0; 3];
                for a in 0..3 {
                    for (c, xc) in x.iter_mut().enumerate() {
                        *xc += l[a] * fill[(t[a] as usize, c)];
                    }
                }
                x
            };
            for a in 0..3 {
                let wl = self.weight * l[a];
                for (c, xc) in x.iter().enumerate() {
                    b[(t[a] as usize, c)] += wl * xc;
                }
            }
        }
        valid
    }
}
