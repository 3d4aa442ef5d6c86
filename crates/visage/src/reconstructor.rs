//! [`Reconstructor`]: frames in, a fused metric face mesh per frame out — one frame at a time
//! ([`Reconstructor::process`]) or a whole input on threads ([`Reconstructor::run`]).

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

use visage_camera::Intrinsics;
use visage_face::{model_files, CanonicalMesh, FaceMesh, FaceTracker};
use visage_fusion::{FaceTemplate, LandmarkAnchor, MeshKind, SurfaceFusion};
use visage_mesh::TriMesh;
use visage_morphable::{CanonicalCorrespondence, FaceFitter, FaceModel, IctModel};
use visage_video::Frame;

use crate::config::{Builder, ModelSource, Parameters};
use crate::depth_stage::DepthStage;
use crate::keypoint_motion::KeypointMotion;
use crate::pipeline::{run_stages, Stages};
use crate::recorder::Recorder;
use crate::stages::{FaceStage, FuseStage, FusedDepth, Irises, ModelStage, Surfaces, Tracked};
use crate::{DepthSource, Error, FrameSink, Input, TemporalMode};
use visage_face::CutDetector;
use visage_face::{
    DistanceSmoother, LandmarkSmoother, CLIP_LATENCY_FRAMES, DEFAULT_DISTANCE_SMOOTHING,
};
use visage_rig::EyeRig;
use visage_rig::RestPose;
use visage_rig::{BlendshapeFrame, IctToArkit, MouthLeak, PoseLeak};
use visage_run_folder::LandmarksFrame;
use visage_run_folder::{FrameMetrics, MeshSummary, Report, RunStatus, RunSummary, RunTiming};

/// The video pipeline: face tracking, landmarks and the metric face fit, depth, and fusion into
/// a temporally stable metric surface on a fixed mesh. Set up once ([`Reconstructor::builder`]:
/// models loaded, operators assembled and factored), then fed frames.
pub struct Reconstructor {
    face: FaceStage,
    fuse: FuseStage,
    mode: TemporalMode,
    clip: visage_fem::ClipOptions,
    parameters: Parameters,
    /// The fitted morphable model and its stage, if any.
    model: Option<Arc<FaceModel>>,
    model_stage: Option<ModelStage>,
    /// The keypoint check of the head's motion, when on.
    keypoints: Option<KeypointMotion>,
    /// The depth maps from outside the face fit, when the depth source gives them.
    depth: Option<DepthStage>,
    setup_ms: f64,
    recorder: Recorder,
    /// The last frame's results (reused buffers).
    surfaces: Surfaces,
    mesh: TriMesh,
    landmarks: Option<LandmarksFrame>,
    warning: Option<String>,
    blendshapes: Option<BlendshapeFrame>,
    irises: Option<Irises>,
    /// Frames [`Reconstructor::push`] tracked, waiting for the rest of the pipeline.
    pending: VecDeque<(Tracked, Frame)>,
}

/// One frame's results from [`Reconstructor::process`].
#[derive(Debug)]
pub struct FrameResult<'a> {
    /// Status, stage times, solver and surface figures, head pose.
    pub metrics: &'a FrameMetrics,
    /// The tracked face (468 landmarks, frame pixels) and its metric head pose.
    pub landmarks: &'a LandmarksFrame,
    /// Why the frame has no mesh, or a problem worth a warning.
    pub warning: Option<&'a str>,
    /// ARKit blendshape weights and head rotation of the morphable-model fit.
    pub blendshapes: Option<&'a BlendshapeFrame>,
    /// The irises, when the model is fitted and the iris network's file is present.
    pub irises: Option<&'a Irises>,
    mesh: Option<&'a TriMesh>,
    surfaces: Option<&'a Surfaces>,
}

impl<'a> FrameResult<'a> {
    /// Input frame index.
    pub fn index(&self) -> usize {
        self.metrics.index
    }

