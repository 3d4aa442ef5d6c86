//! The benchmark driver: sequences → noisy inputs → methods → metrics.

use std::collections::BTreeMap;

use visage_camera::{DepthKind, DepthMap};
use visage_face::{CanonicalMesh, DEFAULT_LANDMARK_SMOOTHING};
use visage_fem::{ClipOptions, Weights};
use visage_fusion::{
    FaceDomain, FusionSetup, MeshingOptions, DEFAULT_MAX_DEPTH_M, DOMAIN_MAJORITY,
};
use visage_mesh::Mask;
use visage_morphable::{FaceModel, IctModel, ImportOptions};

use crate::method::{AnchoredInput, Method, MethodInput, MethodRun, ModelInput, VertexKind};
use crate::metrics::{
    evaluate_sequence, MethodSummary, MetricAccumulator, PerFrame, Scored, VertexSet, VertexTruth,
};
use crate::model_fit::{self, benchmark_face_model, ModelFitSummary};
use crate::noise::{NoiseGenerator, NoiseModel};
use crate::relative_depth::{align_to_fitted_model, AlignmentSummary, SequenceAlignment};
use crate::seed::mix_seed;
use crate::sift_anchors::{
    frame_sift_keypoints, random_control_points, sequence_sift_anchors, SiftAnchorInfo,
    SiftAnchorOptions, RANDOM_CONTROL_SALT,
};
use crate::sift_fairing::{FairingKeypoints, SiftFairingOptions, FAIRING_CONTROL_SALT};
use crate::simulated_tracker::{simulate_tracking, TrackedSequence, TrackerNoise};
use crate::synthesis::{synthesize, SynthesisConfig, SyntheticSequence};
use crate::vertex_filter::VertexFilter;
use crate::EvalError;
use visage_morphable::CanonicalCorrespondence;

