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
    /// The record number (records forgotten included) of the last frame whose surfaces were
    /// measured.
    last_measured: Option<usize>,
    /// Vertices of the mesh (0 before the first mesh).
    pub vertices: usize,
    /// Only the newest record is kept (a live session that is not recorded: memory stays flat).
    pub newest_only: bool,
    /// Records dropped for that, before `frames[0]`.
    forgotten: usize,
}

impl Recorder {
    /// Appends a frame's record; returns its position.
    pub fn push(&mut self, metrics: FrameMetrics) -> usize {
        if self.newest_only {
            self.forgotten += self.frames.len();
            self.frames.clear();
        }
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
        let record = self.forgotten + position;
        if self.last_measured.is_none_or(|p| p + 1 != record) {
            self.quality.gap();
        }
        self.last_measured = Some(record);
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

#[cfg(test)]
mod tests {
    use super::*;
    use visage_run_folder::FrameStatus;

    #[test]
    fn newest_only_keeps_one_record_and_counts_the_rest() {
        let record = |i| FrameMetrics::new(i, format!("frame {i}"), FrameStatus::NoFace);
        let mut all = Recorder::default();
        let mut newest = Recorder {
            newest_only: true,
            ..Recorder::default()
        };
        for i in 0..5 {
            assert_eq!(all.push(record(i)), i);
            assert_eq!(newest.push(record(i)), 0);
        }
        assert_eq!(all.frames.len(), 5);
        assert_eq!(newest.frames.len(), 1);
        assert_eq!(newest.frames[0].index, 4);
        assert_eq!(newest.forgotten, 4);
    }
}