    /// The fused metric mesh (camera coordinates: x right, y down, z forward; metres), when
    /// the frame has one.
    pub fn mesh(&self) -> Option<&'a TriMesh> {
        self.mesh
    }

    /// Fused and raw surfaces, on the mesh and at the landmarks, when the frame has a mesh.
    pub fn surfaces(&self) -> Option<&'a Surfaces> {
        self.surfaces
    }
}

/// What a whole-input run did.
pub struct RunOutcome {
    /// Per-frame records, in input order (those of earlier `process` calls included).
    pub frames: Vec<FrameMetrics>,
    pub summary: RunSummary,
    /// The error that stopped the run; the frames before it were processed and handed over.
    pub error: Option<Error>,
    pub parameters: Parameters,
    pub intrinsics: Intrinsics,
    pub mesh: MeshSummary,
    /// This person's fitted identity (when the model was fitted to at least one frame).
    pub identity: Option<Identity>,
}

/// The identity the fit settled on: coefficients of the model's identity modes and the
/// neutral face they give.
#[derive(Clone, Debug)]
pub struct Identity {
    /// Weights of the identity modes (~ N(0, 1) a priori).
    pub coefficients: Vec<f64>,
    /// Frames whose landmarks went into it.
    pub frames: usize,
    model: Arc<FaceModel>,
}

impl Identity {
    /// The fitted neutral face: the model's face region with this identity and no expression,
    /// metres, in the model frame (x to the subject's left, y up, the face looking along +z),
    /// with the model's UVs.
    pub fn neutral_mesh(&self) -> TriMesh {
        let mut vertices = Vec::new();
        self.model.shape(&self.coefficients, &[], &mut vertices);
        TriMesh {
            uvs: self.model.uvs.iter().map(|t| t.map(f64::from)).collect(),
            ..TriMesh::new(vertices, self.model.triangles.clone())
        }
    }
}

impl RunOutcome {
    /// The `metrics.json` record of the run of `input`.
    pub fn report(&self, input: &str) -> Report<&Parameters> {
        Report {
            status: match &self.error {
                None => RunStatus::Complete,
                Some(Error::Interrupted) => RunStatus::Interrupted,
                Some(_) => RunStatus::Failed,
            },
            error: self.error.as_ref().map(|e| error_chain(e)),
            input: input.to_owned(),
            intrinsics: self.intrinsics,
            parameters: &self.parameters,
            selection: None,
            resumed: None,
            mesh: self.mesh.clone(),
            solver: None,
            summary: self.summary.clone(),
            frames: self.frames.clone(),
        }
    }
}

/// An error and its causes, `: `-separated; a cause whose text the message already ends with
/// (many errors quote their source) is not repeated.
pub fn error_chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let part = c.to_string();
        if !text.ends_with(&part) {
            // "cannot write F" then "F: reason": F once.
            let named = part
                .match_indices(": ")
                .map(|(i, _)| i)
                .find(|&i| text.ends_with(&part[..i]));
            text.push_str(": ");
            text.push_str(named.map_or(&part[..], |i| &part[i + 2..]));
        }
        cause = c.source();
    }
    text
}

impl Reconstructor {
    /// Options with defaults; finish with [`Builder::build`] or [`Builder::build_for`].
    pub fn builder() -> Builder {
        Builder::default()
    }