/// Salt of the seed of the Taubin tuning sequence: tuned on data the benchmark never scores.
pub const TUNING_SALT: u64 = 0x7a_0b1e_5eed;
/// Salt that separates a sequence's noise stream from its synthesis stream.
const NOISE_SALT: u64 = 0x0015_e5ee_d000;
/// Salt of a sequence's simulated-tracker stream.
const TRACKER_SALT: u64 = 0x7_2ac4_e5ee_d000;
/// λ (mm⁴ of the canonical face) and μ of the face-anchored fusion in the benchmark: the
/// pipeline's default for depth maps, the best RMSE of a λ × μ sweep on a separate seed
/// (ARCHITECTURE.md, benchmark section). Not `Weights::default()`, which is the image-plane
/// fusion's (λ in reference pixels⁴).
pub const ANCHORED_WEIGHTS: Weights = visage_fusion::ANCHORED_WEIGHTS_MAP;
/// Subdivision of the canonical FaceMesh for the face-anchored mesh in the benchmark.
pub const ANCHORED_SUBDIVISION: usize = 2;
/// Fewest domain pixels a sequence must leave to be meshed.
const MIN_DOMAIN_PIXELS: usize = 64;

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
    /// λ, μ of the image-plane fusion methods.
    pub weights: Weights,
    /// λ (mm⁴), μ of the face-anchored methods.
    pub anchored_weights: Weights,
    /// λ (mm⁴ of the model's face), μ of the model fusion.
    pub model_weights: Weights,
    /// Subdivision factor of the face-anchored mesh (`FaceDomain::subdivide`).
    pub anchored_subdivision: usize,
    /// Noise of the simulated tracker that feeds the face-anchored methods.
    pub tracker: TrackerNoise,
    /// The landmark smoother's acceleration-to-noise ratio (1/s²) in the simulated tracker
    /// (`None`: the landmarks as tracked); default the pipeline's.
    pub landmark_smoothing: Option<f64>,
    pub meshing: MeshingOptions,
    pub clip: ClipOptions,
    pub max_depth_m: f64,
    /// Taubin iteration counts tried on the tuning sequence.
    pub taubin_candidates: Vec<usize>,
    /// The methods to score, by [`Method::name`] (`None`: the default list, [`methods`]);
    /// `raw` is always scored (first: the curvature reference), the others in table order.
    /// The only way to score an [`OPT_IN_METHODS`] one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub methods: Option<Vec<String>>,
    /// SIFT settings of [`Method::StreamingSiftAnchors`] and
    /// [`Method::FaceAnchoredFairedSift`] (its keypoints: every frame's, with the same
    /// upsampling, cap, texture and random control).
    pub sift_anchors: SiftAnchorOptions,
    /// Fairing weights of [`Method::FaceAnchoredFairedSift`].
    pub sift_fairing: SiftFairingOptions,
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
            anchored_weights: ANCHORED_WEIGHTS,
            model_weights: visage_fusion::MODEL_WEIGHTS_MAP,
            anchored_subdivision: ANCHORED_SUBDIVISION,
            tracker: TrackerNoise::default(),
            // The simulated tracker smooths its landmarks as the pipeline does.
            landmark_smoothing: Some(DEFAULT_LANDMARK_SMOOTHING),
            meshing: MeshingOptions::default(),
            clip: ClipOptions::default(),
            max_depth_m: DEFAULT_MAX_DEPTH_M,
            taubin_candidates: vec![0, 1, 2, 3, 5, 8, 12, 20, 30, 50],
            methods: None,
            sift_anchors: SiftAnchorOptions::default(),
            sift_fairing: SiftFairingOptions::default(),
            import: ImportOptions::default(),
            identity_modes: 0,
            expression_modes: Vec::new(),
        }
    }

    /// The quick setting for the test suite: 3 sequences × 24 frames at the full setting's
    /// camera (320×240, f = 350 px) and mesh, 3 identity and 4 expression modes, fewer Taubin
    /// candidates. It used to be 1 sequence × 16 frames at 160×120 and was unrepresentative:
    /// one sequence's draw moves the fusion's RMSE gain over raw by ±8 points (−1 %, −11 %,
    /// +4 % on seeds 0–2), and at half resolution each vertex averages a quarter of the pixels
    /// and the 2-pixel depth-edge band covers twice the face, so the gain shrinks (−7 % on 4
    /// sequences) where the full setting gives −16 %. At this setting streaming gains −17 %
    /// RMSE and 0.58× jitter over raw (full: −16 %, 0.61×).
    pub fn quick() -> BenchmarkConfig {
        let full = BenchmarkConfig::full();
        BenchmarkConfig {
            synthesis: SynthesisConfig {
                frames: 24,
                ..SynthesisConfig::default()
            },
            sequences: 3,
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
        self.anchored_weights.validate()?;
        self.tracker.validate()?;
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
        if let Some(names) = &self.methods {
            let known = all_methods(0, true);
            if let Some(bad) = names.iter().find(|n| !known.iter().any(|m| m.name() == *n)) {
                return Err(EvalError::InvalidConfig {
                    name: "methods",
                    value: bad.clone(),
                    reason: "not a method of the benchmark",
                });
            }
        }
        if self.sift_anchors.max_keypoints == Some(0) {
            return Err(EvalError::InvalidConfig {
                name: "sift_anchors.max_keypoints",
                value: "0".into(),
                reason: "must be at least 1",
            });
        }
        self.sift_fairing.validate()?;
        if self.sift_anchors.frame_step == Some(0) {
            return Err(EvalError::InvalidConfig {
                name: "sift_anchors.frame_step",
                value: "0".into(),
                reason: "must be at least 1",
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

/// The face-anchored methods' fixed parts: the canonical FaceMesh, where it lies on the ICT
/// face, and the face-anchored mesh built on it.
#[derive(Clone, Debug)]
pub struct FaceAnchoring {
    pub canonical: CanonicalMesh,
    pub correspondence: CanonicalCorrespondence,
    pub domain: FaceDomain,
    /// The compact model the fit uses ([`benchmark_face_model`]), its face region as a mesh
    /// and its neutral face (metres).
    pub face_model: FaceModel,
    pub model_domain: FaceDomain,
    pub model_neutral: Vec<[f64; 3]>,
}

impl FaceAnchoring {
    /// Anchors `canonical` on `model`'s face and subdivides it `subdivision` times.
    pub fn new(
        model: &IctModel,
        canonical: CanonicalMesh,
        subdivision: usize,
    ) -> Result<FaceAnchoring, EvalError> {
        let correspondence = CanonicalCorrespondence::new(model, &canonical.vertices)?;
        let domain =
            FaceDomain::subdivide(canonical.vertices.len(), &canonical.triangles, subdivision)?;
        let face_model = benchmark_face_model(model, &correspondence)?;
        let model_domain =
            FaceDomain::subdivide(face_model.vertex_count(), &face_model.triangles, 1)?;
        let model_neutral = face_model
            .neutral
            .iter()
            .map(|p| p.map(f64::from))
            .collect();
        Ok(FaceAnchoring {
            canonical,
            correspondence,
            domain,
            face_model,
            model_domain,
            model_neutral,
        })
    }
}

/// How the face-anchored methods were set up, for the record.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct AnchoringInfo {
    /// Vertices of the face-anchored mesh.
    pub mesh_vertices: usize,
    /// RMS distance of the aligned canonical landmarks from the ICT landmarks, mm.
    pub alignment_rms_mm: f64,
    /// Median and largest distance of the aligned canonical vertices from the ICT face, mm.
    pub projection_median_mm: f64,
    pub projection_max_mm: f64,
}

impl AnchoringInfo {
    fn new(a: &FaceAnchoring) -> AnchoringInfo {
        let mut d = a.correspondence.projection_m.clone();
        d.sort_by(f64::total_cmp);
        AnchoringInfo {
            mesh_vertices: a.domain.vertex_count(),
            alignment_rms_mm: 1e3 * a.correspondence.landmark_rms_m,
            projection_median_mm: 1e3 * d.get(d.len() / 2).copied().unwrap_or(f64::NAN),
            projection_max_mm: 1e3 * d.last().copied().unwrap_or(f64::NAN),
        }
    }
}

/// A scored sequence, for the record.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SequenceInfo {
    pub seed: u64,
    pub distance_m: f64,
    /// Vertices of the image-plane mesh shared by the methods.
    pub mesh_vertices: usize,
    pub domain_pixels: usize,
    /// The SIFT anchors, when [`Method::StreamingSiftAnchors`] ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sift_anchors: Option<SiftAnchorInfo>,
    /// The keypoint-weighted fairing, when [`Method::FaceAnchoredFairedSift`] ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sift_fairing: Option<SiftFairingInfo>,
    /// The relative-depth setting: the alignment of this sequence's frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alignment: Option<AlignmentSummary>,
}

/// The keypoints of [`Method::FaceAnchoredFairedSift`] on a sequence, for the record.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SiftFairingInfo {
    /// Keypoints per frame, mean over the frames.
    pub keypoints_per_frame: f64,
    /// Fraction of the vertices at full weight, mean over the frames (the random control: the
    /// same).
    pub full_weight_fraction: f64,
}

/// Everything `results.json` holds.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BenchmarkResults {
    pub config: BenchmarkConfig,
    pub taubin_tuning: TaubinTuning,
    /// The face-anchored set-up (`None`: those methods did not run).
    pub anchoring: Option<AnchoringInfo>,
    pub sequences: Vec<SequenceInfo>,
    /// Per method (keys: [`Method::name`]).
    pub methods: BTreeMap<String, MethodSummary>,
    /// Per method, per frame index (mean over sequences).
    pub per_frame: BTreeMap<String, PerFrame>,
    /// The face-model fit against the generator's expressions and identity (with the
    /// face-anchored set-up).
    pub model_fit: Option<ModelFitSummary>,
    /// The relative-depth setting: every frame's alignment to the fitted model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alignment: Option<AlignmentSummary>,
}

/// A sequence with its noisy input, the input's meshing domain and, for the face-anchored
/// methods, the simulated tracker's output.
pub struct PreparedSequence<'a> {
    pub truth: SyntheticSequence,
    pub inputs: Vec<DepthMap>,
    pub domain: Mask,
    pub reference: DepthMap,
    pub anchoring: Option<&'a FaceAnchoring>,
    pub tracking: Option<TrackedSequence>,
    /// The SIFT anchors and the mesh they make ([`PreparedSequence::add_sift_anchors`];
    /// `None`: [`Method::StreamingSiftAnchors`] cannot run).
    pub sift: Option<SiftAnchoring>,
    /// Every frame's SIFT keypoints ([`PreparedSequence::add_fairing_keypoints`]; `None`:
    /// [`Method::FaceAnchoredFairedSift`] cannot run).
    pub fairing_keypoints: Option<Vec<Vec<[f64; 2]>>>,
    /// The relative-depth setting: how each frame's relative depth was aligned to metres
    /// before the methods saw it ([`align_to_fitted_model`](crate::align_to_fitted_model)).
    pub alignment: Option<SequenceAlignment>,
}

