//! Where a whole-clip run's results go, frame by frame, in input order
//! ([`crate::Reconstructor::run`]); [`crate::OutputDir`] writes them to files.

use crate::animation::BlendshapeFrame;
use crate::landmarks::LandmarksFrame;
use crate::metrics::FrameMetrics;
use crate::{Error, Surfaces};

/// A meshed frame's final surfaces.
#[derive(Clone, Copy, Debug)]
pub struct MeshFrame<'a> {
    /// Frame index in the input.
    pub index: usize,
    /// The mesh's triangles (fixed for the run).
    pub triangles: &'a [[u32; 3]],
    /// Texture coordinates per vertex (empty: the mesh has none).
    pub uvs: &'a [[f64; 2]],
    pub surfaces: &'a Surfaces,
}

/// Receives a run's results on the calling thread. Every method has a do-nothing default, so
/// `()` is the sink that keeps nothing (a benchmark).
pub trait FrameSink {
    /// Every frame's landmarks record, in input order, as soon as the frame is fused.
    fn landmarks(&mut self, _record: &LandmarksFrame) -> Result<(), Error> {
        Ok(())
    }

    /// A meshed frame's final surfaces, in input order: right after the frame in streaming
    /// mode, after the clip solve in clip mode.
    fn mesh(&mut self, _frame: &MeshFrame<'_>) -> Result<(), Error> {
        Ok(())
    }

    /// A frame's blendshape weights and head and eye rotations (when the model is fitted), in
    /// input order.
    fn blendshapes(&mut self, _frame: &BlendshapeFrame) -> Result<(), Error> {
        Ok(())
    }

    /// A frame is through the pipeline (its mesh, in clip mode, comes later).
    fn frame_done(&mut self, _metrics: &FrameMetrics) {}

    /// Something the user should know about a frame (no face found, no metric fit).
    fn warning(&mut self, _message: &str) {}
}

impl FrameSink for () {}
