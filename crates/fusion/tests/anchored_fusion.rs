//! Face-anchored fusion with the pose-compensated temporal term (ERRATA 17): the rigid-motion
//! commutation the design rests on, no lag under head motion, noise reduction, holes.

#[path = "common/face_scene.rs"]
mod face_scene;

use face_scene::{camera, expression, fuser, observe, pose, template, HALF};
use faer::Mat;
use visage_camera::{DepthKind, DepthMap};
use visage_fem::sparse::sym_matmul;
use visage_fusion::{AnchoredFrame, FaceDomain, FrameDepth, FrameStatus, SurfaceFuser};

fn max_distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max)
}

/// `M (S Rᵀ + 1 tᵀ) = (M S) Rᵀ + (M 1) tᵀ` and `K (S Rᵀ + 1 tᵀ) = (K S) Rᵀ`: the operators act
/// per coordinate and K annihilates constants, so a rigid motion of every vertex moves only the
/// right-hand side.
#[test]
fn rigid_motions_commute_with_the_operators() {
    let (v, t) = template(true);
    let f = fuser(&v, &t, 2, 10.0, 0.5);
    let ops = &f.solver().system().ops;
    let n = f.domain().vertex_count();
    let s = Mat::from_fn(n, 3, |i, c| ((i * 7 + c * 3) % 11) as f64 * 0.01 - 0.05);
    let motion = pose(0.4, 0.03);
    let moved = Mat::from_fn(n, 3, |i, c| {
        motion.apply([s[(i, 0)], s[(i, 1)], s[(i, 2)]])[c]
    });
    let ones = Mat::from_fn(n, 1, |_, _| 1.0);
    for (name, op, translation_survives) in [("M", &ops.mass, true), ("K", &ops.biharmonic, false)]
    {
        let mut lhs = Mat::zeros(n, 3);
        sym_matmul(op, moved.as_ref(), 1.0, 0.0, lhs.as_mut());
        let mut ms = Mat::zeros(n, 3);
        sym_matmul(op, s.as_ref(), 1.0, 0.0, ms.as_mut());
        let mut m1 = Mat::zeros(n, 1);
        sym_matmul(op, ones.as_ref(), 1.0, 0.0, m1.as_mut());
        let mut worst = 0.0f64;
        let mut scale = 0.0f64;
        for i in 0..n {
            let rotated = motion.rotate([ms[(i, 0)], ms[(i, 1)], ms[(i, 2)]]);
            for c in 0..3 {
                let rhs = rotated[c] + m1[(i, 0)] * motion.translation[c];
                worst = worst.max((lhs[(i, c)] - rhs).abs());
                scale = scale.max(lhs[(i, c)].abs());
            }
            if !translation_survives {
                assert!(m1[(i, 0)].abs() < 1e-9 * scale.max(1.0), "{name} 1 ≠ 0");
            }
        }
        assert!(worst <= 1e-12 * scale, "{name}: {worst} vs scale {scale}");
    }
}

/// A head that turns and slides while holding an expression: with pose compensation the
/// fused surface is the static minimiser carried by the head in every frame — no lag, no
/// ghosting — although μ is large.
#[test]
fn a_moving_head_with_a_held_expression_does_not_lag() {
    let (v, t) = template(true);
    let face: Vec<[f64; 3]> = v.iter().map(|&p| expression(p)).collect();
    let mut f = fuser(&v, &t, 1, 10.0, 12.5);
    let mut first_head = None;
    for k in 0..25 {
        let p = pose(0.02 * k as f64, 0.002 * k as f64);
        let (surface, px) = observe(&face, &p);
        let r = f
            .process(&AnchoredFrame {
                template: None,
                landmarks_px: &px,
                pose: p,
                depth: FrameDepth::Surface(&surface),
            })
            .unwrap();
        assert_eq!(r.status, FrameStatus::Solved);
        assert!(r.relative_residual < 1e-10);
        let head: Vec<[f64; 3]> = f.solution().iter().map(|&x| p.apply_inverse(x)).collect();
        let first = first_head.get_or_insert_with(|| head.clone());
        let expected: Vec<[f64; 3]> = first.iter().map(|&x| p.apply(x)).collect();
        let d = max_distance(f.solution(), &expected);
        assert!(
            d < 1e-9,
            "frame {k}: {d} m from the carried static solution"
        );
        // And the static solution is close to the data (λ only removes what is not smooth).
        assert!(max_distance(f.solution(), &surface) < 1.5e-3);
    }
}

