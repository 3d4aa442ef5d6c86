//! The depth maps of a frame that come from outside the face fit: a folder of PNGs, an RGB-D
//! recording's associated map, or a depth network's output aligned to the metric face. Its own
//! thread in [`crate::Reconstructor::run`] (a network costs more than everything else).

use std::sync::Arc;
use std::time::Instant;

use image::RgbImage;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_depth::{align, AlignmentOptions, DepthNetwork, DepthSequence, RgbdRecording};
use visage_face::CanonicalMesh;
use visage_mesh::TriMesh;

use crate::face_depth::{render_faces_depth, render_surface_depth};
use crate::metrics::DepthAlignmentMetrics;
use crate::stages::Tracked;
use crate::Error;

/// Where the maps come from.
pub(crate) enum MapSource {
    Folder(DepthSequence),
    Recording(Box<RgbdRecording>),
    Network(Box<NetworkDepth>),
}

/// A depth network and what its alignment needs: the face it is aligned to.
pub(crate) struct NetworkDepth {
    pub network: DepthNetwork,
    pub canonical: Arc<CanonicalMesh>,
    /// The fitted model's mesh (its vertices rewritten per frame), rendered as the reference
    /// when the model is fitted; else the rigid face fit's surface is.
    pub model_mesh: TriMesh,
    pub options: AlignmentOptions,
}

/// Acquires each frame's depth map.
pub(crate) struct DepthStage {
    pub k: Intrinsics,
    pub source: MapSource,
    /// Depth beyond this is no depth, metres.
    pub max_depth: f64,
}

impl DepthStage {
    /// Whether it needs the frame's image (a network does).
    pub fn needs_image(&self) -> bool {
        matches!(self.source, MapSource::Network(_))
    }

    /// Puts the frame's depth map into `tracked` (none without a face: nothing is fused then).
    /// A recording frame without an associated map, or a network output that cannot be
    /// aligned, gets an empty map: the fusion carries the surface through it.
    ///
    /// # Errors
    /// A missing or unreadable depth file, a map of another size than the frame, a failing
    /// network.
    pub fn acquire(
        &mut self,
        image: Option<&RgbImage>,
        tracked: &mut Tracked,
    ) -> Result<(), Error> {
        if tracked.face.is_none() {
            return Ok(());
        }
        let start = Instant::now();
        let index = tracked.metrics.index;
        let source = tracked.metrics.source.clone();
        let on_frame = |step, e: Error| Error::on_frame(&source, step, e);
        let map = match &mut self.source {
            MapSource::Folder(seq) => read_folder_depth(seq, index, &self.k)?,
            MapSource::Recording(rec) => {
                match rec.depth(index).map_err(|e| on_frame("depth", e.into()))? {
                    Some(map) => {
                        self.k
                            .check_size(map.width, map.height)
                            .map_err(|e| on_frame("depth map of the recording", e.into()))?;
                        map
                    }
                    None => DepthMap::empty(self.k.width, self.k.height, DepthKind::Z),
                }
            }
            MapSource::Network(net) => {
                let image = image.ok_or(Error::InvalidOption {
                    name: "--depth",
                    value: "network".into(),
                    reason: "a depth network needs every frame's image",
                })?;
                let (map, record, warning) = net
                    .infer(&self.k, image, tracked, self.max_depth)
                    .map_err(|e| on_frame("depth network", e))?;
                tracked.metrics.depth_alignment = Some(record);
                if let (Some(w), None) = (warning, &tracked.warning) {
                    tracked.warning = Some(format!("{source}: {w}"));
                }
                map
            }
        };
        tracked.metrics.ms.depth += start.elapsed().as_secs_f64() * 1e3;
        tracked.depth_map = Some(map);
        Ok(())
    }
}

impl NetworkDepth {
    /// Runs the network on the frame, aligns its output to the fitted face and returns the
    /// metric map, the alignment's record and, when it failed, why.
    fn infer(
        &mut self,
        k: &Intrinsics,
        image: &RgbImage,
        tracked: &Tracked,
        max_depth: f64,
    ) -> Result<(DepthMap, DepthAlignmentMetrics, Option<String>), Error> {
        let Some(face) = &tracked.face else {
            unreachable!("acquire returns early without a face");
        };
        let (w, h) = image.dimensions();
        let region = self.network.region(w, h, Some(face.face_box));
        let prediction = self
            .network
            .predict(image, region)
            .map_err(|e| Error::Depth(Box::new(e)))?;
        let output = self.network.config().output.clone();
        let mut reference = match &tracked.model {
            Some(model) => {
                self.model_mesh.vertices.clone_from(&model.camera);
                render_surface_depth(&self.model_mesh, k, DepthKind::Z)?
            }
            None => render_faces_depth(
                std::slice::from_ref(&face.geometry),
                &self.canonical,
                k,
                DepthKind::Z,
            )?,
        };
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
        match align(
            &prediction,
            &reference,
            output.kind,
            output.scale,
            mode,
            &self.options,
        ) {
            Ok(fit) => {
                let map = prediction.depth_map(w, h, output.measures, max_depth, |x| fit.depth(x));
                Ok((map, DepthAlignmentMetrics::aligned(&fit), None))
            }
            Err(failure) => Ok((
                DepthMap::empty(w, h, output.measures),
                DepthAlignmentMetrics::failed(&failure),
                Some(format!(
                    "the depth network's output was not used: {failure}"
                )),
            )),
        }
    }
}

/// Input frame `index`'s map from a depth folder, checked against the camera.
fn read_folder_depth(seq: &DepthSequence, index: usize, k: &Intrinsics) -> Result<DepthMap, Error> {
    if index >= seq.frames.len() {
        return Err(Error::MissingDepth {
            dir: seq.dir.clone(),
            frames: seq.frames.len(),
            index,
        });
    }
    let map = seq.read(index)?;
    k.check_size(map.width, map.height)
        .map_err(|e| Error::on_frame(&seq.frames[index].display().to_string(), "depth frame", e))?;
    Ok(map)
}
