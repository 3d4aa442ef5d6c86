//! Everything fixed for a sequence: the planar mesh over the domain and its operators.

use faer::Mat;
use visage_camera::{DepthMap, Intrinsics};
use visage_fem::domain::domain_coordinates;
use visage_fem::{
    biharmonic, cotan_laplacian, lumped_mass, mass_matrix, Operators, PixelQuadrature,
};
use visage_mesh::{
    flip_depth_aware, sample_domain, Mask, OneRing, PlanarMesh, SamplingOptions, TriangulationKind,
};

use crate::FusionError;

/// Gauss–Seidel sweeps of the harmonic in-painting of a frame without predecessor.
pub const INPAINT_SWEEPS: usize = 50;

/// How to mesh the domain (paper §4, ERRATA 9–10).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeshingOptions {
    /// Grid spacing in pixels.
    pub spacing: u32,
    /// Planar, depth-aware, or chosen by the flatness ratio.
    pub triangulation: TriangulationKind,
    /// Curvature refinement tolerance in metres (`None`: off).
    pub refine_tolerance_m: Option<f64>,
}

/// The most vertices of an image-plane mesh: a 2000×2000-pixel face at the default spacing
/// of 4 pixels. Memory grows with them: a 4000×4000 photo at `--spacing 2` (about 225,000
/// vertices) peaked at 1.5 GB and took 45 s for its one frame; `--spacing 1` (900,000) went
/// past 2.4 GB before it was stopped.
pub const MAX_MESH_VERTICES: usize = 250_000;

/// Refuses a grid of `spacing` pixels over `pixels` pixels that would pass
/// [`MAX_MESH_VERTICES`], before any memory is reserved for it.
fn check_vertex_count(pixels: usize, spacing: u32) -> Result<(), FusionError> {
    let spacing = spacing.max(1);
    let estimate = pixels / (spacing as usize * spacing as usize);
    if estimate <= MAX_MESH_VERTICES {
        return Ok(());
    }
    let smallest = (pixels as f64 / MAX_MESH_VERTICES as f64).sqrt().ceil() as u32;
    Err(FusionError::TooManyVertices {
        spacing,
        pixels,
        estimate,
        limit: MAX_MESH_VERTICES,
        smallest,
    })
}

impl Default for MeshingOptions {
    fn default() -> Self {
        let s = SamplingOptions::default();
        MeshingOptions {
            spacing: s.spacing,
            triangulation: TriangulationKind::Auto,
            refine_tolerance_m: s.refine_tolerance,
        }
    }
}

/// The sequence's fixed mesh, its finite-element operators and the data-term quadrature.
#[derive(Debug)]
pub struct FusionSetup {
    pub k: Intrinsics,
    pub mesh: PlanarMesh,
    /// Flatness ratio of the reference depth (ERRATA 9).
    pub flatness_ratio: f64,
    /// Flips made by the depth-aware variant (`None` when the planar mesh was kept).
    pub depth_aware_flips: Option<usize>,
    /// Vertices added at the caller's anchor points ([`FusionSetup::with_anchors`]; 0 from
    /// [`FusionSetup::new`]).
    pub anchor_vertices: usize,
    /// Per vertex: on the domain boundary.
    pub boundary: Vec<bool>,
    pub ring: OneRing,
    /// Unit ray of each vertex (Eq. (2.1)).
    pub rays: Vec<[f64; 3]>,
    pub quadrature: PixelQuadrature,
    pub ops: Operators,
}

impl FusionSetup {
    /// Meshes `domain` (pixels to cover) using `reference` (a depth map of the sequence, e.g.
    /// its per-pixel mean) for refinement, the flatness ratio and depth-aware flips, and
    /// assembles M, M_D and K.
    pub fn new(
        k: &Intrinsics,
        domain: &Mask,
        reference: &DepthMap,
        options: &MeshingOptions,
    ) -> Result<Self, FusionError> {
        Self::with_anchors(k, domain, reference, options, &[])
    }

