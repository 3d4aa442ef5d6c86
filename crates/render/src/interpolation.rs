//! Perspective-correct interpolation with affine functions of the pixel centre: step 7 of
//! Algorithm 3.
//!
//! A set-up's edge functions `E_i` are affine in screen space and proportional to the
//! screen-space barycentrics `λ_i`, and `1/w` is affine there too. Hence `q_i = E_i / w_i` is
//! affine, `D = Σ q_i = ΣE / z`, and an attribute with corner values `a_i` has the
//! perspective-correct value `a = Σ a_i q_i / D` — its numerator `Σ a_i q_i` is one more affine
//! function. So each set-up gets one [`Plane`] per attribute channel, and a pixel costs one
//! division (`1/D`, shared by every channel) and a multiply-add and a multiply per channel.

use rayon::prelude::*;
use visage_mesh::TriMesh;

use crate::albedo::Albedo;
use crate::plane::Plane;
use crate::rasterize::ScreenTriangle;

/// Channels interpolated across a set-up: the camera-space normal (three), then the albedo
/// source's (see [`VertexChannels`]).
pub(crate) const CHANNELS: usize = 6;

/// Per mesh vertex, the values of the channels a set-up interpolates: the camera-space normal
/// (Eq. (6.2), rounded to `f32`), then the albedo source's — texel-space position
/// ([`crate::Texture::texel_coords`]) for a textured albedo, linear RGB for vertex colours.
/// Gathered once per vertex and frame rather than at every set-up of the vertex's triangles.
#[derive(Debug, Default)]
pub(crate) struct VertexChannels {
    values: Vec<[f64; CHANNELS]>,
    /// How many albedo channels are used: 2, 3, or 0 for a constant albedo.
    albedo_channels: usize,
}

impl VertexChannels {
    /// The channel values of the three vertices of `triangle` (indices must be valid: meshes
    /// are validated before rasterisation).
    #[inline(always)]
    fn of_triangle(&self, triangle: [u32; 3]) -> [&[f64; CHANNELS]; 3] {
        triangle.map(|v| &self.values[v as usize])
    }

    /// Fills the table for the vertices of `mesh` with camera-space normals `normal(v)` and the
    /// albedo source `albedo` (whose attribute the mesh must have). In parallel over vertices.
    pub(crate) fn fill(
        &mut self,
        mesh: &TriMesh,
        normal: impl Fn(usize) -> [f32; 3] + Sync,
        albedo: &Albedo<'_>,
    ) {
        let source = |v: usize| -> [f64; 3] {
            match albedo {
                Albedo::Texture { texture, .. } => {
                    let [x, y] = texture.texel_coords(mesh.uvs[v]);
                    [x, y, 0.0]
                }
                Albedo::VertexColors => {
                    let [r, g, b] = mesh.colors[v];
                    [r.into(), g.into(), b.into()]
                }
                Albedo::Constant(_) => [0.0; 3],
            }
        };
        self.albedo_channels = match albedo {
            Albedo::Texture { .. } => 2,
            Albedo::VertexColors => 3,
            Albedo::Constant(_) => 0,
        };
        self.values.resize(mesh.vertices.len(), [0.0; CHANNELS]);
        self.values
            .par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(v, out)| {
                let [nx, ny, nz] = normal(v);
                let [a, b, c] = source(v);
                *out = [nx.into(), ny.into(), nz.into(), a, b, c];
            });
    }
}

/// Planes per set-up ([`SetupPlanes`]): `D` (the inverse-depth numerator), the normal's three
/// channels, the albedo source's three, and a zero pad — eight, so that each coefficient of
/// all of them is one 512-bit vector.
pub(crate) const LINES: usize = 8;

/// Index of the first normal plane in [`SetupPlanes`].
pub(crate) const NORMAL: usize = 1;

/// Index of the first albedo-source plane in [`SetupPlanes`].
pub(crate) const ALBEDO: usize = 4;

