//! The staged whole-clip run ([`crate::Reconstructor::run`]): six stages on their own
//! threads, joined by bounded queues ([`QUEUE_CAPACITY`] frames each), and the sink on the
//! calling thread, frames in input order:
//!
//! ```text
//! decode ──► track + landmarks + rigid fit ──► eyes + model fit ──► keypoint check
//!        ──► depth maps (folder, recording, network) ──► fuse ──► sink
//! ```
//!
//! (The keypoint check and the depth maps pass frames straight on unless they are on.)
//!
//! Memory is flat in the clip length in streaming mode: at most `QUEUE_CAPACITY` frames wait
//! in each queue (and the landmark smoother's latency in the face stage), surface buffers travel back from the sink to the fusion for reuse, and the
//! fusion step allocates nothing (face mesh). What grows is the per-frame record (a few
//! hundred bytes a frame). Clip mode keeps every frame's right-hand side and streaming
//! solution until the end (≈ 9 · 8 bytes per vertex and frame), then solves each face track
//! and hands the meshes to the sink.
//!
//! Errors: a stage that fails stops and drops its queue; the stages after it finish what they
//! received (the sink keeps what it got), the stages before it stop when their next send
//! fails. The first error in pipeline order is the run's error.

use std::collections::VecDeque;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};
use std::time::Instant;

use visage_camera::Intrinsics;
use visage_fem::{ClipOptions, SurfaceQuality};
use visage_fusion::ClipFrame;
use visage_morphable::FaceFitter;
use visage_video::{Frame, FramePool};

use crate::depth_stage::DepthStage;
use crate::input::Decoded;
use crate::keypoint_motion::KeypointMotion;
use crate::process_stats::{cpu_seconds, peak_rss_mib};
use crate::recorder::Recorder;
use crate::sink::FrameSink;
use crate::stages::{FaceStage, FuseStage, ModelStage, Surfaces, Tracked};
use crate::{Error, Input, TemporalMode};
use visage_rig::BlendshapeFrame;
use visage_run_folder::LandmarksFrame;
use visage_run_folder::{FrameMetrics, FrameQuality, RunTiming};

/// Frames waiting between two stages.
pub const QUEUE_CAPACITY: usize = 3;

enum ToSink {
    /// The mesh's triangles, sent once before its first surface.
    Topology(Vec<[u32; 3]>),
    /// A frame, with its surfaces when its mesh is final now (streaming mode).
    Frame {
        metrics: Box<FrameMetrics>,
        landmarks: Box<LandmarksFrame>,
        warning: Option<String>,
        blendshapes: Option<Box<BlendshapeFrame>>,
        surfaces: Option<Box<Surfaces>>,
    },
    /// Clip mode, after the clip solve: a frame's final surfaces.
    ClipSurfaces {
        index: usize,
        surfaces: Box<Surfaces>,
        quality: (SurfaceQuality, SurfaceQuality),
        relative_residual: f64,
        extra_fuse_ms: f64,
    },
}

/// What the stages run with.
pub(crate) struct Stages {
    pub face: FaceStage,
    pub model: Option<ModelStage>,
    pub keypoints: Option<KeypointMotion>,
    pub depth: Option<DepthStage>,
    pub fuse: FuseStage,
    pub mode: TemporalMode,
    pub clip: ClipOptions,
}

