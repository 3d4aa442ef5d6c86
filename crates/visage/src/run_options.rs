//! What `visage run` takes besides its input and output folder, as data ([`RunOptions`]): the
//! reconstruction ([`PipelineOptions`]), the folder's files, the faces followed and the exports.
//! The command line fills it from its flags and the Python package's `visage.run` from its
//! keyword arguments; [`crate::run_clip`] runs it.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use visage_export::ExportOptions;
use visage_face::FaceTarget;
use visage_mesh::io::PlyFormat;
use visage_run_folder::InputFile;

use crate::{Error, FolderOptions, FrameFilter, KeptFrames, ModelSource, PipelineOptions};

/// Which faces a run meshes (`--faces`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Faces {
    /// The largest in view (a warning says when there were others).
    #[default]
    Largest,
    /// Every face of the first frame that shows one, each tracked on its own into
    /// `OUT/face-N/` (N from left to right), with `OUT/faces.json` listing them.
    All,
}

/// The options of `visage run` (`visage run --help` says what each does; the field is the
/// flag, snake_case). [`Default`] is the command line's defaults.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// The input and the reconstruction.
    pub pipeline: PipelineOptions,
    /// Also a PLY per frame in `meshes/`.
    pub ply: bool,
    /// Also the raw (unfused) surface, a PLY per frame in `raw/`.
    pub save_raw: bool,
    /// PLYs in ASCII rather than binary.
    pub ascii: bool,
    /// Replace a previous run in the folder (its files are removed first, others stay).
    pub overwrite: bool,
    /// Continue the run in the folder where it stopped.
    pub resume: bool,
    /// The largest face, or every face each into its own folder.
    pub faces: Faces,
    /// The files made from the folder after the run (`--glb`, `--texture`, `--plots`,
    /// `--report`, `--preview`).
    pub exports: ExportOptions,
}

impl RunOptions {
    /// The options of [`crate::run_into`] for a run of `input` that follows `target`: the
    /// folder's files, the frames kept for the exports (`keep`), `stop` to end it early.
    ///
    /// # Errors
    /// The input file cannot be read (to fingerprint it).
    pub fn folder_options(
        &self,
        input: &Path,
        target: FaceTarget,
        keep: Option<(FrameFilter, KeptFrames)>,
        stop: &Arc<AtomicBool>,
    ) -> Result<FolderOptions, Error> {
        let format = match self.ascii {
            true => PlyFormat::Ascii,
            false => PlyFormat::BinaryLittleEndian,
        };
        Ok(FolderOptions {
            input_name: input.display().to_string(),
            input_file: InputFile::of(input)?,
            resume: self.resume,
            ply: (format, self.ply, self.save_raw),
            blendshapes: !matches!(self.pipeline.model, ModelSource::None),
            keep,
            stop: Some(stop.clone()),
            target,
        })
    }
}
