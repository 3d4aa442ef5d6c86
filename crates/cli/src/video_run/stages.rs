//! The streaming pipeline of `visage run` (issue #6, item 5): four stages on their own
//! threads, joined by bounded queues ([`QUEUE_CAPACITY`] frames each), frames out in input
//! order:
//!
//! ```text
//! decode ──► track + landmarks + fit ──► depth + fuse ──► write (this thread)
//! ```
//!
//! Memory is flat in the clip length in streaming mode: at most `QUEUE_CAPACITY` frames wait
//! in each queue, surface buffers travel back from the writer to the fusion for reuse, the
//! fusion step allocates nothing (face mesh), and `landmarks.json` is streamed to disk. What
//! grows is the per-frame metrics record (a few hundred bytes a frame). Clip mode keeps every
//! frame's right-hand side and streaming solution until the end (≈ 9 · 8 bytes per vertex and
//! frame), then solves the clip and writes the meshes.
//!
//! Errors: a stage that fails stops and drops its queue; the stages after it finish what they
//! received (meshes written so far stay), the stages before it stop when their next send
//! fails. The first error (in pipeline order) is the run's error.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::time::Instant;

use anyhow::{anyhow, Context};
use indicatif::ProgressBar;
use serde_json::Value;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_face::{
    fit_face_geometry, render_faces_depth, CanonicalMesh, FaceGeometry, FaceTracker,
};
use visage_fem::ClipOptions;
use visage_mesh::io::{write_ply_with, PlyFormat};
use visage_mesh::TriMesh;
use visage_pipeline::{write_atomically, DepthSequence, FrameQuality, FrameStatus};
use visage_video::{Frame, FrameSource};

use super::process_stats::{cpu_seconds, peak_rss_mib};
use super::run_metrics::{
    FrameMetrics, PoseMetrics, QualityMeter, RunStatus, RunSummary, RunTiming, StageTimes,
};
use super::surface_fusion::{ClipFrame, FaceFrame, MeshKind, SurfaceFusion};
use crate::commands::landmarks::{face_json, pose_json};

/// Frames waiting between two stages.
pub const QUEUE_CAPACITY: usize = 3;

/// Where each frame's depth comes from.
pub enum DepthSource {
    /// The metric face fit (the face CNN surface).
    Face,
    /// 16-bit PNG depth maps, the i-th file for input frame i.
    Dir(DepthSequence),
}

/// Streaming (causal) or the exact clip minimiser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TemporalMode {
    Streaming,
    Clip,
}

/// What to write.
pub enum Output {
    /// `dir/meshes/NNNNNN.ply` (and `raw/` with `save_raw`), `dir/landmarks.json`.
    Files {
        dir: PathBuf,
        save_raw: bool,
        format: PlyFormat,
    },
    /// Nothing (`visage bench`): the same pipeline without the mesh and landmark writes.
    Nothing,
}

/// A validated run configuration.
pub struct RunConfig<'a> {
    pub k: Intrinsics,
    pub canonical: &'a CanonicalMesh,
    pub depth: DepthSource,
    pub mode: TemporalMode,
    pub clip: ClipOptions,
    /// Keep input frames whose index is a multiple of this.
    pub every: usize,
    /// Stop after this many kept frames.
    pub max_frames: Option<usize>,
    pub output: Output,
    pub progress: ProgressBar,
}

/// What a run did: per-frame metrics, totals, and the error that stopped it, if any.
pub struct RunOutcome {
    pub frames: Vec<FrameMetrics>,
    pub summary: RunSummary,
    pub error: Option<anyhow::Error>,
    /// Vertices of the mesh (0 when no frame was meshed).
    pub vertices: usize,
}

struct Decoded {
    frame: Frame,
    decode_ms: f64,
}

struct TrackedFace {
    landmarks_px: Vec<[f64; 2]>,
    geometry: FaceGeometry,
    face_box: [f32; 4],
}

struct Tracked {
    index: usize,
    source: String,
    decode_ms: f64,
    track_ms: f64,
    fit_ms: f64,
    detector_ran: bool,
    face: Option<TrackedFace>,
    landmarks_json: Value,
}

/// One frame's surfaces (buffers recycled between the fusion and the writer).
#[derive(Default)]
struct Surfaces {
    fused: Vec<[f64; 3]>,
    raw: Vec<[f64; 3]>,
    fused_landmarks: Vec<[f64; 3]>,
    raw_landmarks: Vec<[f64; 3]>,
    landmarks_px: Vec<[f64; 2]>,
}