    pub(crate) fn new(
        builder: Builder,
        k: Intrinsics,
        fps: Option<f64>,
    ) -> Result<Reconstructor, Error> {
        let start = Instant::now();
        let params = builder.fusion_params()?;
        let smoothing = builder.checked_smoothing()?;
        let latency = match builder.mode {
            TemporalMode::Streaming => builder.latency,
            TemporalMode::Clip => builder.latency.max(CLIP_LATENCY_FRAMES),
        };
        let uses_model =
            params.mesh == MeshKind::Model || matches!(builder.depth, DepthSource::Model);
        if uses_model && matches!(builder.model, ModelSource::None) {
            return Err(Error::InvalidOption {
                name: "--mesh/--depth",
                value: "model".into(),
                reason: "the model mesh and the model depth need the face model fit",
            });
        }
        let models = builder
            .models
            .clone()
            .unwrap_or_else(model_files::models_dir);
        let canonical = Arc::new(CanonicalMesh::load(&models)?);
        let mut mesh = FaceMesh::load(&models)?;
        // The eyes run in the model stage (its own thread in `run`), not in the tracker.
        let iris = mesh.iris.take().map(|net| [net.clone(), net]);
        let mut tracker = FaceTracker::new(mesh);
        tracker.target = builder.face_target;
        let model_name = builder.model.describe();
        let model = match builder.model {
            ModelSource::Embedded => Some(FaceModel::embedded()),
            ModelSource::IctFolder(dir) => {
                let ict = IctModel::load(&dir)?;
                let landmarks = CanonicalCorrespondence::new(&ict, &canonical.vertices)?;
                Some(FaceModel::from_ict(&ict, &landmarks)?)
            }
            ModelSource::Given(m) => Some(*m),
            ModelSource::None => None,
        }
        .map(Arc::new);
        let fusion = match (&model, params.mesh) {
            (Some(m), MeshKind::Model) => {
                let vertices: Vec<[f64; 3]> = m.neutral.iter().map(|p| p.map(f64::from)).collect();
                let uvs: Vec<[f64; 2]> = m.uvs.iter().map(|t| t.map(f64::from)).collect();
                let landmarks: Vec<LandmarkAnchor> = m
                    .landmarks
                    .iter()
                    .zip(&m.landmark_offsets)
                    .map(|(p, o)| LandmarkAnchor {
                        triangle: p.triangle,
                        bary: p.bary,
                        offset: o.map(f64::from),
                    })
                    .collect();
                let template = FaceTemplate {
                    vertices: &vertices,
                    triangles: &m.triangles,
                    landmarks: Some(&landmarks),
                    uvs: &uvs,
                };
                SurfaceFusion::new(params, template, k)?
            }
            _ => {
                let template = FaceTemplate {
                    vertices: &canonical.vertices,
                    triangles: &canonical.triangles,
                    landmarks: None,
                    uvs: &canonical.uvs,
                };
                SurfaceFusion::new(params, template, k)?
            }
        };
        let parameters = Parameters {
            fusion: params,
            mode: builder.mode,
            depth: builder.depth.describe(),
            model: model_name,
            landmark_smoothing: smoothing,
            latency_frames: if smoothing.is_some() { latency } else { 0 },
            keypoint_motion: builder.keypoint_motion,
        };
        let model_mesh = TriMesh::new(
            Vec::new(),
            model
                .as_ref()
                .map_or_else(Vec::new, |m| m.triangles.clone()),
        );
        let model_stage = model.as_ref().map(|m| ModelStage {
            k,
            fitter: FaceFitter::new(m, builder.fit),
            to_arkit: IctToArkit::new(&m.expression_names),
            iris,
            rest: builder.rest_pose.then(|| RestPose::new(m)),
            pose_leak: builder.pose_leak.then(PoseLeak::embedded),
            mouth_leak: builder.mouth_leak.then(MouthLeak::embedded),
            weights: Vec::with_capacity(m.expressions.len()),
            // A depth network is aligned to the fitted model's surface.
            surface: (uses_model || builder.depth.needs_reference()).then(|| Arc::clone(m)),
            eyes: EyeRig::default(),
        });
        let fused_depth = match &builder.depth {
            DepthSource::Face => FusedDepth::Face,
            DepthSource::Model => FusedDepth::Model,
            _ => FusedDepth::Maps,
        };
        let depth = match builder.depth {
            DepthSource::Face | DepthSource::Model => None,
            DepthSource::Maps(provider) => Some(DepthStage::new(
                k,
                provider,
                params.max_depth_m,
                &canonical,
                &model_mesh,
            )),
        };
        let mut mesh = TriMesh::new(Vec::new(), Vec::new());
        if let Some(t) = fusion.triangles() {
            mesh.triangles = t.to_vec();
        }
        mesh.uvs = fusion.uvs().to_vec();
        Ok(Reconstructor {
            face: FaceStage {
                k,
                canonical: canonical.clone(),
                tracker,
                fps,
                smoother: smoothing.map(|r| LandmarkSmoother::new(r, latency)),
                cuts: CutDetector::default(),
                last_tracked: None,
                waiting: VecDeque::new(),
                distance: smoothing.map(|_| DistanceSmoother::new(DEFAULT_DISTANCE_SMOOTHING)),
                distance_track: false,
            },
            model_stage,
            model,
            keypoints: builder
                .keypoint_motion
                .then(|| KeypointMotion::new(k, Arc::clone(&canonical))),
            depth,
            fuse: FuseStage {
                k,
                canonical,
                depth: fused_depth,
                fusion,
                model_mesh,
            },
            mode: builder.mode,
            clip: builder.clip,
            parameters,
            setup_ms: start.elapsed().as_secs_f64() * 1e3,
            recorder: Recorder::default(),
            surfaces: Surfaces::default(),
            mesh,
            landmarks: None,
            warning: None,
            blendshapes: None,
            irises: None,
            pending: VecDeque::new(),
        })
    }

