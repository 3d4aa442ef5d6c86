//! What opens a run's input and sets its reconstructor up, as data: the options `visage run`
//! and `visage bench` share and the Python package's `visage.run` takes, named like their
//! flags, with the flags' defaults ([`PipelineOptions`]); [`PipelineOptions::open`] is the one
//! mapping from them to the input and the [`Builder`](crate::Builder).

use std::path::{Path, PathBuf};

use visage_camera::{DepthKind, Intrinsics, RigidTransform};
use visage_depth::{
    AlignMode, AlignedNetwork, DepthNetwork, DepthSequence, EdgeMask, NetworkConfig, NetworkRegion,
    Registration, RgbdLayout, RgbdOptions, RgbdRecording,
};
use visage_face::{FaceTarget, DEFAULT_LANDMARK_SMOOTHING, DEFAULT_LATENCY_FRAMES};
use visage_fusion::{MeshKind, MeshingOptions};

use crate::{
    Camera, DepthSource, Error, FrameSink, Input, ModelSource, Reconstructor, TemporalMode,
    DEFAULT_SUBDIVISION,
};

/// Depth units per metre of a folder of depth PNGs (millimetres) when `depth_scale` is not
/// given; a TUM recording's own default is its dataset's (5000).
pub const DEFAULT_DEPTH_SCALE: f64 = 1000.0;

/// The options of a run's input and reconstruction (`visage run --help` says what each does;
/// the field is the flag, snake_case). [`Default`] is the command line's defaults.
#[derive(Clone, Debug)]
pub struct PipelineOptions {
    /// The input is an RGB-D recording (`--rgbd`): the TUM RGB-D layout or the folders `rgb/`
    /// and `depth/`; each colour frame is fused with its depth map.
    pub rgbd: bool,
    /// Depth units per metre of depth PNGs (`None`: 5000 for a TUM recording, else
    /// [`DEFAULT_DEPTH_SCALE`]).
    pub depth_scale: Option<f64>,
    /// With `rgbd`: the depth camera's intrinsics JSON; the depth is then registered to the
    /// colour camera (`intrinsics`, which must be given), moved by `depth_to_color`.
    pub depth_intrinsics: Option<PathBuf>,
    /// The rigid motion from depth to colour camera coordinates, a JSON file (metres; `None`:
    /// none).
    pub depth_to_color: Option<PathBuf>,
    /// With `rgbd`: use every depth value, flying pixels and hole rims included.
    pub keep_depth_edges: bool,
    /// A depth network's description (JSON) when it is not `MODEL.json` beside the network.
    pub depth_config: Option<PathBuf>,
    /// Camera intrinsics JSON for the input's size (not with `fov_deg`).
    pub intrinsics: Option<PathBuf>,
    /// Horizontal field of view in degrees; `None` (and no `intrinsics`): an image's EXIF
    /// 35 mm-equivalent focal length, else 60°.
    pub fov_deg: Option<f64>,
    /// The depth source as `--depth` names it: `face`, `model`, a depth network
    /// (`MODEL.onnx`) or a folder of 16-bit PNG depth maps. Not used with `rgbd`.
    pub depth: String,
    /// Smoothness weight λ (`None`: the mesh's and depth source's default).
    pub lambda: Option<f64>,
    /// Temporal weight μ (`None`: the mesh's and depth source's default).
    pub mu: Option<f64>,
    /// The landmark smoother's acceleration-to-noise ratio (1/s²), or `None` for `off`.
    pub smoothing: Option<f64>,
    /// Frames the landmark smoother waits for before giving a frame out.
    pub latency: usize,
    /// The mesh design: anchored on the face, the paper's image plane, or the fitted model's.
    pub mesh: MeshKind,
    /// Streaming (causal) or the exact minimiser over the clip.
    pub mode: TemporalMode,
    /// Face mesh: subdivision of the FaceMesh template.
    pub subdivision: usize,
    /// Fair every fused surface with this smoothing length in millimetres.
    pub fair: Option<f64>,
    /// Check every frame's head motion against SIFT keypoints.
    pub keypoints: bool,
    /// Image mesh: grid spacing in pixels.
    pub spacing: u32,
    /// Process every N-th input frame.
    pub every: usize,
    /// Stop after this many processed frames.
    pub max_frames: Option<usize>,
    /// The model files' folder (`None`: `$VISAGE_MODELS`, else `./models` or a `models/`
    /// folder beside the executable).
    pub models: Option<PathBuf>,
    /// The morphable face model fitted (`--model DIR`: an ICT-FaceKit folder; `--no-fit`:
    /// [`ModelSource::None`]).
    pub model: ModelSource,
}