enum ToWriter {
    /// The mesh's triangles, sent once before its first surface.
    Topology(Vec<[u32; 3]>),
    /// A frame, with its surfaces when a mesh is to be written now (streaming mode).
    Frame {
        metrics: Box<FrameMetrics>,
        landmarks_json: Value,
        surfaces: Option<Box<Surfaces>>,
    },
    /// Clip mode, after the clip solve: a frame's final surfaces.
    ClipSurfaces {
        index: usize,
        surfaces: Box<Surfaces>,
        quality: FrameQuality,
        relative_residual: f64,
        extra_fuse_ms: f64,
    },
}

/// Runs the pipeline on `source` with the tracker and fusion given, writing per `config`.
/// Set-up time (models, operators) is `setup_ms`, recorded in the summary.
pub fn run_pipeline(
    config: &RunConfig<'_>,
    source: FrameSource,
    tracker: FaceTracker,
    fusion: SurfaceFusion,
    setup_ms: f64,
) -> RunOutcome {
    let start = Instant::now();
    let cpu_start = cpu_seconds();
    let (decoded_tx, decoded_rx) = sync_channel::<Decoded>(QUEUE_CAPACITY);
    let (tracked_tx, tracked_rx) = sync_channel::<Tracked>(QUEUE_CAPACITY);
    let (written_tx, written_rx) = sync_channel::<ToWriter>(QUEUE_CAPACITY);
    let (recycle_tx, recycle_rx) = sync_channel::<Box<Surfaces>>(2 * QUEUE_CAPACITY + 2);
    let mut writer = Writer::new(config);
    let (errors, writer_error) = std::thread::scope(|scope| {
        let decode = scope.spawn(|| decode_stage(config, source, decoded_tx));
        let track = scope.spawn(|| track_stage(config, tracker, decoded_rx, tracked_tx));
        let fuse = scope.spawn(|| fuse_stage(config, fusion, tracked_rx, written_tx, recycle_rx));
        let writer_error = writer.run(written_rx, recycle_tx).err();
        let join = |h: std::thread::ScopedJoinHandle<'_, anyhow::Result<()>>, name: &str| {
            h.join()
                .unwrap_or_else(|_| Err(anyhow!("internal error: the {name} stage panicked")))
                .err()
        };
        (
            [
                join(decode, "decode"),
                join(track, "tracking"),
                join(fuse, "fusion"),
            ],
            writer_error,
        )
    });
    let error = errors.into_iter().flatten().next().or(writer_error);
    let error = match (error, writer.finish()) {
        (Some(e), _) => Some(e),
        (None, Err(e)) => Some(e),
        (None, Ok(())) => None,
    };
    let wall_s = start.elapsed().as_secs_f64();
    let timing = RunTiming {
        wall_s,
        setup_ms,
        cpu_s: cpu_seconds().zip(cpu_start).map(|(b, a)| b - a),
        peak_rss_mib: peak_rss_mib(),
    };
    config.progress.finish_and_clear();
    let summary = RunSummary::of(&writer.frames, writer.quality.summary(), timing);
    RunOutcome {
        frames: writer.frames,
        summary,
        error,
        vertices: writer.vertices,
    }
}

fn decode_stage(
    config: &RunConfig<'_>,
    mut source: FrameSource,
    out: SyncSender<Decoded>,
) -> anyhow::Result<()> {
    let mut kept = 0usize;
    let mut decode_ms = 0.0;
    loop {
        if config.max_frames.is_some_and(|m| kept >= m) {
            return Ok(());
        }
        let t = Instant::now();
        let Some(frame) = source.next() else {
            return Ok(());
        };
        decode_ms += t.elapsed().as_secs_f64() * 1e3;
        let frame = frame?;
        if frame.index % config.every != 0 {
            continue;
        }
        kept += 1;
        if out.send(Decoded { frame, decode_ms }).is_err() {
            return Ok(()); // a later stage stopped
        }
        decode_ms = 0.0;
    }
}

