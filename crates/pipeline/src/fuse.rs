//! `visage fuse`: a depth-map sequence in, a fused mesh sequence and its metrics out
//! (paper §2 and §4; ERRATA 1–6, 13).

use std::path::{Path, PathBuf};
use std::time::Instant;

use faer::{Mat, MatRef};
use serde::Serialize;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_fem::{
    solve_clip, ClipOptions, FusionSystem, StreamingSolver, SurfaceMetrics, SurfaceQuality, Weights,
};
use visage_mesh::io::write_ply;
use visage_mesh::TriMesh;

use crate::report::{
    FrameMetrics, FrameQuality, FrameStatus, FuseReport, FuseSummary, MeshSummary, SolverSummary,
};
use crate::{write_atomically, DepthSequence, FusionSetup, MeshingOptions, PipelineError};

/// Depth values beyond this (metres) count as invalid by default (sensor saturation, far
/// background).
pub const DEFAULT_MAX_DEPTH_M: f64 = 10.0;

/// Which temporal model to solve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Causal, frame by frame (live capture).
    #[default]
    Streaming,
    /// The exact minimiser over the whole clip.
    Clip,
}

/// Options of a fusion run (everything but the weights).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FuseOptions {
    pub mode: Mode,
    pub meshing: MeshingOptions,
    pub depth_kind: DepthKind,
    /// Stored value / `depth_scale` = metres.
    pub depth_scale: f64,
    pub max_depth_m: f64,
    pub clip: ClipOptions,
    /// Also write the data term's target on the same mesh (`raw/`).
    pub save_raw: bool,
}

impl Default for FuseOptions {
    fn default() -> Self {
        FuseOptions {
            mode: Mode::Streaming,
            meshing: MeshingOptions::default(),
            depth_kind: DepthKind::Z,
            depth_scale: 1000.0,
            max_depth_m: DEFAULT_MAX_DEPTH_M,
            clip: ClipOptions::default(),
            save_raw: false,
        }
    }
}

/// Per-frame fusion on a fixed set-up: data sampling, hole filling, right-hand side, solve and
/// metrics. Buffers are allocated once; the per-frame path allocates nothing except when a
/// frame without predecessor needs in-painting (first frame, reset).
pub struct Fuser {
    setup: FusionSetup,
    solver: StreamingSolver,
    metrics: SurfaceMetrics,
    max_depth: f64,
    raw: Mat<f64>,
    fill: Mat<f64>,
    b: Mat<f64>,
    x: Mat<f64>,
    valid: Vec<bool>,
    positions: Vec<[f64; 3]>,
}

/// What [`Fuser::process`] measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameResult {
    pub status: FrameStatus,
    pub valid_fraction: f64,
    pub rhs_seconds: f64,
    pub solve_seconds: f64,
    pub relative_residual: f64,
}

impl Fuser {
    /// Wraps a set-up and its factored system.
    pub fn new(setup: FusionSetup, system: FusionSystem, max_depth: f64) -> Self {
        let n = setup.vertex_count();
        Fuser {
            metrics: SurfaceMetrics::new(n, &setup.mesh.triangles, &setup.boundary),
            solver: StreamingSolver::new(system),
            setup,
            max_depth,
            raw: Mat::zeros(n, 3),
            fill: Mat::zeros(n, 3),
            b: Mat::zeros(n, 3),
            x: Mat::zeros(n, 3),
            valid: vec![false; n],
            positions: vec![[0.0; 3]; n],
        }
    }

    pub fn setup(&self) -> &FusionSetup {
        &self.setup
    }

    pub fn solver(&self) -> &StreamingSolver {
        &self.solver
    }

    pub fn solver_mut(&mut self) -> &mut StreamingSolver {
        &mut self.solver
    }

