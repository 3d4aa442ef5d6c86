//! Regenerates the landmark network's view correction the fit applies
//! (`crates/morphable/data/landmark_view_correction.bin`): neutral heads of random ICT-FaceKit
//! identities (N(0, 1) weights, seeds 1000–1015), textured with the built-in real face, are
//! rendered over ±45° yaw and ±30° pitch in 5° steps and tracked (`visage_eval::tracked_views`);
//! the table is learned from them (`ViewCorrection::learn`). Eight more identities (seeds
//! 1016–1023) are held out and only scored: the head rotation a rigid fit reads, and the
//! landmarks' distance from the face's projected points at the true pose, without and with the
//! table.
//!
//! ```sh
//! cargo run --release -p visage-eval --example landmark_view_correction -- \
//!     ../shared/data/ict-facekit/FaceXModel models crates/morphable/data/landmark_view_correction.bin
//! ```
//! Deterministic: the renders, the networks and the least squares have no randomness but the
//! seeded identities. About four minutes on two cores.

use std::path::PathBuf;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use visage_camera::{Intrinsics, RigidTransform};
use visage_eval::{standard_normal, tracked_views, HeadRender, ViewGrid};
use visage_face::{FaceMesh, FaceTracker};
use visage_morphable::fit::rigid_pose::refine_pose;
use visage_morphable::fit::{FaceFitter, FitOptions, ViewCorrection, ViewSample};
use visage_morphable::FaceModel;

const TRAIN_SEEDS: std::ops::Range<u64> = 1000..1016;
const HELD_OUT_SEEDS: std::ops::Range<u64> = 1016..1024;

/// The rotation taking `truth` to `estimate`, as angles about the head's x (pitch), y (yaw)
/// and z (roll), degrees.
fn rotation_error_deg(truth: &RigidTransform, estimate: &RigidTransform) -> [f64; 3] {
    let (a, b) = (&truth.rotation, &estimate.rotation);
    let e: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[k][i] * b[k][j]).sum()));
    [
        (e[2][1] - e[1][2]) / 2.0,
        (e[0][2] - e[2][0]) / 2.0,
        (e[1][0] - e[0][1]) / 2.0,
    ]
    .map(|v: f64| v.asin().to_degrees())
}

fn score(k: &Intrinsics, samples: &[ViewSample], table: Option<&ViewCorrection>, rigid: &[f64]) {
    let (mut rotation, mut distance, mut n) = ([0.0; 3], 0.0, 0.0);
    let mut corrected = Vec::new();
    for s in samples {
        match table {
            Some(t) => t.correct(
                k,
                &s.estimated_pose,
                &s.points,
                &s.landmarks_px,
                &mut corrected,
            ),
            None => corrected.clone_from(&s.landmarks_px),
        }
        let mut pose = s.estimated_pose;
        refine_pose(k, &mut pose, &s.points, &corrected, rigid, 10);
        for (r, e) in rotation.iter_mut().zip(rotation_error_deg(&s.pose, &pose)) {
            *r += e * e;
        }
        distance += corrected
            .iter()
            .zip(&s.points)
            .map(|(u, &x)| {
                let v = k.project(s.pose.apply(x));
                ((u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2)).sqrt()
            })
            .sum::<f64>()
            / s.points.len() as f64;
        n += 1.0;
    }
    let rms = rotation.map(|r| (r / n).sqrt());
    println!(
        "  {:<13} rotation error RMS pitch {:.2}°, yaw {:.2}°, roll {:.2}°; landmarks {:.2} px from the face's points",
        if table.is_some() { "with table" } else { "without" },
        rms[0],
        rms[1],
        rms[2],
        distance / n
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args_os().skip(1).map(PathBuf::from);
    let (Some(ict), Some(models), Some(out)) = (args.next(), args.next(), args.next()) else {
        return Err("usage: landmark_view_correction ICT_FACEXMODEL MODELS OUT.bin".into());
    };
    let k = Intrinsics::from_fov(640, 480, 55.0)?;
    let render = HeadRender::load(&ict, k, 0.5)?;
    let model = FaceModel::embedded();
    let fitter = FaceFitter::new(&model, FitOptions::default());
    let mut rigid = vec![0.0; model.landmarks.len()];
    for j in fitter.rigid_landmarks() {
        rigid[j] = 1.0;
    }
    let mut tracker = FaceTracker::new(FaceMesh::load(&models)?);
    let grid = ViewGrid::default();
    let modes = render.model().identity_modes.len();
    let mut views =
        |seeds: std::ops::Range<u64>| -> Result<Vec<ViewSample>, Box<dyn std::error::Error>> {
            let mut all = Vec::new();
            for seed in seeds {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                let identity: Vec<f64> = (0..modes).map(|_| standard_normal(&mut rng)).collect();
                let samples =
                    tracked_views(&render, &model, &mut tracker, &identity, &grid, &rigid)?;
                eprintln!(
                    "identity seed {seed}: {} of {} views tracked",
                    samples.len(),
                    grid.poses().len()
                );
                all.extend(samples);
            }
            Ok(all)
        };
    let train = views(TRAIN_SEEDS)?;
    let held_out = views(HELD_OUT_SEEDS)?;
    let table = ViewCorrection::learn(&train, &k, grid.max_view())
        .ok_or("the tracked views do not span the table's terms")?;
    for (name, samples) in [("learned on", &train), ("held out", &held_out)] {
        println!("{name}: {} views", samples.len());
        score(&k, samples, None, &rigid);
        score(&k, samples, Some(&table), &rigid);
    }
    std::fs::write(&out, table.to_bytes())?;
    println!("wrote {}", out.display());
    Ok(())
}
