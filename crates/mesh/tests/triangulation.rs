//! Properties of the sample triangulation over a small corpus of domains.

use visage_camera::{DepthKind, DepthMap, Intrinsics};
use visage_mesh::{
    edge_key, edge_triangles, flip_depth_aware, orient2d, sample_domain, Mask, PlanarMesh,
    SamplingOptions,
};

/// Determinant of the in-circle test: > 0 when `d` lies strictly inside the circumcircle of
/// the counter-clockwise (y-up) triangle `(a, b, c)`.
fn incircle(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let row = |p: [f64; 2]| {
        let (x, y) = (p[0] - d[0], p[1] - d[1]);
        [x, y, x * x + y * y]
    };
    let (a, b, c) = (row(a), row(b), row(c));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

fn corpus() -> Vec<(&'static str, Mask, u32)> {
    let shape = |w: u32, h: u32, f: &dyn Fn(f64, f64) -> bool| {
        let mut m = Mask::filled(w, h, false);
        for v in 0..h {
            for u in 0..w {
                m.data[(v * w + u) as usize] = f(u as f64, v as f64);
            }
        }
        m
    };
    vec![
        ("rectangle", Mask::filled(37, 23, true), 4),
        ("rectangle-spacing-1", Mask::filled(9, 7, true), 1),
        (
            "disc",
            shape(80, 70, &|u, v| {
                (u - 40.0).powi(2) + (v - 35.0).powi(2) < 900.0
            }),
            4,
        ),
        (
            "annulus",
            shape(90, 90, &|u, v| {
                let r2 = (u - 45.0).powi(2) + (v - 45.0).powi(2);
                r2 < 40.0 * 40.0 && r2 > 12.0 * 12.0
            }),
            3,
        ),
        (
            "two-blobs",
            shape(100, 60, &|u, v| {
                (u - 25.0).powi(2) + (v - 30.0).powi(2) < 400.0
                    || (u - 75.0).abs() + (v - 30.0).abs() < 20.0
            }),
            5,
        ),
    ]
}

/// A bumpy depth map over the mask so refinement adds centre samples.
fn bumpy_depth(mask: &Mask) -> DepthMap {
    let mut d = DepthMap::empty(mask.width, mask.height, DepthKind::Z);
    for v in 0..mask.height {
        for u in 0..mask.width {
            let i = (v * mask.width + u) as usize;
            if mask.data[i] {
                d.data[i] =
                    (0.6 + 0.02 * ((u as f64) * 0.4).sin() * ((v as f64) * 0.3).cos()) as f32;
            }
        }
    }
    d
}

fn check_valid(name: &str, mesh: &PlanarMesh, area: f64) {
    // Orientation: every triangle has negative signed area (normals face the camera).
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| mesh.points[i as usize]);
        assert!(
            orient2d(a, b, c) < 0.0,
            "{name}: triangle {t} {tri:?} has the wrong orientation"
        );
    }
    // Coverage: the triangles tile exactly the domain.
    assert!(
        (mesh.area() - area).abs() < 1e-9 * area,
        "{name}: area {} vs {}",
        mesh.area(),
        area
    );
    // Manifold edges; every constraint edge is a boundary edge of exactly one triangle.
    let edges = edge_triangles(&mesh.triangles);
    assert!(
        edges.values().all(|t| t.len() <= 2),
        "{name}: an edge has more than two triangles"
    );
    for e in &mesh.constraint_edges {
        let tris = edges.get(&edge_key(e[0], e[1]));
        assert_eq!(
            tris.map(Vec::len),
            Some(1),
            "{name}: constraint edge {e:?} missing or interior"
        );
    }
    // No triangle has vertices that are never used (every sample is in the mesh).
    let mut used = vec![false; mesh.points.len()];
    mesh.triangles
        .iter()
        .flatten()
        .for_each(|&i| used[i as usize] = true);
    assert!(used.iter().all(|&u| u), "{name}: unused sample point");
}