    /// [`FusionSetup::new`] with `anchors` (pixel positions `(u, v)`, e.g. keypoints — paper
    /// §3's "semantic anchors") added as vertices after the grid and refinement samples, each
    /// only inside `domain` and clear of the other samples ([`Samples::add_anchors`],
    /// [`visage_mesh::ANCHOR_MIN_SEPARATION`]). No anchors give `new`'s mesh exactly.
    ///
    /// [`Samples::add_anchors`]: visage_mesh::Samples::add_anchors
    pub fn with_anchors(
        k: &Intrinsics,
        domain: &Mask,
        reference: &DepthMap,
        options: &MeshingOptions,
        anchors: &[[f64; 2]],
    ) -> Result<Self, FusionError> {
        k.check_size(domain.width, domain.height)?;
        check_vertex_count(domain.count(), options.spacing)?;
        let sampling = SamplingOptions {
            spacing: options.spacing,
            refine_tolerance: options.refine_tolerance_m,
            ..Default::default()
        };
        let mut samples = sample_domain(domain, Some((reference, k)), &sampling)?;
        let anchor_vertices = samples.add_anchors(domain, anchors, options.spacing);
        let mut mesh = PlanarMesh::triangulate(&samples)?;
        let flatness_ratio = reference.flatness_ratio().unwrap_or(0.0);
        let depth_aware_flips = if options.triangulation.uses_depth(flatness_ratio) {
            let positions = reference_positions(&mesh, reference, k);
            Some(flip_depth_aware(&mut mesh, &positions)?)
        } else {
            None
        };
        let xi = domain_coordinates(&mesh.points, k);
        let l = cotan_laplacian(&xi, &mesh.triangles)?;
        let m_lumped = lumped_mass(&xi, &mesh.triangles)?;
        let quadrature = PixelQuadrature::new(&mesh.points, &mesh.triangles, k);
        let ops = Operators {
            mass: mass_matrix(&xi, &mesh.triangles)?,
            data_mass: quadrature.mass_matrix()?,
            biharmonic: biharmonic(&l, &m_lumped)?,
        };
        Ok(FusionSetup {
            k: *k,
            boundary: mesh.boundary_vertices(),
            ring: OneRing::new(mesh.points.len(), &mesh.triangles),
            rays: mesh.points.iter().map(|p| k.ray(p[0], p[1])).collect(),
            flatness_ratio,
            depth_aware_flips,
            anchor_vertices,
            quadrature,
            ops,
            mesh,
        })
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.mesh.points.len()
    }

    /// Samples `depth` at every vertex: `raw[i] = D(x_i) ρ(x_i)` (bilinear over valid
    /// neighbours, values beyond `max_depth` ignored) and `valid[i]` whether that was possible.
    /// Returns the number of valid vertices. Allocates nothing.
    pub fn sample_vertices(
        &self,
        depth: &DepthMap,
        max_depth: f64,
        raw: &mut Mat<f64>,
        valid: &mut [bool],
    ) -> usize {
        let mut count = 0;
        for (i, p) in self.mesh.points.iter().enumerate() {
            let d = depth
                .sample_ray_distance(&self.k, p[0], p[1])
                .filter(|&d| depth.kind.from_ray_distance(d, self.rays[i]) <= max_depth);
            valid[i] = d.is_some();
            if let Some(d) = d {
                for c in 0..3 {
                    raw[(i, c)] = d * self.rays[i][c];
                }
                count += 1;
            }
        }
        count
    }

