//! The deferred shading pass, steps 7–10 of Algorithm 3: every visible pixel of the visibility
//! buffer is reconstructed exactly once (depth, barycentrics) and shaded by Eq. (6.4).
//!
//! A row is walked in spans of equal set-up id. What depends on the set-up (perspective-correct
//! weights, depth, interpolated normal, texture sample) is computed span by span into a block of
//! [`LANES`] pixels held as structure of arrays; the rest (view vector, normalisation, the
//! two-sided flip, Blinn–Phong) runs over the whole block in branch-free loops that compile to
//! SIMD code. Per pixel the operations and their order are those of a scalar evaluation, so the
//! image does not depend on how a row falls into blocks.

use visage_camera::{DepthKind, Intrinsics};
use visage_mesh::TriMesh;

use crate::frame::Albedo;
use crate::rasterize::{ScreenTriangle, NO_TRIANGLE};
use crate::shading::{BlinnPhong, SurfaceLanes, LANES};

/// Attributes at the three corners of a set-up (mesh barycentrics `B`, one row per corner):
/// a pixel's attribute is `Σ_i w_i · (B a)_i` with the corner weights `w`, which equals
/// `Σ_j bary_j a_j`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct CornerAttributes {
    /// Camera-space vertex normals (not normalised).
    normals: [[f32; 3]; 3],
    /// Texel-space positions ([`crate::Texture::texel_coords`]) for a textured albedo.
    texel: [[f64; 2]; 3],
    /// Vertex colours for a vertex-colour albedo.
    color: [[f32; 3]; 3],
}

impl CornerAttributes {
    /// The attributes of set-up `st` of `mesh`, with camera-space vertex normals `normals`.
    /// Indices must be valid (meshes are validated before rasterisation).
    pub(crate) fn new(
        st: &ScreenTriangle,
        mesh: &TriMesh,
        normals: &[[f32; 3]],
        albedo: &Albedo<'_>,
    ) -> CornerAttributes {
        let t = mesh.triangles[st.triangle() as usize].map(|i| i as usize);
        let bc = st.corner_bary();
        let at_corners = |a: [[f32; 3]; 3]| -> [[f32; 3]; 3] {
            std::array::from_fn(|i| {
                std::array::from_fn(|c| {
                    bc[i][0] * a[0][c] + bc[i][1] * a[1][c] + bc[i][2] * a[2][c]
                })
            })
        };
        let mut out = CornerAttributes {
            normals: at_corners(t.map(|i| normals[i])),
            ..CornerAttributes::default()
        };
        match albedo {
            Albedo::Texture { texture, .. } => {
                let uv = t.map(|i| mesh.uvs[i]);
                out.texel = std::array::from_fn(|i| {
                    let b = bc[i].map(f64::from);
                    texture.texel_coords(std::array::from_fn(|c| {
                        b[0] * uv[0][c] + b[1] * uv[1][c] + b[2] * uv[2][c]
                    }))
                });
            }
            Albedo::VertexColors => out.color = at_corners(t.map(|i| mesh.colors[i])),
            Albedo::Constant(_) => {}
        }
        out
    }
}

/// Everything the pass needs that is constant over a frame.
pub(crate) struct DeferredPass<'a> {
    /// Corner attributes, indexed like the rasteriser's set-up chunks.
    pub corners: &'a [Vec<CornerAttributes>],
    pub shader: BlinnPhong,
    pub albedo: Albedo<'a>,
    pub background: [f32; 3],
    pub two_sided: bool,
    pub intrinsics: Intrinsics,
    pub kind: DepthKind,
}

/// Visible pixels of a row awaiting shading: the scratch of [`DeferredPass::shade_tile`], kept
/// by each worker across tiles.
pub(crate) struct Block {
    /// Number of pixels held.
    len: usize,
    /// Their columns.
    column: [u32; LANES],
    /// Their ray coordinate `x' = (u − c_x)/f_x`.
    ray_x: [f32; LANES],
    /// `normal`: interpolated, not yet normalised; `albedo`: final; `view`: filled at flush.
    surface: SurfaceLanes,
}

