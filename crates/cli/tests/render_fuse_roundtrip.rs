//! `visage render --depth-out` composes with `visage fuse --depth`: a rendered sphere is fused
//! back onto the sphere, in both depth conventions.

mod common;

use common::{run_ok, s};

use visage_camera::Intrinsics;
use visage_mesh::io::{read_ply, write_obj};
use visage_mesh::TriMesh;

const CENTRE: [f64; 3] = [0.0, 0.0, 0.5];
const RADIUS: f64 = 0.1;

/// A UV sphere of `RADIUS` around `CENTRE`, fine enough that facets deviate < 0.1 mm.
fn sphere() -> TriMesh {
    let (rings, segments) = (96u32, 192u32);
    let mut vertices = Vec::new();
    for r in 0..=rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..segments {
            let phi = 2.0 * std::f64::consts::PI * s as f64 / segments as f64;
            vertices.push([
                CENTRE[0] + RADIUS * theta.sin() * phi.cos(),
                CENTRE[1] + RADIUS * theta.cos(),
                CENTRE[2] + RADIUS * theta.sin() * phi.sin(),
            ]);
        }
    }
    let mut triangles = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * segments + s, r * segments + (s + 1) % segments);
            let (c, d) = (a + segments, b + segments);
            triangles.push([a, b, c]);
            triangles.push([b, d, c]);
        }
    }
    TriMesh::new(vertices, triangles)
}

#[test]
fn rendered_depth_fuses_back_onto_the_sphere() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("sphere.obj");
    write_obj(&mesh, &sphere()).unwrap();
    let cam = tmp.path().join("cam.json");
    Intrinsics::new(120, 100, 150.0, 150.0, 59.5, 49.5)
        .unwrap()
        .save_json(&cam)
        .unwrap();
    for kind in ["z", "ray"] {
        let depth = tmp.path().join(format!("depth_{kind}"));
        std::fs::create_dir_all(&depth).unwrap();
        for f in 0..3 {
            let png = depth.join(format!("{f:03}.png"));
            run_ok(&[
                "render",
                s(&mesh),
                "--intrinsics",
                s(&cam),
                "--depth-out",
                s(&png),
                "--depth-kind",
                kind,
            ]);
        }
        let out = tmp.path().join(format!("fused_{kind}"));
        run_ok(&[
            "fuse",
            "--depth",
            s(&depth),
            "--intrinsics",
            s(&cam),
            "--out",
            s(&out),
            "--depth-kind",
            kind,
            "--lambda",
            "0.1",
            "--quiet",
        ]);
        let fused = read_ply(&out.join("meshes/000002.ply")).unwrap();
        let boundary = visage_mesh::edge_triangles(&fused.triangles)
            .into_iter()
            .filter(|(_, t)| t.len() == 1)
            .flat_map(|((a, b), _)| [a, b])
            .collect::<std::collections::HashSet<u32>>();
        let mut errors: Vec<f64> = fused
            .vertices
            .iter()
            .enumerate()
            .filter(|(i, _)| !boundary.contains(&(*i as u32)))
            .map(|(_, p)| {
                let d = [p[0] - CENTRE[0], p[1] - CENTRE[1], p[2] - CENTRE[2]];
                ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() - RADIUS).abs()
            })
            .collect();
        assert!(errors.len() > 100, "{kind}: too few interior vertices");
        errors.sort_by(f64::total_cmp);
        let median = errors[errors.len() / 2];
        // Millimetre quantisation of the PNG limits the accuracy to ~0.3 mm per pixel.
        assert!(
            median < 0.5e-3,
            "{kind}: median distance to the sphere {median} m"
        );
    }
}
