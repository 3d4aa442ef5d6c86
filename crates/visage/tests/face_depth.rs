//! Metric geometry and dense depth on the astronaut portrait (60° horizontal field of view).

use visage::{render_faces_depth, DepthKind, Intrinsics};
use visage_face::{fit_face_geometry, CanonicalMesh, FaceMesh};
use visage_testdata::require;

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn astronaut_depth_is_metric_and_matches_the_fitted_mesh() {
    let data = require(visage_testdata::shared_dir().join("data"));
    let models = visage_testdata::models_dir();
    for file in visage_testdata::MODEL_FILES {
        require(models.join(file));
    }
    let img = image::open(data.join("images/astronaut.png"))
        .unwrap()
        .to_rgb8();
    let mut mesh = FaceMesh::load(&models).unwrap();
    let canonical = CanonicalMesh::load(&models).unwrap();
    assert_eq!(canonical.triangles.len(), 898);
    assert_eq!(canonical.vertices.len(), 468);
    let faces = mesh.process(&img).unwrap();
    let k = Intrinsics::from_fov(img.width(), img.height(), 60.0).unwrap();
    let g = fit_face_geometry(&canonical, &faces[0].landmarks.points, &k).unwrap();
    println!(
        "pose t = {:?} m, rms {:.2} px",
        g.pose.translation, g.rms_px
    );
    assert!(g.rms_px < 6.0, "rigid fit reprojection rms {} px", g.rms_px);
    let depth = render_faces_depth(std::slice::from_ref(&g), &canonical, &k, DepthKind::Z).unwrap();
    let mut valid: Vec<f32> = depth.data.iter().copied().filter(|&d| d > 0.0).collect();
    valid.sort_by(f32::total_cmp);
    let median = valid[valid.len() / 2];
    println!(
        "face pixels {}, median depth {median:.3} m, range {:.3}..{:.3} m",
        valid.len(),
        valid[0],
        valid[valid.len() - 1]
    );
    // A face ≈ 94 px wide in a 512 px, 60° image: about 0.7–1.2 m away.
    assert!((0.4..2.0).contains(&median), "median depth {median} m");
    assert!(
        valid[valid.len() - 1] - valid[0] < 0.25,
        "a face is shallower than 25 cm"
    );
    // Identical in shape to the fitted mesh: at each vertex's projection, the rendered depth is
    // the vertex's z (front-facing vertices; tolerance for the pixel-centre sampling).
    let mut checked = 0;
    for v in &g.metric_landmarks {
        let p = k.project(*v);
        let (u, w) = (p[0].round(), p[1].round());
        let d = depth.at(u as u32, w as u32) as f64;
        if d > 0.0 && (d - v[2]).abs() < 0.01 {
            checked += 1;
        }
    }
    assert!(
        checked > 400,
        "only {checked} of 468 vertices agree with the rendered depth within 1 cm"
    );
    // The mask is the projected face: its area is close to the landmarks' hull (bbox bound).
    let b = faces[0].bbox;
    assert!((valid.len() as f32) < 1.5 * b[2] * b[3] * 1.6 && valid.len() > 2000);
}