#[test]
fn planar_triangulation_is_constrained_delaunay() {
    let k = Intrinsics::from_fov(100, 100, 60.0).unwrap();
    for (name, mask, spacing) in corpus() {
        let depth = bumpy_depth(&mask);
        let kk = Intrinsics {
            width: mask.width,
            height: mask.height,
            ..k
        };
        let opts = SamplingOptions {
            spacing,
            refine_tolerance: Some(1e-4),
            ..Default::default()
        };
        let samples = sample_domain(&mask, Some((&depth, &kk)), &opts).unwrap();
        let mesh = PlanarMesh::triangulate(&samples).unwrap();
        check_valid(name, &mesh, samples.grid.area());
        let constrained: std::collections::HashSet<_> = mesh
            .constraint_edges
            .iter()
            .map(|e| edge_key(e[0], e[1]))
            .collect();
        let mut checked = 0;
        for (edge, tris) in edge_triangles(&mesh.triangles) {
            if tris.len() != 2 || constrained.contains(&edge) {
                continue;
            }
            let t = mesh.triangles[tris[0]];
            let d = mesh.triangles[tris[1]]
                .into_iter()
                .find(|&v| v != edge.0 && v != edge.1)
                .unwrap();
            // (a, b, c) is clockwise in the y-up sense; reverse it for the in-circle test.
            let p = |i: u32| mesh.points[i as usize];
            let det = incircle(p(t[0]), p(t[2]), p(t[1]), p(d));
            let scale = (spacing as f64).powi(4);
            assert!(
                det <= 1e-9 * scale,
                "{name}: edge {edge:?} is not locally Delaunay (det {det})"
            );
            checked += 1;
        }
        assert!(checked > 0, "{name}: no interior edge checked");
    }
}

#[test]
fn depth_aware_flips_keep_the_planar_triangulation_valid() {
    // A steep surface: depth jumps from 0.5 m to 1.0 m across a slanted ramp.
    let (w, h) = (64u32, 48u32);
    let k = Intrinsics::from_fov(w, h, 60.0).unwrap();
    let mut depth = DepthMap::empty(w, h, DepthKind::Z);
    for v in 0..h {
        for u in 0..w {
            let t = ((u as f64 + 0.5 * v as f64 - 40.0) / 6.0).clamp(0.0, 1.0);
            depth.data[(v * w + u) as usize] = (0.5 + 0.5 * t) as f32;
        }
    }
    assert!(depth.flatness_ratio().unwrap() > 0.15);
    let mask = Mask::from_valid_depth(&depth);
    let samples = sample_domain(
        &mask,
        None,
        &SamplingOptions {
            spacing: 4,
            ..Default::default()
        },
    )
    .unwrap();
    let mut mesh = PlanarMesh::triangulate(&samples).unwrap();
    let before = mesh.triangles.clone();
    let positions: Vec<[f64; 3]> = mesh
        .points
        .iter()
        .map(|p| {
            let z = depth.sample_ray_distance(&k, p[0], p[1]).unwrap();
            k.backproject(p[0], p[1], z)
        })
        .collect();
    let flips = flip_depth_aware(&mut mesh, &positions).unwrap();
    assert!(flips > 0, "a steep ramp must trigger flips");
    assert_ne!(before, mesh.triangles);
    check_valid("ramp after flips", &mesh, samples.grid.area());
    // No remaining edge both violates the 3-D criterion and is flippable in the image.
    for (edge, tris) in edge_triangles(&mesh.triangles) {
        if tris.len() != 2 {
            continue;
        }
        let c = mesh.triangles[tris[0]]
            .into_iter()
            .find(|&v| v != edge.0 && v != edge.1)
            .unwrap();
        let d = mesh.triangles[tris[1]]
            .into_iter()
            .find(|&v| v != edge.0 && v != edge.1)
            .unwrap();
        let angle = |o: u32| {
            let x = |i: u32| positions[i as usize];
            let (u, v) = (
                [
                    x(edge.0)[0] - x(o)[0],
                    x(edge.0)[1] - x(o)[1],
                    x(edge.0)[2] - x(o)[2],
                ],
                [
                    x(edge.1)[0] - x(o)[0],
                    x(edge.1)[1] - x(o)[1],
                    x(edge.1)[2] - x(o)[2],
                ],
            );
            let dot = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
            let cr = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            (cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2])
                .sqrt()
                .atan2(dot)
        };
        if angle(c) + angle(d) > std::f64::consts::PI * (1.0 + 1e-6) {
            let p = |i: u32| mesh.points[i as usize];
            let (oa, ob) = (
                orient2d(p(c), p(d), p(edge.0)),
                orient2d(p(c), p(d), p(edge.1)),
            );
            assert!(
                oa * ob >= -1e-9,
                "edge {edge:?} violates the 3-D criterion yet is flippable"
            );
        }
    }
}

#[test]
fn flips_reject_positions_of_the_wrong_length() {
    let samples =
        sample_domain(&Mask::filled(9, 9, true), None, &SamplingOptions::default()).unwrap();
    let mut mesh = PlanarMesh::triangulate(&samples).unwrap();
    assert!(flip_depth_aware(&mut mesh, &[[0.0; 3]; 2]).is_err());
}
