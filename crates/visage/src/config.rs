//! How a reconstruction is set up: camera, depth source, mesh design, temporal mode, weights
//! and model files ([`Builder`], from [`crate::Reconstructor::builder`]).

use std::path::PathBuf;

use serde::Serialize;
use visage_camera::{Intrinsics, DEFAULT_FOV_DEG};
use visage_depth::DepthProvider;
use visage_face::FaceTarget;
use visage_fem::{ClipOptions, Weights};
use visage_fusion::{
    FusionParams, MeshKind, MeshingOptions, ANCHORED_WEIGHTS_FACE, ANCHORED_WEIGHTS_MAP,
    DEFAULT_MAX_DEPTH_M, MODEL_WEIGHTS_MAP,
};

use visage_morphable::{FaceModel, FitOptions};

use crate::{Error, Input};
use visage_face::{DEFAULT_LANDMARK_SMOOTHING, DEFAULT_LATENCY_FRAMES, MAX_LATENCY_FRAMES};

/// Default subdivision of the FaceMesh template for the face mesh (≈ 1.8k vertices).
pub const DEFAULT_SUBDIVISION: usize = 2;

/// The camera's intrinsics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Camera {
    /// Known intrinsics (they must match the frame size).
    Intrinsics(Intrinsics),
    /// A horizontal field of view in degrees, principal point at the image centre.
    FovDeg(f64),
    /// An image input's EXIF 35 mm-equivalent focal length when it has one
    /// (`f = f35 · diagonal / 43.27 mm`), else [`DEFAULT_FOV_DEG`].
    #[default]
    Auto,
}

/// Where each frame's depth comes from.
#[derive(Debug, Default)]
pub enum DepthSource {
    /// The metric face fit's surface (the face "CNN depth").
    #[default]
    Face,
    /// The morphable model fitted to the frame: this person's face with the frame's
    /// expression (needs the model fit).
    Model,
    /// A depth map per frame from a provider: a folder of 16-bit PNG maps, the i-th file for
    /// input frame i (`DepthSequence`); an RGB-D recording's maps, the one associated with
    /// each colour frame (`RgbdRecording`; the input must be the recording's colour frames, in
    /// its order); a depth network run on every frame, its output aligned to the metric face —
    /// the fitted model's surface, or the face fit's without the model — where it is not
    /// metric (`AlignedNetwork`).
    Maps(Box<dyn DepthProvider>),
}

impl DepthSource {
    /// Depth maps from `provider`.
    pub fn maps(provider: impl DepthProvider + 'static) -> Self {
        DepthSource::Maps(Box::new(provider))
    }

    /// `"face"`, `"model"` or the provider's file or folder.
    pub fn describe(&self) -> String {
        match self {
            DepthSource::Face => "face".into(),
            DepthSource::Model => "model".into(),
            DepthSource::Maps(provider) => provider.describe(),
        }
    }

    /// Whether each frame's depth is a map read or computed for it (a folder, a network, a
    /// recording), rather than a fitted surface.
    pub fn is_map(&self) -> bool {
        matches!(self, DepthSource::Maps(_))
    }

    /// Whether the maps are aligned to the fitted face (a depth network's), which then must
    /// be kept for them.
    pub fn needs_reference(&self) -> bool {
        matches!(self, DepthSource::Maps(provider) if provider.needs_reference())
    }
}

/// Causal streaming or the exact whole-clip minimiser (ERRATA 1, 4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TemporalMode {
    /// Past frames only (live capture); memory does not grow with the clip.
    #[default]
    Streaming,
    /// The whole clip solved at once; every frame's system is kept until the end.
    Clip,
}

/// Which morphable face model is fitted to the landmarks.
#[derive(Clone, Debug, Default)]
pub enum ModelSource {
    /// The compact ICT-FaceKit model shipped with visage (30 identity modes, 53 expressions).
    #[default]
    Embedded,
    /// A full ICT-FaceKit folder (its `FaceXModel` folder or a checkout of the repository).
    IctFolder(PathBuf),
    /// A model built by the caller.
    Given(Box<FaceModel>),
    /// No fit: no blendshapes, no identity.
    None,
}

