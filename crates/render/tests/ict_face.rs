//! Acceptance: the ICT-FaceKit neutral face renders to a depth map whose back-projection lies on
//! the mesh (max point-to-mesh distance ≤ 0.05 mm).

mod common;

use visage_camera::{DepthKind, Intrinsics, RigidTransform};
use visage_render::{render_depth, NO_TRIANGLE};

/// Acceptance bound on the distance of back-projected depth to the mesh, metres.
const MAX_DISTANCE_M: f64 = 0.05e-3;

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
fn ict_neutral_face_depth_back_projects_onto_the_mesh() {
    let path = visage_testdata::require(
        visage_testdata::shared_dir().join("data/ict-facekit/FaceXModel/generic_neutral_mesh.obj"),
    );
    let mut mesh = visage_mesh::io::read_obj(&path).unwrap();
    // Centimetres → metres.
    mesh.vertices
        .iter_mut()
        .for_each(|p| *p = p.map(|c| c * 0.01));
    // ICT is y-up with the face looking along +z: turn it 180° about x to face the camera,
    // and place the face 45 cm in front of it.
    let k = Intrinsics::new(640, 480, 900.0, 900.0, 319.5, 239.5).unwrap();
    let pose = RigidTransform::new(
        [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
        [0.0, 0.12, 0.55],
    )
    .unwrap();
    for kind in [DepthKind::Z, DepthKind::Ray] {
        let out = render_depth(&mesh, &k, Some(&pose), kind).unwrap();
        let r = pose.rotation;
        let (mut covered, mut worst) = (0usize, 0.0f64);
        for v in 0..k.height {
            for u in 0..k.width {
                let idx = (v * k.width + u) as usize;
                let d = out.depth.data[idx];
                if d == 0.0 {
                    assert_eq!(out.triangle_id[idx], NO_TRIANGLE);
                    continue;
                }
                covered += 1;
                let dist = kind.to_ray_distance(d as f64, k.ray(u as f64, v as f64));
                let x = k.backproject(u as f64, v as f64, dist);
                let t = mesh.triangles[out.triangle_id[idx] as usize].map(|i| {
                    let p = mesh.vertices[i as usize];
                    std::array::from_fn(|row| {
                        r[row][0] * p[0]
                            + r[row][1] * p[1]
                            + r[row][2] * p[2]
                            + pose.translation[row]
                    })
                });
                // Distance to the visible triangle bounds the distance to the mesh.
                let e = common::point_triangle_distance2(x, t[0], t[1], t[2]).sqrt();
                worst = worst.max(e);
            }
        }
        println!(
            "{kind:?}: {covered} covered pixels, max point-to-mesh distance {:.3e} mm",
            worst * 1e3
        );
        assert!(
            covered > 30_000,
            "the face fills a good part of the image: {covered}"
        );
        assert!(worst <= MAX_DISTANCE_M, "{worst} m");
    }
}
