//! The benchmark driver: sequences → noisy inputs → methods → metrics (issue #5).

use std::collections::BTreeMap;

use visage_camera::{DepthKind, DepthMap};
use visage_fem::{ClipOptions, Weights};
use visage_mesh::Mask;
use visage_morphable::{IctModel, ImportOptions};
use visage_pipeline::{FusionSetup, MeshingOptions, DEFAULT_MAX_DEPTH_M, DOMAIN_MAJORITY};

use crate::method::{Method, MethodInput, MethodRun};
use crate::metrics::{evaluate_sequence, MethodSummary, MetricAccumulator, PerFrame};
use crate::noise::{NoiseGenerator, NoiseModel};
use crate::synthesis::{synthesize, SynthesisConfig, SyntheticSequence};
use crate::EvalError;

/// Salt of the seed of the Taubin tuning sequence: tuned on data the benchmark never scores.
pub const TUNING_SALT: u64 = 0x7a_0b1e_5eed;
/// Salt that separates a sequence's noise stream from its synthesis stream.
const NOISE_SALT: u64 = 0x0015_e5ee_d000;
/// Fewest domain pixels a sequence must leave to be meshed.
const MIN_DOMAIN_PIXELS: usize = 64;

/// SplitMix64 (Steele et al. 2014): decorrelated seeds from consecutive integers.
pub fn mix_seed(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d1_049b_1331_11eb);
    z ^ (z >> 31)
}

/// Everything that decides a benchmark's numbers (the `config` of `results.json`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BenchmarkConfig {
    pub synthesis: SynthesisConfig,
    /// Name of the noise preset (see [`crate::NOISE_PRESETS`]).
    pub noise_name: String,
    pub noise: NoiseModel,
    /// Number of scored sequences.
    pub sequences: usize,
    /// Master seed: sequence s uses `mix_seed(seed + s)`.
    pub seed: u64,
    /// λ, μ of the fusion methods.
    pub weights: Weights,
    pub meshing: MeshingOptions,
    pub clip: ClipOptions,
    pub max_depth_m: f64,
    /// Taubin iteration counts tried on the tuning sequence.
    pub taubin_candidates: Vec<usize>,
    /// The modes imported from the model (recorded for reproducibility).
    #[serde(skip)]
    pub import: ImportOptions,
    /// Identity and expression modes actually used.
    pub identity_modes: usize,
    pub expression_modes: Vec<String>,
}

/// Expressions of the quick setting: the most visible ones of the shared subset.
pub const QUICK_EXPRESSIONS: [&str; 4] = ["jawOpen", "mouthSmile_L", "eyeBlink_R", "browInnerUp_L"];

impl BenchmarkConfig {
    /// The full setting: 10 sequences × 120 frames at 320×240, `cnn-like` noise, the paper's
    /// λ, μ, every mode of the model.
    pub fn full() -> BenchmarkConfig {
        BenchmarkConfig {
            synthesis: SynthesisConfig::default(),
            noise_name: "cnn-like".into(),
            noise: NoiseModel::cnn_like(),
            sequences: 10,
            seed: 0,
            weights: Weights::default(),
            meshing: MeshingOptions::default(),
            clip: ClipOptions::default(),
            max_depth_m: DEFAULT_MAX_DEPTH_M,
            taubin_candidates: vec![0, 1, 2, 3, 5, 8, 12, 20, 30, 50],
            import: ImportOptions::default(),
            identity_modes: 0,
            expression_modes: Vec::new(),
        }
    }

    /// The quick setting for the test suite: 1 sequence × 16 frames at 160×120 (f = 175 px),
    /// 3 identity and 4 expression modes, 3-pixel mesh spacing, fewer Taubin candidates.
    pub fn quick() -> BenchmarkConfig {
        let full = BenchmarkConfig::full();
        BenchmarkConfig {
            synthesis: SynthesisConfig {
                width: 160,
                height: 120,
                focal_px: 175.0,
                frames: 16,
                ..SynthesisConfig::default()
            },
            sequences: 1,
            meshing: MeshingOptions {
                spacing: 3,
                ..MeshingOptions::default()
            },
            taubin_candidates: vec![0, 1, 2, 4, 8, 16],
            import: ImportOptions {
                max_identities: Some(3),
                expressions: Some(QUICK_EXPRESSIONS.iter().map(|s| s.to_string()).collect()),
            },
            ..full
        }
    }

    /// Errors on values outside their ranges.
    pub fn validate(&self) -> Result<(), EvalError> {
        self.synthesis.validate()?;
        self.noise.validate()?;
        self.weights.validate()?;
        if self.sequences == 0 {
            return Err(EvalError::InvalidConfig {
                name: "sequences",
                value: "0".into(),
                reason: "need at least one sequence",
            });
        }
        if self.taubin_candidates.is_empty() {
            return Err(EvalError::InvalidConfig {
                name: "taubin_candidates",
                value: "[]".into(),
                reason: "need at least one iteration count",
            });
        }
        if !(self.max_depth_m.is_finite() && self.max_depth_m > 0.0) {
            return Err(EvalError::InvalidConfig {
                name: "max_depth_m",
                value: self.max_depth_m.to_string(),
                reason: "must be positive",
            });
        }
        Ok(())
    }
}

