//! `visage landmarks`: 468 FaceMesh landmarks per face and frame (paper §3), optionally the
//! metric face pose and dense depth maps that `visage fuse --depth` reads.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use serde_json::json;
use visage::{check_fov, render_faces_depth, LandmarkReader};
use visage_camera::{write_depth_png, DepthKind, Intrinsics, DEFAULT_FOV_DEG};
use visage_face::model_files;
use visage_video::{is_image_path, FrameSource};

/// Arguments of `visage landmarks`.
#[derive(Args, Debug)]
pub struct LandmarksArgs {
    /// Images, videos or folders of images. A single image reports every face; a video or a
    /// folder is a sequence: the largest face is tracked (the detector runs only when it is
    /// lost), or with `--faces all` every face of every frame is reported.
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// In a sequence, report the largest face (tracked) or every face (both detectors, near
    /// and far faces, run on every frame; on a single image, too).
    #[arg(long, value_enum, default_value = "largest")]
    faces: crate::commands::run::FacesArg,
    /// Write the JSON here instead of standard output.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write, per frame, a 16-bit PNG z-depth map in millimetres (0 = no face) of the
    /// fitted metric face mesh into this folder (`visage fuse --depth DIR` reads it).
    #[arg(long)]
    depth_out: Option<PathBuf>,
    /// Camera intrinsics JSON ({"width","height","fx","fy","cx","cy"}); default: --fov-deg.
    #[arg(long, conflicts_with = "fov_deg")]
    intrinsics: Option<PathBuf>,
    /// Horizontal field of view (degrees) when no intrinsics file is given.
    #[arg(long)]
    fov_deg: Option<f64>,
    /// Model directory; default: $VISAGE_MODELS, else ./models or a models/ folder beside the executable (see `visage models fetch`).
    #[arg(long)]
    models: Option<PathBuf>,
}

/// Runs `visage landmarks`.
pub fn run(args: LandmarksArgs) -> anyhow::Result<()> {
    let fov = args.fov_deg.unwrap_or(DEFAULT_FOV_DEG);
    check_fov(fov)?;
    let intrinsics = args
        .intrinsics
        .as_deref()
        .map(Intrinsics::load_json)
        .transpose()
        .context("cannot use --intrinsics")?;
    let models = args.models.clone().unwrap_or_else(model_files::models_dir);
    let every_face = args.faces == crate::commands::run::FacesArg::All;
    let mut reader = LandmarkReader::load(&models, every_face)?;
    if let Some(dir) = &args.depth_out {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let mut frames_json = Vec::new();
    let mut frame_counter = 0usize;
    let mut faces_found = 0usize;
    // A failure part-way (a video that breaks) keeps the frames read before it: they are
    // written, and the error says so.
    let mut read_all = || -> anyhow::Result<()> {
        for input in &args.inputs {
            let still = input.is_file() && is_image_path(input);
            reader.start();
            let source = FrameSource::open(input)?;
            for frame in source {
                let frame = frame?;
                let (w, h) = frame.image.dimensions();
                let k = match intrinsics {
                    Some(k) => {
                        k.check_size(w, h)
                            .with_context(|| format!("{}: --intrinsics", frame.source))?;
                        k
                    }
                    None => Intrinsics::from_fov(w, h, fov)?,
                };
                let faces = reader.read(frame, &k, still)?;
                for warning in &faces.warnings {
                    eprintln!("warning: {warning}");
                }
                faces_found += faces.record.faces.len();
                if let Some(dir) = &args.depth_out {
                    let depth = render_faces_depth(
                        &faces.geometries,
                        reader.canonical(),
                        &k,
                        DepthKind::Z,
                    )?;
                    let path = dir.join(format!("depth_{frame_counter:06}.png"));
                    write_depth_png(&path, &depth, 1000.0)
                        .with_context(|| format!("cannot write {}", path.display()))?;
                }
                frames_json.push(faces.record);
                frame_counter += 1;
            }
        }
        Ok(())
    };
    if let Err(e) = read_all() {
        write_json(args.out.as_deref(), &json!({ "frames": frames_json }))?;
        let written = match &args.out {
            Some(path) => format!("{} lists them", path.display()),
            None => "standard output got them".to_owned(),
        };
        return Err(e.context(format!(
            "stopped after {frame_counter} frame{} ({written})",
            if frame_counter == 1 { "" } else { "s" }
        )));
    }
    let (tracked, detector_runs) = reader.tracking();
    if tracked > 0 {
        eprintln!(
            "tracked {tracked} video frames, detector ran on {detector_runs} ({:.1}%)",
            100.0 * detector_runs as f64 / tracked as f64
        );
    }
    let doc = json!({ "frames": frames_json });
    write_json(args.out.as_deref(), &doc)?;
    if faces_found == 0 {
        return Err(crate::exit::Failure {
            code: crate::exit::NO_FACE,
            error: anyhow::anyhow!(
                "no face was found in any of the {frame_counter} frames (the landmarks file \
                 lists them, without faces)"
            ),
        }
        .into());
    }
    Ok(())
}

fn write_json(out: Option<&Path>, doc: &serde_json::Value) -> anyhow::Result<()> {
    let text = serde_json::to_string(doc)?;
    match out {
        Some(path) => Ok(visage::write_atomically(path, |tmp| {
            std::fs::write(tmp, &text).map_err(|source| visage::run_folder::RunFolderError::Write {
                path: tmp.to_owned(),
                source,
            })
        })?),
        None => {
            let mut stdout = std::io::stdout().lock();
            writeln!(stdout, "{text}").context("cannot write to standard output")
        }
    }
}
