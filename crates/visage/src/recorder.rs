//! The per-frame records of a run and its quality figures, kept on the consuming thread.

use visage_camera::Intrinsics;

use visage_run_folder::{FrameMetrics, RunSummary, RunTiming};

use crate::quality::QualityMeter;
use crate::{Error, FrameSink, MeshFrame, Surfaces};

/// Frame records in input order and the quality meter over the meshed frames.
#[derive(Default)]
pub(crate) struct Recorder {
    pub frames: Vec<FrameMetrics>,
    quality: QualityMeter,
    /// Position in `frames` of the last frame whose surfaces were measured.
    last_measured: Option<usize>,
    /// Vertices of the mesh (0 before the first mesh).
    pub vertices: usize,
}

impl Recorder {
    /// Appends a frame's record; returns its position.
    pub fn push(&mut self, metrics: FrameMetrics) -> usize {
        self.frames.push(metrics);
        self.frames.len() - 1
    }

    /// The position of the frame with input index `index`.
    pub fn position(&self, index: usize) -> Option<usize> {
        self.frames.binary_search_by_key(&index, |f| f.index).ok()
    }

    /// Measures the meshed frame at `position` (its final surfaces): the jitter pair with the
    /// previous meshed frame (when it is the frame before) and its reprojection errors.
    pub fn measure(&mut self, position: usize, k: &Intrinsics, s: &Surfaces) {
        if self.last_measured.is_none_or(|p| p + 1 != position) {
            self.quality.gap();
        }
        self.last_measured = Some(position);
        self.vertices = s.fused.len();
        let (f, r) = self.quality.push(
            k,
            &s.fused,
            &s.raw,
            &s.fused_landmarks,
            &s.raw_landmarks,
            &s.landmarks_px,
        );
        let m = &mut self.frames[position];
        m.reprojection_px = f;
        m.reprojection_raw_px = r;
    }

    /// A meshed frame's tail: measures its final surfaces `s` (as [`Self::measure`]) and
    /// hands them, on the mesh of `triangles` and `uvs`, to `sink`.
    pub fn mesh(
        &mut self,
        position: usize,
        k: &Intrinsics,
        s: &Surfaces,
        triangles: &[[u32; 3]],
        uvs: &[[f64; 2]],
        sink: &mut dyn FrameSink,
    ) -> Result<(), Error> {
        self.measure(position, k, s);
        sink.mesh(&MeshFrame {
            index: self.frames[position].index,
            triangles,
            uvs,
            surfaces: s,
        })
    }

    /// The run's totals.
    pub fn summary(&self, timing: RunTiming) -> RunSummary {
        RunSummary::of(&self.frames, self.quality.summary(), timing)
    }
}