impl Default for Block {
    fn default() -> Self {
        Block {
            len: 0,
            column: [0; LANES],
            ray_x: [0.0; LANES],
            surface: SurfaceLanes::default(),
        }
    }
}

/// Output rows of the pass (a tile's or one row): colour, depth, and triangle ids and
/// barycentrics (empty when not wanted), each a whole number of image rows.
pub(crate) struct Rows<'a> {
    pub color: &'a mut [[f32; 3]],
    pub depth: &'a mut [f32],
    pub triangle: &'a mut [u32],
    pub bary: &'a mut [[f32; 3]],
}

impl DeferredPass<'_> {
    /// Shades the tile of image rows from `row0` on whose visibility buffer is `index` (set-up
    /// ids into `chunks`) into `out`.
    ///
    /// On x86-64 CPUs with AVX2 the pass is compiled a second time for 256-bit vectors and chosen
    /// at run time; Rust never fuses or reorders floating-point operations, so the results are
    /// identical.
    pub(crate) fn shade_tile(
        &self,
        block: &mut Block,
        row0: usize,
        chunks: &[Vec<ScreenTriangle>],
        index: &[u32],
        out: Rows<'_>,
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above).
            unsafe { self.shade_tile_avx2(block, row0, chunks, index, out) };
            return;
        }
        self.shade_tile_inline(block, row0, chunks, index, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn shade_tile_avx2(
        &self,
        block: &mut Block,
        row0: usize,
        chunks: &[Vec<ScreenTriangle>],
        index: &[u32],
        out: Rows<'_>,
    ) {
        self.shade_tile_inline(block, row0, chunks, index, out);
    }

    #[inline(always)]
    fn shade_tile_inline(
        &self,
        block: &mut Block,
        row0: usize,
        chunks: &[Vec<ScreenTriangle>],
        index: &[u32],
        out: Rows<'_>,
    ) {
        let w = self.intrinsics.width as usize;
        // Rows of the optional buffers, or empty rows when a buffer is not wanted.
        let mut t_rows = out.triangle.chunks_mut(w);
        let mut b_rows = out.bary.chunks_mut(w);
        for (r, ((setups, color), depth)) in index
            .chunks(w)
            .zip(out.color.chunks_mut(w))
            .zip(out.depth.chunks_mut(w))
            .enumerate()
        {
            let row = Rows {
                color,
                depth,
                triangle: t_rows.next().unwrap_or_default(),
                bary: b_rows.next().unwrap_or_default(),
            };
            self.shade_row(block, row0 + r, chunks, setups, row);
        }
    }

    /// Shades row `y` whose visibility buffer row is `setups` into `row` (one image row; the
    /// visible triangle and barycentrics only where those buffers are not empty).
    #[inline(always)]
    fn shade_row(
        &self,
        block: &mut Block,
        y: usize,
        chunks: &[Vec<ScreenTriangle>],
        setups: &[u32],
        row: Rows<'_>,
    ) {
        let Rows {
            color: c_row,
            depth: d_row,
            triangle: t_row,
            bary: b_row,
        } = row;
        let k = &self.intrinsics;
        let (inv_fx, inv_fy) = (1.0 / k.fx, 1.0 / k.fy);
        let yf = y as f64;
        let yr = (yf - k.cy) * inv_fy;
        let yr2_plus_1 = yr * yr + 1.0;
        let w = c_row.len();
        let mut x = 0;
        while x < w {
            let s = setups[x];
            let end = x + setups[x..].iter().take_while(|&&t| t == s).count();
            let id = ((s >> 16) as usize, (s & 0xffff) as usize);
            let found = (s != NO_TRIANGLE)
                .then(|| {
                    let st = chunks.get(id.0)?.get(id.1)?;
                    Some((st, self.corners.get(id.0)?.get(id.1)?))
                })
                .flatten();
            let Some((st, ca)) = found else {
                c_row[x..end].fill(self.background);
                d_row[x..end].fill(0.0);
                if let Some(t) = t_row.get_mut(x..end) {
                    t.fill(NO_TRIANGLE);
                }
                if let Some(b) = b_row.get_mut(x..end) {
                    b.fill([0.0; 3]);
                }
                x = end;
                continue;
            };
            let rows = st.rows(yf);
            for (x, d) in (x..end).zip(&mut d_row[x..end]) {
                let (wt, z) = st.corner_weights(&rows, x as f64);
                let wf = wt.map(|v| v as f32);
                let xr = (x as f64 - k.cx) * inv_fx;
                let value = match self.kind {
                    DepthKind::Z => z,
                    DepthKind::Ray => z * (xr * xr + yr2_plus_1).sqrt(),
                };
                *d = value as f32;
                if let Some(t) = t_row.get_mut(x) {
                    *t = st.triangle();
                }
                if let Some(bb) = b_row.get_mut(x) {
                    *bb = st.mesh_bary(&wt).map(|v| v as f32);
                }
                let lane = block.len;
                let surface = &mut block.surface;
                let cn = &ca.normals;
                for (c, normal) in surface.normal.iter_mut().enumerate() {
                    normal[lane] = wf[0] * cn[0][c] + wf[1] * cn[1][c] + wf[2] * cn[2][c];
                }
                let albedo = match self.albedo {
                    Albedo::Texture { texture, wrap } => {
                        let cxy = &ca.texel;
                        let xy = std::array::from_fn(|c| {
                            wt[0] * cxy[0][c] + wt[1] * cxy[1][c] + wt[2] * cxy[2][c]
                        });
                        texture.sample_rgb_at(xy, wrap)
                    }
                    Albedo::VertexColors => {
                        let cc = &ca.color;
                        std::array::from_fn(|c| {
                            wf[0] * cc[0][c] + wf[1] * cc[1][c] + wf[2] * cc[2][c]
                        })
                    }
                    Albedo::Constant(c) => c,
                };
                for (c, a) in albedo.into_iter().enumerate() {
                    surface.albedo[c][lane] = a;
                }
                block.column[lane] = x as u32;
                block.ray_x[lane] = xr as f32;
                block.len += 1;
                if block.len == LANES {
                    self.flush(block, yr as f32, yr2_plus_1 as f32, c_row);
                }
            }
            x = end;
        }
        self.flush(block, yr as f32, yr2_plus_1 as f32, c_row);
    }

    /// Shades the pixels of `block` into `c_row` and empties it. `yr` and `yr2_plus_1` are the
    /// row's ray coordinate `y'` and `y'² + 1`.
    #[inline(always)]
    fn flush(&self, block: &mut Block, yr: f32, yr2_plus_1: f32, c_row: &mut [[f32; 3]]) {
        let m = block.len;
        let s = &mut block.surface;
        for k in 0..m {
            // The surface point is z · (x', y', 1) on this pixel's ray, so the unit view vector
            // (surface → eye) comes from the ray alone.
            let xr = block.ray_x[k];
            let inv = -1.0 / (xr * xr + yr2_plus_1).sqrt();
            let view = [xr * inv, yr * inv, inv];
            let mut n = [s.normal[0][k], s.normal[1][k], s.normal[2][k]];
            let n_len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if n_len > 0.0 {
                let inv = 1.0 / n_len;
                n = n.map(|v| v * inv);
            }
            if self.two_sided && n[0] * view[0] + n[1] * view[1] + n[2] * view[2] < 0.0 {
                n = n.map(|v| -v);
            }
            for c in 0..3 {
                s.normal[c][k] = n[c];
                s.view[c][k] = view[c];
            }
        }
        self.shader.shade_lanes(s, m);
        for (k, &x) in block.column[..m].iter().enumerate() {
            c_row[x as usize] = [s.albedo[0][k], s.albedo[1][k], s.albedo[2][k]];
        }
        block.len = 0;
    }
}
