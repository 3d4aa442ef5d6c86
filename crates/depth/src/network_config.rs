//! How a depth network wants its input and what its output means: the JSON file beside the
//! network (`MODEL.json` for `MODEL.onnx`), every field optional.
//!
//! ```json
//! {
//!   "input":  { "width": 256, "height": 256, "layout": "nchw", "color": "rgb",
//!               "scale": 0.00392156862745098,
//!               "mean": [0.485, 0.456, 0.406], "std": [0.229, 0.224, 0.225],
//!               "resize": "stretch" },
//!   "output": { "kind": "inverse", "scale": 1.0, "measures": "z" },
//!   "region": "face", "face_margin": 0.5, "align": "auto"
//! }
//! ```
//!
//! The defaults are the convention of the common monocular families (MiDaS, DPT, Depth
//! Anything): RGB, channels first, values `pixel / 255` normalised with ImageNet's mean and
//! standard deviation, a relative inverse depth out. `width`/`height` default to the model's
//! own input size (required when the model leaves it open, e.g. Depth Anything exports with
//! dynamic axes; a multiple of 14 or 32 as the family needs).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use visage_camera::DepthKind;

use crate::DepthError;

/// ImageNet's channel means (RGB), the normalisation of most depth networks.
pub const IMAGENET_MEAN: [f32; 3] = [0.485, 0.456, 0.406];
/// ImageNet's channel standard deviations (RGB).
pub const IMAGENET_STD: [f32; 3] = [0.229, 0.224, 0.225];
/// Default growth of the face box on each side for [`NetworkRegion::Face`], as a fraction of
/// the box's larger side: the network sees the head and some of its surroundings.
pub const DEFAULT_FACE_MARGIN: f64 = 0.5;

/// The whole description (module docs).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NetworkConfig {
    pub input: InputSpec,
    pub output: OutputSpec,
    /// What part of the frame the network sees.
    pub region: NetworkRegion,
    /// [`NetworkRegion::Face`]: the face box grown by this fraction of its larger side on each
    /// side (default [`DEFAULT_FACE_MARGIN`]).
    pub face_margin: Option<f64>,
    /// How the output is aligned to the metric face.
    pub align: AlignMode,
}

/// The network's input tensor.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InputSpec {
    /// Input width and height, pixels (default: the model's).
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub layout: Layout,
    pub color: ColorOrder,
    /// A pixel value 0–255 is multiplied by this before the mean and std (default 1/255).
    pub scale: f32,
    /// Per channel (in the input's colour order), subtracted after `scale`.
    pub mean: [f32; 3],
    /// Per channel, divided by after the mean.
    pub std: [f32; 3],
    /// How the region is fitted into the input when their aspect ratios differ.
    pub resize: Resize,
}

impl Default for InputSpec {
    fn default() -> Self {
        InputSpec {
            width: None,
            height: None,
            layout: Layout::Nchw,
            color: ColorOrder::Rgb,
            scale: 1.0 / 255.0,
            mean: IMAGENET_MEAN,
            std: IMAGENET_STD,
            resize: Resize::Stretch,
        }
    }
}

/// The network's output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSpec {
    pub kind: OutputKind,
    /// [`OutputKind::Metric`]: value × scale = metres (e.g. 0.001 for millimetres).
    pub scale: f64,
    /// What a metric value measures: the z coordinate (default) or the distance along the ray.
    pub measures: DepthKind,
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            kind: OutputKind::Inverse,
            scale: 1.0,
            measures: DepthKind::Z,
        }
    }
}

/// Tensor layout of the input.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Layout {
    /// 1 × 3 × H × W (PyTorch exports).
    #[default]
    Nchw,
    /// 1 × H × W × 3 (TensorFlow exports).
    Nhwc,
}

/// Channel order of the input.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColorOrder {
    #[default]
    Rgb,
    Bgr,
}

/// Fitting a region into an input of another aspect ratio ([`NetworkRegion::Frame`]; the face
/// region is always cut at the input's aspect ratio).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Resize {
    /// Scale each axis on its own (MiDaS-style exports with a fixed square input).
    #[default]
    Stretch,
    /// Keep the aspect ratio and pad with the mean colour (letterbox).
    Pad,
}

/// What the network's output value means.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputKind {
    /// Metric depth: value × `scale` metres (ZoeDepth, Depth Anything metric, Metric3D).
    Metric,
    /// Depth up to an unknown scale and shift per frame.
    Relative,
    /// Inverse depth up to an unknown scale and shift per frame (MiDaS, DPT, Depth Anything).
    #[default]
    Inverse,
    /// Disparity (`f · baseline / z`, stereo-trained networks), up to a scale and shift:
    /// aligned as inverse depth.
    Disparity,
}

impl OutputKind {
    /// Whether the value is (an affine function of) inverse depth: then the alignment works
    /// in inverse depth.
    pub fn is_inverse(self) -> bool {
        matches!(self, OutputKind::Inverse | OutputKind::Disparity)
    }
}

