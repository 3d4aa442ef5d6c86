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

use crate::frame::Albedo;
use crate::rasterize::ScreenTriangle;

/// An affine function of the pixel centre `(x, y)`: `c + dx·(x − x₀) + dy·(y − y₀)` about the
/// origin `(x₀, y₀)` of its set-up ([`SetupPlanes::origin`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Plane {
    pub c: f64,
    pub dx: f64,
    pub dy: f64,
}

impl Plane {
    /// `Σ a_i · planes_i`.
    #[inline(always)]
    fn combine(planes: &[Plane; 3], a: [f64; 3]) -> Plane {
        let [p, q, r] = planes;
        Plane {
            c: a[0] * p.c + a[1] * q.c + a[2] * r.c,
            dx: a[0] * p.dx + a[1] * q.dx + a[2] * r.dx,
            dy: a[0] * p.dy + a[1] * q.dy + a[2] * r.dy,
        }
    }

    /// The function along row `v = y − y₀`: its value at `x = x₀` and its slope.
    #[inline(always)]
    pub fn row(&self, v: f64) -> RowLine {
        RowLine {
            at_origin: self.c + self.dy * v,
            dx: self.dx,
        }
    }
}

/// A [`Plane`] restricted to one pixel row: `at_origin + dx · u` with `u = x − x₀`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowLine {
    at_origin: f64,
    dx: f64,
}

impl RowLine {
    /// The value at `u = x − x₀`.
    #[inline(always)]
    pub fn at(&self, u: f64) -> f64 {
        self.at_origin + self.dx * u
    }
}

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

/// Everything a visible pixel of one set-up needs, as planes: depth, normal and albedo source.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SetupPlanes {
    /// `(x₀, y₀)`: the top-left pixel of the set-up's bounding box.
    pub origin: [i32; 2],
    /// `ΣE_i`, so that `z = ΣE / D`.
    pub edge_sum: f64,
    /// `D = Σ q_i`.
    pub inverse_depth: Plane,
    /// Numerators of the camera-space vertex normal (not normalised).
    pub normal: [Plane; 3],
    /// Numerators of the albedo source: texel-space position ([`crate::Texture::texel_coords`],
    /// first two) for a textured albedo, linear RGB for vertex colours, unused for a constant.
    pub albedo: [Plane; 3],
}

impl SetupPlanes {
    /// The planes of set-up `st` of a mesh with triangles `triangles` and per-vertex channels
    /// `channels`. Indices must be valid (meshes are validated before rasterisation).
    #[inline(always)]
    pub(crate) fn new(
        st: &ScreenTriangle,
        triangles: &[[u32; 3]],
        channels: &VertexChannels,
    ) -> SetupPlanes {
        let [t0, t1, t2] = triangles[st.triangle() as usize];
        let values = &channels.values;
        let [a0, a1, a2] = [
            &values[t0 as usize],
            &values[t1 as usize],
            &values[t2 as usize],
        ];
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
        SetupPlanes {
            origin: st.origin(),
            edge_sum,
            inverse_depth: Plane::combine(&q, [1.0; 3]),
            normal: [channel(0), channel(1), channel(2)],
            albedo: [albedo(0), albedo(1), albedo(2)],
        }
    }
}
