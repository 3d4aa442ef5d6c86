//! `visage`: temporally stable metric 3-D face meshes from video, on a CPU.
//!
//! A thin binary over the library crates: each subcommand lives in `commands/<name>.rs`, parses
//! its raw flags into a validated configuration and calls the libraries.
//!
//! Exit codes: 0 success; 1 an internal error (a bug); 2 bad input or an unusable environment
//! (missing or malformed files, invalid parameters, unwritable output), with a message that
//! names the file and the problem; 3 no face in any frame of the input (`run`, `landmarks`);
//! 130 interrupted (Ctrl-C, SIGTERM) after writing what was done. Usage errors from the
//! argument parser also exit with 2. `docs/errors.md` lists what each bad input gives.

#![forbid(unsafe_code)]

mod commands;
mod exit;
mod interrupt;
mod progress;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Temporally stable, metric 3-D face meshes from RGB video, in real time on a CPU.
///
/// `visage run VIDEO --out OUT` writes a fused face mesh per frame; `visage COMMAND --help`
/// explains each command. Exit codes: 0 success, 1 internal error, 2 bad input or
/// environment (the message names the file and the problem), 3 no face in the whole input,
/// 130 interrupted.
#[derive(Parser)]
#[command(name = "visage", version, max_term_width = 80)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Video or images in, a fused metric face mesh per frame out
    ///
    /// Writes OUT/sequence.pc2 with mesh.obj (every frame's surface; a PLY per frame with
    /// --ply), landmarks.json, metrics.json, camera.json and the blendshape curves; with
    /// --glb, --texture, --plots, --report, --preview also those (as `visage export`
    /// makes them). Exit
    /// codes: 0 done; 2 bad input (missing or corrupt input — a broken video keeps the frames
    /// before the break —, intrinsics for another size, unwritable output, missing models);
    /// 1 internal error.
    Run(commands::run::RunArgs),
    /// `run` over one shard of a manifest of clips (array jobs), resumable, exactly once
    ///
    /// Each clip goes to OUT/ID/ whole, with done.json (input SHA-256, options, version,
    /// output checksums) or error.json; clips already done are skipped. The shard comes from
    /// --shard-index/--shard-count or the scheduler (Slurm, Kubernetes Indexed Job, AWS
    /// Batch). `visage batch status OUT` summarises a batch folder. Exit codes: 0 every clip
    /// done; 3 some failed (the others finished); 2 bad invocation; 130 interrupted.
    Batch(commands::batch::BatchArgs),
    /// The `run` pipeline without writing meshes, timed per stage
    ///
    /// Decoding, tracking, the metric fit, depth and fusion all run and the quality figures
    /// are measured; prints JSON (frames per second, per-stage median and 95th percentile,
    /// CPU per frame with the decoder, peak memory, jitter and reprojection error).
    Bench(commands::bench::BenchArgs),
    /// Fuse a folder of 16-bit PNG depth maps into a mesh sequence
    ///
    /// The image-plane mesh over the pixels with depth in at least half of the frames,
    /// fused frame by frame (streaming) or over the whole clip.
    Fuse(commands::fuse::FuseArgs),
    /// Make the animated glTF, texture, plots, report or preview video of a run's output folder
    ///
    /// Reads OUT/sequence.pc2, mesh.obj, camera.json, metrics.json, landmarks.json and
    /// blendshapes.json, and the input again for the texture and the preview. Without flags:
    /// everything but the preview video.
    Export(commands::export::ExportCommandArgs),
    /// Fair a mesh: Willmore-type smoothing with soft positional constraints
    ///
    /// Minimises ∫|Δv|² dA + γ ∫ w |v − p|² dA (paper Eq. 5.3 as corrected) by preconditioned
    /// conjugate gradients; prints iterations, residual and the surface figures as JSON.
    Fair(commands::fair::FairArgs),
    /// Time the factor-once solver at several mesh sizes (JSON)
    BenchSolver(commands::bench_solver::BenchSolverArgs),
    /// Render a mesh to a colour PNG and/or a 16-bit depth PNG
    Render(commands::render::RenderArgs),
    /// A camera or a stream, processed as it arrives and streamed out (VMC, Live Link Face)
    ///
    /// Frame by frame, causally: when processing falls behind, the newest frame wins and the
    /// others are dropped and counted. The closing line gives frames in, processed and dropped,
    /// and the latency from capture to the streams.
    Live(commands::live::LiveArgs),
    /// Landmarks, metric head pose and face depth maps
    ///
    /// 468 FaceMesh landmarks per face and frame of images or videos, the metric head pose,
    /// and optionally the fitted face's depth maps (which `visage fuse --depth` reads).
    Landmarks(commands::landmarks::LandmarksArgs),
    /// SIFT keypoints and descriptors of an image (JSON in OpenCV's conventions)
    ///
    /// Scale-space extrema of the difference of Gaussians with sub-pixel refinement, 36-bin
    /// orientations and 128-byte descriptors (Lowe 2004, as OpenCV computes them).
    Keypoints(commands::keypoints::KeypointsArgs),
    /// SIFT matches between two images (ratio test and mutual check)
    Match(commands::matches::MatchArgs),
    /// Fetch or check the pinned MediaPipe model files
    ///
    /// Apache-2.0 model files from the npm package @mediapipe/face_mesh, sha256-checked.
    Models(commands::models::ModelsArgs),
    /// Build the compact face model from an ICT-FaceKit folder
    Model(commands::model::ModelArgs),
    /// Benchmarks against ground truth
    ///
    /// `visage eval synthetic`: ICT-FaceKit sequences with known geometry, CNN-like depth
    /// noise, the fusion methods against baselines.
    Eval(commands::eval::EvalArgs),
}

fn main() -> ExitCode {
    // A negative number is a value (`--fov-deg -5` is then refused by its range check, which
    // says why), not an unknown flag; clap does not pass this setting down by itself.
    let (lambda, mu) = commands::run::weight_help();
    let command = Cli::command().mut_subcommands(|c| {
        let c = c.allow_negative_numbers(true);
        // The weights' help states the pipeline's defaults, from the constants themselves.
        if c.get_arguments().any(|a| a.get_id() == "lambda") && c.get_name() != "eval" {
            c.mut_arg("lambda", |a| {
                a.help(lambda.clone()).long_help(lambda.clone())
            })
            .mut_arg("mu", |a| a.help(mu.clone()).long_help(mu.clone()))
        } else {
            c
        }
    });
    let cli = match Cli::from_arg_matches(&command.get_matches()) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let result = match cli.command {
        Command::Run(args) => commands::run::run(args),
        Command::Batch(args) => commands::batch::run(args),
        Command::Bench(args) => commands::bench::run(args),
        Command::Fuse(args) => commands::fuse::run(args),
        Command::Export(args) => commands::export::run(args),
        Command::Fair(args) => commands::fair::run(args),
        Command::BenchSolver(args) => commands::bench_solver::run(args),
        Command::Render(args) => commands::render::run(args),
        Command::Live(args) => commands::live::run(args),
        Command::Landmarks(args) => commands::landmarks::run(args),
        Command::Keypoints(args) => commands::keypoints::run(args),
        Command::Match(args) => commands::matches::run(args),
        Command::Models(args) => commands::models::run(args),
        Command::Model(args) => commands::model::run(args),
        Command::Eval(args) => commands::eval::run(args),
    };
    exit::report(result)
}
