//! The factor-once solvers: accuracy, consistency of the streaming and clip modes, optimality.

mod common;

use common::{max_abs_diff, rms_diff, setup};
use faer::Mat;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use visage_fem::{
    apply_clip_operator, clip_energy, frame_energy, solve_clip, ClipOptions, StreamingSolver,
};

fn smooth(xn: f64, yn: f64) -> f64 {
    0.6 + 0.08 * (xn * 3.0).cos() * (yn * 2.5).sin() + 0.1 * (xn * xn + yn * yn)
}

fn noisy_frames(s: &common::Setup, frames: usize, seed: u64) -> Vec<Mat<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..frames)
        .map(|f| {
            let mut d = s.depth(|x, y| smooth(x, y) + 0.01 * (f as f64 * 0.3).sin() * x);
            for v in d.data.iter_mut() {
                *v += rng.random_range(-0.004..0.004);
            }
            s.rhs(&d)
        })
        .collect()
}

#[test]
fn streaming_step_residual_is_tiny() {
    let s = setup(64, 48, 4);
    let mut solver = StreamingSolver::new(s.system(2.5, 12.5));
    let bs = noisy_frames(&s, 3, 1);
    let mut x = Mat::zeros(s.mesh.points.len(), 3);
    for (k, b) in bs.iter().enumerate() {
        let r = solver.step(b.as_ref(), x.as_mut());
        assert_eq!(r.temporal, k > 0);
        assert!(
            r.relative_residual <= 1e-10,
            "frame {k}: residual {}",
            r.relative_residual
        );
    }
}

#[test]
fn vanishing_lambda_reproduces_the_data() {
    // A fronto-parallel plane back-projects to a field linear in (u, v): P1 represents it exactly.
    let s = setup(40, 30, 3);
    let plane = |_: f64, _: f64| 0.75;
    let b = s.rhs(&s.depth(plane));
    let mut solver = StreamingSolver::new(s.system(1e-12, 0.0));
    let mut x = Mat::zeros(s.mesh.points.len(), 3);
    solver.step(b.as_ref(), x.as_mut());
    let err = max_abs_diff(&x, &s.truth(plane));
    assert!(err < 1e-6, "max error {err} m");
}

#[test]
fn smooth_surface_error_falls_with_refinement() {
    let mut errors = Vec::new();
    for spacing in [8, 4, 2] {
        let s = setup(97, 73, spacing);
        let b = s.rhs(&s.depth(smooth));
        let mut solver = StreamingSolver::new(s.system(1e-3, 0.0));
        let mut x = Mat::zeros(s.mesh.points.len(), 3);
        solver.step(b.as_ref(), x.as_mut());
        errors.push(rms_diff(&x, &s.truth(smooth)));
    }
    assert!(errors[0] < 1e-3, "coarse error {} m", errors[0]);
    assert!(
        errors[1] < 0.6 * errors[0] && errors[2] < 0.6 * errors[1],
        "errors {errors:?}"
    );
}

#[test]
fn streaming_without_temporal_weight_equals_independent_solves() {
    let s = setup(48, 40, 4);
    let bs = noisy_frames(&s, 4, 2);
    let mut streaming = StreamingSolver::new(s.system(2.5, 0.0));
    let n = s.mesh.points.len();
    for b in &bs {
        let mut x = Mat::zeros(n, 3);
        streaming.step(b.as_ref(), x.as_mut());
        let mut fresh = StreamingSolver::new(s.system(2.5, 0.0));
        let mut y = Mat::zeros(n, 3);
        fresh.step(b.as_ref(), y.as_mut());
        assert!(max_abs_diff(&x, &y) < 1e-12);
    }
}

