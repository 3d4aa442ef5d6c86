//! `visage model build`: the compact face model the fit uses, derived from an ICT-FaceKit
//! folder and the canonical FaceMesh (the landmark correspondence). The file shipped in
//! `crates/morphable/data/` is made by
//! `visage model build --ict ICT-FaceKit/FaceXModel --out crates/morphable/data/ict_face_model.bin`.

use std::path::PathBuf;

use clap::{Args, Subcommand};
use visage_face::{model_files, CanonicalMesh};
use visage_morphable::{CanonicalCorrespondence, FaceModel, IctModel};

/// Arguments of `visage model`.
#[derive(Args, Debug)]
pub struct ModelArgs {
    #[command(subcommand)]
    command: ModelCommand,
}

#[derive(Subcommand, Debug)]
enum ModelCommand {
    /// Build the compact face model from an ICT-FaceKit folder
    Build {
        /// The ICT-FaceKit model: its FaceXModel folder or a checkout of the repository.
        #[arg(long)]
        ict: PathBuf,
        /// The model file to write.
        #[arg(long)]
        out: PathBuf,
        /// Folder of the MediaPipe model files (the canonical face); default as for `run`.
        #[arg(long)]
        models: Option<PathBuf>,
    },
}

/// Runs `visage model`.
pub fn run(args: ModelArgs) -> anyhow::Result<()> {
    let ModelCommand::Build { ict, out, models } = args.command;
    let models = models.unwrap_or_else(model_files::models_dir);
    let canonical = CanonicalMesh::load(&models)?;
    let ict = IctModel::load(&ict)?;
    let landmarks = CanonicalCorrespondence::new(&ict, &canonical.vertices)?;
    let model = FaceModel::from_ict(&ict, &landmarks)?;
    model.write(&out)?;
    let worst = landmarks.projection_m.iter().fold(0.0f64, |a, &b| a.max(b));
    eprintln!(
        "wrote {}: {} vertices, {} identity and {} expression modes; landmarks {:.1} mm \
         (RMS) from the alignment, at most {:.1} mm from the surface",
        out.display(),
        model.vertex_count(),
        model.identity.len(),
        model.expressions.len(),
        landmarks.landmark_rms_m * 1e3,
        worst * 1e3
    );
    Ok(())
}