/// How the Taubin iteration count was chosen.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TaubinTuning {
    /// Seed of the tuning sequence (never scored).
    pub seed: u64,
    /// The chosen count: smallest RMSE on the tuning sequence.
    pub iterations: usize,
    /// (iterations, RMSE mm) per candidate.
    pub rmse_mm: Vec<(usize, f64)>,
}

/// A scored sequence, for the record.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SequenceInfo {
    pub seed: u64,
    pub distance_m: f64,
    /// Vertices of the image-plane mesh shared by the methods.
    pub mesh_vertices: usize,
    pub domain_pixels: usize,
}

/// Everything `results.json` holds.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BenchmarkResults {
    pub config: BenchmarkConfig,
    pub taubin_tuning: TaubinTuning,
    pub sequences: Vec<SequenceInfo>,
    /// Per method (keys: [`Method::name`]).
    pub methods: BTreeMap<String, MethodSummary>,
    /// Per method, per frame index (mean over sequences).
    pub per_frame: BTreeMap<String, PerFrame>,
}

/// A sequence with its noisy input and the input's meshing domain.
pub struct PreparedSequence {
    pub truth: SyntheticSequence,
    pub inputs: Vec<DepthMap>,
    pub domain: Mask,
    pub reference: DepthMap,
}

impl PreparedSequence {
    /// Synthesises the sequence of `seed`, draws its noise and derives the domain (pixels valid
    /// in at least [`DOMAIN_MAJORITY`] of the frames) and reference (their mean depth), as
    /// `visage fuse` does from files.
    pub fn new(
        model: &IctModel,
        config: &BenchmarkConfig,
        seed: u64,
    ) -> Result<PreparedSequence, EvalError> {
        let truth = synthesize(model, &config.synthesis, seed)?;
        let mut noise = NoiseGenerator::new(config.noise, mix_seed(seed ^ NOISE_SALT))?;
        let inputs: Vec<DepthMap> = truth.frames.iter().map(|f| noise.apply(&f.depth)).collect();
        let (w, h) = (truth.k.width, truth.k.height);
        let n = (w * h) as usize;
        let (mut count, mut sum) = (vec![0usize; n], vec![0.0f64; n]);
        for d in &inputs {
            for (p, &z) in d.data.iter().enumerate() {
                if DepthMap::is_valid(z) && (z as f64) <= config.max_depth_m {
                    count[p] += 1;
                    sum[p] += z as f64;
                }
            }
        }
        let need = (DOMAIN_MAJORITY * inputs.len() as f64).ceil() as usize;
        let domain = Mask {
            width: w,
            height: h,
            data: count.iter().map(|&c| c > 0 && c >= need).collect(),
        };
        if domain.count() < MIN_DOMAIN_PIXELS {
            return Err(EvalError::Degenerate {
                seed,
                reason: format!(
                    "{} pixels valid in half of the frames (need {MIN_DOMAIN_PIXELS})",
                    domain.count()
                ),
            });
        }
        let mut reference = DepthMap::empty(w, h, DepthKind::Z);
        for p in 0..n {
            if count[p] > 0 {
                reference.data[p] = (sum[p] / count[p] as f64) as f32;
            }
        }
        Ok(PreparedSequence {
            truth,
            inputs,
            domain,
            reference,
        })
    }

    /// The methods' common input with `weights`.
    pub fn input<'a>(&'a self, config: &'a BenchmarkConfig, weights: Weights) -> MethodInput<'a> {
        MethodInput {
            k: &self.truth.k,
            domain: &self.domain,
            reference: &self.reference,
            meshing: &config.meshing,
            weights,
            clip: &config.clip,
            max_depth_m: config.max_depth_m,
            frames: &self.inputs,
        }
    }

    /// The image-plane mesh the methods share (deterministic, so equal to theirs).
    pub fn setup(&self, config: &BenchmarkConfig) -> Result<FusionSetup, EvalError> {
        Ok(FusionSetup::new(
            &self.truth.k,
            &self.domain,
            &self.reference,
            &config.meshing,
        )?)
    }
}

/// Seed of scored sequence `s`.
pub fn sequence_seed(master: u64, s: usize) -> u64 {
    mix_seed(master.wrapping_add(s as u64))
}

/// Picks the Taubin iteration count with the smallest RMSE on a sequence drawn from
/// `mix_seed(seed ^ TUNING_SALT)`.
pub fn tune_taubin(model: &IctModel, config: &BenchmarkConfig) -> Result<TaubinTuning, EvalError> {
    let seed = mix_seed(config.seed ^ TUNING_SALT);
    let seq = PreparedSequence::new(model, config, seed)?;
    let setup = seq.setup(config)?;
    let input = seq.input(config, config.weights);
    let mut rmse_mm = Vec::new();
    for &iterations in &config.taubin_candidates {
        let run = Method::Taubin { iterations }.run(&input)?;
        let mut acc = [MetricAccumulator::default()];
        evaluate_sequence(&seq.truth, &setup, &[&run.solutions], 0, &mut acc);
        rmse_mm.push((iterations, acc[0].summary().rmse_mm));
    }
    let iterations = rmse_mm
        .iter()
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
        .map_or(0, |p| p.0);
    Ok(TaubinTuning {
        seed,
        iterations,
        rmse_mm,
    })
}