/// Without pose compensation the same motion would lag: fusing in camera coordinates with the
/// head's pose held fixed (identity) leaves the surface behind the data by far more.
#[test]
fn pose_compensation_is_what_removes_the_lag() {
    let (v, t) = template(true);
    let face: Vec<[f64; 3]> = v.iter().map(|&p| expression(p)).collect();
    let mut compensated = fuser(&v, &t, 1, 10.0, 12.5);
    let mut fixed = fuser(&v, &t, 1, 10.0, 12.5);
    let still = pose(0.0, 0.0);
    let (mut lag_compensated, mut lag_fixed) = (0.0f64, 0.0f64);
    for k in 0..15 {
        let p = pose(0.03 * k as f64, 0.003 * k as f64);
        let (surface, px) = observe(&face, &p);
        for (f, pose_given, lag) in [
            (&mut compensated, p, &mut lag_compensated),
            (&mut fixed, still, &mut lag_fixed),
        ] {
            f.process(&AnchoredFrame {
                template: None,
                landmarks_px: &px,
                pose: pose_given,
                depth: FrameDepth::Surface(&surface),
            })
            .unwrap();
            *lag = lag.max(max_distance(f.solution(), &surface));
        }
    }
    assert!(lag_compensated < 1.5e-3, "{lag_compensated}");
    assert!(
        lag_fixed > 5.0 * lag_compensated,
        "fixed {lag_fixed} vs compensated {lag_compensated}"
    );
}

/// White noise on the landmarks' 3-D points is averaged over space and time.
#[test]
fn noise_is_reduced_on_a_moving_head() {
    use rand::{Rng, SeedableRng};
    let (v, t) = template(true);
    let face: Vec<[f64; 3]> = v.iter().map(|&p| expression(p)).collect();
    let mut f = fuser(&v, &t, 2, 10.0, 2.0);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let (mut raw_err, mut fused_err, mut count) = (0.0, 0.0, 0usize);
    let mut truth = vec![[0.0; 3]; f.domain().vertex_count()];
    for k in 0..40 {
        let p = pose(0.25 * (k as f64 * 0.2).sin(), 0.0);
        let (clean, px) = observe(&face, &p);
        let noisy: Vec<[f64; 3]> = clean
            .iter()
            .map(|q| q.map(|c| c + 0.002 * (rng.random::<f64>() - 0.5) * 3.46))
            .collect();
        f.process(&AnchoredFrame {
            template: None,
            landmarks_px: &px,
            pose: p,
            depth: FrameDepth::Surface(&noisy),
        })
        .unwrap();
        f.domain().interpolate(&clean, &mut truth);
        if k >= 5 {
            for ((r, s), g) in f.raw().iter().zip(f.solution()).zip(&truth) {
                for c in 0..3 {
                    raw_err += (r[c] - g[c]).powi(2);
                    fused_err += (s[c] - g[c]).powi(2);
                }
            }
            count += truth.len();
        }
    }
    let (raw, fused) = (
        (raw_err / count as f64).sqrt(),
        (fused_err / count as f64).sqrt(),
    );
    assert!(fused < 0.5 * raw, "fused {fused} vs raw {raw}");
}

/// A depth map of the flat template placed by `pose` (z-depth), with holes where `hole` says.
fn plane_depth(p: &visage_camera::RigidTransform, hole: impl Fn(u32, u32) -> bool) -> DepthMap {
    let k = camera();
    let normal = p.rotate([0.0, 0.0, 1.0]);
    let offset: f64 = (0..3).map(|c| normal[c] * p.translation[c]).sum();
    let mut d = DepthMap::empty(k.width, k.height, DepthKind::Z);
    for y in 0..k.height {
        for x in 0..k.width {
            if hole(x, y) {
                continue;
            }
            let r = [(x as f64 - k.cx) / k.fx, (y as f64 - k.cy) / k.fy, 1.0];
            let z = offset / (0..3).map(|c| normal[c] * r[c]).sum::<f64>();
            d.data[(y * k.width + x) as usize] = z as f32;
        }
    }
    d
}