/// The part of the frame the network sees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NetworkRegion {
    /// The tracked face's box, grown by `face_margin`, at the input's aspect ratio: the
    /// network's resolution goes to the face.
    #[default]
    Face,
    /// The whole frame.
    Frame,
}

/// How a network's output is brought to the metric face.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AlignMode {
    /// `none` for metric outputs, `scale_shift` for the others.
    #[default]
    Auto,
    /// Used as they are (metric outputs only); the residual against the face is still measured.
    None,
    /// A scale per frame.
    Scale,
    /// A scale and a shift per frame, in the output's own space.
    ScaleShift,
}

impl NetworkConfig {
    /// The description in `path` (JSON, module docs).
    ///
    /// # Errors
    /// An unreadable file, invalid JSON, an unknown field or a value out of range — naming the
    /// file.
    pub fn load(path: &Path) -> Result<NetworkConfig, DepthError> {
        let text = std::fs::read_to_string(path).map_err(|source| DepthError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// [`NetworkConfig::load`] of text already read from `path`.
    pub fn parse(text: &str, path: &Path) -> Result<NetworkConfig, DepthError> {
        let config: NetworkConfig = serde_json::from_str(text.trim_start_matches('\u{feff}'))
            .map_err(|e| DepthError::Config {
                path: path.to_owned(),
                reason: e.to_string(),
            })?;
        config.validate().map_err(|reason| DepthError::Config {
            path: path.to_owned(),
            reason,
        })?;
        Ok(config)
    }

    /// The description beside `model` (its name with `.json`), if that file exists.
    pub fn beside(model: &Path) -> Option<PathBuf> {
        let path = model.with_extension("json");
        path.is_file().then_some(path)
    }

    /// The alignment actually used.
    pub fn alignment(&self) -> AlignMode {
        match (self.align, self.output.kind) {
            (AlignMode::Auto, OutputKind::Metric) => AlignMode::None,
            (AlignMode::Auto, _) => AlignMode::ScaleShift,
            (mode, _) => mode,
        }
    }

    /// The face region's margin.
    pub fn face_margin(&self) -> f64 {
        self.face_margin.unwrap_or(DEFAULT_FACE_MARGIN)
    }

    /// What is wrong with the values, if anything.
    pub fn validate(&self) -> Result<(), String> {
        let i = &self.input;
        for (name, v) in [("input.width", i.width), ("input.height", i.height)] {
            if let Some(v) = v {
                if !(2..=8192).contains(&v) {
                    return Err(format!("{name} = {v}: must lie between 2 and 8192 pixels"));
                }
            }
        }
        if !(i.scale.is_finite() && i.scale > 0.0) {
            return Err(format!(
                "input.scale = {}: must be positive and finite",
                i.scale
            ));
        }
        if i.mean.iter().any(|m| !m.is_finite()) {
            return Err("input.mean: must be finite".into());
        }
        if i.std.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(format!("input.std = {:?}: must be positive", i.std));
        }
        let o = &self.output;
        if !(o.scale.is_finite() && o.scale > 0.0) {
            return Err(format!(
                "output.scale = {}: must be positive and finite",
                o.scale
            ));
        }
        if self.align == AlignMode::None && o.kind != OutputKind::Metric {
            return Err(format!(
                "align = \"none\" needs a metric output; a {:?} output has no scale of its own",
                o.kind
            )
            .to_lowercase());
        }
        if let Some(m) = self.face_margin {
            if !(m.is_finite() && (0.0..=4.0).contains(&m)) {
                return Err(format!("face_margin = {m}: must lie between 0 and 4"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_common_families_convention() {
        let c = NetworkConfig::parse("{}", Path::new("n.json")).unwrap();
        assert_eq!(c.input.mean, IMAGENET_MEAN);
        assert_eq!(c.output.kind, OutputKind::Inverse);
        assert_eq!(c.alignment(), AlignMode::ScaleShift);
        let metric = NetworkConfig::parse(
            r#"{"output": {"kind": "metric", "scale": 0.001}}"#,
            Path::new("n.json"),
        )
        .unwrap();
        assert_eq!(metric.alignment(), AlignMode::None);
        assert!(metric.output.kind == OutputKind::Metric && metric.output.scale == 0.001);
    }

    #[test]
    fn mistakes_name_the_file_and_the_field() {
        let bad = |text: &str| {
            NetworkConfig::parse(text, Path::new("dir/net.json"))
                .unwrap_err()
                .to_string()
        };
        let e = bad(r#"{"ouput": {}}"#);
        assert!(e.contains("dir/net.json") && e.contains("ouput"), "{e}");
        let e = bad(r#"{"output": {"kind": "depthish"}}"#);
        assert!(e.contains("depthish"), "{e}");
        let e = bad(r#"{"input": {"std": [1, 0, 1]}}"#);
        assert!(e.contains("input.std"), "{e}");
        let e = bad(r#"{"align": "none"}"#);
        assert!(e.contains("metric"), "{e}");
        let e = bad(r#"{"input": {"width": 1}}"#);
        assert!(e.contains("input.width"), "{e}");
    }
}