/// Runs `input` through the stages into `sink`, recording into `recorder`. Returns the wall
/// and CPU time and the first error.
pub(crate) fn run_stages(
    stages: Stages,
    input: Input,
    recorder: &mut Recorder,
    triangles: &mut Vec<[u32; 3]>,
    sink: &mut dyn FrameSink,
) -> (RunTiming, Option<Error>, Option<FaceFitter>) {
    let start = Instant::now();
    let cpu_start = cpu_seconds();
    let Stages {
        mut face,
        mut model,
        mut keypoints,
        mut depth,
        mut fuse,
        mode,
        clip,
    } = stages;
    let k = face.k;
    let (decoded_tx, decoded_rx) = sync_channel::<Decoded>(QUEUE_CAPACITY);
    let (tracked_tx, tracked_rx) = sync_channel::<(Tracked, Frame)>(QUEUE_CAPACITY);
    let (depth_tx, depth_rx) = sync_channel::<Tracked>(QUEUE_CAPACITY);
    let (fused_tx, fused_rx) = sync_channel::<ToSink>(QUEUE_CAPACITY);
    let (recycle_tx, recycle_rx) = sync_channel::<Box<Surfaces>>(2 * QUEUE_CAPACITY + 2);
    let mut consumer = Consumer {
        k,
        clip_mode: mode == TemporalMode::Clip,
        pending: VecDeque::new(),
        recorder,
        triangles,
        uvs: fuse.fusion.uvs().to_vec(),
        sink,
    };
    let (errors, sink_error) = std::thread::scope(|scope| {
        // Frames the later stages are done with go back to the decoder's buffers.
        let pool = input.frame_pool();
        let decode = scope.spawn(move || decode_stage(input, decoded_tx));
        let face = &mut face;
        let track = scope.spawn(move || track_stage(face, decoded_rx, tracked_tx));
        let model = &mut model;
        let depth_images = depth.as_ref().is_some_and(DepthStage::needs_image);
        let keep_frames = keypoints.is_some() || depth_images;
        // Without keypoints and outside depth maps, the model stage hands its frames straight
        // to the fusion: two threads fewer to wake per frame.
        let direct = keypoints.is_none() && depth.is_none();
        let (modelling, checking, depth_maps) = if direct {
            let to_fusion =
                move |(tracked, _): (Tracked, Option<Frame>)| depth_tx.send(tracked).is_ok();
            let modelling =
                scope.spawn(move || model_stage(model, false, pool, tracked_rx, to_fusion));
            (modelling, None, None)
        } else {
            let (modelled_tx, modelled_rx) = sync_channel(QUEUE_CAPACITY);
            let (checked_tx, checked_rx) = sync_channel(QUEUE_CAPACITY);
            let to_checks = move |item| modelled_tx.send(item).is_ok();
            let model_pool = pool.clone();
            let modelling = scope
                .spawn(move || model_stage(model, keep_frames, model_pool, tracked_rx, to_checks));
            let keypoints = &mut keypoints;
            let keypoint_pool = pool.clone();
            let checking = scope.spawn(move || {
                keypoint_stage(
                    keypoints,
                    depth_images,
                    keypoint_pool,
                    modelled_rx,
                    checked_tx,
                )
            });
            let depth = &mut depth;
            let depth_maps = scope.spawn(move || depth_stage(depth, pool, checked_rx, depth_tx));
            (modelling, Some(checking), Some(depth_maps))
        };
        let fusion =
            scope.spawn(move || fuse_stage(&mut fuse, mode, &clip, depth_rx, fused_tx, recycle_rx));
        let sink_error = consumer.run(fused_rx, recycle_tx).err();
        let join = |h: std::thread::ScopedJoinHandle<'_, Result<(), Error>>, name| {
            h.join().unwrap_or(Err(Error::Panic(name))).err()
        };
        (
            [
                join(decode, "decode"),
                join(track, "tracking"),
                join(modelling, "model"),
                checking.and_then(|h| join(h, "keypoints")),
                depth_maps.and_then(|h| join(h, "depth")),
                join(fusion, "fusion"),
            ],
            sink_error,
        )
    });
    let error = errors.into_iter().flatten().next().or(sink_error);
    let timing = RunTiming {
        wall_s: start.elapsed().as_secs_f64(),
        setup_ms: 0.0,
        cpu_s: cpu_seconds().zip(cpu_start).map(|(b, a)| b - a),
        peak_rss_mib: peak_rss_mib(),
    };
    (timing, error, model.map(|m| m.fitter))
}

fn decode_stage(mut input: Input, out: SyncSender<Decoded>) -> Result<(), Error> {
    while let Some(decoded) = input.next_decoded() {
        if out.send(decoded?).is_err() {
            return Ok(()); // a later stage stopped
        }
    }
    Ok(())
}

fn track_stage(
    face: &mut FaceStage,
    input: Receiver<Decoded>,
    out: SyncSender<(Tracked, Frame)>,
) -> Result<(), Error> {
    for Decoded { frame, decode_ms } in input {
        for done in face.track(frame, decode_ms)? {
            if out.send(done).is_err() {
                return Ok(());
            }
        }
    }
    for done in face.finish()? {
        if out.send(done).is_err() {
            return Ok(());
        }
    }
    Ok(())
}

/// Hands `frame` back to the decoder's buffers, when it has them.
fn recycle(pool: &Option<FramePool>, frame: Frame) {
    if let Some(pool) = pool {
        pool.recycle(frame);
    }
}

/// The model fit; the frame goes on only when the keypoint check needs it (else back to
/// `pool`). `out` hands a frame to the next stage, `false` when that stage has stopped.
fn model_stage(
    model: &mut Option<ModelStage>,
    keep_frames: bool,
    pool: Option<FramePool>,
    input: Receiver<(Tracked, Frame)>,
    mut out: impl FnMut((Tracked, Option<Frame>)) -> bool,
) -> Result<(), Error> {
    for (mut tracked, frame) in input {
        if let Some(model) = model {
            model.fit(&frame.image, &mut tracked)?;
        }
        let frame = if keep_frames {
            Some(frame)
        } else {
            recycle(&pool, frame);
            None
        };
        if !out((tracked, frame)) {
            return Ok(()); // a later stage stopped
        }
    }
    Ok(())
}