impl Default for PipelineOptions {
    fn default() -> Self {
        PipelineOptions {
            rgbd: false,
            depth_scale: None,
            depth_intrinsics: None,
            depth_to_color: None,
            keep_depth_edges: false,
            depth_config: None,
            intrinsics: None,
            fov_deg: None,
            depth: "face".to_owned(),
            lambda: None,
            mu: None,
            smoothing: Some(DEFAULT_LANDMARK_SMOOTHING),
            latency: DEFAULT_LATENCY_FRAMES,
            mesh: MeshKind::Face,
            mode: TemporalMode::Streaming,
            subdivision: DEFAULT_SUBDIVISION,
            fair: None,
            keypoints: false,
            spacing: MeshingOptions::default().spacing,
            every: 1,
            max_frames: None,
            models: None,
            model: ModelSource::Embedded,
        }
    }
}

impl PipelineOptions {
    /// Checks that `input` (the video, folder or image; with `rgbd` the recording) can be
    /// read at all, before anything is written for it.
    ///
    /// # Errors
    /// [`Error::Unreadable`].
    pub fn check_input(&self, input: &Path) -> Result<(), Error> {
        std::fs::metadata(input)
            .map(|_| ())
            .map_err(|source| Error::Unreadable {
                path: input.to_owned(),
                source,
            })
    }

    /// The input, frame selection applied; `sink` is told what an RGB-D recording holds.
    ///
    /// # Errors
    /// An input that cannot be opened, a recording that cannot be used, a frame selection out
    /// of range.
    pub fn open_input(&self, input: &Path, sink: &mut impl FrameSink) -> Result<Input, Error> {
        Ok(self.open_input_and_recording(input, None, sink)?.0)
    }

    /// The input (frame selection applied) and a reconstructor set up for it, following
    /// `target`. `sink` is told what the run assumed for the user ([`FrameSink::caution`]: the
    /// camera from an image's EXIF or a dataset's default) and what the input and depth
    /// network are ([`FrameSink::notice`]).
    ///
    /// # Errors
    /// Everything a flag can name that cannot be used: the input, an intrinsics file (or one
    /// for another image size), a depth folder, network or recording, the models, an option
    /// out of range.
    pub fn open(
        &self,
        input: &Path,
        target: FaceTarget,
        sink: &mut impl FrameSink,
    ) -> Result<(Input, Reconstructor), Error> {
        let given = self
            .intrinsics
            .as_ref()
            .map(|path| Intrinsics::load_json(path))
            .transpose()?;
        let (opened, recording) = self.open_input_and_recording(input, given, sink)?;
        let camera = match (&self.intrinsics, given, self.fov_deg) {
            (Some(path), Some(k), _) => {
                let (width, height) = opened.size();
                k.check_size(width, height)
                    .map_err(|source| Error::IntrinsicsSize {
                        path: path.clone(),
                        input: input.to_owned(),
                        width,
                        height,
                        source,
                    })?;
                Camera::Intrinsics(k)
            }
            (_, _, Some(fov)) => Camera::FovDeg(fov),
            _ if recording
                .as_ref()
                .is_some_and(|r| r.layout == RgbdLayout::Tum)
                && opened.size() == (640, 480) =>
            {
                sink.caution(
                    "intrinsics: the TUM RGB-D default camera (fx = fy = 525, cx = 319.5, \
                     cy = 239.5; the freiburg calibrations differ by up to 1.5 %); pass \
                     --intrinsics for yours",
                );
                Camera::Intrinsics(Intrinsics::new(640, 480, 525.0, 525.0, 319.5, 239.5)?)
            }
            _ => {
                if let Some((path, f35)) = opened.exif_focal_35mm() {
                    sink.caution(&format!(
                        "intrinsics: {f35} mm (35 mm equivalent) from the EXIF of {}",
                        path.display()
                    ));
                }
                Camera::Auto
            }
        };
        let depth = match recording {
            Some(recording) => DepthSource::maps(recording),
            None => self.depth_source(sink)?,
        };
        let mut builder = Reconstructor::builder()
            .camera(camera)
            .depth(depth)
            .mesh(self.mesh)
            .mode(self.mode)
            .subdivision(self.subdivision)
            .spacing(self.spacing)
            .landmark_smoothing(self.smoothing)
            .latency(self.latency)
            .fairing(self.fair)
            .keypoint_motion(self.keypoints)
            .face_target(target)
            .model(self.model.clone());
        if let Some(lambda) = self.lambda {
            builder = builder.lambda(lambda);
        }
        if let Some(mu) = self.mu {
            builder = builder.mu(mu);
        }
        if let Some(dir) = &self.models {
            builder = builder.models_dir(dir);
        }
        let reconstructor = builder.build_for(&opened)?;
        Ok((opened, reconstructor))
    }