/// Everything a visible pixel of one set-up needs, as planes: depth, normal and albedo source,
/// stored as structure of arrays (see [`LINES`]) so that a pixel evaluates all of them in a few
/// vector operations ([`SetupPlanes::at`]).
///
/// Plane 0 is `D = Σ q_i`; planes [`NORMAL`].. are the numerators of the camera-space vertex
/// normal (not normalised); planes [`ALBEDO`].. those of the albedo source: texel-space position
/// ([`crate::Texture::texel_coords`], first two) for a textured albedo, linear RGB for vertex
/// colours, zero for a constant.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SetupPlanes {
    /// `(x₀, y₀)`: the top-left pixel of the set-up's bounding box.
    pub origin: [i32; 2],
    /// `ΣE_i`, so that `z = ΣE / D`.
    pub edge_sum: f64,
    /// Per plane, its value at the origin and its slopes in `x` and `y`.
    pub c: [f64; LINES],
    pub dx: [f64; LINES],
    pub dy: [f64; LINES],
}

impl SetupPlanes {
    /// The set-up with origin `origin`, `ΣE = edge_sum` and planes `D`, normal, albedo source.
    #[inline(always)]
    fn from_planes(origin: [i32; 2], edge_sum: f64, planes: [Plane; LINES - 1]) -> SetupPlanes {
        let mut p = SetupPlanes {
            origin,
            edge_sum,
            ..SetupPlanes::default()
        };
        for (i, plane) in planes.into_iter().enumerate() {
            (p.c[i], p.dx[i], p.dy[i]) = (plane.c, plane.dx, plane.dy);
        }
        p
    }

    /// Every plane at the pixel `(u, v) = (x − x₀, y − y₀)`: `(c + dy·v) + dx·u`, lane by lane.
    #[inline(always)]
    pub fn at(&self, u: f64, v: f64) -> [f64; LINES] {
        std::array::from_fn(|i| (self.c[i] + self.dy[i] * v) + self.dx[i] * u)
    }

    /// The planes of the set-ups `bin` (ids `chunk << 16 | index` into `chunks`) into `planes`
    /// (cleared first), in bin order: [`SetupPlanes::new`] of each.
    ///
    /// On x86-64 CPUs with AVX2 each plane is computed in the lanes of one 256-bit register
    /// ([`SetupPlanes::new_avx2`]), chosen at run time; the planes are identical.
    pub(crate) fn of_bin(
        planes: &mut Vec<SetupPlanes>,
        bin: &[u32],
        chunks: &[Vec<ScreenTriangle>],
        triangles: &[[u32; 3]],
        channels: &VertexChannels,
    ) {
        planes.clear();
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: `of_bin_avx2` is compiled for AVX2, which the run-time check just above
            // found on this CPU; it is otherwise safe, bounds-checked code.
            unsafe { Self::of_bin_avx2(planes, bin, chunks, triangles, channels) };
            return;
        }
        planes.extend(bin.iter().map(|&s| {
            let st = &chunks[(s >> 16) as usize][(s & 0xffff) as usize];
            SetupPlanes::new(st, triangles, channels)
        }));
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn of_bin_avx2(
        planes: &mut Vec<SetupPlanes>,
        bin: &[u32],
        chunks: &[Vec<ScreenTriangle>],
        triangles: &[[u32; 3]],
        channels: &VertexChannels,
    ) {
        planes.reserve(bin.len());
        for &s in bin {
            let st = &chunks[(s >> 16) as usize][(s & 0xffff) as usize];
            planes.push(SetupPlanes::new_avx2(st, triangles, channels));
        }
    }

    /// The planes of set-up `st` of a mesh with triangles `triangles` and per-vertex channels
    /// `channels`. Indices must be valid (meshes are validated before rasterisation).
    #[inline(always)]
    pub(crate) fn new(
        st: &ScreenTriangle,
        triangles: &[[u32; 3]],
        channels: &VertexChannels,
    ) -> SetupPlanes {
        let [a0, a1, a2] = channels.of_triangle(triangles[st.triangle() as usize]);
        let (q, edge_sum) = st.perspective_planes();
        // Corner `i` of the set-up is the point `Σ_j B_ij v_j` of the mesh triangle, so
        // `Σ_i a_i q_i = Σ_j A_j Σ_i B_ij q_i`: one plane per mesh vertex `j`, then one
        // combination per channel. Unclipped set-ups (almost all) have the vertices as corners,
        // in order or with the last two swapped for orientation, decided at set-up: constant
        // indices keep the planes in registers.
        let vertex: [Plane; 3] = match st.vertex_corners() {
            Some([0, 1, 2]) => q,
            Some([0, 2, 1]) => [q[0], q[2], q[1]],
            Some(c) => c.map(|i| q[i as usize]),
            None => {
                let bc = st.corner_bary();
                std::array::from_fn(|j| {
                    Plane::combine(&q, [bc[0][j].into(), bc[1][j].into(), bc[2][j].into()])
                })
            }
        };
        // One channel's plane from its values at the mesh triangle's vertices.
        let channel = |c: usize| Plane::combine(&vertex, [a0[c], a1[c], a2[c]]);
        let albedo = |c: usize| {
            if c < channels.albedo_channels {
                channel(3 + c)
            } else {
                Plane::default()
            }
        };
        SetupPlanes::from_planes(
            st.origin(),
            edge_sum,
            [
                Plane::sum(&q),
                channel(0),
                channel(1),
                channel(2),
                albedo(0),
                albedo(1),
                albedo(2),
            ],
        )
    }

