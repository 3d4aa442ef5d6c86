//! A monocular depth network from an ONNX file, run by `tract` (pure Rust): loading with the
//! checks that give a clear error for a file that is not a depth network, and per frame the
//! region cut and resized into the input tensor, the inference and the raw output.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use image::RgbImage;
use tract_onnx::pb;
use tract_onnx::prelude::*;

use crate::network_config::{ColorOrder, Layout, NetworkConfig, NetworkRegion, Resize};
use crate::{DepthError, FrameRegion, Prediction};

/// Most input-pixel taps per axis when a region is averaged down into the input.
const MAX_TAPS: usize = 4;

/// The ONNX `FLOAT` element type.
const ONNX_FLOAT: i32 = 1;

/// A depth network ready to run: the optimised plan, its input and output sizes and how to
/// feed it.
#[derive(Clone)]
pub struct DepthNetwork {
    path: PathBuf,
    config: NetworkConfig,
    plan: Arc<TypedRunnableModel>,
    /// Input width and height, pixels.
    input_size: (u32, u32),
    /// Output width and height, pixels.
    output_size: (u32, u32),
    /// Scratch: the input tensor's values.
    input: Vec<f32>,
}

impl std::fmt::Debug for DepthNetwork {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DepthNetwork")
            .field("path", &self.path)
            .field("input_size", &self.input_size)
            .field("output_size", &self.output_size)
            .field("config", &self.config)
            .finish()
    }
}

/// A tensor's declared dimensions: a size, or a name the model leaves open.
#[derive(Clone, Debug, PartialEq)]
enum Dim {
    Fixed(i64),
    Open(String),
}

impl std::fmt::Display for Dim {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Dim::Fixed(n) => write!(f, "{n}"),
            Dim::Open(name) if name.is_empty() => f.write_str("?"),
            Dim::Open(name) => f.write_str(name),
        }
    }
}

fn shape_text(dims: &[Dim]) -> String {
    let parts: Vec<String> = dims.iter().map(Dim::to_string).collect();
    format!("[{}]", parts.join(", "))
}

impl DepthNetwork {
    /// Loads `path` with `config`, or with the description beside it (`MODEL.json`) when
    /// `config` is `None` and that file exists, else the defaults ([`NetworkConfig`]).
    ///
    /// # Errors
    /// Every error names the file: unreadable, not ONNX, operators the runtime lacks, an input
    /// that is not one image (rank 4, 3 channels, batch 1, float), an input size neither the
    /// model nor the description fixes (or they disagree), an output that is not one depth map
    /// of the input's aspect ratio.
    pub fn load(path: &Path, config: Option<NetworkConfig>) -> Result<DepthNetwork, DepthError> {
        let config = match config {
            Some(c) => c,
            None => match NetworkConfig::beside(path) {
                Some(json) => NetworkConfig::load(&json)?,
                None => NetworkConfig::default(),
            },
        };
        config.validate().map_err(|reason| DepthError::Config {
            path: path.to_owned(),
            reason,
        })?;
        let bytes = std::fs::read(path).map_err(|source| DepthError::Io {
            path: path.to_owned(),
            source,
        })?;
        let onnx = tract_onnx::onnx();
        let proto =
            onnx.proto_model_for_read(&mut &bytes[..])
                .map_err(|e| DepthError::NotOnnx {
                    path: path.to_owned(),
                    reason: format!("{e:#}"),
                })?;
        let graph = proto.graph.as_ref().ok_or_else(|| DepthError::NotOnnx {
            path: path.to_owned(),
            reason: "the file holds no graph".into(),
        })?;
        let mut unsupported: Vec<String> = graph
            .node
            .iter()
            .filter(|n| !onnx.op_register.0.contains_key(&n.op_type))
            .map(|n| n.op_type.clone())
            .collect();
        unsupported.sort();
        unsupported.dedup();
        if !unsupported.is_empty() {
            return Err(DepthError::UnsupportedOperators {
                path: path.to_owned(),
                ops: unsupported,
            });
        }
        let shape_error = |reason: String| DepthError::Shape {
            path: path.to_owned(),
            reason,
        };
        let (input_name, input_dims) = single_image_input(graph).map_err(shape_error)?;
        let input_size = input_size(&input_name, &input_dims, &config).map_err(shape_error)?;
        let (w, h) = (input_size.0 as usize, input_size.1 as usize);
        let shape: [usize; 4] = match config.input.layout {
            Layout::Nchw => [1, 3, h, w],
            Layout::Nhwc => [1, h, w, 3],
        };
        let runtime = |stage: &str, e: TractError| DepthError::Runtime {
            path: path.to_owned(),
            reason: format!("{stage}: {e:#}"),
        };
        let model = onnx
            .model_for_proto_model(&proto)
            .map_err(|e| runtime("cannot build the network", e))?
            .with_input_fact(0, f32::fact(shape).into())
            .map_err(|e| runtime("cannot set the input", e))?;
        let typed = model
            .into_optimized()
            .map_err(|e| runtime("cannot prepare the network", e))?;
        let output_fact = typed
            .output_fact(0)
            .map_err(|e| runtime("no output", e))?
            .clone();
        let output_shape: Vec<usize> = output_fact
            .shape
            .as_concrete()
            .ok_or_else(|| {
                shape_error(format!(
                    "the output's shape {:?} is not fixed by a {w}×{h} input",
                    output_fact.shape
                ))
            })?
            .to_vec();
        let output_size = depth_map_size(&output_shape, input_size).map_err(shape_error)?;
        let plan = typed
            .into_runnable()
            .map_err(|e| runtime("cannot plan the network", e))?;
        Ok(DepthNetwork {
            path: path.to_owned(),
            config,
            plan,
            input_size,
            output_size,
            input: vec![0.0; 3 * w * h],
        })
    }

