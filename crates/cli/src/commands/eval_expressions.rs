//! `visage eval expressions`: recorded ARKit takes replayed on a rendered ICT-FaceKit head,
//! run through the pipeline as a video, and the weights it reads scored against the ones
//! played. `visage-eval` does the work; this parses the flags, writes and prints.

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::Args;
use visage::Intrinsics;
use visage_eval::{
    evaluate_expressions, expression_table, write_expression_results, ExpressionOptions,
    HeadMotion, HeadRender, IdentityChoice, ReplayOptions,
};

/// Arguments of `visage eval expressions`.
#[derive(Args, Debug)]
pub struct ExpressionsArgs {
    /// Live Link Face CSV takes (the 52 ARKit curves; rows without tracking are skipped).
    #[arg(required = true)]
    pub takes: Vec<PathBuf>,
    /// Output folder (created): results.json, plots/TAKE/SHAPE.svg, frames/ with
    /// --save-frames.
    #[arg(long)]
    pub out: PathBuf,
    /// The ICT-FaceKit model: its FaceXModel folder or a checkout of the repository.
    #[arg(long)]
    pub model: PathBuf,
    /// Folder of the MediaPipe model files (default: as `visage run`).
    #[arg(long)]
    pub models: Option<PathBuf>,
    /// Whose face: an ICT-FaceKit identity mode N (its identityNNN.obj) or `random`.
    #[arg(long, default_value = "0")]
    pub identity: String,
    /// Seed of the head motion (and of a random identity).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Largest head yaw, degrees.
    #[arg(long, default_value_t = HeadMotion::default().yaw_deg)]
    pub yaw: f64,
    /// Largest head pitch, degrees.
    #[arg(long, default_value_t = HeadMotion::default().pitch_deg)]
    pub pitch: f64,
    /// Largest head roll, degrees.
    #[arg(long, default_value_t = HeadMotion::default().roll_deg)]
    pub roll: f64,
    /// Largest sideways and vertical head translation, metres.
    #[arg(long, default_value_t = HeadMotion::default().shift_m)]
    pub shift: f64,
    /// Largest head translation toward or away from the camera, metres.
    #[arg(long, default_value_t = HeadMotion::default().depth_shift_m)]
    pub depth_shift: f64,
    /// Hold the neutral face while the head moves (every change the pipeline reads is the
    /// head's motion leaking into the weights); the takes still set the length and clock.
    #[arg(long)]
    pub rigid: bool,
    /// With --rigid: hold this row of each take (counted among rows with tracking) instead of
    /// the neutral face.
    #[arg(long, requires = "rigid")]
    pub rigid_row: Option<usize>,
    /// First row played (among rows with tracking).
    #[arg(long, default_value_t = 0)]
    pub start: usize,
    /// Play every N-th row (the frame rate drops accordingly).
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// Play at most this many frames per take.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Frame width, pixels.
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Frame height, pixels.
    #[arg(long, default_value_t = 480)]
    pub height: u32,
    /// Horizontal field of view, degrees (the pipeline is given these exact intrinsics).
    #[arg(long, default_value_t = 55.0)]
    pub fov_deg: f64,
    /// Distance of the face from the camera at rest, metres.
    #[arg(long, default_value_t = 0.5)]
    pub distance: f64,
    /// Write this many frames of each take, evenly spread, as PNG (OUT/frames/).
    #[arg(long, default_value_t = 0)]
    pub save_frames: usize,
}

/// Runs `visage eval expressions`.
pub fn expressions(args: ExpressionsArgs) -> anyhow::Result<()> {
    let identity = match args.identity.as_str() {
        "random" => IdentityChoice::Random,
        n => IdentityChoice::Mode(n.parse().with_context(|| {
            format!("--identity {n}: expected an identity mode number or `random`")
        })?),
    };
    if args.width == 0 || args.height == 0 {
        bail!("--width and --height must be at least 1");
    }
    visage::check_fov(args.fov_deg)?;
    let f = 0.5 * args.width as f64 / (0.5 * args.fov_deg.to_radians()).tan();
    let k = Intrinsics::new(
        args.width,
        args.height,
        f,
        f,
        (args.width as f64 - 1.0) / 2.0,
        (args.height as f64 - 1.0) / 2.0,
    )?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let frames_dir = (args.save_frames > 0).then(|| args.out.join("frames"));
    if let Some(dir) = &frames_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let options = ExpressionOptions {
        replay: ReplayOptions {
            identity,
            seed: args.seed,
            motion: HeadMotion {
                yaw_deg: args.yaw,
                pitch_deg: args.pitch,
                roll_deg: args.roll,
                shift_m: args.shift,
                depth_shift_m: args.depth_shift,
            },
            rigid: args.rigid.then_some(args.rigid_row),
            start: args.start,
            stride: args.stride,
            max_frames: args.max_frames,
            only: None,
        },
        models: args.models,
        save_frames: args.save_frames,
        frames_dir,
        keep_pose_leak: false,
        keep_mouth_leak: false,
    };
    let render = HeadRender::load(&args.model, k, args.distance).with_context(|| {
        format!(
            "cannot set up the head renderer with the ICT-FaceKit model in {}",
            args.model.display()
        )
    })?;
    let render = std::sync::Arc::new(render);
    let results = evaluate_expressions(&args.takes, &render, &options)?;
    write_expression_results(&args.out, &results)?;
    print!("{}", expression_table(&results));
    Ok(())
}