/// A sequence's SIFT anchors ([`sequence_sift_anchors`]: its first frame, or every k-th) and
/// the image-plane mesh with them added, which [`Method::StreamingSiftAnchors`] builds the
/// same way.
#[derive(Debug)]
pub struct SiftAnchoring {
    /// Keypoint positions, pixels (with [`SiftAnchorOptions::random_control`], the random
    /// points that replace them).
    pub points: Vec<[f64; 2]>,
    /// Frames searched.
    pub frames: usize,
    pub setup: FusionSetup,
}

impl SiftAnchoring {
    /// Keypoints found and vertices added.
    pub fn info(&self) -> SiftAnchorInfo {
        SiftAnchorInfo {
            keypoints: self.points.len(),
            frames: self.frames,
            vertices_added: self.setup.anchor_vertices,
        }
    }
}

impl<'a> PreparedSequence<'a> {
    /// Synthesises the sequence of `seed`, draws its noise and derives the domain (pixels valid
    /// in at least [`DOMAIN_MAJORITY`] of the frames) and reference (their mean depth), as
    /// `visage fuse` does from files; with `anchoring`, also tracks it
    /// ([`simulate_tracking`], its own seed stream). A relative noise model's frames are first
    /// aligned to the face model fitted to the tracked landmarks (that needs `anchoring`).
    pub fn new(
        model: &IctModel,
        anchoring: Option<&'a FaceAnchoring>,
        config: &BenchmarkConfig,
        seed: u64,
    ) -> Result<PreparedSequence<'a>, EvalError> {
        let truth = synthesize(model, &config.synthesis, seed)?;
        let mut noise = NoiseGenerator::new(config.noise, mix_seed(seed ^ NOISE_SALT))?;
        let mut inputs: Vec<DepthMap> =
            truth.frames.iter().map(|f| noise.apply(&f.depth)).collect();
        let tracking = anchoring
            .map(|a| {
                simulate_tracking(
                    &truth,
                    &a.correspondence,
                    &a.canonical,
                    &config.tracker,
                    config.landmark_smoothing,
                    mix_seed(seed ^ TRACKER_SALT),
                )
            })
            .transpose()?;
        let alignment = if config.noise.relative_inverse {
            let (Some(a), Some(t)) = (anchoring, &tracking) else {
                return Err(EvalError::InvalidConfig {
                    name: "noise",
                    value: config.noise_name.clone(),
                    reason: "relative depth is aligned to the fitted face model: needs the \
                             model files (--models)",
                });
            };
            Some(align_to_fitted_model(
                &truth,
                t,
                &a.face_model,
                config.max_depth_m,
                &mut inputs,
            )?)
        } else {
            None
        };
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
            anchoring,
            tracking,
            sift: None,
            fairing_keypoints: None,
            alignment,
        })
    }

    /// Finds the SIFT anchors ([`BenchmarkConfig::sift_anchors`]: the first frame, or every
    /// k-th) and meshes the domain with them, for [`Method::StreamingSiftAnchors`].
    pub fn add_sift_anchors(&mut self, config: &BenchmarkConfig) -> Result<(), EvalError> {
        let (mut points, frames) = sequence_sift_anchors(&self.truth, &config.sift_anchors)?;
        if config.sift_anchors.random_control {
            points = random_control_points(
                &points,
                &self.domain,
                mix_seed(self.truth.seed ^ RANDOM_CONTROL_SALT),
            );
        }
        let setup = FusionSetup::with_anchors(
            &self.truth.k,
            &self.domain,
            &self.reference,
            &config.meshing,
            &points,
        )?;
        self.sift = Some(SiftAnchoring {
            points,
            frames,
            setup,
        });
        Ok(())
    }

    /// Finds every frame's SIFT keypoints ([`frame_sift_keypoints`] with
    /// [`BenchmarkConfig::sift_anchors`]), for [`Method::FaceAnchoredFairedSift`].
    pub fn add_fairing_keypoints(&mut self, config: &BenchmarkConfig) -> Result<(), EvalError> {
        self.fairing_keypoints = Some(frame_sift_keypoints(&self.truth, &config.sift_anchors)?);
        Ok(())
    }

    /// The methods' common input: `weights` for the image-plane fusion, `anchored_weights` for
    /// the face-anchored one, `model_weights` for the model fusion.
    pub fn input<'b>(
        &'b self,
        config: &'b BenchmarkConfig,
        weights: Weights,
        anchored_weights: Weights,
        model_weights: Weights,
    ) -> MethodInput<'b> {
        MethodInput {
            k: &self.truth.k,
            domain: &self.domain,
            reference: &self.reference,
            meshing: &config.meshing,
            weights,
            clip: &config.clip,
            max_depth_m: config.max_depth_m,
            frames: &self.inputs,
            anchored: self
                .anchoring
                .zip(self.tracking.as_ref())
                .map(|(a, tracking)| AnchoredInput {
                    domain: &a.domain,
                    template: &a.canonical.vertices,
                    tracking,
                    weights: anchored_weights,
                    model: Some(ModelInput {
                        model: &a.face_model,
                        domain: &a.model_domain,
                        neutral: &a.model_neutral,
                        weights: model_weights,
                    }),
                }),
            sift_anchors: self.sift.as_ref().map(|s| s.points.as_slice()),
            fairing_keypoints: self
                .fairing_keypoints
                .as_ref()
                .map(|frames| FairingKeypoints {
                    frames,
                    options: config.sift_fairing,
                    random_control: config
                        .sift_anchors
                        .random_control
                        .then(|| mix_seed(self.truth.seed ^ FAIRING_CONTROL_SALT)),
                }),
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

    /// Scores `runs` into `accumulators` (same order); `raw` is [`Method::Raw`]'s run, the
    /// curvature reference of the image-plane methods.
    ///
    /// # Errors
    /// A face-anchored run on a sequence prepared without anchoring.
    pub fn evaluate(
        &self,
        setup: &FusionSetup,
        raw: &MethodRun,
        runs: &[&MethodRun],
        accumulators: &mut [MetricAccumulator],
    ) -> Result<(), EvalError> {
        let image_truth = VertexTruth::image_plane(&self.truth, setup);
        let image = VertexSet {
            triangles: &setup.mesh.triangles,
            boundary: &setup.boundary,
            truth: &image_truth,
        };
        let sift_truth = self
            .sift
            .as_ref()
            .filter(|_| {
                runs.iter()
                    .any(|r| r.vertices == VertexKind::SiftAnchoredImagePlane)
            })
            .map(|s| (s, VertexTruth::image_plane(&self.truth, &s.setup)));
        let sift = sift_truth.as_ref().map(|(s, truth)| VertexSet {
            triangles: &s.setup.mesh.triangles,
            boundary: &s.setup.boundary,
            truth,
        });
        let anchored_truth = self
            .anchoring
            .zip(self.tracking.as_ref())
            .map(|(a, t)| (a, VertexTruth::anchored(&a.domain, &t.truth)));
        let anchored = anchored_truth.as_ref().map(|(a, truth)| VertexSet {
            triangles: &a.domain.triangles,
            boundary: &a.domain.boundary,
            truth,
        });
        let model_truth = self.anchoring.map(|a| {
            (
                a,
                VertexTruth::model(&self.truth, a.face_model.vertex_count()),
            )
        });
        let model = model_truth.as_ref().map(|(a, truth)| VertexSet {
            triangles: &a.model_domain.triangles,
            boundary: &a.model_domain.boundary,
            truth,
        });
        let scored = runs
            .iter()
            .map(|r| {
                Ok(match r.vertices {
                    VertexKind::ImagePlane => Scored {
                        vertices: image,
                        solutions: &r.solutions,
                        raw: r.raw.as_deref().unwrap_or(&raw.solutions),
                    },
                    VertexKind::SiftAnchoredImagePlane => Scored {
                        vertices: sift.ok_or(EvalError::InvalidConfig {
                            name: "method",
                            value: "streaming_sift_anchors".into(),
                            reason: "scored on a sequence prepared without SIFT anchors",
                        })?,
                        solutions: &r.solutions,
                        raw: r.raw.as_deref().unwrap_or(&r.solutions),
                    },
                    VertexKind::Anchored => Scored {
                        vertices: anchored.ok_or(EvalError::InvalidConfig {
                            name: "method",
                            value: "face-anchored".into(),
                            reason: "scored on a sequence prepared without anchoring",
                        })?,
                        solutions: &r.solutions,
                        raw: r.raw.as_deref().unwrap_or(&r.solutions),
                    },
                    VertexKind::Model => Scored {
                        vertices: model.ok_or(EvalError::InvalidConfig {
                            name: "method",
                            value: "model".into(),
                            reason: "scored on a sequence prepared without the face model",
                        })?,
                        solutions: &r.solutions,
                        raw: r.raw.as_deref().unwrap_or(&r.solutions),
                    },
                })
            })
            .collect::<Result<Vec<Scored<'_>>, EvalError>>()?;
        evaluate_sequence(&self.truth, &scored, accumulators);
        Ok(())
    }
}

