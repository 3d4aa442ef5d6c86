//! The per-frame face-model fit (pose, identity, 53 expressions from 468 landmarks), warm: the
//! steady state of a video, alternating two frames of a talking, turning face.

use criterion::{criterion_group, criterion_main, Criterion};
use visage_camera::{Intrinsics, RigidTransform};
use visage_morphable::fit::rigid_pose::{exp_so3, mat3_mul};
use visage_morphable::fit::{LandmarkBasis, FRONTAL};
use visage_morphable::{FaceFitter, FaceModel, FitOptions};

fn frame(basis: &LandmarkBasis, k: &Intrinsics, e: &[f64], turn: f64) -> Vec<[f64; 2]> {
    let pose = RigidTransform {
        rotation: mat3_mul(&exp_so3([0.05, turn, 0.0]), &FRONTAL),
        translation: [0.0, 0.0, 0.55],
    };
    let mut points = vec![[0.0; 3]; basis.landmark_count()];
    basis.landmarks(&vec![0.3; basis.identity_count], e, &mut points);
    points.iter().map(|&p| k.project(pose.apply(p))).collect()
}

fn fit(c: &mut Criterion) {
    let model = FaceModel::embedded();
    let basis = LandmarkBasis::new(&model);
    let k = Intrinsics::from_fov(1280, 720, 60.0).unwrap();
    let mut e = vec![0.0; basis.expression_count];
    let frames = [frame(&basis, &k, &e, 0.1), {
        e[model.expression_index("jawOpen").unwrap()] = 0.4;
        e[model.expression_index("mouthSmile_L").unwrap()] = 0.3;
        frame(&basis, &k, &e, 0.15)
    }];
    let mut fitter = FaceFitter::new(&model, FitOptions::default());
    for _ in 0..30 {
        fitter.fit(&k, &frames[0], None);
    }
    let mut i = 0;
    c.bench_function("face_fit_468_landmarks", |b| {
        b.iter(|| {
            i += 1;
            fitter.fit(&k, &frames[i % 2], None)
        })
    });
}

criterion_group!(benches, fit);
criterion_main!(benches);