/// Vertices whose depth is missing take the previous surface carried by the head (or the
/// posed template on a first frame), and a frame without any depth is carried.
#[test]
fn holes_follow_the_head() {
    let (v, t) = template(false);
    let mut f = fuser(&v, &t, 2, 10.0, 0.5);
    let n = f.domain().vertex_count();
    let mut truth = vec![[0.0; 3]; n];
    for k in 0..12 {
        let p = pose(0.03 * k as f64, 0.002 * k as f64);
        let (clean, px) = observe(&v, &p);
        // A hole sweeping over the left half of the face after the first frames.
        let depth = plane_depth(&p, |x, _| k >= 3 && x < 320);
        let r = f
            .process(&AnchoredFrame {
                template: None,
                landmarks_px: &px,
                pose: p,
                depth: FrameDepth::Map(&depth),
            })
            .unwrap();
        assert_eq!(r.status, FrameStatus::Solved);
        if k >= 3 {
            assert!(r.valid_fraction < 0.9 && r.valid_fraction > 0.1);
        }
        f.domain().interpolate(&clean, &mut truth);
        let d = max_distance(f.solution(), &truth);
        // float32 depth and bilinear sampling: sub-0.1 mm.
        assert!(d < 1e-4, "frame {k}: {d} m");
    }
    // No depth at all: the previous surface, moved with the head.
    let p = pose(0.4, 0.03);
    let (clean, px) = observe(&v, &p);
    let empty = DepthMap::empty(640, 480, DepthKind::Z);
    let r = f
        .process(&AnchoredFrame {
            template: None,
            landmarks_px: &px,
            pose: p,
            depth: FrameDepth::Map(&empty),
        })
        .unwrap();
    assert_eq!(r.status, FrameStatus::Carried);
    f.domain().interpolate(&clean, &mut truth);
    assert!(max_distance(f.solution(), &truth) < 1e-4);
    // A fresh fuser with no depth on its first frame has nothing to carry.
    let mut fresh = fuser(&v, &t, 1, 10.0, 0.5);
    let r = fresh
        .process(&AnchoredFrame {
            template: None,
            landmarks_px: &px,
            pose: p,
            depth: FrameDepth::Map(&empty),
        })
        .unwrap();
    assert_eq!(r.status, FrameStatus::NoData);
}

/// The raw sample of a surface at a vertex's pixel lies on its template triangle's plane and
/// projects onto the pixel (what rasterising the surface and reading the depth would give).
#[test]
fn surface_samples_are_perspective_correct() {
    let (v, t) = template(true);
    let face: Vec<[f64; 3]> = v.iter().map(|&p| expression(p)).collect();
    let mut f = fuser(&v, &t, 3, 10.0, 0.5);
    let p = pose(0.5, 0.04);
    let (surface, px) = observe(&face, &p);
    f.process(&AnchoredFrame {
        template: None,
        landmarks_px: &px,
        pose: p,
        depth: FrameDepth::Surface(&surface),
    })
    .unwrap();
    let k = camera();
    for (i, (x, pixel)) in f.raw().iter().zip(f.pixels()).enumerate() {
        let q = k.project(*x);
        assert!((q[0] - pixel[0]).abs() < 1e-9 && (q[1] - pixel[1]).abs() < 1e-9);
        let a = f.domain().anchors[i];
        let [p0, p1, p2] =
            f.domain().template_triangles[a.triangle as usize].map(|j| surface[j as usize]);
        let e1: [f64; 3] = std::array::from_fn(|c| p1[c] - p0[c]);
        let e2: [f64; 3] = std::array::from_fn(|c| p2[c] - p0[c]);
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let off: f64 = (0..3).map(|c| n[c] * (x[c] - p0[c])).sum();
        let norm = (n.iter().map(|c| c * c).sum::<f64>()).sqrt();
        assert!((off / norm).abs() < 1e-12, "vertex {i} off its plane");
    }
}

