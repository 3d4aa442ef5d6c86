//! The paper's fusion on its fixed image-plane mesh (Sections 2 and 4; ERRATA 1–6): per
//! frame, sample the depth at the vertices, fill holes, assemble the data right-hand side and
//! take one streaming step on the factored system.

use std::time::Instant;

use faer::{Mat, MatRef};
use visage_camera::{DepthMap, Intrinsics, RigidTransform};
use visage_fem::{FusionSystem, StreamingSolver, SurfaceMetrics, SurfaceQuality};

use crate::{ClipState, FrameStatus, FusedFrame, FusionError, FusionSetup, SurfaceFuser};

/// Depth values beyond this (metres) count as invalid by default (sensor saturation, far
/// background).
pub const DEFAULT_MAX_DEPTH_M: f64 = 10.0;

/// Per-frame fusion on a fixed image-plane set-up: data sampling, hole filling, right-hand
/// side, solve. Buffers are allocated once; the per-frame path allocates nothing except when a
/// frame without predecessor needs in-painting (first frame, reset).
pub struct ImagePlaneFuser {
    setup: FusionSetup,
    solver: StreamingSolver,
    metrics: SurfaceMetrics,
    max_depth: f64,
    raw: Mat<f64>,
    fill: Mat<f64>,
    b: Mat<f64>,
    x: Mat<f64>,
    valid: Vec<bool>,
    /// `x` and `raw` as points (what [`SurfaceFuser::solution`] and [`SurfaceFuser::raw`] give).
    solution_points: Vec<[f64; 3]>,
    raw_points: Vec<[f64; 3]>,
}

impl ImagePlaneFuser {
    /// Wraps a set-up and its factored system; depth beyond `max_depth` metres is missing.
    pub fn new(setup: FusionSetup, system: FusionSystem, max_depth: f64) -> Self {
        let n = setup.vertex_count();
        ImagePlaneFuser {
            metrics: SurfaceMetrics::new(n, &setup.mesh.triangles, &setup.boundary),
            solver: StreamingSolver::new(system),
            setup,
            max_depth,
            raw: Mat::zeros(n, 3),
            fill: Mat::zeros(n, 3),
            b: Mat::zeros(n, 3),
            x: Mat::zeros(n, 3),
            valid: vec![false; n],
            solution_points: vec![[0.0; 3]; n],
            raw_points: vec![[0.0; 3]; n],
        }
    }

    pub fn setup(&self) -> &FusionSetup {
        &self.setup
    }

    pub fn solver(&self) -> &StreamingSolver {
        &self.solver
    }

    /// Fuses one depth frame. Pixels without valid depth take the previous solution (or, with
    /// no predecessor, an in-painting of the valid vertex samples); a frame with no valid pixel
    /// is carried over from the previous solution, or reported as `NoData` if there is none.
    ///
    /// # Errors
    /// When the depth map's size is not the set-up camera's.
    pub fn process(&mut self, depth: &DepthMap) -> Result<FusedFrame, FusionError> {
        self.setup.k.check_size(depth.width, depth.height)?;
        let result = self.fuse(depth);
        if result.status != FrameStatus::NoData {
            to_positions(self.x.as_ref(), &mut self.solution_points);
            to_positions(self.raw.as_ref(), &mut self.raw_points);
        }
        Ok(result)
    }

    fn fuse(&mut self, depth: &DepthMap) -> FusedFrame {
        let start = Instant::now();
        let pixels = self.setup.quadrature.len().max(1);
        let mut result = FusedFrame::unsolved(FrameStatus::Solved);
        self.setup
            .sample_vertices(depth, self.max_depth, &mut self.raw, &mut self.valid);
        match self.solver.previous() {
            Some(prev) => self.fill.copy_from(prev),
            None => {
                self.fill.copy_from(&self.raw);
                if !self.setup.inpaint(&mut self.fill, &self.valid) {
                    // Not one vertex sample: fall back to the mean valid depth, if any.
                    let Some(d) = mean_valid_distance(depth, &self.setup.k, self.max_depth) else {
                        return FusedFrame::unsolved(FrameStatus::NoData);
                    };
                    for i in 0..self.setup.vertex_count() {
                        for c in 0..3 {
                            self.fill[(i, c)] = d * self.setup.rays[i][c];
                        }
                    }
                }
            }
        }
        for i in (0..self.setup.vertex_count()).filter(|&i| !self.valid[i]) {
            for c in 0..3 {
                self.raw[(i, c)] = self.fill[(i, c)];
            }
        }
        let valid = self.setup.quadrature.assemble_rhs(
            depth,
            self.max_depth,
            self.fill.as_ref(),
            self.b.as_mut(),
        );
        result.valid_fraction = valid as f64 / pixels as f64;
        result.rhs_seconds = start.elapsed().as_secs_f64();
        if valid == 0 {
            // Sensor glitch: keep the previous solution (we only get here with one).
            self.x.copy_from(&self.fill);
            self.raw.copy_from(&self.fill);
            result.status = FrameStatus::Carried;
            return result;
        }
        let solve = Instant::now();
        let report = self.solver.step(self.b.as_ref(), self.x.as_mut());
        result.solve_seconds = solve.elapsed().as_secs_f64();
        result.relative_residual = report.relative_residual;
        result
    }
}

impl SurfaceFuser for ImagePlaneFuser {
    fn triangles(&self) -> &[[u32; 3]] {
        &self.setup.mesh.triangles
    }

    fn solution(&self) -> &[[f64; 3]] {
        &self.solution_points
    }

    fn raw(&self) -> &[[f64; 3]] {
        &self.raw_points
    }

    fn reset(&mut self) {
        self.solver.reset();
    }

    fn frame_quality(&mut self) -> (SurfaceQuality, SurfaceQuality) {
        (
            self.metrics.evaluate(&self.raw_points),
            self.metrics.evaluate(&self.solution_points),
        )
    }

    fn clip_state(&self) -> ClipState {
        ClipState {
            b: self.b.clone(),
            x: self.x.clone(),
            pose: RigidTransform::IDENTITY,
            offset: Mat::zeros(0, 3),
        }
    }

    fn system_mut(&mut self) -> &mut FusionSystem {
        self.solver.system_mut()
    }

    fn load_clip_solution(&mut self, state: &ClipState, raw: &[[f64; 3]]) {
        self.x.copy_from(&state.x);
        to_positions(self.x.as_ref(), &mut self.solution_points);
        self.raw_points.copy_from_slice(raw);
        for (i, p) in raw.iter().enumerate() {
            for (c, &value) in p.iter().enumerate() {
                self.raw[(i, c)] = value;
            }
        }
    }
}

fn mean_valid_distance(depth: &DepthMap, k: &Intrinsics, max_depth: f64) -> Option<f64> {
    let (mut sum, mut count) = (0.0, 0usize);
    for v in 0..depth.height {
        for u in 0..depth.width {
            let d = depth.at(u, v);
            if DepthMap::is_valid(d) && d as f64 <= max_depth {
                sum += depth
                    .kind
                    .to_ray_distance(d as f64, k.ray(u as f64, v as f64));
                count += 1;
            }
        }
    }
    (count > 0).then(|| sum / count as f64)
}

/// Copies a #V × 3 field into a vertex array of the same length.
pub fn to_positions(x: MatRef<'_, f64>, out: &mut [[f64; 3]]) {
    for (i, p) in out.iter_mut().enumerate() {
        *p = [x[(i, 0)], x[(i, 1)], x[(i, 2)]];
    }
}