impl ModelSource {
    /// How `metrics.json` names it.
    pub fn describe(&self) -> String {
        match self {
            ModelSource::Embedded => "embedded".into(),
            ModelSource::IctFolder(dir) => dir.display().to_string(),
            ModelSource::Given(_) => "given".into(),
            ModelSource::None => "none".into(),
        }
    }
}

/// The parameters of a video reconstruction, as `metrics.json` records them.
#[derive(Clone, Debug, Serialize)]
pub struct Parameters {
    #[serde(flatten)]
    pub fusion: FusionParams,
    pub mode: TemporalMode,
    /// `"face"` or the depth folder.
    pub depth: String,
    /// The morphable model fitted: `"embedded"`, an ICT-FaceKit folder, or `"none"`.
    pub model: String,
    /// The landmark smoother's acceleration-to-noise ratio (1/s²); `null`: off.
    pub landmark_smoothing: Option<f64>,
    /// Frames the landmark smoother waits for before giving a frame out.
    pub latency_frames: usize,
    /// Whether SIFT keypoints check the head's motion.
    pub keypoint_motion: bool,
}

impl visage_run_folder::RunParameters for Parameters {
    fn cannot_resume(&self) -> Option<&'static str> {
        if self.mode == TemporalMode::Clip {
            return Some(
                "a clip-mode run solves the whole clip at once and cannot go on part-way. Pass \
                 --overwrite to start again",
            );
        }
        if self.fusion.mesh == MeshKind::Image {
            return Some(
                "the image-plane mesh is built from the first frame's face, and a resumed run \
                 would build another. Pass --overwrite to start again",
            );
        }
        None
    }

    fn latency_frames(&self) -> usize {
        self.latency_frames
    }

    fn fits_model(&self) -> bool {
        self.model != "none"
    }
}

/// Sets up a [`crate::Reconstructor`]. Every option has a default: the face mesh on the face
/// fit's surface, streaming, the weights that suit the depth source, the camera from the
/// input, the models from `$VISAGE_MODELS` or `./models`.
#[derive(Debug)]
pub struct Builder {
    pub(crate) camera: Camera,
    pub(crate) depth: DepthSource,
    pub(crate) mesh: MeshKind,
    pub(crate) mode: TemporalMode,
    pub(crate) lambda: Option<f64>,
    pub(crate) mu: Option<f64>,
    pub(crate) subdivision: Option<usize>,
    pub(crate) spacing: Option<u32>,
    pub(crate) clip: ClipOptions,
    pub(crate) models: Option<PathBuf>,
    pub(crate) model: ModelSource,
    pub(crate) fit: FitOptions,
    pub(crate) rest_pose: bool,
    pub(crate) pose_leak: bool,
    pub(crate) mouth_leak: bool,
    pub(crate) landmark_smoothing: Option<f64>,
    pub(crate) latency: usize,
    pub(crate) fairing_length_mm: Option<f64>,
    pub(crate) keypoint_motion: bool,
    pub(crate) face_target: FaceTarget,
}

impl Default for Builder {
    fn default() -> Self {
        Builder {
            camera: Camera::default(),
            depth: DepthSource::default(),
            mesh: MeshKind::default(),
            mode: TemporalMode::default(),
            lambda: None,
            mu: None,
            subdivision: None,
            spacing: None,
            clip: ClipOptions::default(),
            models: None,
            model: ModelSource::default(),
            fit: FitOptions::default(),
            rest_pose: true,
            pose_leak: true,
            mouth_leak: true,
            landmark_smoothing: Some(DEFAULT_LANDMARK_SMOOTHING),
            latency: DEFAULT_LATENCY_FRAMES,
            fairing_length_mm: None,
            keypoint_motion: false,
            face_target: FaceTarget::Largest,
        }
    }
}

impl Builder {
    /// Whether blendshape weights are relative to the person's resting face, estimated from
    /// the frames so far (default), or to the model's neutral face.
    pub fn rest_pose(mut self, on: bool) -> Self {
        self.rest_pose = on;
        self
    }

    /// Whether what the head's turn alone adds to each blendshape weight, learned on renders
    /// of neutral heads (`visage_rig::PoseLeak`), is taken off (default), or the weights are
    /// given as the fit reads them (to learn that table).
    pub fn pose_leak(mut self, on: bool) -> Self {
        self.pose_leak = on;
        self
    }