    /// The camera the meshes are in.
    pub fn intrinsics(&self) -> &Intrinsics {
        &self.face.k
    }

    /// The parameters, as `metrics.json` records them.
    pub fn parameters(&self) -> &Parameters {
        &self.parameters
    }

    /// Vertices of the mesh (the image-plane mesh: 0 before its first face).
    pub fn vertex_count(&self) -> usize {
        self.fuse.fusion.vertex_count()
    }

    /// The identity the fit has settled on so far (frame by frame, it firms up over the first
    /// frames); `None` before the model was fitted to a frame, or without the model.
    pub fn identity(&self) -> Option<Identity> {
        let (model, stage) = self.model.as_ref().zip(self.model_stage.as_ref())?;
        let fitter = &stage.fitter;
        (fitter.identity_frames() > 0).then(|| Identity {
            coefficients: fitter.identity().to_vec(),
            frames: fitter.identity_frames(),
            model: Arc::clone(model),
        })
    }

    /// The records of the frames processed so far, in input order.
    pub fn frames(&self) -> &[FrameMetrics] {
        &self.recorder.frames
    }

    /// Processes one frame, causally (streaming: clip mode needs the whole input, see
    /// [`Reconstructor::run`]). Frames must come in input order. A frame without a face has
    /// no mesh and restarts the temporal history.
    ///
    /// # Errors
    /// A frame of another size than the camera's, a network or fusion failure.
    pub fn process(&mut self, frame: &Frame) -> Result<FrameResult<'_>, Error> {
        // One frame in, that frame out: the landmark smoother without latency.
        self.face.make_causal();
        let Some((tracked, _)) = self.face.track(frame.clone(), 0.0)?.pop() else {
            unreachable!("without latency every frame comes out at once");
        };
        self.complete(tracked, frame)
    }

    /// Tracks `frame` with the landmark smoother's latency kept (the builder's
    /// [`Builder::latency`]): the frames it completes — with latency 1, the one
    /// before it; at a cut or a lost face, the ones held back too — wait for
    /// [`Reconstructor::next_result`], in input order. For a live source whose curves may
    /// trail by a frame for the smoother's look-ahead.
    ///
    /// # Errors
    /// As [`Reconstructor::process`].
    pub fn push(&mut self, frame: &Frame) -> Result<(), Error> {
        let done = self.face.track(frame.clone(), 0.0)?;
        self.pending.extend(done);
        Ok(())
    }

    /// Whether every frame's record is kept for [`Reconstructor::finish`] (the default), or
    /// only the newest one, so that memory stays flat over a live session that is not
    /// recorded (every record kept, it grows by about 0.8 KB a frame: 90 MB an hour at 30 fps).
    pub fn keep_records(&mut self, all: bool) {
        self.recorder.newest_only = !all;
    }

    /// The input has ended: the frames the smoother still holds back are completed (see
    /// [`Reconstructor::push`]).
    ///
    /// # Errors
    /// As [`Reconstructor::process`].
    pub fn push_end(&mut self) -> Result<(), Error> {
        let done = self.face.finish()?;
        self.pending.extend(done);
        Ok(())
    }

    /// The next frame [`Reconstructor::push`] completed, through the rest of the pipeline;
    /// `None` when none waits.
    pub fn next_result(&mut self) -> Option<Result<FrameResult<'_>, Error>> {
        let (tracked, frame) = self.pending.pop_front()?;
        Some(self.complete(tracked, &frame))
    }

    /// A tracked frame through the model, keypoint, depth and fusion stages, recorded.
    fn complete(&mut self, mut tracked: Tracked, frame: &Frame) -> Result<FrameResult<'_>, Error> {
        if let Some(model) = &mut self.model_stage {
            model.fit(&frame.image, &mut tracked)?;
        }
        if let Some(keypoints) = &mut self.keypoints {
            keypoints.observe(&frame.image, &mut tracked);
        }
        if let Some(depth) = &mut self.depth {
            depth.acquire(Some(&frame.image), &mut tracked)?;
        }
        self.fuse.fuse(&mut tracked)?;
        let has_mesh = tracked.metrics.has_mesh();
        let position = self.recorder.push(tracked.metrics);
        if let (true, Some(face)) = (has_mesh, &tracked.face) {
            let start = Instant::now();
            self.fuse
                .fill_surfaces(&face.landmarks_px, &face.tracked_px, &mut self.surfaces);
            self.recorder
                .measure(position, &self.face.k, &self.surfaces);
            if self.mesh.triangles.is_empty() {
                if let Some(t) = self.fuse.fusion.triangles() {
                    self.mesh.triangles = t.to_vec();
                }
            }
            self.mesh.vertices.clear();
            self.mesh.vertices.extend_from_slice(&self.surfaces.fused);
            self.recorder.frames[position].ms.write = start.elapsed().as_secs_f64() * 1e3;
        }
        self.warning = tracked.warning;
        self.blendshapes = tracked.blendshapes;
        self.irises = tracked.irises;
        let landmarks = self.landmarks.insert(tracked.landmarks);
        if has_mesh {
            landmarks.set_fused(&self.face.k, &self.surfaces.fused_landmarks);
        }
        Ok(FrameResult {
            metrics: &self.recorder.frames[position],
            landmarks,
            warning: self.warning.as_deref(),
            blendshapes: self.blendshapes.as_ref(),
            irises: self.irises.as_ref(),
            mesh: has_mesh.then_some(&self.mesh),
            surfaces: has_mesh.then_some(&self.surfaces),
        })
    }

    /// What the frames given to [`Reconstructor::process`] came to, as [`Reconstructor::run`]
    /// reports a run: the records, the summary (wall time from `started`, CPU time since
    /// `cpu_at_start`, as [`crate::process_stats`] reads it), the identity; `error` is what
    /// stopped it, if anything.
    pub fn finish(
        self,
        started: Instant,
        cpu_at_start: Option<f64>,
        error: Option<Error>,
    ) -> RunOutcome {
        let identity = self.identity();
        let timing = RunTiming {
            wall_s: started.elapsed().as_secs_f64(),
            setup_ms: self.setup_ms,
            cpu_s: crate::process_stats::cpu_seconds()
                .zip(cpu_at_start)
                .map(|(now, then)| now - then),
            peak_rss_mib: crate::process_stats::peak_rss_mib(),
        };
        let summary = self.recorder.summary(timing);
        RunOutcome {
            mesh: MeshSummary {
                vertices: self.recorder.vertices.max(self.fuse.fusion.vertex_count()),
                triangles: self.mesh.triangles.len(),
                ..MeshSummary::default()
            },
            frames: self.recorder.frames,
            summary,
            error,
            parameters: self.parameters,
            intrinsics: self.face.k,
            identity,
        }
    }

    /// Processes every frame of `input` in the configured mode and hands the results to `sink`
    /// in input order: decoding, tracking and fusion run on their own threads. Stops at the
    /// first error (in `RunOutcome::error`); what came before is kept.
    pub fn run(self, input: Input, sink: &mut dyn FrameSink) -> RunOutcome {
        let Reconstructor {
            face,
            fuse,
            mode,
            clip,
            parameters,
            setup_ms,
            mut recorder,
            mesh,
            model,
            model_stage,
            keypoints,
            depth,
            ..
        } = self;
        let k = face.k;
        let vertices_before = fuse.fusion.vertex_count();
        let mut triangles = mesh.triangles;
        let stages = Stages {
            face,
            model: model_stage,
            keypoints,
            depth,
            fuse,
            mode,
            clip,
        };
        let (timing, error, fitter) =
            run_stages(stages, input, &mut recorder, &mut triangles, sink);
        let identity = model.zip(fitter).and_then(|(model, fitter)| {
            (fitter.identity_frames() > 0).then(|| Identity {
                coefficients: fitter.identity().to_vec(),
                frames: fitter.identity_frames(),
                model,
            })
        });
        let summary = recorder.summary(RunTiming { setup_ms, ..timing });
        RunOutcome {
            mesh: MeshSummary {
                vertices: recorder.vertices.max(vertices_before),
                triangles: triangles.len(),
                ..MeshSummary::default()
            },
            frames: recorder.frames,
            summary,
            error,
            parameters,
            intrinsics: k,
            identity,
        }
    }
}

