//! `visage eval synthetic`: the ground-truth benchmark — synthetic ICT-FaceKit
//! sequences, CNN-like depth noise, the paper's fusion against baselines.
//!
//! Flags are parsed in two stages: [`SyntheticArgs`] (raw, clap) → `BenchmarkConfig`
//! (validated by the library); `visage-eval` does the work.

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::{Args, Subcommand};
use visage_eval::{
    run_benchmark, run_sweep, sweep_table, table, write_first_frames, write_results, write_sweep,
    BenchmarkConfig, FaceAnchoring, Method, NoiseModel, ANCHORED_WEIGHTS,
};
use visage_face::CanonicalMesh;
use visage_fem::Weights;
use visage_morphable::IctModel;

use super::run::SmoothingArg;

/// Arguments of `visage eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    #[command(subcommand)]
    pub command: EvalCommand,
}

/// Benchmarks.
#[derive(Subcommand, Debug)]
pub enum EvalCommand {
    /// Synthetic ICT-FaceKit sequences with known ground truth: writes OUT/results.json,
    /// results.csv, error/jitter plots (SVG) and prints a table.
    Synthetic(Box<SyntheticArgs>),
    /// Real clips: the temporal model's landmarks against EMA, One-Euro, Kalman and Gaussian
    /// filters on the tracked landmarks (jitter, deviation, lag, per region); writes
    /// OUT/results.json and a jitter-against-deviation chart (SVG) per clip, prints a table.
    Video(super::eval_video::VideoArgs),
    /// Recorded ARKit takes (Live Link Face CSV) replayed on a rendered ICT-FaceKit head under
    /// a moving head pose, run through the pipeline as a video, and its 52 weights, head
    /// rotation and identity scored against the played ones: writes OUT/results.json and a
    /// plot per take and shape (SVG), prints a table.
    Expressions(Box<super::eval_expressions::ExpressionsArgs>),
}