    /// Whether what the mouth's shapes alone add to the upper face's weights (the landmark
    /// network's cross-talk: a sneer that follows speech), learned on renders of heads that
    /// only talk (`visage_rig::MouthLeak`), is taken off (default, after the pose leak), or
    /// the weights are given without it (to learn that table).
    pub fn mouth_leak(mut self, on: bool) -> Self {
        self.mouth_leak = on;
        self
    }

    /// The temporal model of the tracked landmarks: a constant-velocity Kalman smoother with
    /// this ratio of acceleration to measurement noise (1/s²; larger follows faster and
    /// smooths less), or `None` to use every frame's landmarks as tracked. Default
    /// [`DEFAULT_LANDMARK_SMOOTHING`].
    pub fn landmark_smoothing(mut self, accel_ratio: Option<f64>) -> Self {
        self.landmark_smoothing = accel_ratio;
        self
    }

    /// How many later frames the landmark smoother waits for before giving a frame out
    /// (default [`DEFAULT_LATENCY_FRAMES`]; 0: a causal filter, every frame given out at
    /// once). [`crate::Reconstructor::run`] honours it; [`crate::Reconstructor::process`]
    /// answers every frame at once, so it smooths causally whatever this says. Clip mode
    /// waits for at least [`crate::CLIP_LATENCY_FRAMES`].
    pub fn latency(mut self, frames: usize) -> Self {
        self.latency = frames;
        self
    }

    /// Fairs every fused surface (paper §5, `visage fair`) with this smoothing length in
    /// millimetres (`γ = ℓ⁻⁴`), or not (default). The system is factored once per run.
    pub fn fairing(mut self, length_mm: Option<f64>) -> Self {
        self.fairing_length_mm = length_mm;
        self
    }

    /// Checks every frame's head motion against SIFT keypoints on the face (matched with the
    /// previous frame's, lifted onto the fitted surface, a rigid motion by RANSAC) and records
    /// the disagreement per frame (`FrameMetrics::keypoint_motion`). Off by default: a few
    /// milliseconds a frame.
    pub fn keypoint_motion(mut self, on: bool) -> Self {
        self.keypoint_motion = on;
        self
    }

    /// Which face to follow when several are in view: the largest (default), or the one at a
    /// box (`FaceTarget::Near`, pixels), which the track then keeps to.
    pub fn face_target(mut self, target: FaceTarget) -> Self {
        self.face_target = target;
        self
    }

    /// Checks the landmark smoothing ratio and the latency.
    pub(crate) fn checked_smoothing(&self) -> Result<Option<f64>, Error> {
        if self.latency > MAX_LATENCY_FRAMES {
            return Err(Error::InvalidOption {
                name: "--latency",
                value: self.latency.to_string(),
                reason: "at most 30 frames (every frame waiting is held in memory)",
            });
        }
        match self.landmark_smoothing {
            Some(r) if !(r.is_finite() && r > 0.0) => Err(Error::InvalidOption {
                name: "--smoothing",
                value: visage_camera::number(r),
                reason: "must be a positive number (or \"off\")",
            }),
            r => Ok(r),
        }
    }

    pub fn camera(mut self, camera: Camera) -> Self {
        self.camera = camera;
        self
    }

    pub fn intrinsics(self, k: Intrinsics) -> Self {
        self.camera(Camera::Intrinsics(k))
    }

    pub fn fov_deg(self, fov: f64) -> Self {
        self.camera(Camera::FovDeg(fov))
    }

    pub fn depth(mut self, depth: DepthSource) -> Self {
        self.depth = depth;
        self
    }

    pub fn mesh(mut self, mesh: MeshKind) -> Self {
        self.mesh = mesh;
        self
    }

    pub fn mode(mut self, mode: TemporalMode) -> Self {
        self.mode = mode;
        self
    }

    /// Smoothness weight λ (face mesh: mm⁴ of the canonical face; image mesh: reference
    /// pixels⁴). Default: 1 on the face fit's surface, 10 on depth maps or the image mesh.
    pub fn lambda(mut self, lambda: f64) -> Self {
        self.lambda = Some(lambda);
        self
    }

    /// Temporal weight μ (dimensionless). Default: 0.5, the face mesh on depth maps 1.
    pub fn mu(mut self, mu: f64) -> Self {
        self.mu = Some(mu);
        self
    }

