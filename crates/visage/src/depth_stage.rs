//! The depth maps of a frame that come from outside the face fit, asked of the run's
//! [`DepthProvider`] (a folder of PNGs, an RGB-D recording's associated map, a depth network's
//! output aligned to the metric face). Its own thread in [`crate::Reconstructor::run`] (a
//! network costs more than everything else).

use std::sync::Arc;
use std::time::Instant;

use image::RgbImage;
use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_depth::{DepthProvider, DepthRequest};
use visage_face::CanonicalMesh;
use visage_mesh::TriMesh;

use crate::face_depth::{render_faces_depth, render_surface_depth};
use crate::stages::{FittedModel, Tracked, TrackedFace};
use crate::Error;
use visage_run_folder::DepthAlignmentMetrics;

/// The fitted face a provider's output is aligned to, rendered per frame.
struct ReferenceFace {
    canonical: Arc<CanonicalMesh>,
    /// The fitted model's mesh (its vertices rewritten per frame), rendered as the reference
    /// when the model is fitted; else the rigid face fit's surface is.
    model_mesh: TriMesh,
}

/// Acquires each frame's depth map.
pub(crate) struct DepthStage {
    k: Intrinsics,
    provider: Box<dyn DepthProvider>,
    /// Depth beyond this is no depth, metres.
    max_depth: f64,
    /// When the provider aligns its maps to the fitted face.
    reference: Option<ReferenceFace>,
}

impl DepthStage {
    /// The stage of `provider`; `canonical` and `model_mesh` (the fitted model's triangles)
    /// render the reference face when the provider needs one.
    pub fn new(
        k: Intrinsics,
        provider: Box<dyn DepthProvider>,
        max_depth: f64,
        canonical: &Arc<CanonicalMesh>,
        model_mesh: &TriMesh,
    ) -> DepthStage {
        let reference = provider.needs_reference().then(|| ReferenceFace {
            canonical: Arc::clone(canonical),
            model_mesh: model_mesh.clone(),
        });
        DepthStage {
            k,
            provider,
            max_depth,
            reference,
        }
    }

    /// Whether it needs the frame's image (a network does).
    pub fn needs_image(&self) -> bool {
        self.provider.needs_image()
    }

    /// Puts the frame's depth map into `tracked` (none without a face: nothing is fused then),
    /// and the alignment's record and warning when the provider aligns. A recording frame
    /// without an associated map, or a network output that cannot be aligned, gets an empty
    /// map: the fusion carries the surface through it.
    ///
    /// # Errors
    /// A missing or unreadable depth file, a map of another size than the frame, a failing
    /// network.
    pub fn acquire(
        &mut self,
        image: Option<&RgbImage>,
        tracked: &mut Tracked,
    ) -> Result<(), Error> {
        let Some(face) = &tracked.face else {
            return Ok(());
        };
        let start = Instant::now();
        let source = tracked.metrics.source.clone();
        let reference = match &mut self.reference {
            // Named as the step of the one provider that aligns so far, a depth network.
            Some(r) => Some(
                r.render(&self.k, face, tracked.model.as_ref())
                    .map_err(|e| Error::on_frame(&source, "depth network", e))?,
            ),
            None => None,
        };
        let depth = self.provider.depth_map(DepthRequest {
            index: tracked.metrics.index,
            source: &source,
            image,
            k: &self.k,
            face_box: face.face_box,
            reference,
            max_depth: self.max_depth,
        })?;
        if let Some(alignment) = &depth.alignment {
            tracked.metrics.depth_alignment = Some(match alignment {
                Ok(fit) => DepthAlignmentMetrics::aligned(fit),
                Err(failure) => DepthAlignmentMetrics::failed(failure),
            });
        }
        if let (Some(w), None) = (depth.warning, &tracked.warning) {
            tracked.warning = Some(format!("{source}: {w}"));
        }
        tracked.metrics.ms.depth += start.elapsed().as_secs_f64() * 1e3;
        tracked.depth_map = Some(depth.map);
        Ok(())
    }
}

impl ReferenceFace {
    /// The z-depth of the fitted model when it is fitted, else of the rigid face fit.
    fn render(
        &mut self,
        k: &Intrinsics,
        face: &TrackedFace,
        model: Option<&FittedModel>,
    ) -> Result<DepthMap, Error> {
        match model {
            Some(model) => {
                self.model_mesh.vertices.clone_from(&model.camera);
                render_surface_depth(&self.model_mesh, k, DepthKind::Z)
            }
            None => render_faces_depth(
                std::slice::from_ref(&face.geometry),
                &self.canonical,
                k,
                DepthKind::Z,
            ),
        }
    }
}
