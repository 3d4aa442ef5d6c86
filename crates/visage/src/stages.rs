//! The two halves of a frame's work, used alike by [`crate::Reconstructor::process`] (one
//! thread) and by the staged whole-clip run ([`crate::pipeline`], one thread each):
//! [`FaceStage`] tracks the face, regresses its landmarks and fits the metric face;
//! [`FuseStage`] gets the frame's depth and fuses it into the surface.

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

use image::RgbImage;
use visage_camera::RigidTransform;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_face::{
    fit_face_geometry, CanonicalMesh, Eye, EyeLandmarks, Eyes, Face, FaceGeometry, FaceTracker,
    IrisLandmarker, NUM_IRIS_POINTS,
};
use visage_fusion::{ClipFrame, FaceFrame, FusedSurfaces, MeshKind, ModelFrame, SurfaceFusion};
use visage_mesh::TriMesh;
use visage_morphable::fit::rigid_pose::mat3_mul;
use visage_morphable::fit::FRONTAL;
use visage_morphable::FaceFitter;
use visage_morphable::FaceModel;
use visage_video::Frame;

use crate::face_depth::{render_faces_depth, render_surface_depth};
use crate::Error;
use visage_face::{face_jumped, CutDetector};
use visage_face::{DistanceSmoother, LandmarkSmoother};
use visage_rig::{lips_closed, RestPose};
use visage_rig::{live_link_angles, BlendshapeFrame, IctToArkit, MouthLeak, PoseLeak};
use visage_rig::{EyeObservation, EyeRig, LidPoints};
use visage_run_folder::{FaceRecord, LandmarksFrame};
use visage_run_folder::{FrameMetrics, FrameQuality, FrameStatus, PoseMetrics};

/// A face found and fitted in a frame.
pub(crate) struct TrackedFace {
    /// The 468 landmarks the pipeline works with (the temporal model's), frame pixels.
    pub landmarks_px: Vec<[f64; 2]>,
    /// The same with the relative z (x, y in frame pixels, z relative).
    pub points: Vec<[f32; 3]>,
    /// The landmarks as the network gave them for this frame, frame pixels.
    pub tracked_px: Vec<[f64; 2]>,
    pub geometry: FaceGeometry,
    /// `[x, y, w, h]`, frame pixels.
    pub face_box: [f32; 4],
}

/// A frame after [`FaceStage::track`].
pub(crate) struct Tracked {
    /// The frame's record, stage times up to the fit filled in.
    pub metrics: FrameMetrics,
    pub face: Option<TrackedFace>,
    pub landmarks: LandmarksFrame,
    /// Warnings for the user (no face, no metric fit).
    pub warning: Option<String>,
    /// The morphable-model fit's blendshape record (when the model is fitted and a face was).
    pub blendshapes: Option<BlendshapeFrame>,
    /// The irises the eye network found, when it ran ([`Irises`]).
    pub irises: Option<Irises>,
    /// The fitted model's surface, when the model mesh or the model depth needs it.
    pub model: Option<FittedModel>,
    /// The frame starts a new shot: the temporal terms restart here.
    pub cut: bool,
    /// The frame's depth map from outside the face fit ([`crate::depth_stage`]), when the
    /// depth source gives one.
    pub depth_map: Option<DepthMap>,
}

/// Both irises, the subject's right eye then the left (MediaPipe's refined landmarks 468–472
/// and 473–477, in that order): each the iris network's centre, then the four rim points
/// ([`EyeLandmarks::iris`]'s order), `[x, y]` frame pixels.
pub type Irises = [[[f64; 2]; NUM_IRIS_POINTS]; 2];

/// The morphable model fitted to a frame, as a surface.
pub(crate) struct FittedModel {
    /// Model frame → camera.
    pub pose: RigidTransform,
    /// The fitted face (identity and the frame's expression), model frame, metres.
    pub shape: Vec<[f64; 3]>,
    /// The same in camera coordinates, and projected (pixels).
    pub camera: Vec<[f64; 3]>,
    pub pixels: Vec<[f64; 2]>,
}

impl FittedModel {
    fn frame(&self) -> ModelFrame<'_> {
        ModelFrame {
            pose: self.pose,
            shape: &self.shape,
            camera: &self.camera,
            pixels: &self.pixels,
        }
    }
}