impl Builder {
    /// A reconstructor for frames of `width × height` pixels ([`crate::Camera::Auto`]: the
    /// default field of view).
    ///
    /// # Errors
    /// Invalid options, intrinsics for another size, missing or corrupt model files.
    pub fn build(self, width: u32, height: u32) -> Result<Reconstructor, Error> {
        let k = self.intrinsics_for(width, height, None)?;
        Reconstructor::new(self, k, None)
    }

    /// A reconstructor for `input`'s frames ([`crate::Camera::Auto`]: an image input's EXIF
    /// focal length when it has one).
    ///
    /// # Errors
    /// As [`Builder::build`].
    pub fn build_for(self, input: &Input) -> Result<Reconstructor, Error> {
        let k = self.intrinsics_for_input(input)?;
        Reconstructor::new(self, k, input.frame_rate())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use visage_run_folder::RunFolderError;

    #[derive(Debug)]
    struct Quoting(std::io::Error);

    impl std::fmt::Display for Quoting {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "x.png: {}", self.0)
        }
    }

    impl std::error::Error for Quoting {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    #[test]
    fn a_cause_the_message_already_quotes_is_not_repeated() {
        let e = Quoting(std::io::Error::other("no such file"));
        assert_eq!(error_chain(&e), "x.png: no such file");
        let wrapped = Error::from(RunFolderError::Write {
            path: "out.json".into(),
            source: std::io::Error::other("disk full"),
        });
        let text = error_chain(&wrapped);
        assert_eq!(text.matches("disk full").count(), 1, "{text}");
    }

    #[test]
    fn a_cause_that_starts_with_the_file_just_named_names_it_once() {
        let e = Error::from(RunFolderError::WriteMesh {
            path: "o/sequence.pc2.tmp".into(),
            source: visage_mesh::io::MeshIoError::Io {
                path: "o/sequence.pc2.tmp".into(),
                source: std::io::Error::other("File too large"),
            },
        });
        assert_eq!(
            error_chain(&e),
            "cannot write o/sequence.pc2.tmp: File too large"
        );
    }
}