    /// The network file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// How it is fed and read.
    pub fn config(&self) -> &NetworkConfig {
        &self.config
    }

    /// Input width and height, pixels.
    pub fn input_size(&self) -> (u32, u32) {
        self.input_size
    }

    /// Output width and height, pixels.
    pub fn output_size(&self) -> (u32, u32) {
        self.output_size
    }

    /// The region of a `width × height` frame the network sees, given the tracked face's box
    /// (`[x, y, w, h]` pixels; needed by [`NetworkRegion::Face`]).
    pub fn region(&self, width: u32, height: u32, face_box: Option<[f32; 4]>) -> FrameRegion {
        let aspect = self.input_size.0 as f64 / self.input_size.1 as f64;
        match (self.config.region, face_box) {
            (NetworkRegion::Face, Some(b)) => {
                FrameRegion::around_face(b, self.config.face_margin(), aspect)
            }
            _ => match self.config.input.resize {
                Resize::Stretch => FrameRegion::frame(width, height),
                Resize::Pad => FrameRegion::padded_frame(width, height, aspect),
            },
        }
    }

    /// Runs the network on `region` of `image` (pixels outside the frame: the nearest edge
    /// pixel for a face region, the mean colour for a padded frame).
    ///
    /// # Errors
    /// The runtime failed (named with the file).
    pub fn predict(
        &mut self,
        image: &RgbImage,
        region: FrameRegion,
    ) -> Result<Prediction, DepthError> {
        let pad_with_mean =
            self.config.region == NetworkRegion::Frame && self.config.input.resize == Resize::Pad;
        fill_input(
            image,
            region,
            &self.config,
            self.input_size,
            pad_with_mean,
            &mut self.input,
        );
        let (w, h) = (self.input_size.0 as usize, self.input_size.1 as usize);
        let shape: [usize; 4] = match self.config.input.layout {
            Layout::Nchw => [1, 3, h, w],
            Layout::Nhwc => [1, h, w, 3],
        };
        let runtime = |e: TractError| DepthError::Runtime {
            path: self.path.clone(),
            reason: format!("inference failed: {e:#}"),
        };
        let tensor = Tensor::from_shape(&shape, &self.input).map_err(runtime)?;
        let outputs = self
            .plan
            .run(tvec!(tensor.into_tvalue()))
            .map_err(runtime)?;
        let out = outputs[0].cast_to::<f32>().map_err(runtime)?;
        let view = out.try_as_plain_ram().map_err(runtime)?;
        let values = view.as_slice::<f32>().map_err(runtime)?;
        let (ow, oh) = self.output_size;
        if values.len() != ow as usize * oh as usize {
            return Err(DepthError::Shape {
                path: self.path.clone(),
                reason: format!(
                    "the output has {} values where {ow}×{oh} were announced",
                    values.len()
                ),
            });
        }
        Ok(Prediction {
            region,
            width: ow,
            height: oh,
            values: values.to_vec(),
        })
    }
}