/// The morphable-model fit and the eyes: the fitter, the mapping of its expressions to ARKit's
/// blendshapes, and the iris network when its model file is present.
pub(crate) struct ModelStage {
    pub k: Intrinsics,
    pub fitter: FaceFitter,
    pub to_arkit: IctToArkit,
    /// One iris network per eye, so the two run at once.
    pub iris: Option<[IrisLandmarker; 2]>,
    /// Weights relative to the person's resting face (None: relative to the model's neutral).
    pub rest: Option<RestPose>,
    /// What the head's turn alone adds to the weights, taken off them.
    pub pose_leak: Option<PoseLeak>,
    /// What the mouth's shapes alone add to the upper face's weights, taken off them after the
    /// pose leak.
    pub mouth_leak: Option<MouthLeak>,
    /// Scratch: the calibrated weights.
    pub weights: Vec<f64>,
    /// The model, when its fitted surface is needed downstream (the model mesh or depth).
    pub surface: Option<Arc<FaceModel>>,
    /// The eyes: lids, gaze, and the gaze held through blinks.
    pub eyes: EyeRig,
}

impl ModelStage {
    /// Fits the model to a tracked face (`image` is its frame, for the eyes) and records the
    /// blendshapes; a frame without a face ends the fit's track.
    pub fn fit(&mut self, image: &RgbImage, tracked: &mut Tracked) -> Result<(), Error> {
        let start = Instant::now();
        if tracked.face.is_none() || tracked.cut {
            self.fitter.lose_track();
            self.eyes.lose_track();
        }
        let Some(face) = &tracked.face else {
            return Ok(());
        };
        let rotation = mat3_mul(&face.geometry.pose.rotation, &FRONTAL);
        let fit = self.fitter.fit(&self.k, &face.landmarks_px, Some(rotation));
        let metrics = &mut tracked.metrics;
        let mut b = BlendshapeFrame::new(metrics.index, metrics.time_s.unwrap_or(0.0));
        self.weights.clear();
        self.weights.extend_from_slice(&fit.expression);
        if let Some(rest) = &mut self.rest {
            rest.calibrate(&mut self.weights, lips_closed(&face.landmarks_px));
        }
        b.weights = self.to_arkit.weights(&self.weights);
        b.head = live_link_angles(&mat3_mul(&FRONTAL, &fit.pose.rotation));
        if let Some([right_net, left_net]) = &mut self.iris {
            let points = &face.points;
            let (right, left) = rayon::join(
                || right_net.eye(image, points, Eye::Right),
                || left_net.eye(image, points, Eye::Left),
            );
            let eye_error = |e| Error::on_frame(&metrics.source, "eyes", e);
            let eyes = Eyes {
                right: right.map_err(eye_error)?,
                left: left.map_err(eye_error)?,
            };
            let rim = |eye: &EyeLandmarks| eye.iris.map(|p| [p[0] as f64, p[1] as f64]);
            tracked.irises = Some([rim(&eyes.right), rim(&eyes.left)]);
            let points = self.fitter.landmark_points();
            let observe = |eye: &EyeLandmarks, corners: [usize; 2]| {
                let c = eye.iris_center();
                EyeObservation {
                    lids: eye.lid_points().map(|[upper, lower, c0, c1]| LidPoints {
                        upper,
                        lower,
                        corners: [c0, c1],
                    }),
                    iris_px: [c[0] as f64, c[1] as f64],
                    corners: corners.map(|i| points[i]),
                }
            };
            let observed = [
                observe(&eyes.right, [33, 133]),
                observe(&eyes.left, [362, 263]),
            ];
            self.eyes
                .apply(&self.k, &fit.pose, observed, self.rest.as_mut(), &mut b);
        }
        if let Some(leak) = &self.pose_leak {
            leak.remove(b.head, &mut b.weights);
        }
        if let Some(leak) = &self.mouth_leak {
            leak.remove(&mut b.weights);
        }
        metrics.model_fit_px = Some(fit.mean_error_px);
        if let Some(model) = &self.surface {
            let mut shape = Vec::with_capacity(model.vertex_count());
            model.shape(self.fitter.identity(), &fit.expression, &mut shape);
            let camera: Vec<[f64; 3]> = shape.iter().map(|&p| fit.pose.apply(p)).collect();
            let pixels = camera.iter().map(|&p| self.k.project(p)).collect();
            tracked.model = Some(FittedModel {
                pose: fit.pose,
                shape,
                camera,
                pixels,
            });
        }
        metrics.ms.fit += start.elapsed().as_secs_f64() * 1e3;
        tracked.blendshapes = Some(b);
        Ok(())
    }
}

