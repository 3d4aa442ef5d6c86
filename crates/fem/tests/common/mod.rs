//! Shared set-up for the finite-element tests: a planar mesh over an image, its operators and
//! depth maps of analytic surfaces.
#![allow(dead_code)]

use faer::Mat;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_fem::domain::domain_coordinates;
use visage_fem::{
    biharmonic, cotan_laplacian, lumped_mass, mass_matrix, FusionSystem, Operators,
    PixelQuadrature, Weights,
};
use visage_mesh::{sample_domain, Mask, PlanarMesh, SamplingOptions};

pub struct Setup {
    pub k: Intrinsics,
    pub mesh: PlanarMesh,
    pub quadrature: PixelQuadrature,
    pub ops: Operators,
}

pub fn setup(width: u32, height: u32, spacing: u32) -> Setup {
    let k = Intrinsics::from_fov(width, height, 60.0).unwrap();
    let samples = sample_domain(
        &Mask::filled(width, height, true),
        None,
        &SamplingOptions {
            spacing,
            refine_tolerance: None,
            ..Default::default()
        },
    )
    .unwrap();
    let mesh = PlanarMesh::triangulate(&samples).unwrap();
    let xi = domain_coordinates(&mesh.points, &k);
    let l = cotan_laplacian(&xi, &mesh.triangles).unwrap();
    let ml = lumped_mass(&xi, &mesh.triangles).unwrap();
    let quadrature = PixelQuadrature::new(&mesh.points, &mesh.triangles, &k);
    let ops = Operators {
        mass: mass_matrix(&xi, &mesh.triangles).unwrap(),
        data_mass: quadrature.mass_matrix().unwrap(),
        biharmonic: biharmonic(&l, &ml).unwrap(),
    };
    Setup {
        k,
        mesh,
        quadrature,
        ops,
    }
}

impl Setup {
    pub fn system(&self, lambda: f64, mu: f64) -> FusionSystem {
        FusionSystem::new(self.ops.clone(), Weights { lambda, mu }).unwrap()
    }

    /// z-depth map of the surface `z(x_n, y_n)` (normalised image coordinates).
    pub fn depth(&self, z: impl Fn(f64, f64) -> f64) -> DepthMap {
        let mut d = DepthMap::empty(self.k.width, self.k.height, DepthKind::Z);
        for v in 0..self.k.height {
            for u in 0..self.k.width {
                let (xn, yn) = (
                    (u as f64 - self.k.cx) / self.k.fx,
                    (v as f64 - self.k.cy) / self.k.fy,
                );
                d.data[(v * self.k.width + u) as usize] = z(xn, yn) as f32;
            }
        }
        d
    }

    /// The true surface point at each vertex for z-depth function `z`.
    pub fn truth(&self, z: impl Fn(f64, f64) -> f64) -> Mat<f64> {
        let n = self.mesh.points.len();
        Mat::from_fn(n, 3, |i, c| {
            let p = self.mesh.points[i];
            let (xn, yn) = (
                (p[0] - self.k.cx) / self.k.fx,
                (p[1] - self.k.cy) / self.k.fy,
            );
            let zz = z(xn, yn);
            [xn * zz, yn * zz, zz][c]
        })
    }

    pub fn rhs(&self, depth: &DepthMap) -> Mat<f64> {
        let n = self.mesh.points.len();
        let mut b = Mat::zeros(n, 3);
        let fill = Mat::zeros(n, 3);
        self.quadrature
            .assemble_rhs(depth, f64::INFINITY, fill.as_ref(), b.as_mut());
        b
    }
}

pub fn max_abs_diff(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    let mut m = 0.0f64;
    for c in 0..a.ncols() {
        for i in 0..a.nrows() {
            m = m.max((a[(i, c)] - b[(i, c)]).abs());
        }
    }
    m
}

pub fn rms_diff(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
    let mut s = 0.0;
    for c in 0..a.ncols() {
        for i in 0..a.nrows() {
            s += (a[(i, c)] - b[(i, c)]).powi(2);
        }
    }
    (s / a.nrows() as f64).sqrt()
}