    /// The last solution (#V × 3, metres).
    pub fn solution(&self) -> MatRef<'_, f64> {
        self.x.as_ref()
    }

    /// The last data target at the vertices, holes filled as the solver filled them.
    pub fn raw(&self) -> MatRef<'_, f64> {
        self.raw.as_ref()
    }

    /// The last data right-hand side.
    pub fn rhs(&self) -> MatRef<'_, f64> {
        self.b.as_ref()
    }

    /// Fuses one depth frame. Pixels without valid depth take the previous solution (or, with
    /// no predecessor, an in-painting of the valid vertex samples); a frame with no valid pixel
    /// is carried over from the previous solution, or reported as `NoData` if there is none.
    pub fn process(&mut self, depth: &DepthMap) -> FrameResult {
        let start = Instant::now();
        let pixels = self.setup.quadrature.len().max(1);
        let mut result = FrameResult {
            status: FrameStatus::Solved,
            valid_fraction: 0.0,
            rhs_seconds: 0.0,
            solve_seconds: 0.0,
            relative_residual: 0.0,
        };
        self.setup
            .sample_vertices(depth, self.max_depth, &mut self.raw, &mut self.valid);
        match self.solver.previous() {
            Some(prev) => self.fill.copy_from(prev),
            None => {
                self.fill.copy_from(&self.raw);
                if !self.setup.inpaint(&mut self.fill, &self.valid) {
                    // Not one vertex sample: fall back to the mean valid depth, if any.
                    let Some(d) = mean_valid_distance(depth, &self.setup.k, self.max_depth) else {
                        result.status = FrameStatus::NoData;
                        return result;
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

    /// Mean |H| and roughness of the last raw target and of the last solution.
    pub fn frame_quality(&mut self) -> (SurfaceQuality, SurfaceQuality) {
        to_positions(self.raw.as_ref(), &mut self.positions);
        let raw = self.metrics.evaluate(&self.positions);
        to_positions(self.x.as_ref(), &mut self.positions);
        (raw, self.metrics.evaluate(&self.positions))
    }

    /// Mean |H| and roughness of a vertex field (#V × 3).
    pub fn quality(&mut self, x: MatRef<'_, f64>) -> SurfaceQuality {
        to_positions(x, &mut self.positions);
        self.metrics.evaluate(&self.positions)
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

/// Runs `visage fuse`: reconstructs every frame of `sequence` seen by camera `k` into
/// `out_dir/meshes/NNNNNN.ply` (and `raw/` with `save_raw`), and writes `out_dir/metrics.json`.
///
/// All frames are validated before anything is written. Every file is written under a
/// temporary name and renamed when complete. If the run fails part-way, `metrics.json` still
/// records the frames done, with `"status": "failed"` and the error.
/// `progress(done, total)` is called after each frame.
pub fn fuse_sequence(
    sequence: &DepthSequence,
    k: &Intrinsics,
    weights: Weights,
    options: &FuseOptions,
    out_dir: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<FuseReport, PipelineError> {
    weights.validate()?;
    if options.max_depth_m.is_nan() || options.max_depth_m <= 0.0 {
        return Err(PipelineError::InvalidOption {
            name: "max-depth",
            value: options.max_depth_m.to_string(),
            reason: "must be positive",
        });
    }
    let survey = sequence.survey(options.max_depth_m)?;
    k.check_size(survey.width, survey.height)?;
    let setup_start = Instant::now();
    let setup = FusionSetup::new(k, &survey.domain, &survey.mean_depth, &options.meshing)?;
    let system = FusionSystem::new(setup.ops.clone(), weights)?;
    let setup_ms = setup_start.elapsed().as_secs_f64() * 1e3;
    let mut fuser = Fuser::new(setup, system, options.max_depth_m);

    let meshes_dir = out_dir.join("meshes");
    let raw_dir = out_dir.join("raw");
    for dir in std::iter::once(&meshes_dir).chain(options.save_raw.then_some(&raw_dir)) {
        std::fs::create_dir_all(dir).map_err(|source| PipelineError::Io {
            path: dir.clone(),
            source,
        })?;
    }
    let setup = fuser.setup();
    let mut report = FuseReport {
        status: "running".into(),
        error: None,
        input: sequence.dir.display().to_string(),
        width: survey.width,
        height: survey.height,
        parameters: *options,
        weights,
        mesh: MeshSummary {
            vertices: setup.vertex_count(),
            triangles: setup.mesh.triangles.len(),
            boundary_vertices: setup.boundary.iter().filter(|&&b| b).count(),
            flatness_ratio: setup.flatness_ratio,
            depth_aware: setup.depth_aware_flips.is_some(),
            depth_aware_flips: setup.depth_aware_flips.unwrap_or(0),
        },
        solver: SolverSummary {
            factor_nnz: fuser.solver().system().factor_nnz(),
            factor_ms: fuser.solver().system().factor_seconds() * 1e3,
            setup_ms,
            clip: None,
            clip_ms: None,
        },
        frames: Vec::new(),
        summary: FuseSummary::of(&[]),
    };
    let mut writer = MeshWriter {
        mesh: TriMesh::new(
            vec![[0.0; 3]; setup.vertex_count()],
            setup.mesh.triangles.clone(),
        ),
        meshes_dir,
        raw_dir: options.save_raw.then_some(raw_dir),
    };
    let outcome = match options.mode {
        Mode::Streaming => run_streaming(sequence, &mut fuser, &mut writer, &mut report, progress),
        Mode::Clip => run_clip(
            sequence,
            &mut fuser,
            &mut writer,
            &mut report,
            &options.clip,
            progress,
        ),
    };
    report.summary = FuseSummary::of(&report.frames);
    if let Err(e) = &outcome {
        report.status = "failed".into();
        report.error = Some(e.to_string());
    } else {
        report.status = "complete".into();
    }
    let metrics_path = out_dir.join("metrics.json");
    write_atomically(&metrics_path, |tmp| {
        let text = serde_json::to_string_pretty(&report).map_err(|e| PipelineError::Io {
            path: tmp.to_owned(),
            source: e.into(),
        })?;
        std::fs::write(tmp, text).map_err(|source| PipelineError::Io {
            path: tmp.to_owned(),
            source,
        })
    })?;
    outcome.map(|()| report)
}

/// Metrics of a frame without a surface.
const NO_SURFACE: SurfaceQuality = SurfaceQuality {
    mean_abs_h: 0.0,
    roughness: 0.0,
};

struct MeshWriter {
    mesh: TriMesh,
    meshes_dir: PathBuf,
    raw_dir: Option<PathBuf>,
}

impl MeshWriter {
    fn write(
        &mut self,
        index: usize,
        solution: MatRef<'_, f64>,
        raw: MatRef<'_, f64>,
    ) -> Result<(), PipelineError> {
        let name = format!("{index:06}.ply");
        to_positions(solution, &mut self.mesh.vertices);
        write_atomically(&self.meshes_dir.join(&name), |p| write_ply(p, &self.mesh))?;
        if let Some(dir) = &self.raw_dir {
            to_positions(raw, &mut self.mesh.vertices);
            write_atomically(&dir.join(&name), |p| write_ply(p, &self.mesh))?;
        }
        Ok(())
    }
}

fn frame_metrics(
    index: usize,
    source: &Path,
    r: &FrameResult,
    raw: SurfaceQuality,
    fused: SurfaceQuality,
) -> FrameMetrics {
    FrameMetrics {
        index,
        source: source.display().to_string(),
        status: r.status,
        valid_fraction: r.valid_fraction,
        rhs_ms: r.rhs_seconds * 1e3,
        solve_ms: r.solve_seconds * 1e3,
        relative_residual: r.relative_residual,
        quality: FrameQuality::of(&raw, &fused),
    }
}

fn warn_status(sequence: &DepthSequence, index: usize, status: FrameStatus) {
    let path = sequence.frames[index].display();
    match status {
        FrameStatus::Carried => {
            eprintln!("warning: {path}: no valid depth; previous frame's surface carried over")
        }
        FrameStatus::NoData => {
            eprintln!("warning: {path}: no valid depth and no previous frame; no mesh written")
        }
        FrameStatus::Solved => {}
    }
}

fn run_streaming(
    sequence: &DepthSequence,
    fuser: &mut Fuser,
    writer: &mut MeshWriter,
    report: &mut FuseReport,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(), PipelineError> {
    let total = sequence.frames.len();
    for index in 0..total {
        let depth = sequence.read(index)?;
        let r = fuser.process(&depth);
        warn_status(sequence, index, r.status);
        let (raw_q, fused_q) = if r.status == FrameStatus::NoData {
            (NO_SURFACE, NO_SURFACE)
        } else {
            writer.write(index, fuser.solution(), fuser.raw())?;
            fuser.frame_quality()
        };
        report.frames.push(frame_metrics(
            index,
            &sequence.frames[index],
            &r,
            raw_q,
            fused_q,
        ));
        progress(index + 1, total);
    }
    Ok(())
}

fn run_clip(
    sequence: &DepthSequence,
    fuser: &mut Fuser,
    writer: &mut MeshWriter,
    report: &mut FuseReport,
    clip: &ClipOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<(), PipelineError> {
    // Forward streaming pass: fixes the hole filling, gives each frame's data and the initial
    // guess. Frames without data are left out of the clip system.
    let total = sequence.frames.len();
    let mut results = Vec::with_capacity(total);
    let (mut bs, mut xs, mut raws, mut members) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for index in 0..total {
        let depth = sequence.read(index)?;
        let r = fuser.process(&depth);
        warn_status(sequence, index, r.status);
        if r.status != FrameStatus::NoData {
            bs.push(fuser.rhs().to_owned());
            xs.push(fuser.solution().to_owned());
            raws.push(fuser.raw().to_owned());
            members.push(index);
        }
        results.push(r);
        progress(index + 1, 2 * total);
    }
    let start = Instant::now();
    let clip_report = solve_clip(fuser.solver_mut().system_mut(), &bs, &mut xs, clip);
    let clip_seconds = start.elapsed().as_secs_f64();
    report.solver.clip = Some(clip_report);
    report.solver.clip_ms = Some(clip_seconds * 1e3);
    let per_frame = clip_seconds / bs.len().max(1) as f64;
    let mut member = 0;
    for (index, mut r) in results.into_iter().enumerate() {
        let (raw_q, fused_q) = if r.status == FrameStatus::NoData {
            (NO_SURFACE, NO_SURFACE)
        } else {
            let (x, raw) = (&xs[member], &raws[member]);
            debug_assert_eq!(members[member], index);
            member += 1;
            writer.write(index, x.as_ref(), raw.as_ref())?;
            r.solve_seconds = per_frame;
            r.relative_residual = clip_report.relative_residual;
            (fuser.quality(raw.as_ref()), fuser.quality(x.as_ref()))
        };
        report.frames.push(frame_metrics(
            index,
            &sequence.frames[index],
            &r,
            raw_q,
            fused_q,
        ));
        progress(total + index + 1, 2 * total);
    }
    Ok(())
}