    /// Fills the vertices without data (`valid[i] = false`) of `field` by diffusion from the
    /// valid ones: a front first gives each unknown vertex the mean ray distance of its known
    /// neighbours, then [`INPAINT_SWEEPS`] Gauss–Seidel sweeps relax the filled values toward
    /// the harmonic interpolant (each the mean of its neighbours); vertices never reached take
    /// the mean of all known ones.
    /// Used for a frame that has no predecessor (first frame, reset). Returns `false` when no
    /// vertex is valid (nothing to fill from).
    pub fn inpaint(&self, field: &mut Mat<f64>, valid: &[bool]) -> bool {
        let n = self.vertex_count();
        let mut dist: Vec<f64> = (0..n)
            .map(|i| {
                let r = self.rays[i];
                field[(i, 0)] * r[0] + field[(i, 1)] * r[1] + field[(i, 2)] * r[2]
            })
            .collect();
        let mut known = valid.to_vec();
        let known_count = known.iter().filter(|&&k| k).count();
        if known_count == 0 {
            return false;
        }
        let mean = (0..n).filter(|&i| known[i]).map(|i| dist[i]).sum::<f64>() / known_count as f64;
        let mut updates: Vec<(usize, f64)> = Vec::new();
        loop {
            updates.clear();
            for i in (0..n).filter(|&i| !known[i]) {
                let (mut s, mut c) = (0.0, 0);
                for &j in self.ring.of(i) {
                    if known[j as usize] {
                        s += dist[j as usize];
                        c += 1;
                    }
                }
                if c > 0 {
                    updates.push((i, s / c as f64));
                }
            }
            if updates.is_empty() {
                break;
            }
            for &(i, d) in &updates {
                dist[i] = d;
                known[i] = true;
            }
        }
        for _ in 0..INPAINT_SWEEPS {
            for i in (0..n).filter(|&i| !valid[i] && known[i]) {
                let ring = self.ring.of(i);
                if !ring.is_empty() {
                    dist[i] =
                        ring.iter().map(|&j| dist[j as usize]).sum::<f64>() / ring.len() as f64;
                }
            }
        }
        for i in 0..n {
            let d = if known[i] { dist[i] } else { mean };
            if !valid[i] {
                for c in 0..3 {
                    field[(i, c)] = d * self.rays[i][c];
                }
            }
        }
        true
    }
}

/// Back-projection of the reference depth at each vertex (mean valid distance where missing).
fn reference_positions(mesh: &PlanarMesh, reference: &DepthMap, k: &Intrinsics) -> Vec<[f64; 3]> {
    let samples: Vec<Option<f64>> = mesh
        .points
        .iter()
        .map(|p| reference.sample_ray_distance(k, p[0], p[1]))
        .collect();
    let known: Vec<f64> = samples.iter().flatten().copied().collect();
    let mean = if known.is_empty() {
        1.0
    } else {
        known.iter().sum::<f64>() / known.len() as f64
    };
    mesh.points
        .iter()
        .zip(&samples)
        .map(|(p, d)| k.backproject(p[0], p[1], d.unwrap_or(mean)))
        .collect()
}

#[cfg(test)]
mod tests {
    use visage_camera::DepthKind;

    use super::*;

    /// A 48 × 40 bump, in the domain everywhere.
    fn scene() -> (Intrinsics, Mask, DepthMap) {
        let (w, h) = (48, 40);
        let k = Intrinsics::from_fov(w, h, 60.0).unwrap();
        let mut depth = DepthMap::empty(w, h, DepthKind::Z);
        for v in 0..h {
            for u in 0..w {
                let (x, y) = (u as f64 - 24.0, v as f64 - 20.0);
                depth.data[(v * w + u) as usize] =
                    (0.6 - 0.02 * (-(x * x + y * y) / 100.0).exp()) as f32;
            }
        }
        (k, Mask::filled(w, h, true), depth)
    }

    #[test]
    fn anchors_become_vertices_and_none_give_the_plain_mesh() {
        let (k, domain, depth) = scene();
        let options = MeshingOptions::default();
        let plain = FusionSetup::new(&k, &domain, &depth, &options).unwrap();
        let none = FusionSetup::with_anchors(&k, &domain, &depth, &options, &[]).unwrap();
        assert_eq!(none.mesh, plain.mesh);
        assert_eq!(none.anchor_vertices, 0);

        // One anchor in a cell's quarter (kept), one on a grid corner (skipped), one outside.
        let anchors = [[9.0, 13.0], [8.0, 12.0], [60.0, 5.0]];
        let setup = FusionSetup::with_anchors(&k, &domain, &depth, &options, &anchors).unwrap();
        assert_eq!(setup.anchor_vertices, 1);
        assert_eq!(setup.vertex_count(), plain.vertex_count() + 1);
        let i = setup
            .mesh
            .points
            .iter()
            .position(|p| *p == anchors[0])
            .unwrap();
        assert!(setup.mesh.triangles.iter().any(|t| t.contains(&(i as u32))));
        assert_eq!(setup.ops.mass.nrows(), setup.vertex_count());
        assert!((setup.mesh.area() - plain.mesh.area()).abs() < 1e-9);
    }
}
