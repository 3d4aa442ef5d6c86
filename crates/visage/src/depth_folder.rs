//! A depth sequence in, a fused mesh sequence out (`visage fuse`): the paper's image-plane
//! mesh over the sequence's domain (Sections 2 and 4; ERRATA 1–6, 13).

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use visage_camera::{DepthKind, Intrinsics};
use visage_depth::DepthSequence;
use visage_fem::{ClipOptions, FusionSystem, Weights};
use visage_fusion::{
    solve_clip_frames, ClipFrame, ClipState, FrameStatus as FusedStatus, FusionSetup,
    ImagePlaneFuser, MeshingOptions, SequenceSurvey, SurfaceFuser, DEFAULT_MAX_DEPTH_M,
};
use visage_mesh::io::PlyFormat;

use crate::process_stats::{cpu_seconds, peak_rss_mib};
use crate::reconstructor::error_chain;
use crate::recorder::Recorder;
use crate::{Error, OutputDir, Surfaces, TemporalMode};
use visage_run_folder::{
    FrameMetrics, FrameQuality, MeshSummary, Report, RunStatus, RunTiming, SolverSummary,
};

/// Options of a depth-folder fusion, as `metrics.json` records them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FuseOptions {
    /// λ (reference pixels⁴) and μ.
    pub weights: Weights,
    pub mode: TemporalMode,
    pub meshing: MeshingOptions,
    pub depth_kind: DepthKind,
    /// Stored value / `depth_scale` = metres.
    pub depth_scale: f64,
    pub max_depth_m: f64,
    pub clip: ClipOptions,
}

impl Default for FuseOptions {
    fn default() -> Self {
        FuseOptions {
            weights: Weights::default(),
            mode: TemporalMode::Streaming,
            meshing: MeshingOptions::default(),
            depth_kind: DepthKind::Z,
            depth_scale: 1000.0,
            max_depth_m: DEFAULT_MAX_DEPTH_M,
            clip: ClipOptions::default(),
        }
    }
}

/// Reconstructs every frame of `sequence` seen by camera `k` into the folder `out`
/// (`meshes/NNNNNN.ply`, with `save_raw` also `raw/`) and writes `metrics.json` there.
///
/// All frames are validated (sizes, bit depth) before anything is written. If the run fails
/// part-way, `metrics.json` still records the frames done, with `"status": "failed"` and the
/// error. `progress(done, total)` is called after each frame, `warn` with what the user
/// should know about a frame (no valid depth).
///
/// # Errors
/// Invalid weights or options, frames that do not fit together or the camera, a domain that
/// cannot be meshed, unwritable output.
pub fn fuse_depth_folder(
    sequence: &DepthSequence,
    k: &Intrinsics,
    options: &FuseOptions,
    out: &Path,
    save_raw: bool,
    progress: &mut dyn FnMut(usize, usize),
    warn: &mut dyn FnMut(&str),
) -> Result<Report<FuseOptions>, Error> {
    let weights = options.weights;
    weights.validate()?;
    if options.max_depth_m.is_nan() || options.max_depth_m <= 0.0 {
        return Err(Error::InvalidOption {
            name: "--max-depth",
            value: visage_camera::number(options.max_depth_m),
            reason: "must be positive",
        });
    }
    let survey = SequenceSurvey::new(
        &sequence.dir,
        &sequence.frames,
        options.max_depth_m,
        |index| sequence.read(index).map_err(Error::from),
    )?;
    k.check_size(survey.width, survey.height)?;
    let setup_start = Instant::now();
    let setup = FusionSetup::new(k, &survey.domain, &survey.mean_depth, &options.meshing)?;
    let system = FusionSystem::new(setup.ops.clone(), weights)?;
    let setup_ms = setup_start.elapsed().as_secs_f64() * 1e3;
    let mesh = MeshSummary {
        vertices: setup.vertex_count(),
        triangles: setup.mesh.triangles.len(),
        boundary_vertices: Some(setup.boundary.iter().filter(|&&b| b).count()),
        flatness_ratio: Some(setup.flatness_ratio),
        depth_aware_flips: setup.depth_aware_flips,
    };
    let solver = SolverSummary {
        factor_nnz: system.factor_nnz(),
        factor_ms: system.factor_seconds() * 1e3,
        clip: None,
        clip_ms: None,
    };
    let mut out =
        OutputDir::create(out)?.with_ply(PlyFormat::BinaryLittleEndian, true, save_raw)?;
    let mut run = DepthRun {
        sequence,
        fuser: ImagePlaneFuser::new(setup, system, options.max_depth_m),
        k: *k,
        recorder: Recorder::default(),
        surfaces: Surfaces::default(),
        solver,
        out: &mut out,
        progress,
        warn,
    };
    let start = Instant::now();
    let cpu_start = cpu_seconds();
    let outcome = match options.mode {
        TemporalMode::Streaming => run.streaming(),
        TemporalMode::Clip => run.clip(&options.clip),
    };
    let timing = RunTiming {
        wall_s: start.elapsed().as_secs_f64(),
        setup_ms,
        cpu_s: cpu_seconds().zip(cpu_start).map(|(b, a)| b - a),
        peak_rss_mib: peak_rss_mib(),
    };
    let report = Report {
        status: if outcome.is_ok() {
            RunStatus::Complete
        } else {
            RunStatus::Failed
        },
        error: outcome.as_ref().err().map(|e| error_chain(e)),
        input: sequence.dir.display().to_string(),
        intrinsics: *k,
        parameters: *options,
        selection: None,
        resumed: None,
        mesh,
        solver: Some(run.solver),
        summary: run.recorder.summary(timing),
        frames: run.recorder.frames,
    };
    run.out.write_metrics(&report)?;
    outcome.map(|()| report)
}

