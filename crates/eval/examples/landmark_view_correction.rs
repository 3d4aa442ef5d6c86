//! Regenerates the landmark network's view correction the fit applies
//! (`crates/morphable/data/landmark_view_correction.bin`): neutral heads of random ICT-FaceKit
//! identities (N(0, 1) weights, seeds 1000–1015), textured with the built-in real face, are
//! rendered over ±45° yaw and ±30° pitch in 5° steps and tracked (`visage_eval::tracked_views`);
//! the table is learned from them (`ViewCorrection::learn`). Eight more identities (seeds
//! 1016–1023) are held out and only scored: the head rotation a rigid fit reads, and the
//! landmarks' distance from the face's projected points at the true pose, without and with the
//! table. It also prints where the eye network puts the iris of an eye looking straight ahead
//! and its contour's corners, relative to the eye's corners (the points `visage-rig`'s gaze
//! model assumes), and the gaze read from the held-out eyes with the eye placed by the fitted
//! head and by the contour.
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
use visage_eval::{
    gazes, standard_normal, tracked_views, HeadPose, HeadRender, RenderWork, TrackedView, ViewGrid,
};
use visage_face::{FaceMesh, FaceTracker};
use visage_morphable::fit::rigid_pose::refine_pose;
use visage_morphable::fit::view_correction::{centroid, view_of};
use visage_morphable::fit::{FaceFitter, FitOptions, ViewCorrection, ViewSample};
use visage_morphable::FaceModel;
use visage_rig::{
    eye_gaze, ArkitToIct, ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT, EYEBALL_DEPTH_M,
    IRIS_ROTATION_RADIUS_M,
};

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

/// The pose a rigid fit of `s`'s landmarks gives from its uncorrected estimate, with the
/// table's correction when given (`corrected` is scratch space).
fn fitted_pose(
    k: &Intrinsics,
    s: &ViewSample,
    table: Option<&ViewCorrection>,
    rigid: &[f64],
    corrected: &mut Vec<[f64; 2]>,
) -> RigidTransform {
    match table {
        Some(t) => t.correct(
            k,
            &s.estimated_pose,
            view_of(&s.estimated_pose, centroid(&s.points)),
            &s.points,
            &s.landmarks_px,
            corrected,
        ),
        None => corrected.clone_from(&s.landmarks_px),
    }
    let mut pose = s.estimated_pose;
    refine_pose(k, &mut pose, &s.points, corrected, rigid, 10);
    pose
}