    /// [`SetupPlanes::new`] with each plane in the lanes `(c, dx, dy, 0)` of one AVX register:
    /// lane by lane the same operations in the same order, so the same planes.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    #[target_feature(enable = "avx2")]
    fn new_avx2(
        st: &ScreenTriangle,
        triangles: &[[u32; 3]],
        channels: &VertexChannels,
    ) -> SetupPlanes {
        use std::arch::x86_64::{__m256d, _mm256_setzero_pd, _mm256_storeu_pd};
        let [a0, a1, a2] = channels.of_triangle(triangles[st.triangle() as usize]);
        let (q, edge_sum) = st.perspective_planes_x4();
        let vertex: [__m256d; 3] = match st.vertex_corners() {
            Some([0, 1, 2]) => q,
            Some([0, 2, 1]) => [q[0], q[2], q[1]],
            Some([c0, c1, c2]) => [q[c0 as usize], q[c1 as usize], q[c2 as usize]],
            None => {
                let bc = st.corner_bary();
                std::array::from_fn(|j| {
                    combine_x4(&q, [bc[0][j].into(), bc[1][j].into(), bc[2][j].into()])
                })
            }
        };
        let channel = |c: usize| combine_x4(&vertex, [a0[c], a1[c], a2[c]]);
        let zero = _mm256_setzero_pd();
        let albedo = |c: usize| {
            if c < channels.albedo_channels {
                channel(3 + c)
            } else {
                zero
            }
        };
        let mut p = SetupPlanes {
            origin: st.origin(),
            edge_sum,
            ..SetupPlanes::default()
        };
        let first = [sum_x4(&q), channel(0), channel(1), channel(2)];
        let second = [albedo(0), albedo(1), albedo(2), zero];
        for (at, rows) in [(0, first), (4, second)] {
            let [c, dx, dy] = transpose_x4(rows);
            // SAFETY: `p.c`, `p.dx` and `p.dy` are `[f64; LINES]` and `at` is 0 or 4, so each
            // (unaligned) store writes the four `f64` `at..at + 4 ≤ LINES` of its own array.
            unsafe {
                _mm256_storeu_pd(p.c[at..].as_mut_ptr(), c);
                _mm256_storeu_pd(p.dx[at..].as_mut_ptr(), dx);
                _mm256_storeu_pd(p.dy[at..].as_mut_ptr(), dy);
            }
        }
        p
    }
}

/// The coefficients `c`, `dx`, `dy` of four planes in the lanes `(c, dx, dy, ·)` of `rows`,
/// each as the four lanes of one register (a 4 × 3 transpose).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx")]
fn transpose_x4(rows: [std::arch::x86_64::__m256d; 4]) -> [std::arch::x86_64::__m256d; 3] {
    use std::arch::x86_64::*;
    let [r0, r1, r2, r3] = rows;
    // (c0, c1, dy0, dy1), (dx0, dx1, ·, ·), and likewise for planes 2 and 3.
    let (c_dy01, dx01) = (_mm256_unpacklo_pd(r0, r1), _mm256_unpackhi_pd(r0, r1));
    let (c_dy23, dx23) = (_mm256_unpacklo_pd(r2, r3), _mm256_unpackhi_pd(r2, r3));
    [
        _mm256_permute2f128_pd::<0x20>(c_dy01, c_dy23),
        _mm256_permute2f128_pd::<0x20>(dx01, dx23),
        _mm256_permute2f128_pd::<0x31>(c_dy01, c_dy23),
    ]
}