/// The methods scored, in table order.
pub fn methods(taubin_iterations: usize) -> Vec<Method> {
    vec![
        Method::Raw,
        Method::PerFrameBiharmonic,
        Method::Streaming,
        Method::Clip,
        Method::Taubin {
            iterations: taubin_iterations,
        },
    ]
}

/// Runs the benchmark. `progress` receives one line per stage.
pub fn run_benchmark(
    model: &IctModel,
    config: &BenchmarkConfig,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchmarkResults, EvalError> {
    config.validate()?;
    let mut config = config.clone();
    config.identity_modes = model.identity_modes.len();
    config.expression_modes = model.expression_names.clone();
    progress("tuning Taubin iterations on a separate seed");
    let taubin_tuning = tune_taubin(model, &config)?;
    let methods = methods(taubin_tuning.iterations);
    let raw_index = 0;
    let mut accumulators = vec![MetricAccumulator::default(); methods.len()];
    let mut sequences = Vec::new();
    for s in 0..config.sequences {
        let seed = sequence_seed(config.seed, s);
        progress(&format!(
            "sequence {}/{}: synthesis and noise",
            s + 1,
            config.sequences
        ));
        let seq = PreparedSequence::new(model, &config, seed)?;
        let setup = seq.setup(&config)?;
        let input = seq.input(&config, config.weights);
        let runs: Vec<MethodRun> = methods
            .iter()
            .map(|m| {
                progress(&format!(
                    "sequence {}/{}: {}",
                    s + 1,
                    config.sequences,
                    m.name()
                ));
                m.run(&input)
            })
            .collect::<Result<_, _>>()?;
        for (acc, run) in accumulators.iter_mut().zip(&runs) {
            acc.add_time(run.seconds, run.solutions.len());
        }
        let outputs: Vec<&[faer::Mat<f64>]> = runs.iter().map(|r| r.solutions.as_slice()).collect();
        evaluate_sequence(&seq.truth, &setup, &outputs, raw_index, &mut accumulators);
        sequences.push(SequenceInfo {
            seed,
            distance_m: seq.truth.distance_m,
            mesh_vertices: setup.vertex_count(),
            domain_pixels: seq.domain.count(),
        });
    }
    let names = methods.iter().map(|m| m.name().to_string());
    Ok(BenchmarkResults {
        config,
        taubin_tuning,
        sequences,
        methods: names
            .clone()
            .zip(accumulators.iter().map(|a| a.summary()))
            .collect(),
        per_frame: names
            .zip(accumulators.iter().map(|a| a.per_frame()))
            .collect(),
    })
}

/// One point of a λ × μ sweep of the streaming fusion.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SweepPoint {
    pub lambda: f64,
    pub mu: f64,
    pub rmse_mm: f64,
    pub jitter_mm: f64,
    pub lag_frames: f64,
}

/// Scores the streaming fusion for every (λ, μ) on the benchmark's sequences (the same
/// sequences and noise as [`run_benchmark`] with this config).
pub fn run_sweep(
    model: &IctModel,
    config: &BenchmarkConfig,
    lambdas: &[f64],
    mus: &[f64],
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<SweepPoint>, EvalError> {
    config.validate()?;
    let mut acc = vec![MetricAccumulator::default(); lambdas.len() * mus.len()];
    for s in 0..config.sequences {
        progress(&format!("sweep: sequence {}/{}", s + 1, config.sequences));
        let seq = PreparedSequence::new(model, config, sequence_seed(config.seed, s))?;
        let setup = seq.setup(config)?;
        let raw = Method::Raw.run(&seq.input(config, config.weights))?;
        for (li, &lambda) in lambdas.iter().enumerate() {
            for (mi, &mu) in mus.iter().enumerate() {
                let run = Method::Streaming.run(&seq.input(config, Weights { lambda, mu }))?;
                let mut pair = [
                    MetricAccumulator::default(),
                    std::mem::take(&mut acc[li * mus.len() + mi]),
                ];
                evaluate_sequence(
                    &seq.truth,
                    &setup,
                    &[&raw.solutions, &run.solutions],
                    0,
                    &mut pair,
                );
                let [_, a] = pair;
                acc[li * mus.len() + mi] = a;
            }
        }
    }
    let mut out = Vec::new();
    for (li, &lambda) in lambdas.iter().enumerate() {
        for (mi, &mu) in mus.iter().enumerate() {
            let s = acc[li * mus.len() + mi].summary();
            out.push(SweepPoint {
                lambda,
                mu,
                rmse_mm: s.rmse_mm,
                jitter_mm: s.jitter_mm,
                lag_frames: s.lag_frames,
            });
        }
    }
    Ok(out)
}