/// The graph's one image input: its name and declared dimensions (inputs that are also
/// initializers — weights, in older exports — are not inputs).
fn single_image_input(graph: &pb::GraphProto) -> Result<(String, Vec<Dim>), String> {
    let initializers: std::collections::HashSet<&str> =
        graph.initializer.iter().map(|t| t.name.as_str()).collect();
    let inputs: Vec<&pb::ValueInfoProto> = graph
        .input
        .iter()
        .filter(|i| !initializers.contains(i.name.as_str()))
        .collect();
    let [input] = inputs[..] else {
        let names: Vec<&str> = inputs.iter().map(|i| i.name.as_str()).collect();
        return Err(format!(
            "the network has {} inputs ({}); a depth network takes one image",
            names.len(),
            names.join(", ")
        ));
    };
    let Some(pb::type_proto::Value::TensorType(t)) =
        input.r#type.as_ref().and_then(|t| t.value.as_ref())
    else {
        return Err(format!("input '{}' is not a tensor", input.name));
    };
    if t.elem_type != ONNX_FLOAT {
        return Err(format!(
            "input '{}' has ONNX element type {}; visage feeds 32-bit floats (type 1)",
            input.name, t.elem_type
        ));
    }
    let dims = t
        .shape
        .as_ref()
        .map(|s| {
            s.dim
                .iter()
                .map(|d| match &d.value {
                    Some(pb::tensor_shape_proto::dimension::Value::DimValue(n)) => Dim::Fixed(*n),
                    Some(pb::tensor_shape_proto::dimension::Value::DimParam(p)) => {
                        Dim::Open(p.clone())
                    }
                    None => Dim::Open(String::new()),
                })
                .collect()
        })
        .unwrap_or_default();
    Ok((input.name.clone(), dims))
}

/// The input's width and height: the model's, the description's, or both when they agree.
fn input_size(name: &str, dims: &[Dim], config: &NetworkConfig) -> Result<(u32, u32), String> {
    let layout = config.input.layout;
    let want = match layout {
        Layout::Nchw => "1×3×H×W",
        Layout::Nhwc => "1×H×W×3 (\"layout\": \"nhwc\")",
    };
    if dims.len() != 4 {
        return Err(format!(
            "input '{name}' has rank {} (shape {}); a depth network takes one image, {want}",
            dims.len(),
            shape_text(dims)
        ));
    }
    let (c, hd, wd) = match layout {
        Layout::Nchw => (&dims[1], &dims[2], &dims[3]),
        Layout::Nhwc => (&dims[3], &dims[1], &dims[2]),
    };
    let wrong = |what: &str| {
        format!(
            "input '{name}' has shape {}: {what}; a depth network takes {want}",
            shape_text(dims)
        )
    };
    if matches!(dims[0], Dim::Fixed(n) if n != 1) {
        return Err(wrong("a batch of more than one"));
    }
    if matches!(c, Dim::Fixed(n) if *n != 3) {
        return Err(wrong("not 3 colour channels"));
    }
    let side = |d: &Dim, given: Option<u32>, axis: &str| -> Result<u32, String> {
        match (d, given) {
            (Dim::Fixed(n), Some(g)) if *n != g as i64 => Err(format!(
                "input '{name}' is {n} pixels {axis} but the description says input.{axis} = {g}"
            )),
            (Dim::Fixed(n), _) if !(2..=8192).contains(n) => {
                Err(wrong(&format!("{n} pixels {axis}")))
            }
            (Dim::Fixed(n), _) => Ok(*n as u32),
            (Dim::Open(_), Some(g)) => Ok(g),
            (Dim::Open(p), None) => Err(format!(
                "input '{name}' leaves its {axis} open ({}); give input.width and input.height \
                 in the network's description (a JSON file beside it)",
                if p.is_empty() { "?" } else { p }
            )),
        }
    };
    Ok((
        side(wd, config.input.width, "width")?,
        side(hd, config.input.height, "height")?,
    ))
}

/// The output map's width and height from its shape: one map (`H×W` after dropping axes of
/// size 1) at the input's aspect ratio, at least 2×2.
fn depth_map_size(shape: &[usize], input: (u32, u32)) -> Result<(u32, u32), String> {
    let text = format!("{shape:?}");
    let mut dims: Vec<usize> = shape.to_vec();
    while dims.len() > 2 && dims[0] == 1 {
        dims.remove(0);
    }
    if dims.len() == 3 && dims[2] == 1 {
        dims.pop();
    }
    let [h, w] = dims[..] else {
        return Err(format!(
            "the output has shape {text}; a depth network gives one depth map (1×1×H×W, 1×H×W \
             or H×W)"
        ));
    };
    let (iw, ih) = (input.0 as usize, input.1 as usize);
    // The same aspect ratio, within about one output pixel.
    let aspect_ok = (w * ih).abs_diff(h * iw) <= iw.max(ih);
    if w < 2 || h < 2 || !aspect_ok {
        return Err(format!(
            "the output is {w}×{h} (shape {text}) for a {iw}×{ih} input; a depth map must have \
             the input's aspect ratio"
        ));
    }
    Ok((w as u32, h as u32))
}

