//! Acceptance: depth of analytic scenes equals the analytic value within 1e-5 relative at every
//! covered pixel centre; coverage has no holes or double hits.

mod common;

use visage_camera::{DepthKind, Intrinsics, RigidTransform};
use visage_mesh::TriMesh;
use visage_render::{
    render_depth, render_depth_with, Camera, CullMode, Mat3, Mat4, Rasterizer, NO_TRIANGLE,
};

const REL_TOL: f64 = 1e-5;

/// `K⁻¹ (u, v, 1)ᵀ`: the ray through a pixel centre scaled to `z = 1`.
fn ray_z1(k: &Intrinsics, u: f64, v: f64) -> [f64; 3] {
    [(u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[test]
fn steep_plane_depth_is_exact_in_z_and_ray_kinds() {
    let k = Intrinsics::new(160, 120, 150.0, 140.0, 81.3, 58.9).unwrap();
    // A quad rotated 75° about y (seen almost edge-on) and 20° about x, centred 1.2 m away.
    let r = Mat3::rotation([0.0, 1.0, 0.0], 75f64.to_radians())
        .mul(&Mat3::rotation([1.0, 0.0, 0.0], 0.35));
    let (a, b) = (r.mul_vec([1.2, 0.0, 0.0]), r.mul_vec([0.0, 0.8, 0.0]));
    let o = [0.05, -0.03, 1.2];
    let corner = |s: f64, t: f64| {
        [
            o[0] + (s - 0.5) * a[0] + (t - 0.5) * b[0],
            o[1] + (s - 0.5) * a[1] + (t - 0.5) * b[1],
            o[2] + (s - 0.5) * a[2] + (t - 0.5) * b[2],
        ]
    };
    let mesh = TriMesh::new(
        vec![
            corner(0.0, 0.0),
            corner(1.0, 0.0),
            corner(1.0, 1.0),
            corner(0.0, 1.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let n = r.mul_vec([0.0, 0.0, 1.0]);
    let z_render = render_depth(&mesh, &k, None, DepthKind::Z).unwrap();
    let ray_render = render_depth(&mesh, &k, None, DepthKind::Ray).unwrap();
    assert_eq!(ray_render.depth.kind, DepthKind::Ray);
    let (mut covered, mut zmin, mut zmax) = (0, f64::INFINITY, 0.0f64);
    for v in 0..k.height {
        for u in 0..k.width {
            let d = ray_z1(&k, u as f64, v as f64);
            let z = dot(n, o) / dot(n, d);
            // Where does the ray hit the plane in (s, t)? Decide coverage away from the border.
            let p = [z * d[0] - o[0], z * d[1] - o[1], z * d[2] - o[2]];
            let (s, t) = (dot(p, a) / dot(a, a) + 0.5, dot(p, b) / dot(b, b) + 0.5);
            let inside = s > 1e-6 && s < 1.0 - 1e-6 && t > 1e-6 && t < 1.0 - 1e-6;
            let outside = !(-1e-6..=1.0 + 1e-6).contains(&s) || !(-1e-6..=1.0 + 1e-6).contains(&t);
            let idx = (v * k.width + u) as usize;
            let got = z_render.depth.data[idx] as f64;
            if inside {
                assert!(got > 0.0, "pixel ({u}, {v}) must be covered");
            }
            if outside {
                assert_eq!(got, 0.0, "pixel ({u}, {v}) must be background");
                assert_eq!(z_render.triangle_id[idx], NO_TRIANGLE);
            }
            if got > 0.0 {
                covered += 1;
                zmin = zmin.min(z);
                zmax = zmax.max(z);
                assert!(((got - z) / z).abs() <= REL_TOL, "({u}, {v}): {got} vs {z}");
                let dist = z * dot(d, d).sqrt();
                let got_ray = ray_render.depth.data[idx] as f64;
                assert!(
                    ((got_ray - dist) / dist).abs() <= REL_TOL,
                    "({u}, {v}): {got_ray} vs {dist}"
                );
            }
        }
    }
    assert!(
        covered > 2000,
        "the plane covers a good part of the image: {covered}"
    );
    assert!(
        zmax / zmin > 1.5,
        "the plane is steep: z from {zmin} to {zmax}"
    );
}

/// Entry and exit ray parameters of ray `o + t·d` through the box `[−h, h]³`.
fn slab(o: [f64; 3], d: [f64; 3], h: f64) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for i in 0..3 {
        let (a, b) = ((-h - o[i]) / d[i], (h - o[i]) / d[i]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1).then_some((t0, t1))
}

#[test]
fn posed_cube_depth_matches_ray_box_intersection() {
    let k = Intrinsics::new(128, 96, 120.0, 120.0, 63.5, 47.5).unwrap();
    let h = 0.12;
    let cube = common::cube([0.0; 3], h);
    let r = Mat3::rotation([0.4, 1.0, 0.3], 0.9);
    let t = [0.03, -0.02, 0.7];
    let pose = RigidTransform::new(r.0, t).unwrap();
    let out = render_depth(&cube, &k, Some(&pose), DepthKind::Z).unwrap();
    let rt = r.transpose();
    let o_world = rt.mul_vec([-t[0], -t[1], -t[2]]);
    let mut covered = 0;
    for v in 0..k.height {
        for u in 0..k.width {
            let d_world = rt.mul_vec(ray_z1(&k, u as f64, v as f64));
            let idx = (v * k.width + u) as usize;
            let got = out.depth.data[idx] as f64;
            // Camera z equals the ray parameter because the ray direction has z = 1.
            match (
                slab(o_world, d_world, h * (1.0 - 1e-6)),
                slab(o_world, d_world, h * (1.0 + 1e-6)),
            ) {
                (Some((z, _)), _) => {
                    covered += 1;
                    assert!(((got - z) / z).abs() <= REL_TOL, "({u}, {v}): {got} vs {z}");
                }
                (None, None) => assert_eq!(got, 0.0, "({u}, {v}) misses the cube"),
                (None, Some(_)) => {} // within 1e-6 of the silhouette: either answer is right
            }
        }
    }
    assert!(covered > 1500, "{covered}");
}

#[test]
fn sphere_depth_is_the_nearest_ray_triangle_hit() {
    let k = Intrinsics::new(80, 60, 90.0, 90.0, 39.5, 29.5).unwrap();
    let mesh = common::uv_sphere([0.02, 0.01, 0.5], 0.15, 16, 32);
    let out = render_depth(&mesh, &k, None, DepthKind::Ray).unwrap();
    let mut covered = 0;
    for v in 0..k.height {
        for u in 0..k.width {
            let d = k.ray(u as f64, v as f64);
            let nearest = mesh
                .triangles
                .iter()
                .filter_map(|t| {
                    let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
                    common::ray_triangle([0.0; 3], d, a, b, c)
                })
                .filter(|&t| t > 0.0)
                .fold(f64::INFINITY, f64::min);
            let idx = (v * k.width + u) as usize;
            let got = out.depth.data[idx] as f64;
            if nearest.is_finite() {
                // Rays grazing a silhouette edge within the 1e-9 slack may go either way.
                if got == 0.0 {
                    continue;
                }
                covered += 1;
                assert!(
                    ((got - nearest) / nearest).abs() <= REL_TOL,
                    "({u}, {v}): {got} vs {nearest}"
                );
                // The reported triangle is hit by the ray at that same distance.
                let t = mesh.triangles[out.triangle_id[idx] as usize]
                    .map(|i| mesh.vertices[i as usize]);
                let own = common::ray_triangle([0.0; 3], d, t[0], t[1], t[2]).unwrap();
                assert!(((own - nearest) / nearest).abs() <= REL_TOL);
                // And the point lies between the true sphere and the inscribed polyhedron: every
                // triangle spans less than π/16 of arc from its circumcentre.
                let c = [0.02, 0.01, 0.5];
                let p = [got * d[0] - c[0], got * d[1] - c[1], got * d[2] - c[2]];
                let radius = dot(p, p).sqrt();
                assert!(radius <= 0.15 * (1.0 + REL_TOL), "{radius}");
                assert!(
                    radius >= 0.15 * (std::f64::consts::PI / 16.0).cos(),
                    "{radius}"
                );
            } else {
                assert_eq!(got, 0.0, "({u}, {v}) misses the sphere");
            }
        }
    }
    assert!(covered > 1000, "{covered}");
}

/// Number of fragments per pixel, without depth test.
fn coverage_counts(mesh: &TriMesh, camera: &Camera, cull: CullMode) -> Vec<u32> {
    let mut r = Rasterizer::new();
    r.rasterize(
        &mesh.vertices,
        &mesh.triangles,
        &Mat4::IDENTITY,
        camera,
        cull,
    )
    .unwrap();
    let w = camera.intrinsics.width;
    let mut count = vec![0u32; (w * camera.intrinsics.height) as usize];
    for st in r.screen_triangles() {
        st.for_each_pixel(|x, y| count[(y * w + x) as usize] += 1);
    }
    count
}

#[test]
fn closed_meshes_are_covered_exactly_twice_without_culling_and_once_with() {
    let k = Intrinsics::new(96, 72, 100.0, 100.0, 47.5, 35.5).unwrap();
    let cam = Camera::new(k).unwrap();
    let meshes = [
        common::uv_sphere([0.0, 0.0, 0.6], 0.2, 12, 24),
        common::uv_sphere([0.05, -0.02, 0.45], 0.1, 7, 9),
        {
            let mut c = common::cube([0.0; 3], 0.1);
            let r = Mat3::rotation([1.0, 2.0, 0.5], 0.6);
            c.vertices.iter_mut().for_each(|p| {
                let q = r.mul_vec(*p);
                *p = [q[0], q[1], q[2] + 0.5];
            });
            c
        },
    ];
    for mesh in &meshes {
        let all = coverage_counts(mesh, &cam, CullMode::None);
        let front = coverage_counts(mesh, &cam, CullMode::Back);
        let back = coverage_counts(mesh, &cam, CullMode::Front);
        let mut inside = 0;
        for i in 0..all.len() {
            assert!(
                all[i] == 0 || all[i] == 2,
                "pixel {i} covered {} times",
                all[i]
            );
            assert_eq!(
                front[i] * 2,
                all[i],
                "pixel {i}: front faces cover it exactly once"
            );
            assert_eq!(
                back[i] * 2,
                all[i],
                "pixel {i}: back faces cover it exactly once"
            );
            inside += (all[i] == 2) as usize;
        }
        assert!(inside > 300, "{inside}");
        // Depth test then keeps the front surface: visible triangles are front-facing.
        let out = render_depth_with(
            &mut Rasterizer::new(),
            mesh,
            &cam,
            &Mat4::IDENTITY,
            DepthKind::Z,
            CullMode::None,
        )
        .unwrap();
        assert_eq!(out.depth.valid_count(), inside);
    }
}

#[test]
fn vertices_and_edges_on_pixel_centres_follow_the_top_left_rule() {
    // fx = W, principal point at the centre: a vertex at pixel (i, j) on the plane z = 1 has
    // exactly representable coordinates and projects exactly onto that pixel centre.
    let k = Intrinsics::new(64, 64, 64.0, 64.0, 31.5, 31.5).unwrap();
    let cam = Camera::new(k).unwrap();
    let us = [3.0, 10.0, 17.0, 18.0, 30.0, 37.0, 44.0, 60.0];
    let vs = [2.0, 9.0, 16.0, 29.0, 30.0, 43.0, 50.0, 61.0];
    let mut verts = Vec::new();
    for &v in &vs {
        for &u in &us {
            verts.push([(u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0]);
        }
    }
    let n = us.len() as u32;
    let mut tris = Vec::new();
    let mut flip = 0x9e37_79b9u32;
    for j in 0..vs.len() as u32 - 1 {
        for i in 0..n - 1 {
            let (a, b, c, d) = (
                j * n + i,
                j * n + i + 1,
                (j + 1) * n + i + 1,
                (j + 1) * n + i,
            );
            flip = flip.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let pair = if flip >> 16 & 1 == 0 {
                [[a, b, c], [a, c, d]]
            } else {
                [[a, b, d], [b, c, d]]
            };
            for (m, t) in pair.into_iter().enumerate() {
                // Mix windings: coverage must not depend on orientation.
                tris.push(if (flip >> (20 + m)) & 1 == 0 {
                    t
                } else {
                    [t[0], t[2], t[1]]
                });
            }
        }
    }
    let mesh = TriMesh::new(verts, tris);
    let count = coverage_counts(&mesh, &cam, CullMode::None);
    for y in 0..64u32 {
        for x in 0..64u32 {
            let expected = (x as f64 >= us[0]
                && (x as f64) < us[7]
                && y as f64 >= vs[0]
                && (y as f64) < vs[7]) as u32;
            assert_eq!(count[(y * 64 + x) as usize], expected, "pixel ({x}, {y})");
        }
    }
}

#[test]
fn geometry_behind_the_near_plane_is_clipped_not_wrapped() {
    // A floor-like quad from z = −1 (behind the camera) to z = 3: only z ≥ near may show.
    let k = Intrinsics::new(64, 48, 50.0, 50.0, 31.5, 23.5).unwrap();
    let mesh = TriMesh::new(
        vec![
            [-1.0, 0.3, -1.0],
            [1.0, 0.3, -1.0],
            [1.0, 0.3, 3.0],
            [-1.0, 0.3, 3.0],
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    );
    let out = render_depth(&mesh, &k, None, DepthKind::Z).unwrap();
    let mut covered = 0;
    for v in 0..k.height {
        for u in 0..k.width {
            let d = ray_z1(&k, u as f64, v as f64);
            let got = out.depth.data[(v * k.width + u) as usize] as f64;
            if d[1] > 0.0
                && 0.3 / d[1] <= 3.0 * (1.0 - 1e-9)
                && (0.3 / d[1] * d[0]).abs() < 1.0 - 1e-9
            {
                let z = 0.3 / d[1];
                assert!(((got - z) / z).abs() <= REL_TOL, "({u}, {v}): {got} vs {z}");
                covered += 1;
            } else if d[1] <= 0.0 || 0.3 / d[1] > 3.0 * (1.0 + 1e-9) {
                assert_eq!(
                    got, 0.0,
                    "({u}, {v}): above the horizon or beyond the far edge"
                );
            }
        }
    }
    assert!(covered > 500, "{covered}");
}