/// A depth-folder fusion in progress.
struct DepthRun<'a> {
    sequence: &'a DepthSequence,
    fuser: ImagePlaneFuser,
    k: Intrinsics,
    recorder: Recorder,
    surfaces: Surfaces,
    solver: SolverSummary,
    out: &'a mut OutputDir,
    progress: &'a mut dyn FnMut(usize, usize),
    warn: &'a mut dyn FnMut(&str),
}

impl DepthRun<'_> {
    fn streaming(&mut self) -> Result<(), Error> {
        let total = self.sequence.frames.len();
        for index in 0..total {
            let (mut metrics, _) = self.fuse(index, false)?;
            let has_mesh = metrics.has_mesh();
            if has_mesh {
                let (raw, fused) = self.fuser.frame_quality();
                metrics.quality = FrameQuality::of(&raw, &fused);
            }
            let position = self.recorder.push(metrics);
            if has_mesh {
                let start = Instant::now();
                self.write(position)?;
                self.recorder.frames[position].ms.write = start.elapsed().as_secs_f64() * 1e3;
            }
            (self.progress)(index + 1, total);
        }
        Ok(())
    }

    /// Forward streaming pass (fixes the hole filling, gives each frame's data and the initial
    /// guess), then the whole-clip solve over the frames with data.
    fn clip(&mut self, options: &ClipOptions) -> Result<(), Error> {
        let total = self.sequence.frames.len();
        let (mut positions, mut frames) = (Vec::new(), Vec::new());
        for index in 0..total {
            let (metrics, state) = self.fuse(index, true)?;
            let position = self.recorder.push(metrics);
            if let Some(state) = state {
                positions.push(position);
                frames.push(ClipFrame {
                    state,
                    raw: self.fuser.raw().to_vec(),
                    landmarks_px: Vec::new(),
                });
            }
            (self.progress)(index + 1, 2 * total);
        }
        let start = Instant::now();
        let report = solve_clip_frames(&mut self.fuser, &mut frames, options);
        let clip_ms = start.elapsed().as_secs_f64() * 1e3;
        self.solver.clip = Some(report);
        self.solver.clip_ms = Some(clip_ms);
        let share = clip_ms / frames.len().max(1) as f64;
        for (&position, frame) in positions.iter().zip(&frames) {
            let start = Instant::now();
            self.fuser.load_clip_solution(&frame.state, &frame.raw);
            let (raw_q, fused_q) = self.fuser.frame_quality();
            let m = &mut self.recorder.frames[position];
            m.quality = FrameQuality::of(&raw_q, &fused_q);
            m.relative_residual = report.relative_residual;
            m.ms.fuse += share;
            self.write(position)?;
            self.recorder.frames[position].ms.write = start.elapsed().as_secs_f64() * 1e3;
            (self.progress)(total + position + 1, 2 * total);
        }
        Ok(())
    }

    /// Reads and fuses frame `index`: its record, and with `keep_state` its clip state when
    /// it has data.
    fn fuse(
        &mut self,
        index: usize,
        keep_state: bool,
    ) -> Result<(FrameMetrics, Option<ClipState>), Error> {
        let path = &self.sequence.frames[index];
        let start = Instant::now();
        let depth = self.sequence.read(index)?;
        let read_ms = start.elapsed().as_secs_f64() * 1e3;
        let r = self.fuser.process(&depth)?;
        let mut metrics = FrameMetrics::new(index, path.display().to_string(), r.status.into());
        metrics.ms.decode = read_ms;
        metrics.ms.fuse = (r.rhs_seconds + r.solve_seconds) * 1e3;
        metrics.valid_fraction = r.valid_fraction;
        metrics.relative_residual = r.relative_residual;
        match r.status {
            FusedStatus::Carried => (self.warn)(&format!(
                "{}: no valid depth; previous frame's surface carried over",
                path.display()
            )),
            FusedStatus::NoData => (self.warn)(&format!(
                "{}: no valid depth and no previous frame; no mesh written",
                path.display()
            )),
            FusedStatus::Solved => {}
        }
        let state =
            (keep_state && r.status != FusedStatus::NoData).then(|| self.fuser.clip_state());
        Ok((metrics, state))
    }

    /// Measures and writes the current surfaces as the frame at `position`.
    fn write(&mut self, position: usize) -> Result<(), Error> {
        let s = &mut self.surfaces;
        s.fused.clear();
        s.fused.extend_from_slice(self.fuser.solution());
        s.raw.clear();
        s.raw.extend_from_slice(self.fuser.raw());
        let triangles = self.fuser.triangles();
        self.recorder
            .mesh(position, &self.k, s, triangles, &[], &mut *self.out)
    }
}
