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
use visage_eval::{standard_normal, tracked_views, HeadRender, TrackedView, ViewGrid};
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

/// The iris centre of an eye looking straight ahead as the eye network places it, relative to
/// the midpoint of the eye's corners on the face (model frame, mm; x mirrored for the left eye
/// so that + is towards the temple): least squares over the views' true poses. Prints it, and
/// the depth alone fitted per band of yaw.
fn iris_rest_point(k: &Intrinsics, views: &[TrackedView], name: &str) {
    let eyes: [([usize; 2], f64); 2] = [([33, 133], -1.0), ([362, 263], 1.0)];
    let observations: Vec<(RigidTransform, [f64; 3], f64, [f64; 2], f64)> = views
        .iter()
        .filter_map(|v| v.irises.map(|i| (v, i)))
        .flat_map(|(v, irises)| {
            let s = &v.sample;
            let center = s
                .points
                .iter()
                .fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
            let yaw = visage_morphable::fit::view_correction::view_of(
                &s.pose,
                center.map(|c| c / s.points.len() as f64),
            )[0]
            .to_degrees();
            eyes.iter().zip(irises).map(move |((c, side), iris)| {
                let mid: [f64; 3] =
                    std::array::from_fn(|i| 0.5 * (s.points[c[0]][i] + s.points[c[1]][i]));
                (s.pose, mid, *side, iris, yaw)
            })
        })
        .collect();
    let solve =
        |subset: &dyn Fn(f64) -> bool, free: [bool; 3], start: [f64; 3]| -> ([f64; 3], f64) {
            let mut o = start;
            let mut rms = 0.0;
            for _ in 0..6 {
                let (mut n, mut g, mut sum, mut count) = ([[0.0; 3]; 3], [0.0; 3], 0.0, 0.0f64);
                for (pose, mid, side, iris, yaw) in &observations {
                    if !subset(*yaw) {
                        continue;
                    }
                    let x = [mid[0] + side * o[0], mid[1] + o[1], mid[2] + o[2]];
                    let y = pose.apply(x);
                    let u = k.project(y);
                    let r = [iris[0] - u[0], iris[1] - u[1]];
                    sum += r[0] * r[0] + r[1] * r[1];
                    count += 1.0;
                    let iz = 1.0 / y[2];
                    let jp = [
                        [k.fx * iz, 0.0, -k.fx * y[0] * iz * iz],
                        [0.0, k.fy * iz, -k.fy * y[1] * iz * iz],
                    ];
                    let j: [[f64; 3]; 2] = std::array::from_fn(|a| {
                        std::array::from_fn(|b| {
                            let d = (0..3).map(|m| jp[a][m] * pose.rotation[m][b]).sum::<f64>();
                            if b == 0 {
                                d * side
                            } else {
                                d
                            }
                        })
                    });
                    for a in 0..3 {
                        g[a] += j[0][a] * r[0] + j[1][a] * r[1];
                        for b in 0..3 {
                            n[a][b] += j[0][a] * j[0][b] + j[1][a] * j[1][b];
                        }
                    }
                }
                rms = (sum / count.max(1.0)).sqrt();
                for a in 0..3 {
                    if !free[a] {
                        for b in 0..3 {
                            n[a][b] = if a == b { 1.0 } else { 0.0 };
                            n[b][a] = if a == b { 1.0 } else { 0.0 };
                        }
                        g[a] = 0.0;
                    }
                }
                // 3 × 3 solve by Cramer's rule.
                let det = |m: &[[f64; 3]; 3]| {
                    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
                };
                let d = det(&n);
                for c in 0..3 {
                    let mut m = n;
                    for r in 0..3 {
                        m[r][c] = g[r];
                    }
                    o[c] += det(&m) / d;
                }
            }
            (o, rms)
        };
    let (o, rms) = solve(&|_| true, [true; 3], [0.0; 3]);
    println!(
        "{name}: the iris of an eye looking ahead at ({:.2}, {:.2}, {:.2}) mm from the corners' midpoint (towards the temple, up, forward); {:.2} px RMS left",
        o[0] * 1e3, o[1] * 1e3, o[2] * 1e3, rms
    );
    for band in [0.0, 10.0, 20.0, 30.0, 40.0] {
        let (b, rms) = solve(
            &|yaw: f64| yaw.abs() >= band && yaw.abs() < band + 10.0,
            [false, false, true],
            o,
        );
        println!(
            "  |yaw| {band:.0}–{:.0}°: forward {:.2} mm ({rms:.2} px RMS)",
            band + 10.0,
            b[2] * 1e3
        );
    }
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
        |seeds: std::ops::Range<u64>| -> Result<Vec<TrackedView>, Box<dyn std::error::Error>> {
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
    let train_views = views(TRAIN_SEEDS)?;
    let held_out_views = views(HELD_OUT_SEEDS)?;
    let samples = |v: &[TrackedView]| v.iter().map(|t| t.sample.clone()).collect::<Vec<_>>();
    let (train, held_out) = (samples(&train_views), samples(&held_out_views));
    for (name, v) in [("learned on", &train_views), ("held out", &held_out_views)] {
        iris_rest_point(&k, v, name);
    }
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