/// Face tracking, landmarks, the temporal model of the landmarks and the metric face fit.
pub(crate) struct FaceStage {
    pub k: Intrinsics,
    pub canonical: Arc<CanonicalMesh>,
    pub tracker: FaceTracker,
    /// The input's frame rate, for timestamps of frames that have none.
    pub fps: Option<f64>,
    /// The temporal model of the landmarks (None: each frame as tracked).
    pub smoother: Option<LandmarkSmoother>,
    pub cuts: CutDetector,
    /// The previous frame's tracked landmarks, if it had a face.
    pub last_tracked: Option<Vec<[f64; 2]>>,
    /// Frames tracked but not given out yet, in input order (the smoother's latency).
    pub waiting: VecDeque<Observed>,
    /// The head's distance filter (None: as fitted), and whether the last frame given out had
    /// a fitted face.
    pub distance: Option<DistanceSmoother>,
    pub distance_track: bool,
}

/// A frame after tracking, before the temporal model and the fit.
pub(crate) struct Observed {
    frame: Frame,
    metrics: FrameMetrics,
    face: Option<Face>,
    tracked_px: Vec<[f64; 2]>,
    warning: Option<String>,
    cut: bool,
    /// The landmarks to fit (the smoother's), once known; frames without a face are ready
    /// at once.
    points: Option<Vec<[f32; 3]>>,
}

impl Observed {
    fn ready(&self) -> bool {
        self.face.is_none() || self.points.is_some()
    }
}

impl FaceStage {
    /// Tracks the face in `frame` and returns the frames now complete, in input order: this
    /// one at once without latency, else the one `latency` frames back (or several, after a
    /// cut or a lost face ends a track).
    pub fn track(&mut self, frame: Frame, decode_ms: f64) -> Result<Vec<(Tracked, Frame)>, Error> {
        let (w, h) = frame.image.dimensions();
        self.k
            .check_size(w, h)
            .map_err(|e| Error::on_frame(&frame.source, "intrinsics do not fit the frame", e))?;
        let time_s = frame
            .timestamp_s
            .or_else(|| self.fps.map(|fps| frame.index as f64 / fps));
        let t = Instant::now();
        let picture_cut = self.cuts.picture_cut(&frame.image);
        if picture_cut {
            // A new shot: look for the face afresh rather than where it was.
            self.tracker.reset();
        }
        let step = self
            .tracker
            .track(&frame.image)
            .map_err(|e| Error::on_frame(&frame.source, "face tracking", e))?;
        let mut metrics = FrameMetrics::new(frame.index, frame.source.clone(), FrameStatus::NoFace);
        metrics.time_s = time_s;
        metrics.detector_ran = Some(step.detector_ran);
        metrics.faces_seen = step.detector_ran.then_some(step.faces_seen);
        metrics.ms.decode = decode_ms;
        metrics.ms.track = t.elapsed().as_secs_f64() * 1e3;
        let mut cut = picture_cut;
        let mut tracked_px = Vec::new();
        if let Some(face) = &step.face {
            tracked_px = face
                .landmarks
                .points
                .iter()
                .map(|p| [p[0] as f64, p[1] as f64])
                .collect();
            cut |= self
                .last_tracked
                .as_ref()
                .is_some_and(|last| face_jumped(last, &tracked_px));
        }
        // Another person where the last one was (the picture barely changed).
        cut |= self.cuts.face_cut(&frame.image, &tracked_px);
        metrics.cut = cut;
        // A cut or a lost face ends the smoother's track: its waiting frames complete now.
        if cut || step.face.is_none() {
            self.finish_track();
        }
        self.last_tracked = step.face.as_ref().map(|_| tracked_px.clone());
        let warning = step
            .face
            .is_none()
            .then(|| format!("{}: no face found; no mesh", frame.source));
        let mut observed = Observed {
            frame,
            metrics,
            face: step.face,
            tracked_px,
            warning,
            cut,
            points: None,
        };
        match (&observed.face, &mut self.smoother) {
            (Some(face), Some(smoother)) => {
                let smoothed = smoother.push(&face.landmarks.points, time_s);
                self.waiting.push_back(observed);
                if let Some(points) = smoothed {
                    self.complete_next(points);
                }
            }
            (Some(face), None) => {
                observed.points = Some(face.landmarks.points.clone());
                self.waiting.push_back(observed);
            }
            (None, _) => self.waiting.push_back(observed),
        }
        self.take_ready()
    }

