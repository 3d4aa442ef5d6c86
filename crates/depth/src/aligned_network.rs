//! A depth network as a depth source: run on the frame (its face region by default), its output
//! aligned to the fitted metric face where it is not metric, turned into a map over the frame.

use visage_camera::{DepthKind, DepthMap};

use crate::{
    align, AlignmentOptions, DepthError, DepthNetwork, DepthProvider, DepthRequest, ProvidedDepth,
};

/// [`DepthNetwork`] with the per-frame alignment of its output to the reference face
/// ([`align`]): the provider of `--depth MODEL.onnx`.
#[derive(Debug)]
pub struct AlignedNetwork {
    pub network: DepthNetwork,
    pub options: AlignmentOptions,
}

impl AlignedNetwork {
    /// `network` aligned with the default options.
    pub fn new(network: DepthNetwork) -> Self {
        AlignedNetwork {
            network,
            options: AlignmentOptions::default(),
        }
    }
}

impl DepthProvider for AlignedNetwork {
    /// The network's file.
    fn describe(&self) -> String {
        self.network.path().display().to_string()
    }

    fn needs_image(&self) -> bool {
        true
    }

    fn needs_reference(&self) -> bool {
        true
    }

    /// Runs the network on the frame and aligns its output to the reference face. A frame
    /// that cannot be aligned gets an empty map, the failure and a warning saying why.
    fn depth_map(&mut self, request: DepthRequest<'_>) -> Result<ProvidedDepth, DepthError> {
        let on_frame = |e| DepthError::on_frame(request.source, "depth network", e);
        let missing = |what: &str| {
            on_frame(DepthError::Runtime {
                path: self.network.path().to_owned(),
                reason: format!("the frame's {what} was not given"),
            })
        };
        let image = request.image.ok_or_else(|| missing("image"))?;
        let mut reference = request
            .reference
            .ok_or_else(|| missing("reference depth"))?;
        let k = request.k;
        let (w, h) = image.dimensions();
        let region = self.network.region(w, h, Some(request.face_box));
        let prediction = self.network.predict(image, region).map_err(on_frame)?;
        let output = self.network.config().output.clone();
        if output.measures == DepthKind::Ray {
            for v in 0..reference.height {
                for u in 0..reference.width {
                    let i = (v * reference.width + u) as usize;
                    let z = reference.data[i] as f64;
                    if z > 0.0 {
                        reference.data[i] = (z / k.ray(u as f64, v as f64)[2]) as f32;
                    }
                }
            }
            reference.kind = DepthKind::Ray;
        }
        let mode = self.network.config().alignment();
        Ok(
            match align(
                &prediction,
                &reference,
                output.kind,
                output.scale,
                mode,
                &self.options,
            ) {
                Ok(fit) => ProvidedDepth {
                    map: prediction
                        .depth_map(w, h, output.measures, request.max_depth, |x| fit.depth(x)),
                    alignment: Some(Ok(fit)),
                    warning: None,
                },
                Err(failure) => ProvidedDepth {
                    map: DepthMap::empty(w, h, output.measures),
                    warning: Some(format!(
                        "the depth network's output was not used: {failure}"
                    )),
                    alignment: Some(Err(failure)),
                },
            },
        )
    }
}
