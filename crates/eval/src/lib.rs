//! visage-eval: the ground-truth benchmark. The paper reports no error against
//! ground truth; this crate measures it, on synthetic sequences where the truth is known.
//!
//! Pipeline: [`synthesize`] an ICT-FaceKit face sequence (seeded identity, expression
//! trajectories, head motion, camera 0.4–0.8 m away) and render its exact depth with
//! `visage-render` → corrupt the depth with a [`NoiseModel`] that mimics a CNN's errors (and,
//! for the face-anchored fusion, track the face with a [`simulate_tracking`] tracker whose
//! landmarks sit on the ICT face through the [`visage_morphable::CanonicalCorrespondence`]) →
//! run every [`Method`] on the same noisy input → score against the truth ([`metrics`]:
//! point-to-mesh RMSE/median, jitter, lag, curvature improvement and roughness per ERRATA 13,
//! time per frame) → [`write_results`] (`results.json`, `results.csv`, SVG plots) and
//! [`table`].
//!
//! From pixels ([`evaluate_expressions`], `visage eval expressions`): a recorded ARKit take
//! ([`Replay`]) drives a rendered ICT-FaceKit head ([`HeadRender`]: a real skin texture,
//! eyes that follow the take's gaze, a mouth interior) under a seeded head motion
//! ([`HeadPoseTrack`]); the whole pipeline runs on the renders as `visage run` runs a video,
//! and its 52 weights, head rotation and identity are scored against what was played
//! ([`expression_scores`]; [`write_expression_results`], [`expression_table`]).
//!
//! On real clips, where there is no truth: [`evaluate_video`] runs the pipeline four ways
//! (per-frame fit, streaming, causal, clip mode) and [`evaluate_clip`] measures each against
//! filters on the tracked landmarks (`visage eval video`).
//!
//! Everything is deterministic given the configuration and seed, except the `ms_per_frame`
//! timing fields.

#![forbid(unsafe_code)]

mod benchmark;
mod clip_runs;
mod error;
mod expression_benchmark;
mod expression_replay;
mod expression_report;
pub mod expression_scores;
mod face_texture;
mod first_frames;
mod head_pose_track;
mod head_render;
mod head_texture;
mod landmark_views;
mod method;
pub mod metrics;
pub mod model_fit;
mod noise;
mod normal;
mod relative_depth;
mod report;
mod rgbd_export;
mod seed;
mod sift_anchors;
mod sift_fairing;
pub mod simulated_tracker;
mod skin_texture;
mod synthesis;
mod table_heads;
mod taubin;
mod trajectory;
mod vertex_filter;
mod video_report;

pub use benchmark::{
    methods, run_benchmark, run_sweep, selected_methods, sequence_seed, tune_taubin, AnchoringInfo,
    BenchmarkConfig, BenchmarkResults, FaceAnchoring, PreparedSequence, SequenceInfo,
    SiftAnchoring, SiftFairingInfo, SweepPoint, TaubinTuning, ANCHORED_SUBDIVISION,
    ANCHORED_WEIGHTS, OPT_IN_METHODS, QUICK_EXPRESSIONS, TUNING_SALT,
};
pub use clip_runs::{evaluate_video, VideoOptions};
pub use error::{ClipRunError, EvalError};
pub use expression_benchmark::{
    evaluate_expressions, Curves, ExpressionOptions, ExpressionResults, ExpressionSummary,
    ShapeScore, TakeResult, LEAK_QUANTILE,
};
pub use expression_replay::{gazes, IdentityChoice, PlayedFrame, Replay, ReplayOptions};
pub use expression_report::{expression_table, write_expression_results, TABLE_SHAPES};
pub use face_texture::face_texture;
pub use first_frames::write_first_frames;
pub use head_pose_track::{HeadMotion, HeadPose, HeadPoseTrack};
pub use head_render::{HeadRender, RenderWork, BACKGROUND, IRIS_RADIUS_M, PUPIL_RADIUS_M};
pub use head_texture::{head_texture, EyeLayout, Part, ATLAS_COLUMNS, ATLAS_ROWS};
pub use landmark_views::{tracked_views, TrackedView, ViewGrid};
pub use method::{
    AnchoredInput, Method, MethodInput, MethodRun, ModelInput, VertexKind,
    BENCHMARK_FAIRING_LENGTH_M,
};
pub use metrics::{
    evaluate_sequence, moving_frames, MethodSummary, MetricAccumulator, PerFrame, Scored,
    VertexSet, VertexTruth,
};
pub use noise::{NoiseGenerator, NoiseModel, NOISE_PRESETS};
pub use normal::standard_normal;
pub use relative_depth::{align_to_fitted_model, AlignmentSummary, SequenceAlignment};
pub use report::{csv, sweep_table, table, write_results, write_sweep};
pub use rgbd_export::{write_tum_recording, RecordingClock};
pub use seed::mix_seed;
pub use sift_anchors::{
    frame_sift_keypoints, gray_render, random_control_points, sequence_sift_anchors, sift_anchors,
    SiftAnchorInfo, SiftAnchorOptions,
};
pub use sift_fairing::{
    control_order, keypoint_weights, random_control_weights, FairingKeypoints, SiftFairingOptions,
    FAIRING_CONTROL_SALT, SIFT_FAIRING_BASE_WEIGHT, SIFT_FAIRING_RADIUS_PX,
};
pub use simulated_tracker::{simulate_tracking, TrackedSequence, TrackerNoise};
pub use skin_texture::{sequence_skin_albedo, skin_albedo};
pub use synthesis::{
    synthesize, SynthesisConfig, SyntheticFrame, SyntheticSequence, EXPRESSION_ACTIVITY,
    PIVOT_DEPTH_M, SKIN_ALBEDO,
};
pub use table_heads::{
    head_curves, head_replay, run_two_at_a_time, table_render, Head, HELD_OUT_HEADS, TRAINING_HEADS,
};
pub use taubin::{taubin_smooth, TAUBIN_LAMBDA, TAUBIN_MU};
pub use trajectory::{keyframe_trajectory, smoothstep, SEGMENT_FRAMES};
pub use vertex_filter::{
    VertexFilter, EMA_ALPHA, GAUSSIAN_SIGMA_FRAMES, KALMAN_RATIO, ONE_EURO_BETA,
    ONE_EURO_MIN_CUTOFF_HZ, SYNTHETIC_FRAME_INTERVAL_S,
};
pub use video_report::{
    evaluate_clip, stability_chart_svg, stability_table, ClipReport, ClipTracks, Comparison,
    MethodFigures, PipelineOutput, RegionFigures,
};
pub use visage_plot::{heatmap_svg, line_chart_svg, xy_chart_svg, Series, XySeries};