/// Writes the normalised pixels of `region` into `input` (the input's layout and colour
/// order): each input pixel the mean of up to [`MAX_TAPS`]² bilinear samples over its
/// footprint in the frame.
fn fill_input(
    image: &RgbImage,
    region: FrameRegion,
    config: &NetworkConfig,
    (w, h): (u32, u32),
    pad_with_mean: bool,
    input: &mut [f32],
) {
    let spec = &config.input;
    let (fw, fh) = image.dimensions();
    let taps = |extent: f64, n: u32| ((extent / n as f64).round() as usize).clamp(1, MAX_TAPS);
    let (tx, ty) = (taps(region.width, w), taps(region.height, h));
    let step = [region.width / w as f64, region.height / h as f64];
    let order: [usize; 3] = match spec.color {
        ColorOrder::Rgb => [0, 1, 2],
        ColorOrder::Bgr => [2, 1, 0],
    };
    let plane = (w * h) as usize;
    let raw = image.as_raw();
    let pixel = |x: usize, y: usize, c: usize| raw[(y * fw as usize + x) * 3 + c] as f32;
    for b in 0..h {
        for a in 0..w {
            let [cu, cv] = region.grid_to_frame(w, h, a as f64, b as f64);
            let outside = cu < -0.5 || cv < -0.5 || cu > fw as f64 - 0.5 || cv > fh as f64 - 0.5;
            let mut sum = [0.0f32; 3];
            if !(outside && pad_with_mean) {
                for j in 0..ty {
                    let v = cv + ((j as f64 + 0.5) / ty as f64 - 0.5) * step[1];
                    let v = v.clamp(0.0, (fh - 1) as f64);
                    let (v0, fv) = (v.floor() as usize, (v - v.floor()) as f32);
                    let v1 = (v0 + 1).min(fh as usize - 1);
                    for i in 0..tx {
                        let u = cu + ((i as f64 + 0.5) / tx as f64 - 0.5) * step[0];
                        let u = u.clamp(0.0, (fw - 1) as f64);
                        let (u0, fu) = (u.floor() as usize, (u - u.floor()) as f32);
                        let u1 = (u0 + 1).min(fw as usize - 1);
                        for (c, s) in sum.iter_mut().enumerate() {
                            let top = pixel(u0, v0, c) + fu * (pixel(u1, v0, c) - pixel(u0, v0, c));
                            let bottom =
                                pixel(u0, v1, c) + fu * (pixel(u1, v1, c) - pixel(u0, v1, c));
                            *s += top + fv * (bottom - top);
                        }
                    }
                }
            }
            let n = (tx * ty) as f32;
            let index = (b * w + a) as usize;
            for (slot, &c) in order.iter().enumerate() {
                // The mean colour pads: 0 after normalisation.
                let value = if outside && pad_with_mean {
                    0.0
                } else {
                    (sum[c] / n * spec.scale - spec.mean[slot]) / spec.std[slot]
                };
                match spec.layout {
                    Layout::Nchw => input[slot * plane + index] = value,
                    Layout::Nhwc => input[index * 3 + slot] = value,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_shapes_that_are_one_map_at_the_inputs_aspect_ratio() {
        assert_eq!(depth_map_size(&[1, 1, 32, 32], (64, 64)), Ok((32, 32)));
        assert_eq!(depth_map_size(&[1, 256, 384], (384, 256)), Ok((384, 256)));
        assert_eq!(depth_map_size(&[518, 518], (518, 518)), Ok((518, 518)));
        assert_eq!(depth_map_size(&[1, 60, 80, 1], (640, 480)), Ok((80, 60)));
        // One pixel of rounding: 37×37 from 518 / 14.
        assert!(depth_map_size(&[1, 1, 37, 37], (518, 518)).is_ok());
        assert!(depth_map_size(&[1, 1, 16, 48], (64, 64)).is_err());
        assert!(depth_map_size(&[1, 3, 64, 64], (64, 64)).is_err());
        assert!(depth_map_size(&[64], (64, 64)).is_err());
    }

    #[test]
    fn the_input_is_normalised_in_the_described_order() {
        let mut image = RgbImage::new(4, 4);
        for p in image.pixels_mut() {
            *p = image::Rgb([255, 0, 51]);
        }
        let mut config = NetworkConfig::default();
        config.input.color = ColorOrder::Bgr;
        config.input.layout = Layout::Nhwc;
        config.input.mean = [0.0; 3];
        config.input.std = [1.0; 3];
        let mut input = vec![0.0; 3 * 2 * 2];
        fill_input(
            &image,
            FrameRegion::frame(4, 4),
            &config,
            (2, 2),
            false,
            &mut input,
        );
        assert!((input[0] - 0.2).abs() < 1e-6, "blue first: {input:?}");
        assert!((input[2] - 1.0).abs() < 1e-6 && input[1].abs() < 1e-6);
    }
}