fn track_stage(
    config: &RunConfig<'_>,
    mut tracker: FaceTracker,
    input: Receiver<Decoded>,
    out: SyncSender<Tracked>,
) -> anyhow::Result<()> {
    for Decoded { frame, decode_ms } in input {
        let (w, h) = frame.image.dimensions();
        config
            .k
            .check_size(w, h)
            .with_context(|| format!("{}: intrinsics do not fit the frame", frame.source))?;
        let t = Instant::now();
        let step = tracker
            .track(&frame.image)
            .with_context(|| format!("{}: face tracking", frame.source))?;
        let track_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let mut faces_json = Vec::new();
        let face = match step.face {
            Some(face) => {
                let mut json = face_json(&face);
                let fit = fit_face_geometry(config.canonical, &face.landmarks.points, &config.k);
                let tracked = match fit {
                    Ok(geometry) => {
                        json["pose"] = pose_json(&geometry);
                        Some(TrackedFace {
                            landmarks_px: face
                                .landmarks
                                .points
                                .iter()
                                .map(|p| [p[0] as f64, p[1] as f64])
                                .collect(),
                            geometry,
                            face_box: face.bbox,
                        })
                    }
                    Err(e) => {
                        config
                            .progress
                            .suspend(|| eprintln!("warning: {}: no metric fit: {e}", frame.source));
                        None
                    }
                };
                faces_json.push(json);
                tracked
            }
            None => {
                config
                    .progress
                    .suspend(|| eprintln!("warning: {}: no face found; no mesh", frame.source));
                None
            }
        };
        let fit_ms = t.elapsed().as_secs_f64() * 1e3;
        let landmarks_json = serde_json::json!({
            "source": frame.source,
            "index": frame.index,
            "width": w,
            "height": h,
            "faces": faces_json,
        });
        let tracked = Tracked {
            index: frame.index,
            source: frame.source,
            decode_ms,
            track_ms,
            fit_ms,
            detector_ran: step.detector_ran,
            face,
            landmarks_json,
        };
        if out.send(tracked).is_err() {
            return Ok(());
        }
    }
    Ok(())
}

/// Clip mode: the frames of one track (no face lost in between) and their indices.
type ClipSegment = Vec<(usize, ClipFrame)>;

