//! [`LiveRecording`]: a live session written to the folder `visage run` writes — the point
//! cache, `landmarks.json`, the blendshape curves, `camera.json`, the identity and a
//! `metrics.json` that lists every frame with its capture-to-send latency — so a take can be
//! exported afterwards with `visage export`. The same streams, atomic names and final
//! `metrics.json` as a run (`visage_run_folder::OutputDir`); a recording cannot be resumed
//! (a live source cannot be read again).

use std::path::Path;

use visage_run_folder::{FrameSelection, MeshOutput, OutputDir, RunDescription};

use crate::{Error, FrameResult, Reconstructor, RunOutcome};

/// A live session being recorded.
pub struct LiveRecording {
    out: OutputDir,
    input: String,
}

impl LiveRecording {
    /// Starts the folder `dir` (already claimed: see `visage_run_folder::claim`) for frames
    /// from `input` processed by `reconstructor`: `camera.json` and a `metrics.json` that says
    /// `"running"`.
    ///
    /// # Errors
    /// The folder or its files cannot be written.
    pub fn start(dir: &Path, reconstructor: &Reconstructor, input: &str) -> Result<Self, Error> {
        let out = OutputDir::create(dir)?
            .with_point_cache()?
            .with_landmarks()?
            .with_blendshapes(None)?;
        out.write_camera(reconstructor.intrinsics())?;
        out.write_running(&RunDescription {
            input,
            input_file: None,
            intrinsics: reconstructor.intrinsics(),
            parameters: reconstructor.parameters(),
            selection: FrameSelection {
                every: 1,
                max_frames: None,
            },
        })?;
        Ok(LiveRecording {
            out,
            input: input.to_owned(),
        })
    }

    /// Writes one processed frame.
    ///
    /// # Errors
    /// A file cannot be written.
    pub fn write(&mut self, result: &FrameResult<'_>) -> Result<(), Error> {
        self.out.write_landmarks(result.landmarks)?;
        if let (Some(mesh), Some(surfaces)) = (result.mesh(), result.surfaces()) {
            self.out.write_mesh(&MeshOutput {
                index: result.index(),
                triangles: &mesh.triangles,
                uvs: &mesh.uvs,
                fused: &surfaces.fused,
                raw: &surfaces.raw,
            })?;
        }
        if let Some(b) = result.blendshapes {
            self.out.write_blendshapes(b)?;
        }
        Ok(())
    }

    /// Finishes the streamed files, writes the identity and `metrics.json`: `outcome`'s report
    /// with each frame's `latency_ms` (`latencies`: frame index and milliseconds).
    ///
    /// # Errors
    /// A file cannot be written (`metrics.json` is still attempted).
    pub fn finish(mut self, outcome: &RunOutcome, latencies: &[(usize, f64)]) -> Result<(), Error> {
        let mut first_error = self.out.finish().err().map(Error::from);
        if let Some(identity) = &outcome.identity {
            if let Err(e) = self.out.write_identity(
                &identity.neutral_mesh(),
                &identity.coefficients,
                identity.frames,
            ) {
                first_error.get_or_insert(e.into());
            }
        }
        let mut metrics =
            serde_json::to_value(outcome.report(&self.input)).map_err(|e| Error::Input {
                path: self.out.dir().join(visage_run_folder::file_names::METRICS),
                reason: format!("cannot encode the run's figures: {e}"),
            })?;
        if let Some(frames) = metrics["frames"].as_array_mut() {
            let by_index: std::collections::HashMap<usize, f64> =
                latencies.iter().copied().collect();
            for f in frames {
                let index = f["index"].as_u64().map(|i| i as usize);
                if let Some(ms) = index.and_then(|i| by_index.get(&i)) {
                    f["latency_ms"] = serde_json::json!(ms);
                }
            }
        }
        if let Err(e) = self.out.write_metrics(&metrics) {
            first_error.get_or_insert(e.into());
        }
        first_error.map_or(Ok(()), Err)
    }
}