    /// Makes the landmark smoother causal (latency 0: every frame given out at once).
    pub fn make_causal(&mut self) {
        if let Some(s) = &mut self.smoother {
            s.make_causal();
        }
    }

    /// The frames still held back (the end of the input).
    pub fn finish(&mut self) -> Result<Vec<(Tracked, Frame)>, Error> {
        self.finish_track();
        self.take_ready()
    }

    /// Gives the smoother's waiting frames their landmarks and restarts it.
    fn finish_track(&mut self) {
        if let Some(smoother) = &mut self.smoother {
            for points in smoother.finish() {
                self.complete_next(points);
            }
        }
    }

    /// The smoothed landmarks of the oldest waiting frame that has a face and none yet.
    fn complete_next(&mut self, points: Vec<[f32; 3]>) {
        if let Some(o) = self.waiting.iter_mut().find(|o| !o.ready()) {
            o.points = Some(points);
        }
    }

    /// Fits and gives out the ready frames at the front of the queue.
    fn take_ready(&mut self) -> Result<Vec<(Tracked, Frame)>, Error> {
        let mut out = Vec::new();
        while self.waiting.front().is_some_and(Observed::ready) {
            if let Some(o) = self.waiting.pop_front() {
                out.push(self.settle(o));
            }
        }
        Ok(out)
    }

    /// The metric face fit of a frame's (smoothed) landmarks and its records.
    fn settle(&mut self, o: Observed) -> (Tracked, Frame) {
        let Observed {
            frame,
            mut metrics,
            face,
            tracked_px,
            mut warning,
            cut,
            points,
        } = o;
        let t = Instant::now();
        let (w, h) = frame.image.dimensions();
        let mut faces = Vec::new();
        let tracked_face = match (face, points) {
            (Some(face), Some(points)) => {
                match fit_face_geometry(&self.canonical, &points, &self.k) {
                    Ok(mut geometry) => {
                        if let Some(d) = &mut self.distance {
                            if cut || !self.distance_track {
                                d.reset();
                            }
                            d.smooth(&mut geometry, metrics.time_s);
                        }
                        faces.push(FaceRecord::new(&face, Some(&geometry)));
                        Some(TrackedFace {
                            landmarks_px: points
                                .iter()
                                .map(|p| [p[0] as f64, p[1] as f64])
                                .collect(),
                            points,
                            tracked_px,
                            geometry,
                            face_box: face.bbox,
                        })
                    }
                    Err(e) => {
                        faces.push(FaceRecord::new(&face, None));
                        warning = Some(format!("{}: no metric fit: {e}", frame.source));
                        metrics.fit_error = Some(e.to_string());
                        None
                    }
                }
            }
            _ => None,
        };
        self.distance_track = tracked_face.is_some();
        metrics.ms.fit = t.elapsed().as_secs_f64() * 1e3;
        let tracked = Tracked {
            metrics,
            face: tracked_face,
            landmarks: LandmarksFrame {
                source: frame.source.clone(),
                index: frame.index,
                width: w,
                height: h,
                faces,
            },
            warning,
            blendshapes: None,
            irises: None,
            model: None,
            cut,
            depth_map: None,
        };
        (tracked, frame)
    }
}

/// One frame's surfaces (buffers reused from frame to frame): fused and raw on the mesh, both
/// at the 468 landmarks, and the landmark pixels as tracked.
#[derive(Clone, Debug, Default)]
pub struct Surfaces {
    /// #V camera-space points, metres.
    pub fused: Vec<[f64; 3]>,
    /// The unfused surface on the same mesh.
    pub raw: Vec<[f64; 3]>,
    /// The fused and raw surfaces at the 468 landmarks (NaN where a landmark falls outside
    /// the image-plane mesh).
    pub fused_landmarks: Vec<[f64; 3]>,
    pub raw_landmarks: Vec<[f64; 3]>,
    /// The landmarks as the network gave them (before the temporal model), frame pixels.
    pub landmarks_px: Vec<[f64; 2]>,
}

/// Which depth the fusion fuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FusedDepth {
    /// The rigid face fit's surface.
    Face,
    /// The fitted morphable model's surface.
    Model,
    /// Each frame's map ([`Tracked::depth_map`]).
    Maps,
}