fn fuse_stage(
    config: &RunConfig<'_>,
    mut fusion: SurfaceFusion,
    input: Receiver<Tracked>,
    out: SyncSender<ToWriter>,
    recycle: Receiver<Box<Surfaces>>,
) -> anyhow::Result<()> {
    let mut topology_sent = false;
    let mut segments: Vec<ClipSegment> = vec![Vec::new()];
    for t in input {
        let mut ms = StageTimes {
            decode: t.decode_ms,
            track: t.track_ms,
            fit: t.fit_ms,
            ..StageTimes::default()
        };
        let mut metrics = FrameMetrics {
            index: t.index,
            source: t.source,
            status: RunStatus::NoFace,
            detector_ran: t.detector_ran,
            ms,
            valid_fraction: 0.0,
            relative_residual: 0.0,
            quality: FrameQuality::default(),
            reprojection_px: None,
            reprojection_raw_px: None,
            pose: None,
            fit_rms_px: None,
        };
        let Some(face) = t.face else {
            fusion.reset();
            if segments.last().is_some_and(|s| !s.is_empty()) {
                segments.push(Vec::new());
            }
            if out
                .send(ToWriter::Frame {
                    metrics: Box::new(metrics),
                    landmarks_json: t.landmarks_json,
                    surfaces: None,
                })
                .is_err()
            {
                return Ok(());
            }
            continue;
        };
        metrics.pose = Some(PoseMetrics::of(&face.geometry.pose));
        metrics.fit_rms_px = Some(face.geometry.rms_px);
        let start = Instant::now();
        let dir_map = match &config.depth {
            DepthSource::Dir(seq) => Some(read_depth(seq, t.index, &config.k)?),
            DepthSource::Face => None,
        };
        let needs_render = fusion.needs_face_mask()
            || (matches!(fusion.mesh(), MeshKind::Image) && dir_map.is_none());
        let rendered = if needs_render {
            Some(
                render_faces_depth(
                    std::slice::from_ref(&face.geometry),
                    config.canonical,
                    &config.k,
                    DepthKind::Z,
                )
                .with_context(|| format!("{}: face depth", metrics.source))?,
            )
        } else {
            None
        };
        ms.depth = start.elapsed().as_secs_f64() * 1e3;
        let depth_map = match (&dir_map, fusion.mesh()) {
            (Some(map), _) => Some(map),
            (None, MeshKind::Image) => rendered.as_ref(),
            (None, MeshKind::Face) => None,
        };
        let start = Instant::now();
        let fused = fusion
            .process(&FaceFrame {
                landmarks_px: &face.landmarks_px,
                pose: face.geometry.pose,
                metric_landmarks: &face.geometry.metric_landmarks,
                depth_map,
                face_mask: rendered.as_ref().map(|r| (r, face.face_box)),
            })
            .with_context(|| format!("{}: fusion", metrics.source))?;
        ms.fuse = start.elapsed().as_secs_f64() * 1e3;
        metrics.ms = ms;
        metrics.status = match fused.status {
            FrameStatus::Solved => RunStatus::Solved,
            FrameStatus::Carried => RunStatus::Carried,
            FrameStatus::NoData => RunStatus::NoData,
        };
        metrics.valid_fraction = fused.valid_fraction;
        metrics.relative_residual = fused.relative_residual;
        metrics.quality = FrameQuality::of(&fused.raw_quality, &fused.fused_quality);
        if !topology_sent {
            if let Some(tri) = fusion.triangles() {
                if out.send(ToWriter::Topology(tri.to_vec())).is_err() {
                    return Ok(());
                }
                topology_sent = true;
            }
        }
        let mut surfaces = None;
        if metrics.has_mesh() {
            match config.mode {
                TemporalMode::Streaming => {
                    let mut s = recycle.try_recv().unwrap_or_default();
                    fill_surfaces(&fusion, &face.landmarks_px, &mut s);
                    surfaces = Some(s);
                }
                TemporalMode::Clip => {
                    if let Some(segment) = segments.last_mut() {
                        segment.push((t.index, fusion.clip_frame(&face.landmarks_px)));
                    }
                }
            }
        }
        let message = ToWriter::Frame {
            metrics: Box::new(metrics),
            landmarks_json: t.landmarks_json,
            surfaces,
        };
        if out.send(message).is_err() {
            return Ok(());
        }
    }
    if config.mode == TemporalMode::Clip {
        for segment in segments.into_iter().filter(|s| !s.is_empty()) {
            let start = Instant::now();
            let (indices, mut frames): (Vec<usize>, Vec<ClipFrame>) = segment.into_iter().unzip();
            let report = fusion.solve_clip(&mut frames, &config.clip);
            let share = start.elapsed().as_secs_f64() * 1e3 / frames.len() as f64;
            for (index, frame) in indices.into_iter().zip(&frames) {
                let (raw_q, fused_q) = fusion.load_clip_frame(frame);
                let mut s = recycle.try_recv().unwrap_or_default();
                fill_surfaces(&fusion, &frame.landmarks_px, &mut s);
                let message = ToWriter::ClipSurfaces {
                    index,
                    surfaces: s,
                    quality: FrameQuality::of(&raw_q, &fused_q),
                    relative_residual: report.relative_residual,
                    extra_fuse_ms: share,
                };
                if out.send(message).is_err() {
                    return Ok(());
                }
            }
        }
    }
    Ok(())
}

fn fill_surfaces(fusion: &SurfaceFusion, landmarks_px: &[[f64; 2]], s: &mut Surfaces) {
    s.fused.clear();
    s.fused.extend_from_slice(fusion.fused());
    s.raw.clear();
    s.raw.extend_from_slice(fusion.raw());
    s.landmarks_px.clear();
    s.landmarks_px.extend_from_slice(landmarks_px);
    fusion.landmark_points(landmarks_px, &mut s.fused_landmarks, &mut s.raw_landmarks);
}

fn read_depth(seq: &DepthSequence, index: usize, k: &Intrinsics) -> anyhow::Result<DepthMap> {
    if index >= seq.frames.len() {
        anyhow::bail!(
            "{}: holds {} depth frames; input frame {index} has none",
            seq.dir.display(),
            seq.frames.len()
        );
    }
    let map = seq.read(index)?;
    k.check_size(map.width, map.height)
        .with_context(|| format!("{}: depth frame", seq.frames[index].display()))?;
    Ok(map)
}

/// The last stage: meshes, `landmarks.json`, progress, metrics and quality figures.
struct Writer<'a> {
    config: &'a RunConfig<'a>,
    mesh: TriMesh,
    frames: Vec<FrameMetrics>,
    quality: QualityMeter,
    /// Position in `frames` of the last frame whose surfaces were measured.
    last_measured: Option<usize>,
    vertices: usize,
    landmarks: Option<(PathBuf, BufWriter<File>, bool)>,
}

