//! The benchmark scene shared by `benches/render_frame.rs` and `examples/profile_frame.rs`:
//! a bumpy, face-like height field (124 × 123 vertices, 30 012 triangles) seen from 0.5 m, and a
//! 1024² checker texture.

use visage_mesh::TriMesh;
use visage_render::Texture;

/// The 30k-triangle face-like mesh, metres, camera coordinates.
pub fn face_like_mesh() -> TriMesh {
    let (nu, nv) = (124u32, 123u32);
    let (w, h) = (0.5, 0.28);
    let mut m = TriMesh::default();
    for j in 0..nv {
        for i in 0..nu {
            let (s, t) = (i as f64 / (nu - 1) as f64, j as f64 / (nv - 1) as f64);
            let (x, y) = ((s - 0.5) * w, (t - 0.5) * h);
            // A dome with ripples: depth varies by a few centimetres like a face.
            let z = 0.5 + 4.0 * (x * x + y * y) - 0.01 * (40.0 * x).sin() * (30.0 * y).cos();
            m.vertices.push([x, y, z]);
            m.uvs.push([s, 1.0 - t]);
        }
    }
    for j in 0..nv - 1 {
        for i in 0..nu - 1 {
            let a = j * nu + i;
            let (b, c, d) = (a + 1, a + nu + 1, a + nu);
            m.triangles.push([a, c, b]);
            m.triangles.push([a, d, c]);
        }
    }
    m
}

/// A 1024² checker texture, linear RGBA.
pub fn texture() -> Texture {
    let n = 1024u32;
    let texels = (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            let c = if (i / 64 + j / 64) % 2 == 0 { 0.8 } else { 0.3 };
            [c, 0.6 * c, 0.5 * c, 1.0]
        })
        .collect();
    Texture::new(n, n, texels).expect("valid texture")
}