#[test]
fn clip_mode_solves_the_block_system_and_beats_streaming_energy() {
    let s = setup(48, 40, 4);
    let bs = noisy_frames(&s, 8, 3);
    let n = s.mesh.points.len();
    let mut streaming = StreamingSolver::new(s.system(2.5, 12.5));
    let mut xs: Vec<Mat<f64>> = Vec::new();
    for b in &bs {
        let mut x = Mat::zeros(n, 3);
        streaming.step(b.as_ref(), x.as_mut());
        xs.push(x);
    }
    let mut system = s.system(2.5, 12.5);
    let e_streaming = clip_energy(&system, &xs, &bs);
    let options = ClipOptions {
        tolerance: 1e-10,
        max_iterations: 500,
    };
    let mut clip = xs.clone();
    let report = solve_clip(&mut system, &bs, &mut clip, &options);
    assert!(report.converged, "{report:?}");
    // Independent check of the block system's residual.
    let mut ax: Vec<Mat<f64>> = (0..bs.len()).map(|_| Mat::zeros(n, 3)).collect();
    let mut temp = Mat::zeros(n, 3);
    apply_clip_operator(&system, &clip, &mut ax, &mut temp);
    let (mut num, mut den) = (0.0, 0.0);
    for (a, b) in ax.iter().zip(&bs) {
        for c in 0..3 {
            for i in 0..n {
                num += (a[(i, c)] - b[(i, c)]).powi(2);
                den += b[(i, c)].powi(2);
            }
        }
    }
    assert!(
        (num / den).sqrt() <= 1e-10,
        "block residual {}",
        (num / den).sqrt()
    );
    let e_clip = clip_energy(&system, &clip, &bs);
    assert!(
        e_clip < e_streaming,
        "clip energy {e_clip} ≥ streaming {e_streaming}"
    );
    // Clip mode from a zero start reaches the same minimiser.
    let mut from_zero: Vec<Mat<f64>> = (0..bs.len()).map(|_| Mat::zeros(n, 3)).collect();
    let r = solve_clip(&mut system, &bs, &mut from_zero, &options);
    assert!(r.converged);
    for (a, b) in from_zero.iter().zip(&clip) {
        assert!(max_abs_diff(a, b) < 1e-7);
    }
}

#[test]
fn random_perturbations_never_lower_the_energy() {
    let s = setup(40, 32, 4);
    let bs = noisy_frames(&s, 4, 4);
    let n = s.mesh.points.len();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    // Streaming: the frame energy with its predecessor.
    let mut solver = StreamingSolver::new(s.system(2.5, 12.5));
    let mut prev = Mat::zeros(n, 3);
    solver.step(bs[0].as_ref(), prev.as_mut());
    let mut x = Mat::zeros(n, 3);
    solver.step(bs[1].as_ref(), x.as_mut());
    let system = s.system(2.5, 12.5);
    let e0 = frame_energy(&system, x.as_ref(), bs[1].as_ref(), Some(prev.as_ref()));
    for scale in [1e-6, 1e-4, 1e-2] {
        for _ in 0..10 {
            let mut y = x.clone();
            for c in 0..3 {
                for i in 0..n {
                    y[(i, c)] += scale * rng.random_range(-1.0..1.0);
                }
            }
            let e = frame_energy(&system, y.as_ref(), bs[1].as_ref(), Some(prev.as_ref()));
            assert!(
                e >= e0,
                "streaming energy fell from {e0} to {e} (scale {scale})"
            );
        }
    }
    // Clip: the whole-sequence energy.
    let mut system = s.system(2.5, 12.5);
    let mut xs: Vec<Mat<f64>> = (0..bs.len()).map(|_| Mat::zeros(n, 3)).collect();
    assert!(solve_clip(&mut system, &bs, &mut xs, &ClipOptions::default()).converged);
    let e0 = clip_energy(&system, &xs, &bs);
    for scale in [1e-5, 1e-3] {
        for _ in 0..5 {
            let mut ys = xs.clone();
            let k = rng.random_range(0..ys.len());
            for c in 0..3 {
                for i in 0..n {
                    ys[k][(i, c)] += scale * rng.random_range(-1.0..1.0);
                }
            }
            assert!(clip_energy(&system, &ys, &bs) >= e0);
        }
    }
}

#[test]
fn negative_or_non_finite_weights_are_rejected() {
    let s = setup(16, 16, 4);
    for (l, m) in [(-1.0, 1.0), (1.0, f64::NAN), (f64::INFINITY, 0.0)] {
        let err =
            visage_fem::FusionSystem::new(s.ops.clone(), visage_fem::Weights { lambda: l, mu: m });
        assert!(err.is_err());
    }
}
