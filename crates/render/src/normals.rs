//! Vertex normals and their transformation: Eq. (6.2).

use rayon::prelude::*;
use visage_camera::vec3::{cross, normalize, sub};

use crate::mat4::Mat3;
use crate::simd::with_simd;
use crate::RenderError;

/// The normal matrix `N = (A⁻¹)ᵀ` of the linear part `A` of a transform (Eq. (6.2)): if `t` is
/// tangent to the surface and `n · t = 0`, then `(N n) · (A t) = 0`, also under non-uniform scaling
/// where `A n` would not stay perpendicular.
///
/// # Errors
/// `RenderError::Transform` when `A` is singular or not finite.
pub fn normal_matrix(a: &Mat3) -> Result<Mat3, RenderError> {
    a.inverse_transpose().ok_or_else(|| RenderError::Transform {
        what: "model-view matrix",
        reason: format!(
            "its linear part is singular (det = {}), normals are undefined",
            a.determinant()
        ),
    })
}

/// `ν = N n / ‖N n‖` (Eq. (6.2)); the zero vector stays zero.
#[inline]
pub fn transform_normal(n: &Mat3, normal: [f64; 3]) -> [f64; 3] {
    normalize(n.mul_vec(normal))
}

/// Area-weighted vertex normals `n_i ∝ Σ_{T ∋ i} (v₁ − v₀) × (v₂ − v₀)`, unit length (zero for
/// vertices of no or only degenerate triangles), #V × 3. Indices must be valid.
///
/// # Panics
/// If a triangle index is out of range (callers validate meshes first), unless all three are:
/// such a triangle touches no vertex and is skipped.
pub fn vertex_normals(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut normals = Vec::new();
    vertex_normals_into(vertices, triangles, &mut normals);
    normals
}

/// [`vertex_normals`] into a caller-owned buffer (resized to #V; no allocation once it has
/// grown), for per-frame use.
///
/// Parallel over ranges of vertices (rayon): each range scans the triangles in order and adds
/// the face normals of those that touch it, so every vertex's sum runs over its triangles in
/// triangle order, as in a serial scatter — the result does not depend on the split.
pub fn vertex_normals_into(vertices: &[[f64; 3]], triangles: &[[u32; 3]], acc: &mut Vec<[f64; 3]>) {
    by_vertex_ranges(vertices, triangles, acc, true);
}

/// The sums behind [`vertex_normals`], not normalised: `Σ_{T ∋ i} (v₁ − v₀) × (v₂ − v₀)` (twice
/// the area-weighted normal; zero for vertices of no or only degenerate triangles), #V × 3, for
/// callers that finish them differently (the glb's `f32` unit normals with a default for zero).
/// The same sums, added in the same order, as [`vertex_normals`] normalises.
///
/// # Panics
/// As [`vertex_normals`].
pub fn vertex_normal_sums(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut sums = Vec::new();
    by_vertex_ranges(vertices, triangles, &mut sums, false);
    sums
}

/// The sums of the face normals into `acc` (resized to #V), normalised when `unit`.
fn by_vertex_ranges(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    acc: &mut Vec<[f64; 3]>,
    unit: bool,
) {
    acc.clear();
    acc.resize(vertices.len(), [0.0; 3]);
    // One range per thread (every range reads all triangles), none below the minimum.
    let range_len = MIN_VERTEX_RANGE.max(vertices.len().div_ceil(rayon::current_num_threads()));
    acc.par_chunks_mut(range_len)
        .enumerate()
        .for_each(|(r, sums)| {
            with_simd(
                #[inline(always)]
                || range_normals(vertices, triangles, r * range_len, sums, unit),
            )
        });
}