/// Arguments of `visage eval synthetic`.
#[derive(Args, Debug)]
pub struct SyntheticArgs {
    /// The ICT-FaceKit model: its FaceXModel folder or a checkout of the repository.
    #[arg(long)]
    pub model: PathBuf,
    /// Output folder (created).
    #[arg(long)]
    pub out: PathBuf,
    /// The small setting of the test suite (3 sequences × 24 frames, a few modes);
    /// --sequences/--frames still override it.
    #[arg(long)]
    pub quick: bool,
    /// Number of scored sequences (default 10; quick: 3).
    #[arg(long)]
    pub sequences: Option<usize>,
    /// Frames per sequence (default 120; quick: 24).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Noise preset: none, gaussian, lowfreq, flicker, holes, edges, cnn-like, or relative (a
    /// monocular network's inverse depth up to a per-frame scale and shift, aligned to the
    /// face model fitted to the landmarks before the methods see it; needs --models).
    #[arg(long, default_value = "cnn-like")]
    pub noise: String,
    /// Master seed; the same seed gives the same results.json (timings aside).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The simulated tracker's landmark smoothing (as `visage run --smoothing`): the
    /// acceleration-to-noise ratio (1/s²) or `off`.
    #[arg(long, default_value_t = SmoothingArg(Some(visage::DEFAULT_LANDMARK_SMOOTHING)))]
    pub smoothing: SmoothingArg,
    /// Smoothness weight λ of the image-plane fusion methods (reference pixels⁴).
    #[arg(long, default_value_t = Weights::default().lambda, allow_hyphen_values = true)]
    pub lambda: f64,
    /// Temporal weight μ of the image-plane fusion methods.
    #[arg(long, default_value_t = Weights::default().mu, allow_hyphen_values = true)]
    pub mu: f64,
    /// Smoothness weight λ of the face-anchored methods (mm⁴ of the canonical face).
    #[arg(long, default_value_t = ANCHORED_WEIGHTS.lambda, allow_hyphen_values = true)]
    pub anchored_lambda: f64,
    /// Temporal weight μ of the face-anchored methods.
    #[arg(long, default_value_t = ANCHORED_WEIGHTS.mu, allow_hyphen_values = true)]
    pub anchored_mu: f64,
    /// Folder of the MediaPipe model files (the canonical face of the face-anchored methods;
    /// default: $VISAGE_MODELS, ./models, or models/ beside the executable). Without them the
    /// face-anchored methods are skipped, with a warning.
    #[arg(long)]
    pub models: Option<PathBuf>,
    /// Also sweep a fusion over these λ values (comma-separated), with --sweep-mu;
    /// writes OUT/sweep.json, sweep.csv, sweep_rmse.svg, sweep_jitter.svg.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub sweep_lambda: Vec<f64>,
    /// μ values of the sweep (comma-separated).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub sweep_mu: Vec<f64>,
    /// The method swept: streaming (image-plane) or face_anchored.
    #[arg(long, default_value = "streaming")]
    pub sweep_method: String,
    /// Write the shaded colour image of each sequence's first frame (OUT/frames/).
    #[arg(long)]
    pub save_frames: bool,
    /// Largest head yaw, degrees (default 25; 0 with the two below: a still head).
    #[arg(long)]
    pub max_yaw: Option<f64>,
    /// Largest head pitch, degrees (default 10).
    #[arg(long)]
    pub max_pitch: Option<f64>,
    /// Largest head translation per axis, metres (default 0.03).
    #[arg(long)]
    pub max_translation: Option<f64>,
    /// Score only these methods (comma-separated names as in the table; raw is always
    /// scored). The way to run the experiments kept out of the default table:
    /// streaming_sift_anchors (SIFT keypoints of the first frame as extra mesh vertices),
    /// face_anchored_faired_sift (fairing weighted by each frame's SIFT keypoints).
    #[arg(long, value_delimiter = ',')]
    pub methods: Vec<String>,
    /// Grid spacing of the image-plane mesh, pixels.
    #[arg(long, default_value_t = visage_fusion::MeshingOptions::default().spacing)]
    pub spacing: u32,
    /// streaming_sift_anchors, face_anchored_faired_sift: SIFT without doubling the image
    /// first (fewer, coarser keypoints).
    #[arg(long)]
    pub sift_no_upsample: bool,
    /// streaming_sift_anchors, face_anchored_faired_sift: keep at most this many keypoints,
    /// the strongest (per frame searched).
    #[arg(long)]
    pub sift_max_keypoints: Option<usize>,
    /// streaming_sift_anchors, face_anchored_faired_sift: find the keypoints on renders with a
    /// seeded procedural skin texture (blotches, pores, freckles) instead of the constant
    /// albedo; the depth inputs are unchanged.
    #[arg(long)]
    pub sift_textured: bool,
    /// streaming_sift_anchors: search frames 0, K, 2K, … and add the union of their keypoints
    /// (default: frame 0 only).
    #[arg(long, value_name = "K")]
    pub sift_frame_step: Option<usize>,
    /// streaming_sift_anchors, a control: replace the keypoints inside the meshing domain by
    /// as many seeded random points of it; face_anchored_faired_sift: give full weight to as
    /// many seeded random vertices per frame as the keypoints do.
    #[arg(long)]
    pub sift_random_control: bool,
    /// face_anchored_faired_sift: the fairing weight of the vertices not within 3 px of a
    /// keypoint, in (0, 1] (those within: 1).
    #[arg(long, value_name = "W", default_value_t = visage_eval::SIFT_FAIRING_BASE_WEIGHT)]
    pub sift_fairing_base_weight: f64,
}

/// Runs `visage eval`.
pub fn run(args: EvalArgs) -> anyhow::Result<()> {
    match args.command {
        EvalCommand::Synthetic(a) => synthetic(*a),
        EvalCommand::Video(a) => super::eval_video::video(a),
        EvalCommand::Expressions(a) => super::eval_expressions::expressions(*a),
    }
}

