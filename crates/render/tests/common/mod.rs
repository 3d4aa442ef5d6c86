//! Shared test meshes (included with `mod common;`).
#![allow(dead_code)]

use visage_mesh::TriMesh;

/// Axis-aligned cube `[−h, h]³` centred at `c`, outward-facing (right-handed) triangles.
pub fn cube(c: [f64; 3], h: f64) -> TriMesh {
    let mut v = Vec::new();
    for k in 0..8 {
        let s = |bit: usize| if k >> bit & 1 == 1 { h } else { -h };
        v.push([c[0] + s(0), c[1] + s(1), c[2] + s(2)]);
    }
    // Faces as quads (a, b, c, d) counter-clockwise seen from outside.
    let quads = [
        [0, 2, 3, 1], // z = −h
        [4, 5, 7, 6], // z = +h
        [0, 1, 5, 4], // y = −h
        [2, 6, 7, 3], // y = +h
        [0, 4, 6, 2], // x = −h
        [1, 3, 7, 5], // x = +h
    ];
    let mut t = Vec::new();
    for [a, b, c, d] in quads {
        t.push([a, b, c]);
        t.push([a, c, d]);
    }
    TriMesh::new(v, t)
}

/// A UV sphere of radius `r` centred at `c` with `rings × segments` quads, outward-facing,
/// exact unit normals.
pub fn uv_sphere(c: [f64; 3], r: f64, rings: u32, segments: u32) -> TriMesh {
    let mut v = vec![[c[0], c[1] - r, c[2]]];
    let mut n = vec![[0.0, -1.0, 0.0]];
    for i in 1..rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            let d = [
                theta.sin() * phi.cos(),
                -theta.cos(),
                theta.sin() * phi.sin(),
            ];
            v.push([c[0] + r * d[0], c[1] + r * d[1], c[2] + r * d[2]]);
            n.push(d);
        }
    }
    v.push([c[0], c[1] + r, c[2]]);
    n.push([0.0, 1.0, 0.0]);
    let last = v.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut t = Vec::new();
    for j in 0..segments {
        t.push([0, ring(1, j), ring(1, j + 1)]);
        t.push([last, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c2, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j + 1),
                ring(i + 1, j),
            );
            t.push([a, d, c2]);
            t.push([a, c2, b]);
        }
    }
    let mut m = TriMesh::new(v, t);
    m.normals = n;
    m
}

/// Möller–Trumbore: the ray parameter `t` of ray `o + t·d` hitting triangle `(a, b, c)`.
pub fn ray_triangle(
    o: [f64; 3],
    d: [f64; 3],
    a: [f64; 3],
    b: [f64; 3],
    c: [f64; 3],
) -> Option<f64> {
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let cross = |p: [f64; 3], q: [f64; 3]| {
        [
            p[1] * q[2] - p[2] * q[1],
            p[2] * q[0] - p[0] * q[2],
            p[0] * q[1] - p[1] * q[0],
        ]
    };
    let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    let (e1, e2) = (sub(b, a), sub(c, a));
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = sub(o, a);
    let u = dot(s, p) / det;
    let q = cross(s, e1);
    let v = dot(d, q) / det;
    let eps = 1e-9;
    if u < -eps || v < -eps || u + v > 1.0 + eps {
        return None;
    }
    Some(dot(e2, q) / det)
}

/// Squared distance from `p` to triangle `(a, b, c)` (Ericson, Real-Time Collision Detection
/// §5.1.5).
pub fn point_triangle_distance2(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let add_scaled =
        |x: [f64; 3], y: [f64; 3], s: f64| [x[0] + s * y[0], x[1] + s * y[1], x[2] + s * y[2]];
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let closest = if d1 <= 0.0 && d2 <= 0.0 {
        a
    } else {
        let bp = sub(p, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        let cp = sub(p, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        let vc = d1 * d4 - d3 * d2;
        let vb = d5 * d2 - d1 * d6;
        let va = d3 * d6 - d5 * d4;
        if d3 >= 0.0 && d4 <= d3 {
            b
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            add_scaled(a, ab, d1 / (d1 - d3))
        } else if d6 >= 0.0 && d5 <= d6 {
            c
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            add_scaled(a, ac, d2 / (d2 - d6))
        } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            add_scaled(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)))
        } else {
            let denom = 1.0 / (va + vb + vc);
            let (v, w) = (vb * denom, vc * denom);
            add_scaled(add_scaled(a, ab, v), ac, w)
        }
    };
    let d = sub(p, closest);
    dot(d, d)
}