    /// The depth source `depth` names (without `rgbd`); a network is described to `sink`.
    fn depth_source(&self, sink: &mut impl FrameSink) -> Result<DepthSource, Error> {
        let unusable = |source: Error| Error::CannotUse {
            flag: "--depth",
            source: Box::new(source),
        };
        Ok(match self.depth.as_str() {
            "face" => DepthSource::Face,
            "model" => DepthSource::Model,
            network if network.to_ascii_lowercase().ends_with(".onnx") => {
                let config = self
                    .depth_config
                    .as_ref()
                    .map(|path| NetworkConfig::load(path))
                    .transpose()?;
                let net =
                    DepthNetwork::load(network.as_ref(), config).map_err(|e| unusable(e.into()))?;
                let (iw, ih) = net.input_size();
                let (ow, oh) = net.output_size();
                let c = net.config();
                sink.notice(&format!(
                    "depth network {network}: {iw}×{ih} in, {ow}×{oh} {} out, on the {}, \
                     aligned {}",
                    format!("{:?}", c.output.kind).to_lowercase(),
                    match c.region {
                        NetworkRegion::Face => "face",
                        NetworkRegion::Frame => "whole frame",
                    },
                    match c.alignment() {
                        AlignMode::None => "not at all (metric)",
                        AlignMode::Scale => "by a scale per frame",
                        _ => "by a scale and shift per frame",
                    }
                ));
                DepthSource::maps(AlignedNetwork::new(net))
            }
            dir => DepthSource::maps(
                DepthSequence::open(
                    dir.as_ref(),
                    self.depth_scale.unwrap_or(DEFAULT_DEPTH_SCALE),
                    DepthKind::Z,
                )
                .map_err(|e| unusable(e.into()))?,
            ),
        })
    }

    /// The input (frame selection applied) and, with `rgbd`, its recording (`color`: the
    /// colour camera, for the registration).
    fn open_input_and_recording(
        &self,
        input: &Path,
        color: Option<Intrinsics>,
        sink: &mut impl FrameSink,
    ) -> Result<(Input, Option<RgbdRecording>), Error> {
        let (mut opened, recording) = match self.rgbd {
            false => (Input::open(input)?, None),
            true => {
                let recording = self.open_recording(input, color, sink)?;
                let paths: Vec<PathBuf> =
                    recording.frames.iter().map(|f| f.color.clone()).collect();
                let times: Option<Vec<f64>> = recording.frames.iter().map(|f| f.time_s).collect();
                let opened = match times {
                    Some(times) => {
                        Input::timed_images(input, paths, times, recording.frame_rate())?
                    }
                    // Untimed folder pairs go in name order, as rgb/ lists them.
                    None => Input::open(&input.join("rgb"))?,
                };
                (opened, Some(recording))
            }
        };
        opened = opened.every(self.every)?;
        if let Some(m) = self.max_frames {
            opened = opened.max_frames(m)?;
        }
        Ok((opened, recording))
    }

    /// The RGB-D recording in `dir`, registered to `color` when `depth_intrinsics` is given;
    /// what it holds told to `sink`.
    fn open_recording(
        &self,
        dir: &Path,
        color: Option<Intrinsics>,
        sink: &mut impl FrameSink,
    ) -> Result<RgbdRecording, Error> {
        let registration = match (&self.depth_intrinsics, color) {
            (Some(path), Some(color)) => Some(Registration {
                depth: Intrinsics::load_json(path)?,
                color,
                depth_to_color: match &self.depth_to_color {
                    Some(t) => RigidTransform::load_json(t)?,
                    None => RigidTransform::IDENTITY,
                },
            }),
            _ => None,
        };
        let options = RgbdOptions {
            depth_scale: self.depth_scale,
            registration,
            edges: (!self.keep_depth_edges).then(EdgeMask::default),
            ..RgbdOptions::default()
        };
        let recording = RgbdRecording::open(dir, &options).map_err(|e| Error::CannotUse {
            flag: "--rgbd",
            source: Box::new(e.into()),
        })?;
        sink.notice(&format!(
            "{}: {} recording, {} colour frames, {} with a depth map within {:.0} ms{}",
            dir.display(),
            match recording.layout {
                RgbdLayout::Tum => "TUM RGB-D",
                RgbdLayout::Folders => "rgb/ + depth/",
            },
            recording.frames.len(),
            recording.associated(),
            options.max_time_difference_s * 1e3,
            match recording.unmatched_depth {
                0 => String::new(),
                n => format!(" ({n} depth maps matched no colour frame)"),
            }
        ));
        Ok(recording)
    }
}