/// Seed of scored sequence `s`.
pub fn sequence_seed(master: u64, s: usize) -> u64 {
    mix_seed(master.wrapping_add(s as u64))
}

/// Picks the Taubin iteration count with the smallest RMSE on a sequence drawn from
/// `mix_seed(seed ^ TUNING_SALT)` (`anchoring`: used by the relative-depth setting's
/// alignment).
pub fn tune_taubin(
    model: &IctModel,
    anchoring: Option<&FaceAnchoring>,
    config: &BenchmarkConfig,
) -> Result<TaubinTuning, EvalError> {
    let seed = mix_seed(config.seed ^ TUNING_SALT);
    // The face-anchored set-up only where the input needs it (relative depth is aligned to
    // the fitted face): tracking is not part of the tuning.
    let anchoring = anchoring.filter(|_| config.noise.relative_inverse);
    let seq = PreparedSequence::new(model, anchoring, config, seed)?;
    let setup = seq.setup(config)?;
    let input = seq.input(
        config,
        config.weights,
        config.anchored_weights,
        config.model_weights,
    );
    let raw = Method::Raw.run(&input)?;
    let mut rmse_mm = Vec::new();
    for &iterations in &config.taubin_candidates {
        let run = Method::Taubin { iterations }.run(&input)?;
        let mut acc = [MetricAccumulator::default()];
        seq.evaluate(&setup, &raw, &[&run], &mut acc)?;
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

/// Methods scored only when named in [`BenchmarkConfig::methods`]: experiments that did not
/// earn a place in the default table.
pub const OPT_IN_METHODS: [Method; 2] =
    [Method::StreamingSiftAnchors, Method::FaceAnchoredFairedSift];

/// Every method the benchmark knows, in table order: [`methods`], then [`OPT_IN_METHODS`]
/// (the face-anchored ones when `anchored`).
fn all_methods(taubin_iterations: usize, anchored: bool) -> Vec<Method> {
    let mut m = methods(taubin_iterations, anchored);
    m.extend(
        OPT_IN_METHODS
            .into_iter()
            .filter(|&o| anchored || o != Method::FaceAnchoredFairedSift),
    );
    m
}

/// The methods `config` scores: [`methods`] without [`BenchmarkConfig::methods`]; with it,
/// `raw` and the named ones, in table order.
///
/// # Errors
/// A named face-anchored method without `anchored` (the model files).
pub fn selected_methods(
    config: &BenchmarkConfig,
    taubin_iterations: usize,
    anchored: bool,
) -> Result<Vec<Method>, EvalError> {
    let Some(names) = &config.methods else {
        return Ok(methods(taubin_iterations, anchored));
    };
    let available = all_methods(taubin_iterations, anchored);
    if let Some(missing) = names
        .iter()
        .find(|n| !available.iter().any(|m| m.name() == *n))
    {
        return Err(EvalError::InvalidConfig {
            name: "methods",
            value: missing.clone(),
            reason: "unknown, or needs the face-anchored set-up (the model files)",
        });
    }
    Ok(available
        .into_iter()
        .filter(|m| *m == Method::Raw || names.iter().any(|n| n == m.name()))
        .collect())
}

/// The methods scored by default, in table order (the face-anchored ones when `anchored`).
pub fn methods(taubin_iterations: usize, anchored: bool) -> Vec<Method> {
    let mut m = vec![
        Method::Raw,
        Method::PerFrameBiharmonic,
        Method::Streaming,
        Method::Clip,
        Method::Taubin {
            iterations: taubin_iterations,
        },
    ];
    m.extend(VertexFilter::ALL.map(Method::RawFiltered));
    if anchored {
        m.extend([
            Method::FaceAnchored,
            Method::FaceAnchoredClip,
            Method::FaceAnchoredFaired,
            Method::ModelOnly,
            Method::ModelFusion,
        ]);
    }
    m
}

/// Runs the benchmark; the face-anchored methods run when `anchoring` is given. `progress`
/// receives one line per stage.
pub fn run_benchmark(
    model: &IctModel,
    anchoring: Option<&FaceAnchoring>,
    config: &BenchmarkConfig,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchmarkResults, EvalError> {
    config.validate()?;
    let mut config = config.clone();
    config.identity_modes = model.identity_modes.len();
    config.expression_modes = model.expression_names.clone();
    progress("tuning Taubin iterations on a separate seed");
    let taubin_tuning = tune_taubin(model, anchoring, &config)?;
    let methods = selected_methods(&config, taubin_tuning.iterations, anchoring.is_some())?;
    let with_sift = methods.contains(&Method::StreamingSiftAnchors);
    let with_fairing_sift = methods.contains(&Method::FaceAnchoredFairedSift);
    let mut accumulators = vec![MetricAccumulator::default(); methods.len()];
    let mut sequences = Vec::new();
    let mut model_scores = Vec::new();
    let mut alignments = Vec::new();
    for s in 0..config.sequences {
        let seed = sequence_seed(config.seed, s);
        progress(&format!(
            "sequence {}/{}: synthesis, noise and tracking",
            s + 1,
            config.sequences
        ));
        let mut seq = PreparedSequence::new(model, anchoring, &config, seed)?;
        if with_sift {
            progress(&format!(
                "sequence {}/{}: SIFT anchors",
                s + 1,
                config.sequences
            ));
            seq.add_sift_anchors(&config)?;
        }
        if with_fairing_sift {
            progress(&format!(
                "sequence {}/{}: SIFT keypoints of every frame",
                s + 1,
                config.sequences
            ));
            seq.add_fairing_keypoints(&config)?;
        }
        if let (Some(a), Some(tracking)) = (anchoring, &seq.tracking) {
            progress(&format!(
                "sequence {}/{}: face model fit",
                s + 1,
                config.sequences
            ));
            model_scores.push(model_fit::score(model, &a.face_model, &seq.truth, tracking));
        }
        let setup = seq.setup(&config)?;
        let input = seq.input(
            &config,
            config.weights,
            config.anchored_weights,
            config.model_weights,
        );
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
        let refs: Vec<&MethodRun> = runs.iter().collect();
        seq.evaluate(&setup, &runs[0], &refs, &mut accumulators)?;
        sequences.push(SequenceInfo {
            seed,
            distance_m: seq.truth.distance_m,
            mesh_vertices: setup.vertex_count(),
            domain_pixels: seq.domain.count(),
            sift_anchors: seq.sift.as_ref().map(SiftAnchoring::info),
            sift_fairing: seq.fairing_keypoints.as_ref().and_then(|frames| {
                let fraction = runs.iter().find_map(|r| r.full_weight_fraction)?;
                Some(SiftFairingInfo {
                    keypoints_per_frame: frames.iter().map(Vec::len).sum::<usize>() as f64
                        / frames.len().max(1) as f64,
                    full_weight_fraction: fraction,
                })
            }),
            alignment: seq
                .alignment
                .as_ref()
                .map(|a| AlignmentSummary::of(std::slice::from_ref(a))),
        });
        alignments.extend(seq.alignment.take());
    }
    let names = methods.iter().map(|m| m.name().to_string());
    Ok(BenchmarkResults {
        config,
        taubin_tuning,
        anchoring: anchoring.map(AnchoringInfo::new),
        sequences,
        methods: names
            .clone()
            .zip(accumulators.iter().map(|a| a.summary()))
            .collect(),
        per_frame: names
            .zip(accumulators.iter().map(|a| a.per_frame()))
            .collect(),
        model_fit: (!model_scores.is_empty()).then(|| ModelFitSummary::of(&model_scores)),
        alignment: (!alignments.is_empty()).then(|| AlignmentSummary::of(&alignments)),
    })
}

/// One point of a λ × μ sweep.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SweepPoint {
    pub lambda: f64,
    pub mu: f64,
    pub rmse_mm: f64,
    /// RMSE after each sequence's best scale ([`crate::metrics`]).
    pub rmse_scaled_mm: f64,
    pub jitter_mm: f64,
    pub lag_frames: f64,
}

/// Scores `method` — [`Method::Streaming`] (λ in reference pixels⁴) or
/// [`Method::FaceAnchored`] (λ in mm⁴, needs `anchoring`) — for every (λ, μ) on the
/// benchmark's sequences (the same sequences and noise as [`run_benchmark`] with this config).
pub fn run_sweep(
    model: &IctModel,
    anchoring: Option<&FaceAnchoring>,
    config: &BenchmarkConfig,
    method: Method,
    lambdas: &[f64],
    mus: &[f64],
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<SweepPoint>, EvalError> {
    config.validate()?;
    let mut acc = vec![MetricAccumulator::default(); lambdas.len() * mus.len()];
    for s in 0..config.sequences {
        progress(&format!(
            "sweep {}: sequence {}/{}",
            method.name(),
            s + 1,
            config.sequences
        ));
        let seq = PreparedSequence::new(model, anchoring, config, sequence_seed(config.seed, s))?;
        let setup = seq.setup(config)?;
        let raw = Method::Raw.run(&seq.input(
            config,
            config.weights,
            config.anchored_weights,
            config.model_weights,
        ))?;
        for (li, &lambda) in lambdas.iter().enumerate() {
            for (mi, &mu) in mus.iter().enumerate() {
                let w = Weights { lambda, mu };
                let run = method.run(&seq.input(config, w, w, w))?;
                let a = &mut acc[li * mus.len() + mi];
                seq.evaluate(&setup, &raw, &[&run], std::slice::from_mut(a))?;
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
                rmse_scaled_mm: s.rmse_scaled_mm,
                jitter_mm: s.jitter_mm,
                lag_frames: s.lag_frames,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn method_names_are_unique_and_opt_in_methods_stay_out_of_the_default_list() {
        let all = all_methods(3, true);
        let names: std::collections::BTreeSet<&str> = all.iter().map(Method::name).collect();
        assert_eq!(names.len(), all.len(), "{names:?}");
        assert_eq!(all.len(), 16);
        assert_eq!(all_methods(3, false).len(), 10);
        for m in OPT_IN_METHODS {
            assert!(!methods(3, true).contains(&m), "{}", m.name());
        }
        let config = BenchmarkConfig::quick();
        assert_eq!(
            selected_methods(&config, 3, true).unwrap(),
            methods(3, true)
        );
    }

    #[test]
    fn a_selection_scores_raw_first_and_the_named_methods_in_table_order() {
        let config = BenchmarkConfig {
            methods: Some(vec!["streaming_sift_anchors".into(), "streaming".into()]),
            ..BenchmarkConfig::quick()
        };
        config.validate().unwrap();
        assert_eq!(
            selected_methods(&config, 2, false).unwrap(),
            [Method::Raw, Method::Streaming, Method::StreamingSiftAnchors]
        );
        let face = BenchmarkConfig {
            methods: Some(vec!["face_anchored".into()]),
            ..BenchmarkConfig::quick()
        };
        assert!(selected_methods(&face, 2, false).is_err());
        let faired_sift = BenchmarkConfig {
            methods: Some(vec![
                "face_anchored_faired_sift".into(),
                "face_anchored_faired".into(),
            ]),
            ..BenchmarkConfig::quick()
        };
        faired_sift.validate().unwrap();
        assert!(selected_methods(&faired_sift, 2, false).is_err());
        assert_eq!(
            selected_methods(&faired_sift, 2, true).unwrap(),
            [
                Method::Raw,
                Method::FaceAnchoredFaired,
                Method::FaceAnchoredFairedSift
            ]
        );
        assert_eq!(selected_methods(&face, 2, true).unwrap().len(), 2);
        let unknown = BenchmarkConfig {
            methods: Some(vec!["sift".into()]),
            ..BenchmarkConfig::quick()
        };
        assert!(unknown.validate().is_err());
    }
}