/// The area-weighted normals of the vertices `first..first + sums.len()` into `sums` (zeros on
/// entry): the face normals of the triangles touching the range, in triangle order; made unit
/// when `unit`.
#[inline(always)]
fn range_normals(
    vertices: &[[f64; 3]],
    triangles: &[[u32; 3]],
    first: usize,
    sums: &mut [[f64; 3]],
    unit: bool,
) {
    let len = sums.len();
    // The position in `sums` of vertex `i`, if in the range.
    let local = |i: u32| Some((i as usize).wrapping_sub(first)).filter(|&k| k < len);
    for t in triangles {
        if t.iter().all(|&i| local(i).is_none()) {
            continue;
        }
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let n = cross(sub(b, a), sub(c, a));
        for k in t.iter().filter_map(|&i| local(i)) {
            let s = &mut sums[k];
            s[0] += n[0];
            s[1] += n[1];
            s[2] += n[2];
        }
    }
    if unit {
        for n in sums.iter_mut() {
            *n = normalize(*n);
        }
    }
}

/// Fewest vertices per parallel range of [`vertex_normals_into`].
const MIN_VERTEX_RANGE: usize = 4096;

#[cfg(test)]
mod tests {
    use super::*;
    use visage_camera::vec3::dot;

    #[test]
    fn normals_stay_perpendicular_under_non_uniform_scaling() {
        // A sloped plane with tangents t1, t2 and normal n; scale x by 5, z by 0.2 and rotate.
        let (t1, t2) = ([1.0, 0.0, 1.0], [0.0, 1.0, 0.5]);
        let n = normalize(cross(t1, t2));
        let a = Mat3::rotation([0.3, 1.0, -0.2], 0.7).mul(&Mat3::diagonal([5.0, 1.0, 0.2]));
        let nm = normal_matrix(&a).unwrap();
        let nu = transform_normal(&nm, n);
        assert!((dot(nu, nu) - 1.0).abs() < 1e-14);
        for t in [t1, t2] {
            let ta = normalize(a.mul_vec(t));
            assert!(dot(nu, ta).abs() < 1e-14, "ν ⟂ transformed tangent");
        }
        // The naive A·n is not perpendicular here: the test would catch using A instead of N.
        let naive = normalize(a.mul_vec(n));
        assert!(dot(naive, normalize(a.mul_vec(t1))).abs() > 1e-2);
        assert!(normal_matrix(&Mat3::diagonal([1.0, 0.0, 1.0])).is_err());
    }

    #[test]
    fn vertex_normals_do_not_depend_on_the_thread_count() {
        // A bumpy grid of several vertex ranges, its triangles in a scrambled order so that
        // every range meets triangles all along the list.
        let n = 120u32;
        let v: Vec<[f64; 3]> = (0..n * n)
            .map(|k| {
                let (i, j) = ((k % n) as f64, (k / n) as f64);
                [i, j, (0.3 * i).sin() * (0.2 * j).cos()]
            })
            .collect();
        let mut t = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                t.extend([[a, a + 1, a + n + 1], [a, a + n + 1, a + n]]);
            }
        }
        let m = t.len();
        let t: Vec<[u32; 3]> = (0..m).map(|k| t[k * 7919 % m]).collect();
        let in_pool = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| vertex_normals(&v, &t))
        };
        let serial = in_pool(1);
        // The baseline build (no AVX-512 or AVX2) of the one range of one thread.
        let mut baseline = vec![[0.0; 3]; v.len()];
        range_normals(&v, &t, 0, &mut baseline, true);
        assert_eq!(serial, baseline);
        for threads in [2, 3, 8] {
            let parallel = in_pool(threads);
            for (a, b) in serial.iter().zip(&parallel) {
                assert_eq!(
                    a.map(f64::to_bits),
                    b.map(f64::to_bits),
                    "{threads} threads"
                );
            }
        }
        // The sums are the ones `vertex_normals` normalises, bit for bit.
        let sums = pool_sums(&v, &t);
        let unit: Vec<[f64; 3]> = sums.into_iter().map(normalize).collect();
        assert_eq!(unit, serial);
    }

    fn pool_sums(v: &[[f64; 3]], t: &[[u32; 3]]) -> Vec<[f64; 3]> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        pool.install(|| vertex_normal_sums(v, t))
    }

    #[test]
    fn vertex_normals_of_a_plane_point_along_its_normal() {
        let v = [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        let n = vertex_normals(&v, &[[0, 1, 2], [1, 3, 2]]);
        for x in n {
            assert!((x[2] - 1.0).abs() < 1e-15);
        }
    }
}