/// Depth and fusion.
pub(crate) struct FuseStage {
    pub k: Intrinsics,
    pub canonical: Arc<CanonicalMesh>,
    pub depth: FusedDepth,
    pub fusion: SurfaceFusion,
    /// The fitted model's mesh (its vertices rewritten per frame), to render its depth for the
    /// other meshes.
    pub model_mesh: TriMesh,
}

impl FuseStage {
    /// Fuses a tracked frame and fills in its record. A frame without a face resets the
    /// fusion's history.
    pub fn fuse(&mut self, tracked: &mut Tracked) -> Result<(), Error> {
        let metrics = &mut tracked.metrics;
        if tracked.face.is_none() || tracked.cut {
            self.fusion.reset();
        }
        let Some(face) = &tracked.face else {
            return Ok(());
        };
        metrics.pose = Some(PoseMetrics::of(&face.geometry.pose));
        metrics.fit_rms_px = Some(face.geometry.rms_px);
        let start = Instant::now();
        let given_map = match (self.depth, self.fusion.mesh(), &tracked.model) {
            (FusedDepth::Maps, _, _) => tracked.depth_map.take(),
            // The model mesh samples the fitted surface at its own vertices.
            (FusedDepth::Model, MeshKind::Face | MeshKind::Image, Some(model)) => {
                self.model_mesh.vertices.clone_from(&model.camera);
                Some(
                    render_surface_depth(&self.model_mesh, &self.k, DepthKind::Z)
                        .map_err(|e| Error::on_frame(&metrics.source, "model depth", e))?,
                )
            }
            _ => None,
        };
        // The face fit's surface as a depth map: the image mesh's (and its first frame's mask),
        // and the model mesh's with the face depth.
        let face_depth_as_map = given_map.is_none()
            && match self.fusion.mesh() {
                MeshKind::Image => true,
                MeshKind::Model => self.depth == FusedDepth::Face,
                MeshKind::Face => false,
            };
        let rendered = if face_depth_as_map || self.fusion.needs_face_mask() {
            Some(
                render_faces_depth(
                    std::slice::from_ref(&face.geometry),
                    &self.canonical,
                    &self.k,
                    DepthKind::Z,
                )
                .map_err(|e| Error::on_frame(&metrics.source, "face depth", e))?,
            )
        } else {
            None
        };
        metrics.ms.depth += start.elapsed().as_secs_f64() * 1e3;
        let depth_map = given_map
            .as_ref()
            .or(rendered.as_ref().filter(|_| face_depth_as_map));
        let start = Instant::now();
        let FusedSurfaces {
            frame,
            raw_quality,
            fused_quality,
            fairing_iterations,
        } = self
            .fusion
            .process(&FaceFrame {
                landmarks_px: &face.landmarks_px,
                pose: face.geometry.pose,
                metric_landmarks: &face.geometry.metric_landmarks,
                depth_map,
                face_mask: rendered.as_ref().map(|r| (r, face.face_box)),
                model: tracked.model.as_ref().map(FittedModel::frame),
            })
            .map_err(|e| Error::on_frame(&metrics.source, "fusion", e))?;
        metrics.ms.fuse = start.elapsed().as_secs_f64() * 1e3;
        metrics.status = frame.status.into();
        metrics.valid_fraction = frame.valid_fraction;
        metrics.relative_residual = frame.relative_residual;
        metrics.quality = FrameQuality::of(&raw_quality, &fused_quality);
        metrics.fairing_iterations = fairing_iterations;
        Ok(())
    }

    /// Copies the current surfaces into `s` (the frame just fused, or a loaded clip frame):
    /// `landmarks_px` are the landmarks the frame was fused with, `tracked_px` the network's.
    pub fn fill_surfaces(
        &self,
        landmarks_px: &[[f64; 2]],
        tracked_px: &[[f64; 2]],
        s: &mut Surfaces,
    ) {
        s.fused.clear();
        s.fused.extend_from_slice(self.fusion.fused());
        s.raw.clear();
        s.raw.extend_from_slice(self.fusion.raw());
        s.landmarks_px.clear();
        s.landmarks_px.extend_from_slice(tracked_px);
        self.fusion
            .landmark_points(landmarks_px, &mut s.fused_landmarks, &mut s.raw_landmarks);
    }

    /// The state the clip solve keeps for the frame just fused.
    pub fn clip_frame(&self, landmarks_px: &[[f64; 2]]) -> ClipFrame {
        self.fusion.clip_frame(landmarks_px)
    }
}
