//! Where a whole-clip run's results go, frame by frame, in input order
//! ([`crate::Reconstructor::run`]); [`OutputDir`] writes them to files.

use visage_rig::BlendshapeFrame;
use visage_run_folder::{FrameMetrics, LandmarksFrame, MeshOutput, OutputDir};

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

    /// A run into an output folder ([`crate::run_into`]) starts, to process `frames` frames
    /// (when known).
    fn started(&mut self, _frames: Option<usize>) {}

    /// Something the user may want to know about the run that is not a problem (what a
    /// resumed run kept).
    fn notice(&mut self, _message: &str) {}

    /// A notice the user should have even when they asked for no notices (a quiet command
    /// line): what the run assumed for them (the camera from an image's EXIF or a dataset's
    /// default) or removed from their folder (`overwrite`). By default a notice.
    fn caution(&mut self, message: &str) {
        self.notice(message);
    }

    /// A run into an output folder ([`crate::run_into`]) has had its last frame (its files
    /// are finished next, and then any exports made).
    fn ended(&mut self) {}
}

impl FrameSink for () {}

/// A run's output folder as a sink: the fused surface (and the raw one, for PLYs), the
/// landmarks records and the blendshape curves.
impl FrameSink for OutputDir {
    fn landmarks(&mut self, record: &LandmarksFrame) -> Result<(), Error> {
        Ok(self.write_landmarks(record)?)
    }

    fn mesh(&mut self, frame: &MeshFrame<'_>) -> Result<(), Error> {
        Ok(self.write_mesh(&MeshOutput {
            index: frame.index,
            triangles: frame.triangles,
            uvs: frame.uvs,
            fused: &frame.surfaces.fused,
            raw: &frame.surfaces.raw,
        })?)
    }

    fn blendshapes(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        Ok(self.write_blendshapes(frame)?)
    }
}