#[test]
fn malformed_frames_are_refused() {
    let (v, t) = template(true);
    let mut f = fuser(&v, &t, 1, 10.0, 0.5);
    let p = pose(0.0, 0.0);
    let (surface, px) = observe(&v, &p);
    let short = &px[..10];
    let err = f
        .process(&AnchoredFrame {
            template: None,
            landmarks_px: short,
            pose: p,
            depth: FrameDepth::Surface(&surface),
        })
        .unwrap_err();
    assert!(err.to_string().contains("landmarks"), "{err}");
    let mut bad = p;
    bad.translation[0] = f64::NAN;
    assert!(f
        .process(&AnchoredFrame {
            template: None,
            landmarks_px: &px,
            pose: bad,
            depth: FrameDepth::Surface(&surface),
        })
        .is_err());
    let domain = FaceDomain::subdivide(v.len(), &t, 1).unwrap();
    assert!(visage_fusion::AnchoredFuser::new(
        domain,
        &v[..5],
        camera(),
        visage_fem::Weights::default(),
        10.0
    )
    .is_err());
}

/// A face 10 % larger than the template: the landmark fit (template size) places it 10 % too
/// close; the depth maps measure the scale and the fused surface lands on the real face.
#[test]
fn the_face_scale_is_measured_from_depth_maps() {
    let (v, t) = template(false);
    let mut f = fuser(&v, &t, 2, 10.0, 0.5);
    let big: Vec<[f64; 3]> = v.iter().map(|p| p.map(|c| 1.1 * c)).collect();
    let mut truth = vec![[0.0; 3]; f.domain().vertex_count()];
    for k in 0..8 {
        let p = pose(0.05 * k as f64, 0.002 * k as f64);
        let (clean, px) = observe(&big, &p);
        let mut fitted = p;
        fitted.translation = p.translation.map(|c| c / 1.1);
        let depth = plane_depth(&p, |_, _| false);
        f.process(&AnchoredFrame {
            template: None,
            landmarks_px: &px,
            pose: fitted,
            depth: FrameDepth::Map(&depth),
        })
        .unwrap();
        assert!((f.scale() - 1.1).abs() < 1e-4, "scale {}", f.scale());
        f.domain().interpolate(&clean, &mut truth);
        let d = max_distance(f.solution(), &truth);
        assert!(d < 2e-4, "frame {k}: {d} m");
    }
}

/// With the frame's template given (a fitted model's face), an expression that changes from
/// frame to frame passes through without lag however large μ is: only the deviation from the
/// template is smoothed over time. With the fixed template the same motion lags.
#[test]
fn a_per_frame_template_passes_its_motion_without_lag() {
    let (v, t) = template(true);
    let mut with_template = fuser(&v, &t, 1, 10.0, 12.5);
    let mut fixed = fuser(&v, &t, 1, 10.0, 12.5);
    let (mut lag_template, mut lag_fixed) = (0.0f64, 0.0f64);
    for k in 0..15 {
        // A bump that grows by 1 mm a frame while the head turns.
        let depth = 0.001 * k as f64;
        let face: Vec<[f64; 3]> = v
            .iter()
            .map(|&p| {
                let r2 = (p[0] * p[0] + p[1] * p[1]) / (HALF * HALF);
                [p[0], p[1], p[2] - depth * (-2.0 * r2).exp()]
            })
            .collect();
        let p = pose(0.02 * k as f64, 0.0);
        let (surface, px) = observe(&face, &p);
        for (f, template, lag) in [
            (&mut with_template, Some(face.as_slice()), &mut lag_template),
            (&mut fixed, None, &mut lag_fixed),
        ] {
            f.process(&AnchoredFrame {
                landmarks_px: &px,
                pose: p,
                depth: FrameDepth::Surface(&surface),
                template,
            })
            .unwrap();
            *lag = lag.max(max_distance(f.solution(), &surface));
        }
        // The template alone, posed, is the data here.
        let posed: Vec<[f64; 3]> = with_template.posed_template().collect();
        assert!(max_distance(&posed, &surface) < 1e-12);
    }
    assert!(lag_template < 1e-9, "{lag_template}");
    assert!(lag_fixed > 1e-3, "fixed template: {lag_fixed}");
}

/// A frame template with the wrong number of points is refused.
#[test]
fn a_template_of_the_wrong_size_is_refused() {
    let (v, t) = template(true);
    let mut f = fuser(&v, &t, 1, 10.0, 0.5);
    let (surface, px) = observe(&v, &pose(0.0, 0.0));
    let short = &v[..v.len() - 1];
    let r = f.process(&AnchoredFrame {
        landmarks_px: &px,
        pose: pose(0.0, 0.0),
        depth: FrameDepth::Surface(&surface),
        template: Some(short),
    });
    assert!(r.is_err());
}