fn config(args: &SyntheticArgs) -> anyhow::Result<BenchmarkConfig> {
    let mut c = if args.quick {
        BenchmarkConfig::quick()
    } else {
        BenchmarkConfig::full()
    };
    if let Some(n) = args.sequences {
        c.sequences = n;
    }
    if let Some(f) = args.frames {
        c.synthesis.frames = f;
    }
    if let Some(v) = args.max_yaw {
        c.synthesis.max_yaw_deg = v;
    }
    if let Some(v) = args.max_pitch {
        c.synthesis.max_pitch_deg = v;
    }
    if let Some(v) = args.max_translation {
        c.synthesis.max_translation_m = v;
    }
    c.noise = NoiseModel::preset(&args.noise)?;
    c.noise_name = args.noise.clone();
    c.seed = args.seed;
    c.landmark_smoothing = args.smoothing.0;
    c.weights = Weights {
        lambda: args.lambda,
        mu: args.mu,
    };
    c.anchored_weights = Weights {
        lambda: args.anchored_lambda,
        mu: args.anchored_mu,
    };
    if args.spacing == 0 {
        bail!("--spacing must be at least 1");
    }
    c.meshing.spacing = args.spacing;
    if !args.methods.is_empty() {
        c.methods = Some(args.methods.clone());
    }
    c.sift_anchors.upsample = !args.sift_no_upsample;
    c.sift_anchors.max_keypoints = args.sift_max_keypoints;
    c.sift_anchors.textured = args.sift_textured;
    c.sift_anchors.frame_step = args.sift_frame_step;
    c.sift_anchors.random_control = args.sift_random_control;
    c.sift_fairing.base_weight = args.sift_fairing_base_weight;
    if args.sweep_lambda.is_empty() != args.sweep_mu.is_empty() {
        bail!("--sweep-lambda and --sweep-mu go together");
    }
    sweep_method(&args.sweep_method)?;
    c.validate()?;
    Ok(c)
}

fn sweep_method(name: &str) -> anyhow::Result<Method> {
    match name {
        "streaming" => Ok(Method::Streaming),
        "face_anchored" => Ok(Method::FaceAnchored),
        "model_fusion" => Ok(Method::ModelFusion),
        _ => bail!("--sweep-method {name:?}: expected streaming, face_anchored or model_fusion"),
    }
}