/// [`Plane::combine`] on planes in the lanes `(c, dx, dy, 0)`.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx")]
fn combine_x4(planes: &[std::arch::x86_64::__m256d; 3], a: [f64; 3]) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    let [p, q, r] = planes;
    let term = |a: f64, p: __m256d| _mm256_mul_pd(_mm256_set1_pd(a), p);
    _mm256_add_pd(
        _mm256_add_pd(term(a[0], *p), term(a[1], *q)),
        term(a[2], *r),
    )
}

/// [`Plane::sum`] on planes in the lanes `(c, dx, dy, 0)`.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx")]
fn sum_x4(planes: &[std::arch::x86_64::__m256d; 3]) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::_mm256_add_pd;
    let [p, q, r] = planes;
    _mm256_add_pd(_mm256_add_pd(*p, *q), *r)
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use visage_camera::Intrinsics;

    use super::*;
    use crate::{Camera, CullMode, Mat4, Rasterizer, Texture, Wrap};

    /// Every coefficient of `p`, as bits.
    fn bits(p: &SetupPlanes) -> Vec<u64> {
        let coefficients = (0..LINES).flat_map(|i| [p.c[i], p.dx[i], p.dy[i]]);
        std::iter::once(p.edge_sum)
            .chain(coefficients)
            .map(f64::to_bits)
            .chain([p.origin[0] as u64, p.origin[1] as u64])
            .collect()
    }

    #[test]
    fn avx2_planes_match_the_scalar_planes_bit_for_bit() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
            // Small and large triangles of both orientations, some crossing the near plane.
            let mut mesh = TriMesh::default();
            for k in 0..2000u32 {
                let size = if k % 50 == 0 { 0.5 } else { 0.05 };
                let centre = [
                    rng.random_range(-0.6..0.6),
                    rng.random_range(-0.4..0.4),
                    rng.random_range(0.15..2.0),
                ];
                for _ in 0..3 {
                    mesh.vertices.push(std::array::from_fn(|c| {
                        centre[c] + size * rng.random_range(-1.0..1.0)
                    }));
                    mesh.uvs.push([rng.random(), rng.random()]);
                    mesh.colors.push([rng.random(), rng.random(), rng.random()]);
                }
                mesh.triangles.push([3 * k, 3 * k + 1, 3 * k + 2]);
            }
            let k = Intrinsics::new(320, 240, 300.0, 300.0, 160.0, 120.0).unwrap();
            let camera = Camera::new(k).unwrap().with_clip_planes(0.2, 10.0).unwrap();
            let mut r = Rasterizer::new();
            r.set_up(
                &mesh.vertices,
                &mesh.triangles,
                &Mat4::IDENTITY,
                &camera,
                CullMode::None,
            )
            .unwrap();
            let setups: Vec<&ScreenTriangle> = r.screen_triangles().collect();
            assert!(setups.len() > 1000, "{} set-ups", setups.len());
            assert!(
                setups.iter().any(|st| st.vertex_corners().is_none()),
                "clipped"
            );
            let texture = Texture::new(8, 4, vec![[0.5; 4]; 32]).unwrap();
            let normal = |v: usize| [v as f32 * 0.001, 0.5, -1.0 / (1.0 + v as f32)];
            for albedo in [
                Albedo::Texture {
                    texture: &texture,
                    wrap: Wrap::Clamp,
                },
                Albedo::VertexColors,
                Albedo::Constant([0.5; 3]),
            ] {
                let mut channels = VertexChannels::default();
                channels.fill(&mesh, normal, &albedo);
                for st in &setups {
                    let scalar = SetupPlanes::new(st, &mesh.triangles, &channels);
                    // SAFETY: `new_avx2` is compiled for AVX2, which the run-time check above
                    // found on this CPU.
                    let avx2 = unsafe { SetupPlanes::new_avx2(st, &mesh.triangles, &channels) };
                    assert_eq!(bits(&scalar), bits(&avx2));
                }
                // The same through `of_bin`, which runs its AVX2 build for a whole bin.
                let chunks = vec![setups.iter().map(|&&st| st).collect::<Vec<_>>()];
                let bin: Vec<u32> = (0..setups.len() as u32).collect();
                let mut planes = Vec::new();
                SetupPlanes::of_bin(&mut planes, &bin, &chunks, &mesh.triangles, &channels);
                assert_eq!(planes.len(), setups.len());
                for (st, planes) in setups.iter().zip(&planes) {
                    let scalar = SetupPlanes::new(st, &mesh.triangles, &channels);
                    assert_eq!(bits(&scalar), bits(planes));
                }
            }
        }
    }

    /// The planes reproduce, at every covered pixel centre, the per-pixel reconstruction from
    /// the edge functions (depth, and normal and texel position from the mesh barycentrics),
    /// for set-ups that are whole triangles (in either orientation) and pieces of triangles
    /// clipped by the near plane.
    #[test]
    fn planes_agree_with_the_per_pixel_reconstruction() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut mesh = TriMesh::default();
        for t in 0..40u32 {
            for _ in 0..3 {
                // Every fourth triangle reaches behind the near plane (z < 1 mm).
                let z: f64 = if t % 4 == 0 && rng.random_bool(0.4) {
                    rng.random_range(-0.3..0.0005)
                } else {
                    rng.random_range(0.3..3.0)
                };
                let xy: [f64; 2] = std::array::from_fn(|_| rng.random_range(-0.6..0.6) * z.abs());
                mesh.vertices.push([xy[0], xy[1], z]);
                mesh.uvs
                    .push([rng.random_range(-0.2..1.2), rng.random_range(-0.2..1.2)]);
            }
            mesh.triangles.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        let normals: Vec<[f32; 3]> = (0..mesh.vertices.len())
            .map(|_| std::array::from_fn(|_| rng.random_range(-1.0..1.0)))
            .collect();
        let texture = Texture::new(64, 32, vec![[0.5; 4]; 64 * 32]).unwrap();
        let albedo = Albedo::Texture {
            texture: &texture,
            wrap: Wrap::Repeat,
        };
        let k = Intrinsics::new(160, 120, 90.0, 95.0, 80.3, 59.6).unwrap();
        let mut channels = VertexChannels::default();
        channels.fill(&mesh, |v| normals[v], &albedo);
        let mut raster = Rasterizer::new();
        let camera = Camera::new(k).unwrap();
        raster
            .set_up(
                &mesh.vertices,
                &mesh.triangles,
                &Mat4::IDENTITY,
                &camera,
                CullMode::None,
            )
            .unwrap();
        let (mut pixels, mut clipped) = (0, 0);
        for st in raster.screen_triangles() {
            let planes = SetupPlanes::new(st, &mesh.triangles, &channels);
            let is_clipped = st.vertex_corners().is_none();
            clipped += usize::from(is_clipped);
            // Clipped corners carry `f32` barycentrics, which the two computations combine in
            // different orders (depth does not use them).
            let tolerance = if is_clipped { 1e-6 } else { 1e-9 };
            let close = |a: f64, b: f64, what: &str| {
                assert!(
                    (a - b).abs() <= tolerance * (1.0 + b.abs()),
                    "{what}: {a} vs {b}"
                );
            };
            let t = mesh.triangles[st.triangle() as usize].map(|i| i as usize);
            st.for_each_pixel(|x, y| {
                pixels += 1;
                let (x, y) = (x as f64, y as f64);
                let (w, z) = st.corner_weights(&st.rows(y), x);
                let b = st.mesh_bary(&w);
                let [u, v] = [x - planes.origin[0] as f64, y - planes.origin[1] as f64];
                let at = planes.at(u, v);
                let d = at[0];
                assert!((planes.edge_sum / d - z).abs() <= 1e-12 * z, "depth");
                for c in 0..3 {
                    let n: f64 = (0..3).map(|j| b[j] * normals[t[j]][c] as f64).sum();
                    close(at[NORMAL + c] / d, n, "normal");
                }
                let uv = std::array::from_fn(|c| (0..3).map(|j| b[j] * mesh.uvs[t[j]][c]).sum());
                let texel = texture.texel_coords(uv);
                for (c, texel) in texel.into_iter().enumerate() {
                    close(at[ALBEDO + c] / d, texel, "texel position");
                }
            });
        }
        assert!(
            pixels > 2000 && clipped > 0,
            "{pixels} pixels, {clipped} clipped set-ups"
        );
    }
}
