//! One module per subcommand.

pub mod batch;
pub mod bench;
pub mod bench_solver;
pub mod eval;
pub mod eval_expressions;
pub mod eval_video;
pub mod export;
pub mod fair;
pub mod fuse;
pub mod keypoints;
pub mod landmarks;
pub mod live;
pub mod matches;
pub mod model;
pub mod models;
pub mod render;
pub mod run;