    /// Face mesh: subdivision of the FaceMesh template (1–16, default
    /// [`DEFAULT_SUBDIVISION`]).
    pub fn subdivision(mut self, n: usize) -> Self {
        self.subdivision = Some(n);
        self
    }

    /// Image mesh: grid spacing in pixels.
    pub fn spacing(mut self, pixels: u32) -> Self {
        self.spacing = Some(pixels);
        self
    }

    /// Clip mode's solver options.
    pub fn clip_options(mut self, clip: ClipOptions) -> Self {
        self.clip = clip;
        self
    }

    /// The morphable model fitted to the landmarks (default: the embedded one).
    pub fn model(mut self, model: ModelSource) -> Self {
        self.model = model;
        self
    }

    /// Options of the morphable-model fit.
    pub fn fit_options(mut self, fit: FitOptions) -> Self {
        self.fit = fit;
        self
    }

    /// The folder with the MediaPipe model files (`visage models fetch`).
    pub fn models_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.models = Some(dir.into());
        self
    }

    /// The weights: the ones given, the rest the defaults of the mesh and depth source.
    pub(crate) fn weights(&self) -> Result<Weights, Error> {
        let defaults = match (self.mesh, self.depth.is_map()) {
            (MeshKind::Image, _) => Weights::default(),
            (MeshKind::Face, true) => ANCHORED_WEIGHTS_MAP,
            (MeshKind::Model, true) => MODEL_WEIGHTS_MAP,
            (MeshKind::Face | MeshKind::Model, false) => ANCHORED_WEIGHTS_FACE,
        };
        let weights = Weights {
            lambda: self.lambda.unwrap_or(defaults.lambda),
            mu: self.mu.unwrap_or(defaults.mu),
        };
        weights.validate()?;
        Ok(weights)
    }

    pub(crate) fn fusion_params(&self) -> Result<FusionParams, Error> {
        Ok(FusionParams {
            mesh: self.mesh,
            weights: self.weights()?,
            subdivision: self.subdivision.unwrap_or(DEFAULT_SUBDIVISION),
            meshing: MeshingOptions {
                spacing: self.spacing.unwrap_or(MeshingOptions::default().spacing),
                ..MeshingOptions::default()
            },
            max_depth_m: DEFAULT_MAX_DEPTH_M,
            fairing_gamma: match self.fairing_length_mm {
                None => None,
                Some(l) if l.is_finite() && l > 0.0 => Some((l * 1e-3).powi(-4)),
                Some(l) => {
                    return Err(Error::InvalidOption {
                        name: "--fair",
                        value: visage_camera::number(l),
                        reason: "the smoothing length must be a positive number of millimetres",
                    })
                }
            },
        })
    }

    /// The intrinsics for frames of `width × height` (`exif`: an image input's 35 mm focal
    /// length, used by [`Camera::Auto`]).
    pub(crate) fn intrinsics_for(
        &self,
        width: u32,
        height: u32,
        exif: Option<f64>,
    ) -> Result<Intrinsics, Error> {
        Ok(match self.camera {
            Camera::Intrinsics(k) => {
                k.check_size(width, height)?;
                k
            }
            Camera::FovDeg(fov) => {
                check_fov(fov)?;
                Intrinsics::from_fov(width, height, fov)?
            }
            Camera::Auto => match exif {
                Some(f35) => Intrinsics::from_focal_35mm(width, height, f35)?,
                None => Intrinsics::from_fov(width, height, DEFAULT_FOV_DEG)?,
            },
        })
    }

    /// The intrinsics for `input`'s frames.
    pub(crate) fn intrinsics_for_input(&self, input: &Input) -> Result<Intrinsics, Error> {
        let (w, h) = input.size();
        let exif = match self.camera {
            Camera::Auto => input.exif_focal_35mm().map(|(_, f)| f),
            _ => None,
        };
        self.intrinsics_for(w, h, exif)
    }
}

/// A horizontal field of view between 5° and 170° (`visage_camera::FOV_RANGE_DEG`).
pub fn check_fov(fov: f64) -> Result<(), Error> {
    let (min, max) = visage_camera::FOV_RANGE_DEG;
    if fov.is_finite() && (min..=max).contains(&fov) {
        Ok(())
    } else {
        Err(Error::InvalidOption {
            name: "--fov-deg",
            value: visage_camera::number(fov),
            reason: "must lie between 5 and 170 degrees",
        })
    }
}
