//! Regenerates the landmark network's view correction the fit applies
//! (`crates/morphable/data/landmark_view_correction.bin`): neutral heads of random ICT-FaceKit
//! identities (N(0, 1) weights, seeds 1000–1015), textured with the built-in real face, are
//! rendered over ±45° yaw and ±30° pitch in 5° steps and tracked (`visage_eval::tracked_views`);
//! the table is learned from them (`ViewCorrection::learn`). Eight more identities (seeds
//! 1016–1023) are held out and only scored: the head rotation a rigid fit reads, and the
//! landmarks' distance from the face's projected points at the true pose, without and with the
//! table. It also prints where the eye network puts the iris of an eye looking straight ahead,
//! relative to the eye's corners (the rest point `visage-rig`'s gaze model assumes).
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
use visage_morphable::fit::view_correction::{centroid, view_of};
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
                view_of(&s.estimated_pose, centroid(&s.points)),
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

/// One eye of one view: the true pose, the midpoint of the eye's corners on the face (model
/// frame), which side the eye is on (−1 right, +1 left), the iris pixel and the view's yaw.
struct IrisView {
    pose: RigidTransform,
    mid: [f64; 3],
    side: f64,
    iris: [f64; 2],
    yaw_deg: f64,
}

impl IrisView {
    /// The iris pixel's residual and its Jacobian with respect to the rest point's offset
    /// `o` (towards the temple, up, forward; metres) from the corners' midpoint.
    fn linearise(&self, k: &Intrinsics, o: [f64; 3]) -> ([f64; 2], [[f64; 3]; 2]) {
        let x = [
            self.mid[0] + self.side * o[0],
            self.mid[1] + o[1],
            self.mid[2] + o[2],
        ];
        let y = self.pose.apply(x);
        let u = k.project(y);
        let iz = 1.0 / y[2];
        let jp = [
            [k.fx * iz, 0.0, -k.fx * y[0] * iz * iz],
            [0.0, k.fy * iz, -k.fy * y[1] * iz * iz],
        ];
        let r = &self.pose.rotation;
        let j = std::array::from_fn(|a| {
            std::array::from_fn(|b| {
                let d: f64 = (0..3).map(|m| jp[a][m] * r[m][b]).sum();
                if b == 0 {
                    d * self.side
                } else {
                    d
                }
            })
        });
        ([self.iris[0] - u[0], self.iris[1] - u[1]], j)
    }
}

/// Gauss–Newton on the offset's `free` components over `views`; the offset and the RMS
/// residual (px) at it.
fn fit_rest_point(
    k: &Intrinsics,
    views: &[&IrisView],
    free: [bool; 3],
    start: [f64; 3],
) -> ([f64; 3], f64) {
    let mut o = start;
    for _ in 0..6 {
        let mut n = faer::Mat::<f64>::identity(3, 3);
        let mut g = faer::Mat::<f64>::zeros(3, 1);
        for a in (0..3).filter(|&a| free[a]) {
            n[(a, a)] = 0.0;
        }
        for v in views {
            let (r, j) = v.linearise(k, o);
            for a in (0..3).filter(|&a| free[a]) {
                g[(a, 0)] += j[0][a] * r[0] + j[1][a] * r[1];
                for b in (0..3).filter(|&b| free[b]) {
                    n[(a, b)] += j[0][a] * j[0][b] + j[1][a] * j[1][b];
                }
            }
        }
        let Ok(llt) = n.llt(faer::Side::Lower) else {
            break;
        };
        let step = faer::linalg::solvers::Solve::solve(&llt, &g);
        for (a, o) in o.iter_mut().enumerate() {
            *o += step[(a, 0)];
        }
    }
    let sum: f64 = views
        .iter()
        .map(|v| {
            let (r, _) = v.linearise(k, o);
            r[0] * r[0] + r[1] * r[1]
        })
        .sum();
    (o, (sum / views.len().max(1) as f64).sqrt())
}

/// Where the eye network puts the iris centre of an eye looking straight ahead, relative to
/// the midpoint of the eye's corners on the face (model frame): least squares over the views'
/// true poses, then the depth alone per band of yaw. What `visage-rig`'s gaze model assumes
/// (5 mm in front of the corners) is checked against it.
fn iris_rest_point(k: &Intrinsics, views: &[TrackedView], name: &str) {
    let eyes: [([usize; 2], f64); 2] = [([33, 133], -1.0), ([362, 263], 1.0)];
    let mut observations = Vec::new();
    for v in views {
        let (Some(irises), s) = (v.irises, &v.sample) else {
            continue;
        };
        let yaw_deg = view_of(&s.pose, centroid(&s.points))[0].to_degrees();
        for ((corners, side), iris) in eyes.iter().zip(irises) {
            observations.push(IrisView {
                pose: s.pose,
                mid: std::array::from_fn(|i| {
                    0.5 * (s.points[corners[0]][i] + s.points[corners[1]][i])
                }),
                side: *side,
                iris,
                yaw_deg,
            });
        }
    }
    let all: Vec<&IrisView> = observations.iter().collect();
    let (o, rms) = fit_rest_point(k, &all, [true; 3], [0.0; 3]);
    println!(
        "{name}: the iris of an eye looking ahead at ({:.2}, {:.2}, {:.2}) mm from the corners' midpoint (towards the temple, up, forward); {rms:.2} px RMS left",
        o[0] * 1e3,
        o[1] * 1e3,
        o[2] * 1e3
    );
    for band in [0.0, 10.0, 20.0, 30.0, 40.0] {
        let some: Vec<&IrisView> = observations
            .iter()
            .filter(|v| v.yaw_deg.abs() >= band && v.yaw_deg.abs() < band + 10.0)
            .collect();
        let (b, rms) = fit_rest_point(k, &some, [false, false, true], o);
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