fn synthetic(args: SyntheticArgs) -> anyhow::Result<()> {
    let config = config(&args)?;
    let method = sweep_method(&args.sweep_method)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("{}: cannot create", args.out.display()))?;
    eprintln!("loading {}", args.model.display());
    let model = IctModel::load_with(&args.model, &config.import)?;
    let models = args.models.clone().unwrap_or_else(visage_face::models_dir);
    let anchoring = match CanonicalMesh::load(&models) {
        Ok(canonical) => Some(FaceAnchoring::new(
            &model,
            canonical,
            config.anchored_subdivision,
        )?),
        Err(e) => {
            eprintln!("warning: face-anchored methods skipped: {e}");
            None
        }
    };
    if method != Method::Streaming && anchoring.is_none() && !args.sweep_lambda.is_empty() {
        bail!(
            "--sweep-method {} needs the model files (--models)",
            method.name()
        );
    }
    let mut progress = |line: &str| eprintln!("{line}");
    let results = run_benchmark(&model, anchoring.as_ref(), &config, &mut progress)?;
    write_results(&results, &args.out)?;
    if args.save_frames {
        let dir = args.out.join("frames");
        write_first_frames(&model, &config.synthesis, &results.sequences, &dir)?;
    }
    print!("{}", table(&results));
    println!(
        "taubin iterations: {} (tuned on seed {})",
        results.taubin_tuning.iterations, results.taubin_tuning.seed
    );
    if !args.sweep_lambda.is_empty() {
        let points = run_sweep(
            &model,
            anchoring.as_ref(),
            &config,
            method,
            &args.sweep_lambda,
            &args.sweep_mu,
            &mut progress,
        )?;
        write_sweep(&points, &args.sweep_lambda, &args.sweep_mu, &args.out)?;
        print!("{}", sweep_table(&points));
    }
    println!("wrote {}", args.out.join("results.json").display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args() -> SyntheticArgs {
        SyntheticArgs {
            model: PathBuf::from("model"),
            out: PathBuf::from("out"),
            quick: true,
            sequences: None,
            frames: Some(20),
            noise: "gaussian".into(),
            seed: 3,
            smoothing: SmoothingArg(None),
            lambda: 1.0,
            mu: 2.0,
            sweep_lambda: Vec::new(),
            sweep_mu: Vec::new(),
            sweep_method: "streaming".into(),
            anchored_lambda: 30.0,
            anchored_mu: 4.0,
            models: None,
            save_frames: false,
            max_yaw: Some(0.0),
            max_pitch: None,
            max_translation: None,
            methods: Vec::new(),
            spacing: 4,
            sift_no_upsample: false,
            sift_max_keypoints: None,
            sift_textured: false,
            sift_frame_step: None,
            sift_random_control: false,
            sift_fairing_base_weight: visage_eval::SIFT_FAIRING_BASE_WEIGHT,
        }
    }

    #[test]
    fn flags_become_a_validated_config() {
        let c = config(&args()).unwrap();
        assert_eq!(c.landmark_smoothing, None);
        assert_eq!((c.sequences, c.synthesis.frames, c.seed), (3, 20, 3));
        assert_eq!((c.weights.lambda, c.weights.mu), (1.0, 2.0));
        assert_eq!(
            (c.anchored_weights.lambda, c.anchored_weights.mu),
            (30.0, 4.0)
        );
        let bad_method = SyntheticArgs {
            sweep_method: "clip".into(),
            ..args()
        };
        assert!(config(&bad_method)
            .unwrap_err()
            .to_string()
            .contains("sweep-method"));
        assert_eq!(c.noise, NoiseModel::preset("gaussian").unwrap());
        assert_eq!(
            (c.synthesis.max_yaw_deg, c.synthesis.max_pitch_deg),
            (0.0, 10.0)
        );
        let bad_yaw = SyntheticArgs {
            max_yaw: Some(f64::NAN),
            ..args()
        };
        assert!(config(&bad_yaw)
            .unwrap_err()
            .to_string()
            .contains("max-yaw"));

        let bad_noise = SyntheticArgs {
            noise: "speckle".into(),
            ..args()
        };
        assert!(config(&bad_noise)
            .unwrap_err()
            .to_string()
            .contains("speckle"));
        let bad_mu = SyntheticArgs { mu: -1.0, ..args() };
        assert!(config(&bad_mu).unwrap_err().to_string().contains("mu"));
        let one_frame = SyntheticArgs {
            frames: Some(1),
            ..args()
        };
        assert!(config(&one_frame)
            .unwrap_err()
            .to_string()
            .contains("frames"));
        let half_sweep = SyntheticArgs {
            sweep_lambda: vec![1.0],
            ..args()
        };
        assert!(config(&half_sweep).is_err());
        assert_eq!(c.methods, None);
        let chosen = config(&SyntheticArgs {
            methods: vec!["streaming".into(), "streaming_sift_anchors".into()],
            sift_max_keypoints: Some(200),
            sift_textured: true,
            sift_frame_step: Some(10),
            sift_random_control: true,
            ..args()
        })
        .unwrap();
        assert_eq!(
            chosen.methods.as_deref(),
            Some(
                &[
                    "streaming".to_string(),
                    "streaming_sift_anchors".to_string()
                ][..]
            )
        );
        assert_eq!(chosen.sift_anchors.max_keypoints, Some(200));
        assert!(chosen.sift_anchors.textured);
        assert_eq!(chosen.sift_anchors.frame_step, Some(10));
        assert!(chosen.sift_anchors.random_control);
        assert!(!c.sift_anchors.random_control);
        assert!(!c.sift_anchors.textured);
        assert_eq!(c.sift_anchors.frame_step, None);
        assert_eq!(c.sift_fairing, visage_eval::SiftFairingOptions::default());
        let weighted = config(&SyntheticArgs {
            methods: vec!["face_anchored_faired_sift".into()],
            sift_fairing_base_weight: 0.5,
            ..args()
        })
        .unwrap();
        assert_eq!(weighted.sift_fairing.base_weight, 0.5);
        assert!(config(&SyntheticArgs {
            sift_fairing_base_weight: 0.0,
            ..args()
        })
        .is_err());
        assert!(config(&SyntheticArgs {
            sift_frame_step: Some(0),
            ..args()
        })
        .is_err());
        let unknown = SyntheticArgs {
            methods: vec!["streeming".into()],
            ..args()
        };
        assert!(config(&unknown)
            .unwrap_err()
            .to_string()
            .contains("streeming"));
    }
}