/// The keypoint check, on its own thread (it costs about as much as the model fit); without
/// it, a pass-through. The frame goes on only when `keep_frames` (a depth network needs it;
/// else back to `pool`).
fn keypoint_stage(
    keypoints: &mut Option<KeypointMotion>,
    keep_frames: bool,
    pool: Option<FramePool>,
    input: Receiver<(Tracked, Option<Frame>)>,
    out: SyncSender<(Tracked, Option<Frame>)>,
) -> Result<(), Error> {
    for (mut tracked, frame) in input {
        if let (Some(keypoints), Some(frame)) = (keypoints.as_mut(), &frame) {
            keypoints.observe(&frame.image, &mut tracked);
        }
        let frame = match frame {
            Some(frame) if !keep_frames => {
                recycle(&pool, frame);
                None
            }
            frame => frame,
        };
        if out.send((tracked, frame)).is_err() {
            return Ok(());
        }
    }
    Ok(())
}

/// The depth maps from outside the face fit, on their own thread (a depth network is the
/// costliest stage); without them, a pass-through.
fn depth_stage(
    depth: &mut Option<DepthStage>,
    pool: Option<FramePool>,
    input: Receiver<(Tracked, Option<Frame>)>,
    out: SyncSender<Tracked>,
) -> Result<(), Error> {
    for (mut tracked, frame) in input {
        if let Some(depth) = depth.as_mut() {
            depth.acquire(frame.as_ref().map(|f| &f.image), &mut tracked)?;
        }
        if let Some(frame) = frame {
            recycle(&pool, frame);
        }
        if out.send(tracked).is_err() {
            return Ok(());
        }
    }
    Ok(())
}

/// Clip mode: a face track's frames (input index, fusion state, the landmarks as tracked).
type ClipSegment = Vec<(usize, ClipFrame, Vec<[f64; 2]>)>;

fn fuse_stage(
    fuse: &mut FuseStage,
    mode: TemporalMode,
    clip: &ClipOptions,
    input: Receiver<Tracked>,
    out: SyncSender<ToSink>,
    recycle: Receiver<Box<Surfaces>>,
) -> Result<(), Error> {
    let mut segments: Vec<ClipSegment> = vec![Vec::new()];
    let mut topology_sent = false;
    for mut tracked in input {
        fuse.fuse(&mut tracked)?;
        if !topology_sent {
            if let Some(triangles) = fuse.fusion.triangles() {
                if out.send(ToSink::Topology(triangles.to_vec())).is_err() {
                    return Ok(());
                }
                topology_sent = true;
            }
        }
        let mut surfaces = None;
        // A lost face or a cut ends the clip solve's segment: no temporal coupling across.
        if (tracked.face.is_none() || tracked.cut) && segments.last().is_some_and(|s| !s.is_empty())
        {
            segments.push(Vec::new());
        }
        match (&tracked.face, mode) {
            (None, _) => {}
            (Some(face), TemporalMode::Streaming) if tracked.metrics.has_mesh() => {
                let mut s = recycle.try_recv().unwrap_or_default();
                fuse.fill_surfaces(&face.landmarks_px, &face.tracked_px, &mut s);
                surfaces = Some(s);
            }
            (Some(face), TemporalMode::Clip) if tracked.metrics.has_mesh() => {
                if let Some(segment) = segments.last_mut() {
                    segment.push((
                        tracked.metrics.index,
                        fuse.clip_frame(&face.landmarks_px),
                        face.tracked_px.clone(),
                    ));
                }
            }
            (Some(_), _) => {}
        }
        let message = ToSink::Frame {
            metrics: Box::new(tracked.metrics),
            landmarks: Box::new(tracked.landmarks),
            warning: tracked.warning,
            blendshapes: tracked.blendshapes.map(Box::new),
            surfaces,
        };
        if out.send(message).is_err() {
            return Ok(());
        }
    }
    for segment in segments.into_iter().filter(|s| !s.is_empty()) {
        let start = Instant::now();
        let mut indices = Vec::with_capacity(segment.len());
        let mut frames = Vec::with_capacity(segment.len());
        let mut tracked = Vec::with_capacity(segment.len());
        for (index, frame, tracked_px) in segment {
            indices.push(index);
            frames.push(frame);
            tracked.push(tracked_px);
        }
        let report = fuse.fusion.solve_clip(&mut frames, clip);
        let share = start.elapsed().as_secs_f64() * 1e3 / frames.len() as f64;
        for ((index, frame), tracked_px) in indices.into_iter().zip(&frames).zip(&tracked) {
            let quality = fuse.fusion.load_clip_frame(frame);
            let mut s = recycle.try_recv().unwrap_or_default();
            fuse.fill_surfaces(&frame.landmarks_px, tracked_px, &mut s);
            let message = ToSink::ClipSurfaces {
                index,
                surfaces: s,
                quality,
                relative_residual: report.relative_residual,
                extra_fuse_ms: share,
            };
            if out.send(message).is_err() {
                return Ok(());
            }
        }
    }
    Ok(())
}

