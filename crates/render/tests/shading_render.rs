//! Acceptance: perspective-correct texturing (steep checkerboard against the analytic image),
//! the normal matrix under non-uniform scaling, and bounded shading energy, through the full
//! renderer (Algorithm 3).

use visage_camera::{DepthKind, Intrinsics};
use visage_mesh::TriMesh;
use visage_render::{
    Albedo, Camera, Frame, Light, Mat3, Mat4, Material, Renderer, Scene, Texture, Wrap,
    NO_TRIANGLE, UNLIT,
};

const CHECKS: usize = 8;
const TEXELS_PER_CHECK: usize = 16;

fn checkerboard() -> Texture {
    let n = CHECKS * TEXELS_PER_CHECK;
    let texels = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n / TEXELS_PER_CHECK, k / n / TEXELS_PER_CHECK);
            let c = ((i + j) % 2) as f32;
            [c, c, c, 1.0]
        })
        .collect();
    Texture::new(n as u32, n as u32, texels).unwrap()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[test]
fn steep_checkerboard_matches_the_analytic_image() {
    let k = Intrinsics::new(200, 150, 180.0, 180.0, 99.5, 74.5).unwrap();
    let r = Mat3::rotation([0.0, 1.0, 0.0], 70f64.to_radians());
    let (a, b) = (r.mul_vec([1.0, 0.0, 0.0]), r.mul_vec([0.0, 0.8, 0.0]));
    let o = [0.0, 0.0, 1.0];
    let corner = |s: f64, t: f64| -> [f64; 3] {
        std::array::from_fn(|i| o[i] + (s - 0.5) * a[i] + (t - 0.5) * b[i])
    };
    let mut mesh = TriMesh::new(
        vec![
            corner(0.0, 0.0),
            corner(1.0, 0.0),
            corner(1.0, 1.0),
            corner(0.0, 1.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    mesh.uvs = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let texture = checkerboard();
    let scene = Scene {
        material: UNLIT,
        albedo: Albedo::Texture {
            texture: &texture,
            wrap: Wrap::Clamp,
        },
        background: [0.5; 3],
        ..Scene::default()
    };
    let camera = Camera::new(k).unwrap();
    let mut frame = Frame::new(k.width, k.height, DepthKind::Z);
    Renderer::new()
        .render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut frame)
        .unwrap();

    let n = dot(a, a).sqrt();
    let normal = r.mul_vec([0.0, 0.0, 1.0]);
    let check = |u: f64, v: f64| {
        ((u * CHECKS as f64).floor() as i64 + ((1.0 - v) * CHECKS as f64).floor() as i64) % 2
    };
    let margin = 1.5 / (CHECKS * TEXELS_PER_CHECK) as f64;
    let near_boundary = |x: f64| {
        let f = x * CHECKS as f64;
        (f - f.round()).abs() < margin * CHECKS as f64
    };
    let project = |p: [f64; 3]| [k.fx * p[0] / p[2] + k.cx, k.fy * p[1] / p[2] + k.cy];
    let (mut tested, mut affine_wrong) = (0, 0);
    for v in 0..k.height {
        for u in 0..k.width {
            let d = [(u as f64 - k.cx) / k.fx, (v as f64 - k.cy) / k.fy, 1.0];
            let z = dot(normal, o) / dot(normal, d);
            let p = [z * d[0] - o[0], z * d[1] - o[1], z * d[2] - o[2]];
            let (s, t) = (dot(p, a) / (n * n) + 0.5, dot(p, b) / dot(b, b) + 0.5);
            let idx = (v * k.width + u) as usize;
            if !(margin..=1.0 - margin).contains(&s) || !(margin..=1.0 - margin).contains(&t) {
                continue;
            }
            if near_boundary(s) || near_boundary(t) {
                continue;
            }
            tested += 1;
            let expected = check(s, t) as f32;
            let got = frame.color[idx][0];
            assert!(
                (got - expected).abs() < 1e-4,
                "({u}, {v}): {got} vs {expected} at uv ({s}, {t})"
            );
            // What affine (screen-space) interpolation would have shown at this pixel.
            let tri = frame.triangle_id[idx];
            assert_ne!(tri, NO_TRIANGLE);
            let c = mesh.triangles[tri as usize].map(|i| project(mesh.vertices[i as usize]));
            let area = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
                (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
            };
            let x = [u as f64, v as f64];
            let total = area(c[0], c[1], c[2]);
            let l = [
                area(x, c[1], c[2]) / total,
                area(c[0], x, c[2]) / total,
                area(c[0], c[1], x) / total,
            ];
            let uv = mesh.triangles[tri as usize].map(|i| mesh.uvs[i as usize]);
            let ua = l[0] * uv[0][0] + l[1] * uv[1][0] + l[2] * uv[2][0];
            let va = l[0] * uv[0][1] + l[1] * uv[1][1] + l[2] * uv[2][1];
            affine_wrong += (check(ua, va) as f32 != expected) as usize;
        }
    }
    assert!(tested > 3000, "{tested}");
    // The scene is steep enough that affine interpolation would fail visibly.
    assert!(
        affine_wrong * 10 > tested,
        "affine would be wrong at {affine_wrong} of {tested}"
    );
    assert_eq!(frame.color[0], [0.5; 3], "background");
}

#[test]
fn normals_follow_the_inverse_transpose_under_non_uniform_scaling() {
    let k = Intrinsics::new(64, 48, 60.0, 60.0, 31.5, 23.5).unwrap();
    // A sloped plane in object space with its exact normal.
    let (e1, e2) = ([1.0, 0.0, 1.0], [0.0, 1.0, 0.5]);
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let unit = |a: [f64; 3]| a.map(|x| x / dot(a, a).sqrt());
    let n = unit(cross(e2, e1)); // facing the camera (−z)
    let pt = |s: f64, t: f64| -> [f64; 3] { std::array::from_fn(|i| s * e1[i] + t * e2[i]) };
    let mut mesh = TriMesh::new(
        vec![pt(-1.0, -1.0), pt(1.0, -1.0), pt(1.0, 1.0), pt(-1.0, 1.0)],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    mesh.normals = vec![n; 4];
    // Non-uniform scale, a rotation, then 1.2 m in front of the camera.
    let lin = Mat3::rotation([0.2, 1.0, 0.1], 0.4).mul(&Mat3::diagonal([0.3, 0.25, 0.05]));
    let model = Mat4::from_linear_translation(lin, [0.0, 0.0, 1.2]);
    let truth = unit(cross(lin.mul_vec(e1), lin.mul_vec(e2)));
    let truth = if dot(truth, lin.mul_vec(n)) < 0.0 {
        truth.map(|x| -x)
    } else {
        truth
    };
    let light = Light::white([0.3, -0.4, -1.0]);
    let l = light.direction.map(|x| x as f64);
    let scene = Scene {
        material: Material {
            ka: 0.0,
            kd: 1.0,
            ks: 0.0,
            shininess: 1.0,
        },
        light,
        albedo: Albedo::Constant([1.0; 3]),
        two_sided: false,
        ..Scene::default()
    };
    let mut frame = Frame::new(k.width, k.height, DepthKind::Z);
    Renderer::new()
        .render(&mesh, &Camera::new(k).unwrap(), &model, &scene, &mut frame)
        .unwrap();
    let expected = dot(truth, l).max(0.0) as f32;
    let naive = dot(unit(lin.mul_vec(n)), l).max(0.0) as f32;
    assert!(
        (expected - naive).abs() > 0.05,
        "the scene separates N·n from M·n: {expected} vs {naive}"
    );
    let covered: Vec<_> = frame
        .triangle_id
        .iter()
        .zip(&frame.color)
        .filter(|(t, _)| **t != NO_TRIANGLE)
        .collect();
    assert!(covered.len() > 200, "{}", covered.len());
    for (_, c) in covered {
        assert!((c[0] - expected).abs() < 1e-5, "{} vs {expected}", c[0]);
    }
}

#[test]
fn shaded_frames_stay_within_unit_radiance_and_bad_scenes_are_rejected() {
    let k = Intrinsics::new(48, 36, 40.0, 40.0, 23.5, 17.5).unwrap();
    let mut mesh = TriMesh::new(
        vec![
            [-0.5, -0.5, 1.0],
            [0.5, -0.4, 1.2],
            [0.4, 0.5, 0.9],
            [-0.5, 0.5, 1.1],
            [0.0, 0.0, 0.7],
        ],
        vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
    );
    mesh.colors = vec![
        [1.0, 1.0, 1.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
    ];
    let camera = Camera::new(k).unwrap();
    let mut frame = Frame::new(k.width, k.height, DepthKind::Ray);
    let mut renderer = Renderer::new();
    for (ka, kd, ks, shininess) in [
        (0.2, 0.8, 0.0, 1.0),
        (0.1, 0.5, 0.4, 2.0),
        (0.0, 0.0, 1.0, 1.0),
        (0.3, 0.3, 0.4, 64.0),
    ] {
        for dir in [[0.0, 0.0, -1.0], [0.5, -0.5, -0.2], [0.0, 0.0, 1.0]] {
            let scene = Scene {
                material: Material {
                    ka,
                    kd,
                    ks,
                    shininess,
                },
                light: Light::white(dir),
                albedo: Albedo::VertexColors,
                ..Scene::default()
            };
            renderer
                .render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut frame)
                .unwrap();
            let max = frame.color.iter().flatten().fold(0.0f32, |m, &c| m.max(c));
            assert!(max <= 1.0 + 1e-5, "{max}");
        }
    }
    // Energy-violating material, missing UVs, wrong frame size, empty mesh: errors, not panics.
    let bad = Scene {
        material: Material {
            ka: 0.5,
            kd: 0.6,
            ks: 0.0,
            shininess: 1.0,
        },
        ..Scene::default()
    };
    assert!(renderer
        .render(&mesh, &camera, &Mat4::IDENTITY, &bad, &mut frame)
        .is_err());
    let tex = Texture::new(1, 1, vec![[1.0; 4]]).unwrap();
    let textured = Scene {
        albedo: Albedo::Texture {
            texture: &tex,
            wrap: Wrap::Repeat,
        },
        ..Scene::default()
    };
    let err = renderer
        .render(&mesh, &camera, &Mat4::IDENTITY, &textured, &mut frame)
        .unwrap_err()
        .to_string();
    assert!(err.contains("texture coordinates"), "{err}");
    let mut small = Frame::new(4, 4, DepthKind::Z);
    assert!(renderer
        .render(
            &mesh,
            &camera,
            &Mat4::IDENTITY,
            &Scene::default(),
            &mut small
        )
        .is_err());
    let empty = TriMesh::default();
    let err = renderer
        .render(
            &empty,
            &camera,
            &Mat4::IDENTITY,
            &Scene::default(),
            &mut frame,
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains("empty"), "{err}");
    let singular = Mat4::scaling([1.0, 0.0, 1.0]);
    assert!(renderer
        .render(&mesh, &camera, &singular, &Scene::default(), &mut frame)
        .is_err());
}

#[test]
fn frame_depth_and_ids_match_the_depth_renderer_in_both_kinds() {
    let k = Intrinsics::new(64, 48, 55.0, 57.0, 30.2, 25.1).unwrap();
    let mesh = TriMesh::new(
        vec![
            [-0.4, -0.3, 0.9],
            [0.5, -0.35, 1.3],
            [0.45, 0.4, 0.7],
            [-0.5, 0.3, 1.1],
            [0.0, 0.05, 0.6],
        ],
        vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
    );
    let camera = Camera::new(k).unwrap();
    for kind in [DepthKind::Z, DepthKind::Ray] {
        let mut frame = Frame::new(k.width, k.height, kind);
        Renderer::new()
            .render(
                &mesh,
                &camera,
                &Mat4::IDENTITY,
                &Scene::default(),
                &mut frame,
            )
            .unwrap();
        let reference = visage_render::render_depth(&mesh, &k, None, kind).unwrap();
        assert_eq!(frame.triangle_id, reference.triangle_id);
        assert!(reference.depth.valid_count() > 1000);
        for (a, b) in frame.depth.data.iter().zip(&reference.depth.data) {
            assert!((a - b).abs() <= 1e-6 * b.abs(), "{kind:?}: {a} vs {b}");
        }
    }
}