fn score(k: &Intrinsics, samples: &[ViewSample], table: Option<&ViewCorrection>, rigid: &[f64]) {
    let (mut rotation, mut distance, mut n) = ([0.0; 3], 0.0, 0.0);
    let mut corrected = Vec::new();
    for s in samples {
        let pose = fitted_pose(k, s, table, rigid, &mut corrected);
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
/// frame), which side the eye is on (−1 right, +1 left), a pixel the eye network found (the
/// iris centre, or the contour's corners' midpoint) and the view's yaw.
struct EyeView {
    pose: RigidTransform,
    mid: [f64; 3],
    side: f64,
    seen: [f64; 2],
    yaw_deg: f64,
}

impl EyeView {
    /// The pixel's residual and its Jacobian with respect to the offset `o` (towards the
    /// temple, up, forward; metres) from the corners' midpoint of the point it shows.
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
        ([self.seen[0] - u[0], self.seen[1] - u[1]], j)
    }
}

/// Gauss–Newton on the offset's `free` components over `views`; the offset and the RMS
/// residual (px) at it.
fn fit_rest_point(
    k: &Intrinsics,
    views: &[&EyeView],
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

/// The face's eye-corner landmarks, the subject's `[right, left]`, and their sides.
const EYE_CORNERS: [([usize; 2], f64); 2] = [([33, 133], -1.0), ([362, 263], 1.0)];

/// The midpoint of landmarks `corners` among `points`.
fn midpoint(points: &[[f64; 3]], corners: [usize; 2]) -> [f64; 3] {
    std::array::from_fn(|i| 0.5 * (points[corners[0]][i] + points[corners[1]][i]))
}

/// Each eye of each view with the pixel `seen` picks (`None`: no eye network output).
fn eye_views(
    views: &[TrackedView],
    seen: impl Fn(&TrackedView) -> Option<[[f64; 2]; 2]>,
) -> Vec<EyeView> {
    let mut out = Vec::new();
    for v in views {
        let (Some(pixels), s) = (seen(v), &v.sample) else {
            continue;
        };
        let yaw_deg = view_of(&s.pose, centroid(&s.points))[0].to_degrees();
        for ((corners, side), seen) in EYE_CORNERS.iter().zip(pixels) {
            out.push(EyeView {
                pose: s.pose,
                mid: midpoint(&s.points, *corners),
                side: *side,
                seen,
                yaw_deg,
            });
        }
    }
    out
}

/// Where the eye network puts `what` of an eye looking straight ahead, relative to the
/// midpoint of the eye's corners on the face (model frame): least squares over the views' true
/// poses, then the depth alone per band of yaw. `visage-rig`'s gaze model assumes the iris 5 mm
/// in front of the corners and the contour's corners at `CONTOUR_CORNERS_OFFSET_M`.
fn rest_point(k: &Intrinsics, observations: &[EyeView], what: &str, name: &str) -> [f64; 3] {
    let all: Vec<&EyeView> = observations.iter().collect();
    let (o, rms) = fit_rest_point(k, &all, [true; 3], [0.0; 3]);
    println!(
        "{name}: {what} of an eye looking ahead at ({:.2}, {:.2}, {:.2}) mm from the corners' midpoint (towards the temple, up, forward); {rms:.2} px RMS left",
        o[0] * 1e3,
        o[1] * 1e3,
        o[2] * 1e3
    );
    for band in [0.0, 10.0, 20.0, 30.0, 40.0] {
        let some: Vec<&EyeView> = observations
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
    o
}

/// The gaze `visage-rig` reads from eyes that look straight ahead, at the pose a rigid fit of
/// the corrected landmarks gives: its error (degrees, RMS of yaw and pitch) by band of yaw,
/// with the eye placed by the fitted head alone and by the eye network's contour. Each
/// identity's mean gaze over its views within 10° of head-on is taken off first, as the rest
/// pose's calibration takes off a person's resting gaze.
fn gaze_errors(
    k: &Intrinsics,
    identities: &[Vec<TrackedView>],
    table: &ViewCorrection,
    rigid: &[f64],
) {
    const BANDS: [f64; 5] = [0.0, 10.0, 20.0, 30.0, 40.0];
    let mut sums = [[[0.0; 2]; BANDS.len()]; 2];
    let mut counts = [0usize; BANDS.len()];
    // The same for the eye nearer the camera alone (the rig gives its gaze to the far eye
    // from 30° of turn).
    let mut near_sums = [[[0.0; 2]; BANDS.len()]; 2];
    let mut near_counts = [0usize; BANDS.len()];
    let mut corrected = Vec::new();
    for views in identities {
        // Per view: its band, and each method's gaze of both eyes (yaw, pitch; degrees).
        let mut read = Vec::new();
        for v in views {
            let (Some(irises), Some(contours), s) = (v.irises, v.contour_corners, &v.sample) else {
                continue;
            };
            let pose = fitted_pose(k, s, Some(table), rigid, &mut corrected);
            let view = view_of(&s.pose, centroid(&s.points)).map(f64::to_degrees);
            let mut gazes = [[[0.0; 2]; 2]; 2];
            for (e, (((corners, _), iris), contour)) in
                EYE_CORNERS.iter().zip(irises).zip(contours).enumerate()
            {
                let corners = corners.map(|i| s.points[i]);
                for (m, contour) in [None, Some(contour)].into_iter().enumerate() {
                    let g = eye_gaze(k, &pose, corners, iris, contour).unwrap_or_default();
                    gazes[m][e] = [g.yaw.to_degrees(), g.pitch.to_degrees()];
                }
            }
            read.push((view, gazes));
        }
        let frontal: Vec<_> = read
            .iter()
            .filter(|(v, _)| v[0].abs() < 10.0 && v[1].abs() < 10.0)
            .collect();
        let n = frontal.len().max(1) as f64;
        let rest: [[[f64; 2]; 2]; 2] = std::array::from_fn(|m| {
            std::array::from_fn(|e| {
                std::array::from_fn(|a| frontal.iter().map(|(_, g)| g[m][e][a]).sum::<f64>() / n)
            })
        });
        for (view, gazes) in &read {
            let band = BANDS.iter().rposition(|&b| view[0].abs() >= b).unwrap_or(0);
            counts[band] += 2;
            near_counts[band] += 1;
            // The camera is on the model's +x side (the subject's left) at a positive yaw.
            let near = usize::from(view[0] > 0.0);
            for m in 0..2 {
                for e in 0..2 {
                    for a in 0..2 {
                        let d2 = (gazes[m][e][a] - rest[m][e][a]).powi(2);
                        sums[m][band][a] += d2;
                        if e == near {
                            near_sums[m][band][a] += d2;
                        }
                    }
                }
            }
        }
    }
    for (which, sums, counts) in [
        ("both eyes", &sums, &counts),
        ("the eye nearer the camera", &near_sums, &near_counts),
    ] {
        println!(
            "  gaze of eyes looking ahead, {which}: RMS yaw / pitch (degrees) by |yaw| of the head"
        );
        for (b, band) in BANDS.iter().enumerate() {
            let n = counts[b].max(1) as f64;
            let rms = |m: usize, a: usize| (sums[m][b][a] / n).sqrt();
            println!(
                "    {band:.0}–{:.0}°: placed by the head {:.1} / {:.1}, by the contour {:.1} / {:.1} ({} eyes)",
                band + 10.0,
                rms(0, 0),
                rms(0, 1),
                rms(1, 0),
                rms(1, 1),
                counts[b]
            );
        }
    }
}

/// A larger shift of the iris between two renders of one pose is the tracker moving (pixels).
const MAX_IRIS_SHIFT_PX: f64 = 8.0;

/// How far the contour's corners' midpoint follows the iris when the eyes look away: for
/// each of `identities`, at yaws of 0°, ±15° and ±30° and pitches of 0° and ±15°, the face
/// rendered with its eyes ahead and looking up, down, left and right (the `eyeLook*` weights at
/// 0.6: the eyes turn 15° and the lids follow, as the expression benchmark plays them). The
/// ratio, per image axis, of the contour's midpoint's motion to the iris's, by least squares
/// over both eyes (shifts of more than [`MAX_IRIS_SHIFT_PX`] left out).
fn contour_follows_iris(
    render: &HeadRender,
    tracker: &mut FaceTracker,
    identities: &[Vec<f64>],
) -> Result<[f64; 2], Box<dyn std::error::Error>> {
    let to_ict = ArkitToIct::new(&render.model().expression_names);
    let look = |dir: &str, left_eye_dir: &str| {
        let mut w = [0.0f32; ARKIT_BLENDSHAPE_COUNT];
        for (name, value) in [
            (format!("eyeLook{dir}Right"), 0.6),
            (format!("eyeLook{left_eye_dir}Left"), 0.6),
        ] {
            if let Some(i) = ARKIT_BLENDSHAPES.iter().position(|n| *n == name) {
                w[i] = value;
            }
        }
        w
    };
    // Ahead, then looking up, down, to the subject's left (the right eye in, the left out)
    // and to the right; the axis each one moves the eyes along.
    let looks = [
        (look("", ""), None),
        (look("Up", "Up"), Some(1)),
        (look("Down", "Down"), Some(1)),
        (look("In", "Out"), Some(0)),
        (look("Out", "In"), Some(0)),
    ];
    let mut work = RenderWork::default();
    let (mut cross, mut square) = ([0.0; 2], [0.0; 2]);
    for identity in identities {
        let pivot = render.pivot(identity)?;
        tracker.reset();
        for pitch in [-15.0f64, 0.0, 15.0] {
            for yaw in [-30.0f64, -15.0, 0.0, 15.0, 30.0] {
                let pose = HeadPose {
                    angles: [yaw.to_radians(), pitch.to_radians(), 0.0],
                    shift_m: [0.0; 3],
                };
                let mut ahead: Option<[[[f64; 2]; 2]; 2]> = None;
                // The first render of each pose lets the tracker settle on it.
                for (weights, axis) in std::iter::once(&looks[0]).chain(&looks) {
                    let image = render.render(
                        identity,
                        &to_ict.weights(weights),
                        gazes(weights),
                        &pose,
                        pivot,
                        &mut work,
                    )?;
                    let Some(eyes) = tracker.track(&image)?.face.and_then(|f| f.eyes) else {
                        tracker.reset();
                        continue;
                    };
                    // Per eye: the iris centre and the contour's corners' midpoint.
                    let mut seen = [[[0.0; 2]; 2]; 2];
                    for (s, e) in seen.iter_mut().zip([&eyes.right, &eyes.left]) {
                        let Some([_, _, a, b]) = e.lid_points() else {
                            continue;
                        };
                        let c = e.iris_center();
                        *s = [
                            [c[0] as f64, c[1] as f64],
                            [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])],
                        ];
                    }
                    match (axis, ahead) {
                        (None, _) => ahead = Some(seen),
                        (Some(a), Some(base)) => {
                            for (s, b) in seen.iter().zip(base) {
                                let iris = s[0][*a] - b[0][*a];
                                let contour = s[1][*a] - b[1][*a];
                                // A 15° turn moves the iris about 3.5 px here: more is the
                                // tracker still settling on the pose, not the eye.
                                if iris.abs() > MAX_IRIS_SHIFT_PX {
                                    continue;
                                }
                                cross[*a] += iris * contour;
                                square[*a] += iris * iris;
                            }
                        }
                        (Some(_), None) => {}
                    }
                }
            }
        }
    }
    Ok([0, 1].map(|a| cross[a] / square[a].max(1e-12)))
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
        |seeds: std::ops::Range<u64>| -> Result<Vec<Vec<TrackedView>>, Box<dyn std::error::Error>> {
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
                all.push(samples);
            }
            Ok(all)
        };
    let train_views: Vec<TrackedView> = views(TRAIN_SEEDS)?.concat();
    let held_out_identities = views(HELD_OUT_SEEDS)?;
    let held_out_views = held_out_identities.concat();
    let samples = |v: &[TrackedView]| v.iter().map(|t| t.sample.clone()).collect::<Vec<_>>();
    let (train, held_out) = (samples(&train_views), samples(&held_out_views));
    for (name, v) in [("learned on", &train_views), ("held out", &held_out_views)] {
        let iris = rest_point(&k, &eye_views(v, |v| v.irises), "the iris", name);
        let contour_midpoints = |v: &TrackedView| {
            v.contour_corners
                .map(|eyes| eyes.map(|[a, b]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]))
        };
        let contour = rest_point(
            &k,
            &eye_views(v, contour_midpoints),
            "the contour's corners' midpoint",
            name,
        );
        // The gaze model's iris looks ahead from (0, 0, r − d); the contour's midpoint sits
        // where the iris is seen from it.
        let o: [f64; 3] = std::array::from_fn(|i| contour[i] - iris[i]);
        println!(
            "  {name}: for the gaze model the contour's corners' midpoint lies at ({:.2}, {:.2}, {:.2}) mm",
            o[0] * 1e3,
            o[1] * 1e3,
            (o[2] + IRIS_ROTATION_RADIUS_M - EYEBALL_DEPTH_M) * 1e3
        );
    }
    let table = ViewCorrection::learn(&train, &k, grid.max_view())
        .ok_or("the tracked views do not span the table's terms")?;
    for (name, samples) in [("learned on", &train), ("held out", &held_out)] {
        println!("{name}: {} views", samples.len());
        score(&k, samples, None, &rigid);
        score(&k, samples, Some(&table), &rigid);
    }
    gaze_errors(&k, &held_out_identities, &table, &rigid);
    let identity = |seed: u64| -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..modes).map(|_| standard_normal(&mut rng)).collect()
    };
    for (name, seeds) in [("learned on", TRAIN_SEEDS), ("held out", HELD_OUT_SEEDS)] {
        let identities: Vec<Vec<f64>> = seeds.map(identity).collect();
        let [x, y] = contour_follows_iris(&render, &mut tracker, &identities)?;
        println!(
            "{name}: the contour's corners' midpoint follows the iris by {x:.3} across and {y:.3} up and down"
        );
    }
    std::fs::write(&out, table.to_bytes())?;
    println!("wrote {}", out.display());
    Ok(())
}