/// The calling thread's part: records, quality figures, the sink.
struct Consumer<'a> {
    k: Intrinsics,
    clip_mode: bool,
    /// Clip mode: landmarks records in input order, each waiting (`true`) for its frame's
    /// clip-solved surface (its fused landmarks) or ready.
    pending: VecDeque<(Box<LandmarksFrame>, bool)>,
    recorder: &'a mut Recorder,
    triangles: &'a mut Vec<[u32; 3]>,
    /// Texture coordinates per vertex (empty: none).
    uvs: Vec<[f64; 2]>,
    sink: &'a mut dyn FrameSink,
}

impl Consumer<'_> {
    fn run(
        &mut self,
        input: Receiver<ToSink>,
        recycle: SyncSender<Box<Surfaces>>,
    ) -> Result<(), Error> {
        for message in input {
            match message {
                ToSink::Topology(triangles) => *self.triangles = triangles,
                ToSink::Frame {
                    metrics,
                    landmarks,
                    warning,
                    blendshapes,
                    surfaces,
                } => {
                    let start = Instant::now();
                    if let Some(w) = &warning {
                        self.sink.warning(w);
                    }
                    let mut landmarks = landmarks;
                    if let Some(s) = &surfaces {
                        landmarks.set_fused(&self.k, &s.fused_landmarks);
                    }
                    let waits = self.clip_mode && metrics.has_mesh();
                    if waits || !self.pending.is_empty() {
                        self.pending.push_back((landmarks, waits));
                    } else {
                        self.sink.landmarks(&landmarks)?;
                    }
                    if let Some(b) = &blendshapes {
                        self.sink.blendshapes(b)?;
                    }
                    let position = self.recorder.push(*metrics);
                    if let Some(s) = surfaces {
                        self.mesh(position, &s)?;
                        let _ = recycle.try_send(s);
                    }
                    let m = &mut self.recorder.frames[position];
                    m.ms.write += start.elapsed().as_secs_f64() * 1e3;
                    self.sink.frame_done(m);
                }
                ToSink::ClipSurfaces {
                    index,
                    surfaces,
                    quality,
                    relative_residual,
                    extra_fuse_ms,
                } => {
                    let start = Instant::now();
                    let Some(position) = self.recorder.position(index) else {
                        continue;
                    };
                    let m = &mut self.recorder.frames[position];
                    m.quality = FrameQuality::of(&quality.0, &quality.1);
                    m.relative_residual = relative_residual;
                    m.ms.fuse += extra_fuse_ms;
                    self.mesh(position, &surfaces)?;
                    if let Some(entry) = self.pending.iter_mut().find(|(l, _)| l.index == index) {
                        entry.0.set_fused(&self.k, &surfaces.fused_landmarks);
                        entry.1 = false;
                    }
                    self.flush_landmarks(false)?;
                    let _ = recycle.try_send(surfaces);
                    self.recorder.frames[position].ms.write += start.elapsed().as_secs_f64() * 1e3;
                }
            }
        }
        self.flush_landmarks(true)
    }

    /// Hands the waiting landmarks records that are ready (`all`: every one) to the sink.
    fn flush_landmarks(&mut self, all: bool) -> Result<(), Error> {
        while self.pending.front().is_some_and(|(_, waits)| all || !waits) {
            if let Some((landmarks, _)) = self.pending.pop_front() {
                self.sink.landmarks(&landmarks)?;
            }
        }
        Ok(())
    }

    /// Measures a meshed frame and hands it to the sink.
    fn mesh(&mut self, position: usize, s: &Surfaces) -> Result<(), Error> {
        let (k, triangles, uvs) = (&self.k, &self.triangles[..], &self.uvs);
        self.recorder
            .mesh(position, k, s, triangles, uvs, &mut *self.sink)
    }
}
