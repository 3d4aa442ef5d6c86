//! Regenerates the table of what the mouth's shapes alone add to the upper face's ARKit
//! weights (`crates/rig/data/mouth_leak.bin`, `visage_rig::MouthLeak`): eight ICT-FaceKit
//! identities (modes 1, 2, 5, 8, 12, 17, 25 and 29, the pose-leak table's), textured with the
//! built-in real face, play a take's mouth and jaw only (every other curve held at 0) under the
//! expression benchmark's head motion (±40° yaw, ±25° pitch, ±15° roll, seeds 101–108, every
//! second row), run through the whole pipeline with the pose leak taken off and the mouth leak
//! left on; per upper-face weight, the non-negative coefficients on the mouth's weights are
//! fitted by least squares with a free constant (ridge 1e-4 per frame). Identities 0 and 3
//! are held out and only scored: the upper face's weights (95th and 99th percentiles, each
//! weight's correlation with `jawOpen`) while they talk, without and with the new table.
//!
//! ```sh
//! cargo run --release -p visage-eval --example mouth_leak_table -- \
//!     ../shared/data/ict-facekit/FaceXModel models \
//!     ../shared/data/arkit-takes/alex_rom_3.csv crates/rig/data/mouth_leak.bin
//! ```
//! Deterministic: the renders, the networks and the least squares have no randomness but the
//! seeded head motions. About fifteen minutes on two cores.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use visage_eval::expression_scores::{pearson, quantile_sorted};
use visage_eval::{
    head_curves, head_replay, run_two_at_a_time, table_render, Curves, ExpressionOptions, Head,
    HeadRender, ReplayOptions, HELD_OUT_HEADS, TRAINING_HEADS,
};
use visage_rig::{is_mouth, is_upper_face, MouthLeak, ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT};

const MOTION_DEG: [f64; 3] = [40.0, 25.0, 15.0];
const RIDGE: f64 = 1e-4;
const STRIDE: usize = 2;
/// Coefficients printed.
const REPORTED_COEFFICIENT: f32 = 0.05;

/// The curves of head `who` playing `take`'s mouth under its motion, the mouth leak left on.
fn talking(take: &Path, render: &Arc<HeadRender>, models: &Path, who: Head) -> Curves {
    let options = ExpressionOptions {
        replay: ReplayOptions {
            stride: STRIDE,
            only: Some(
                (0..ARKIT_BLENDSHAPE_COUNT)
                    .filter(|&i| is_mouth(i))
                    .collect(),
            ),
            ..head_replay(who, MOTION_DEG)
        },
        models: Some(models.to_path_buf()),
        keep_mouth_leak: true,
        ..ExpressionOptions::default()
    };
    head_curves(take, render, &options)
}

/// Per upper-face weight of `read`: its 95th and 99th percentiles and its r with `jawOpen`.
fn figures(read: &[[f32; ARKIT_BLENDSHAPE_COUNT]]) -> Vec<(usize, f32, f32, Option<f64>)> {
    let jaw = ARKIT_BLENDSHAPES
        .iter()
        .position(|n| *n == "jawOpen")
        .unwrap();
    let column = |w: usize| -> Vec<f32> { read.iter().map(|r| r[w]).collect() };
    (0..ARKIT_BLENDSHAPE_COUNT)
        .filter(|&w| is_upper_face(w))
        .map(|w| {
            let mut v: Vec<f32> = read.iter().map(|r| r[w]).collect();
            v.sort_by(f32::total_cmp);
            let r = pearson(&column(jaw), &column(w));
            (w, quantile_sorted(&v, 0.95), quantile_sorted(&v, 0.99), r)
        })
        .collect()
}

fn main() {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [model_dir, models, take, out] = args.as_slice() else {
        eprintln!("usage: mouth_leak_table ICT_MODEL_DIR MODELS_DIR TAKE.csv OUT.bin");
        std::process::exit(2);
    };
    let render = table_render(model_dir).expect("the head renderer");
    let run = |heads: &[Head]| run_two_at_a_time(heads, |who| talking(take, &render, models, who));
    let train: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]> = run(&TRAINING_HEADS)
        .into_iter()
        .flat_map(|c| c.read)
        .collect();
    let table = MouthLeak::learn(&train, RIDGE).expect("frames to learn from");
    println!(
        "learned from {} frames of {} heads; coefficients over {REPORTED_COEFFICIENT}:",
        train.len(),
        TRAINING_HEADS.len()
    );
    for u in (0..ARKIT_BLENDSHAPE_COUNT).filter(|&u| is_upper_face(u)) {
        let mut c: Vec<(f32, &str)> = (0..ARKIT_BLENDSHAPE_COUNT)
            .map(|m| (table.coefficient(u, m), ARKIT_BLENDSHAPES[m]))
            .filter(|(c, _)| *c > REPORTED_COEFFICIENT)
            .collect();
        c.sort_by(|a, b| b.0.total_cmp(&a.0));
        let list: Vec<String> = c.iter().map(|(c, n)| format!("{n} {c:.2}")).collect();
        println!("  {:<17} {}", ARKIT_BLENDSHAPES[u], list.join(", "));
    }

    let held_out = &HELD_OUT_HEADS[..2];
    for (who, curves) in held_out.iter().zip(run(held_out)) {
        let removed: Vec<[f32; ARKIT_BLENDSHAPE_COUNT]> = curves
            .read
            .iter()
            .map(|r| {
                let mut w = *r;
                table.remove(&mut w);
                w
            })
            .collect();
        println!(
            "held-out identity {:>2} talking, {} frames: p95 / p99 / r with jawOpen, without → with the table",
            who.0,
            curves.read.len()
        );
        let r = |v: Option<f64>| v.map_or_else(|| "—".to_string(), |r| format!("{r:.2}"));
        for (a, b) in figures(&curves.read).into_iter().zip(figures(&removed)) {
            println!(
                "  {:<17} {:.3} / {:.3} / {:>5} → {:.3} / {:.3} / {:>5}",
                ARKIT_BLENDSHAPES[a.0],
                a.1,
                a.2,
                r(a.3),
                b.1,
                b.2,
                r(b.3)
            );
        }
    }
    std::fs::write(out, table.to_bytes()).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    println!("wrote {}", out.display());
}
