//! Regenerates the table of what the head's turn alone adds to each ARKit weight
//! (`crates/rig/data/pose_leak.bin`, `visage_rig::PoseLeak`): neutral heads of eight
//! ICT-FaceKit identities (modes 1, 2, 5, 8, 12, 17, 25 and 29), textured with the built-in
//! real face, are turned by the expression benchmark's head motion (±40° yaw, ±25° pitch,
//! ±15° roll, seeds 101–108) for the length of a take, run through the whole pipeline with the
//! table off, and the weights' change from each head's median is averaged over the read head
//! angles near each node of a 4° grid (a Gaussian kernel of 3°, pulled toward a cubic fitted
//! by ridge regression, ridge 10, worth one frame), plus two of the kernel's standard
//! deviations about that average (the lids: the average alone). Identities 0, 3, 11 and 20 are held out and only scored: the rigid leak
//! (the benchmark's 99th percentile, and the weights whose own 99th percentile is over 0.15) at
//! ±38° yaw, ±20° pitch and ±10° roll, without and with the new table.
//!
//! ```sh
//! cargo run --release -p visage-eval --example pose_leak_table -- \
//!     ../shared/data/ict-facekit/FaceXModel models \
//!     ../shared/data/arkit-takes/alex_rom_3.csv crates/rig/data/pose_leak.bin
//! ```
//! Deterministic: the renders, the networks and the least squares have no randomness but the
//! seeded head motions. About ten minutes on two cores.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use visage_eval::expression_scores::{quantile_sorted, rigid_leak};
use visage_eval::{
    head_curves, head_replay, run_two_at_a_time, table_render, Curves, ExpressionOptions, Head,
    HeadRender, ReplayOptions, HELD_OUT_HEADS, TRAINING_HEADS,
};
use visage_rig::{LeakLearning, LeakSample, PoseLeak, ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT};

const TRAIN_MOTION_DEG: [f64; 3] = [40.0, 25.0, 15.0];
const TEST_MOTION_DEG: [f64; 3] = [38.0, 20.0, 10.0];
const RIDGE: f64 = 10.0;
const SPACING_DEG: f64 = 4.0;
const BANDWIDTH_DEG: f64 = 3.0;
const PRIOR_FRAMES: f64 = 1.0;
const SPREAD: f64 = 2.0;
const REPORTED_LEAK: f32 = 0.15;

/// The curves of a neutral head `who` turned by its motion over `motion_deg`, the table off.
fn rigid_turn(
    take: &Path,
    render: &Arc<HeadRender>,
    models: &Path,
    who: Head,
    motion_deg: [f64; 3],
    stride: usize,
    max_frames: Option<usize>,
) -> Curves {
    let options = ExpressionOptions {
        replay: ReplayOptions {
            rigid: Some(None),
            stride,
            max_frames,
            ..head_replay(who, motion_deg)
        },
        models: Some(models.to_path_buf()),
        keep_pose_leak: true,
        ..ExpressionOptions::default()
    };
    head_curves(take, render, &options)
}

/// Each weight's change from its median over the turn, with the read angles.
fn samples(curves: &Curves) -> Vec<LeakSample> {
    let medians: [f32; ARKIT_BLENDSHAPE_COUNT] = std::array::from_fn(|w| {
        let mut v: Vec<f32> = curves.read.iter().map(|r| r[w]).collect();
        v.sort_by(f32::total_cmp);
        quantile_sorted(&v, 0.5)
    });
    curves
        .read
        .iter()
        .zip(&curves.read_head)
        .map(|(r, &angles)| LeakSample {
            angles,
            change: std::array::from_fn(|w| r[w] - medians[w]),
        })
        .collect()
}

/// The pooled rigid leak's 99th percentile and the weights whose own is over
/// [`REPORTED_LEAK`], of `read` (every frame is at rest).
fn leak_figures(
    played: &[[f32; ARKIT_BLENDSHAPE_COUNT]],
    read: &[[f32; ARKIT_BLENDSHAPE_COUNT]],
) -> (f32, Vec<String>) {
    let frames: Vec<usize> = (0..read.len()).collect();
    let pooled = quantile_sorted(&rigid_leak(played, read, &frames), 0.99);
    let over = (0..ARKIT_BLENDSHAPE_COUNT)
        .filter_map(|w| {
            let one: Vec<[f32; 1]> = played.iter().map(|p| [p[w]]).collect();
            let mine: Vec<[f32; 1]> = read.iter().map(|r| [r[w]]).collect();
            let p99 = quantile_sorted(&rigid_leak(&one, &mine, &frames), 0.99);
            (p99 > REPORTED_LEAK).then(|| format!("{} {p99:.2}", ARKIT_BLENDSHAPES[w]))
        })
        .collect();
    (pooled, over)
}

fn main() {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [model_dir, models, take, out] = args.as_slice() else {
        eprintln!("usage: pose_leak_table ICT_MODEL_DIR MODELS_DIR TAKE.csv OUT.bin");
        std::process::exit(2);
    };
    let render = table_render(model_dir).expect("the head renderer");
    let train: Vec<LeakSample> = run_two_at_a_time(&TRAINING_HEADS, |who| {
        samples(&rigid_turn(
            take,
            &render,
            models,
            who,
            TRAIN_MOTION_DEG,
            2,
            None,
        ))
    })
    .into_iter()
    .flatten()
    .collect();
    let how = LeakLearning {
        max_angles: TRAIN_MOTION_DEG.map(f64::to_radians),
        spacing: SPACING_DEG.to_radians(),
        bandwidth: BANDWIDTH_DEG.to_radians(),
        prior_frames: PRIOR_FRAMES,
        ridge: RIDGE,
        spread: SPREAD,
    };
    let table = PoseLeak::learn(&train, &how).expect("the normal equations");
    println!(
        "learned from {} frames of {} heads",
        train.len(),
        TRAINING_HEADS.len()
    );

    for who in HELD_OUT_HEADS {
        let c = rigid_turn(take, &render, models, who, TEST_MOTION_DEG, 1, Some(1000));
        let removed: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]> = c
            .read
            .iter()
            .zip(&c.read_head)
            .map(|(r, a)| {
                let mut w = *r;
                table.remove(a.map(|v| v as f32), &mut w);
                w
            })
            .collect();
        for (label, read) in [("without", &c.read), ("with", &removed)] {
            let (p99, over) = leak_figures(&c.played, read);
            println!(
                "held-out identity {:>2}, {label:>7} the table: leak p99 {p99:.3}, {} of 52 over {REPORTED_LEAK}: {}",
                who.0,
                over.len(),
                over.join(", ")
            );
        }
    }
    std::fs::write(out, table.to_bytes()).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    println!("wrote {}", out.display());
}