impl<'a> Writer<'a> {
    fn new(config: &'a RunConfig<'a>) -> Self {
        Writer {
            config,
            mesh: TriMesh::new(Vec::new(), Vec::new()),
            frames: Vec::new(),
            quality: QualityMeter::default(),
            last_measured: None,
            vertices: 0,
            landmarks: None,
        }
    }

    fn run(
        &mut self,
        input: Receiver<ToWriter>,
        recycle: SyncSender<Box<Surfaces>>,
    ) -> anyhow::Result<()> {
        if let Output::Files { dir, .. } = &self.config.output {
            let path = dir.join("landmarks.json");
            let tmp = dir.join("landmarks.json.tmp");
            let file =
                File::create(&tmp).with_context(|| format!("cannot write {}", tmp.display()))?;
            let mut w = BufWriter::new(file);
            w.write_all(b"{\"frames\": [")
                .with_context(|| format!("cannot write {}", tmp.display()))?;
            self.landmarks = Some((path, w, true));
        }
        for message in input {
            match message {
                ToWriter::Topology(triangles) => self.mesh.triangles = triangles,
                ToWriter::Frame {
                    metrics,
                    landmarks_json,
                    surfaces,
                } => {
                    let start = Instant::now();
                    self.write_landmarks(&landmarks_json)?;
                    self.frames.push(*metrics);
                    let position = self.frames.len() - 1;
                    if let Some(s) = surfaces {
                        self.write_surfaces(position, &s)?;
                        let _ = recycle.try_send(s);
                    }
                    self.frames[position].ms.write += start.elapsed().as_secs_f64() * 1e3;
                    self.config.progress.inc(1);
                }
                ToWriter::ClipSurfaces {
                    index,
                    surfaces,
                    quality,
                    relative_residual,
                    extra_fuse_ms,
                } => {
                    let start = Instant::now();
                    let Ok(position) = self.frames.binary_search_by_key(&index, |f| f.index) else {
                        continue;
                    };
                    let m = &mut self.frames[position];
                    m.quality = quality;
                    m.relative_residual = relative_residual;
                    m.ms.fuse += extra_fuse_ms;
                    self.write_surfaces(position, &surfaces)?;
                    let _ = recycle.try_send(surfaces);
                    self.frames[position].ms.write += start.elapsed().as_secs_f64() * 1e3;
                }
            }
        }
        Ok(())
    }

    fn write_landmarks(&mut self, json: &Value) -> anyhow::Result<()> {
        let Some((path, w, first)) = &mut self.landmarks else {
            return Ok(());
        };
        if !*first {
            w.write_all(b",")?;
        }
        *first = false;
        serde_json::to_writer(&mut *w, json)
            .with_context(|| format!("cannot write {}.tmp", path.display()))
    }

    /// Measures a meshed frame and writes its mesh(es).
    fn write_surfaces(&mut self, position: usize, s: &Surfaces) -> anyhow::Result<()> {
        if self.last_measured.is_none_or(|p| p + 1 != position) {
            self.quality.gap();
        }
        self.last_measured = Some(position);
        self.vertices = s.fused.len();
        let (f, r) = self.quality.push(
            &self.config.k,
            &s.fused,
            &s.raw,
            &s.fused_landmarks,
            &s.raw_landmarks,
            &s.landmarks_px,
        );
        let m = &mut self.frames[position];
        m.reprojection_px = f;
        m.reprojection_raw_px = r;
        let Output::Files {
            dir,
            save_raw,
            format,
        } = &self.config.output
        else {
            return Ok(());
        };
        let name = format!("{:06}.ply", m.index);
        let targets = [("meshes", &s.fused, true), ("raw", &s.raw, *save_raw)];
        for (sub, vertices, wanted) in targets {
            if !wanted {
                continue;
            }
            self.mesh.vertices.clear();
            self.mesh.vertices.extend_from_slice(vertices);
            let path = dir.join(sub).join(&name);
            write_atomically(&path, |p| write_ply_with(p, &self.mesh, *format))
                .with_context(|| format!("cannot write {}", path.display()))?;
        }
        Ok(())
    }

    /// Closes `landmarks.json` (valid JSON with the frames so far, also after a failure).
    fn finish(&mut self) -> anyhow::Result<()> {
        let Some((path, mut w, _)) = self.landmarks.take() else {
            return Ok(());
        };
        let tmp = tmp_path(&path);
        w.write_all(b"]}\n")
            .and_then(|()| w.flush())
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        drop(w);
        std::fs::rename(&tmp, &path).with_context(|| format!("cannot write {}", path.display()))
    }
}

fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}
