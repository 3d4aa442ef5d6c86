//! The deferred shading pass, steps 7–10 of Algorithm 3: every visible pixel of the visibility
//! buffer is reconstructed exactly once (depth, normal, albedo source) and shaded by Eq. (6.4).
//!
//! A row is walked pixel by pixel: a visible pixel evaluates all its set-up's planes
//! ([`crate::interpolation`]) in a few vector operations and joins a block of [`LANES`] pixels;
//! the block then divides (once per pixel for depth and every channel), samples the texture and
//! computes the view vector, normalisation, two-sided flip and Blinn–Phong in branch-free
//! lane-parallel loops. Background runs are skipped whole and written with streaming stores.
//!
//! Walking spans of equal set-up instead (the planes evaluated along the row, four pixels at a
//! time) cost ~200 instructions per span and a mispredicted loop exit or two, for spans of 2–3
//! pixels on average. Per pixel the operations and their order do not depend on how a row falls
//! into blocks.

use visage_camera::{DepthKind, Intrinsics};

use crate::albedo::Albedo;
use crate::interpolation::{SetupPlanes, ALBEDO, LINES, NORMAL};
use crate::rasterize::{ScreenTriangle, NO_TRIANGLE};
use crate::shading::{BlinnPhong, SurfaceLanes, LANES};
use crate::simd::with_simd;
use crate::stream;
use crate::texture::TapLanes;

/// Sets every pixel of `pixels` to `color`; a grey (black, the default background) is one
/// streaming `f32` fill ([`stream::fill`]) instead of 12-byte stores.
#[inline(always)]
fn fill_color(pixels: &mut [[f32; 3]], color: [f32; 3]) {
    let [r, g, b] = color.map(f32::to_bits);
    if r == g && g == b {
        stream::fill(pixels.as_flattened_mut(), color[0]);
    } else {
        pixels.fill(color);
    }
}

/// Values compared at once by [`run_end`]: one 512-bit vector of `u32`.
const RUN_CHUNK: usize = 16;

/// The end of the run of values equal to `row[start]` that starts at `start` (`start < len`).
///
/// Short runs (a visible triangle's span: 2–3 pixels on average) are followed value by value;
/// past [`RUN_CHUNK`] values, whole chunks are skipped with one array comparison (a few vector
/// instructions). Background runs span hundreds of pixels, and the value-by-value search had
/// cost 5 instructions for every pixel of the image.
#[inline(always)]
fn run_end(row: &[u32], start: usize) -> usize {
    let s = row[start];
    let near = row.len().min(start + RUN_CHUNK);
    let mut end = start + 1 + row[start + 1..near].iter().take_while(|&&t| t == s).count();
    if end < near {
        return end;
    }
    while row
        .get(end..end + RUN_CHUNK)
        .is_some_and(|chunk| chunk == [s; RUN_CHUNK])
    {
        end += RUN_CHUNK;
    }
    end + row[end..].iter().take_while(|&&t| t == s).count()
}

/// Everything the pass needs that is constant over a frame.
pub(crate) struct DeferredPass<'a> {
    pub shader: BlinnPhong,
    pub albedo: Albedo<'a>,
    pub background: [f32; 3],
    pub two_sided: bool,
    pub intrinsics: Intrinsics,
    pub kind: DepthKind,
}

/// The set-ups of a tile: those overlapping it (`bin`, ids into `chunks`) and their planes
/// (`planes[k]` of set-up `bin[k]`). The tile's visibility buffer holds positions `k`.
#[derive(Clone, Copy)]
pub(crate) struct TileSetups<'a> {
    pub chunks: &'a [Vec<ScreenTriangle>],
    pub bin: &'a [u32],
    pub planes: &'a [SetupPlanes],
}

/// Visible pixels of a row awaiting shading: the scratch of [`DeferredPass::shade_tile`], kept
/// by each worker across tiles.
pub(crate) struct Block {
    /// Number of pixels held.
    len: usize,
    /// Their columns.
    column: [u32; LANES],
    /// Their set-up's `ΣE` and their values of its planes ([`SetupPlanes::at`]: `D`, then the
    /// numerators of the normal and of the albedo source), divided at flush. All planes of a
    /// pixel side by side: one vector store, and the evaluation vectorises.
    edge_sum: [f64; LANES],
    planes: [[f64; LINES]; LANES],
    /// Their depth-buffer values.
    depth: [f32; LANES],
    /// Their ray coordinate `x' = (u − c_x)/f_x`.
    ray_x: [f32; LANES],
    /// Their texel-space positions (textured albedo only, sampled at flush).
    texel: [[f64; LANES]; 2],
    /// Scratch of the texture sampling.
    taps: TapLanes,
    /// `normal`: interpolated, not yet normalised; `albedo`: final; `view`: filled at flush.
    surface: SurfaceLanes,
}

impl Default for Block {
    fn default() -> Self {
        Block {
            len: 0,
            column: [0; LANES],
            edge_sum: [0.0; LANES],
            planes: [[0.0; LINES]; LANES],
            depth: [0.0; LANES],
            ray_x: [0.0; LANES],
            texel: [[0.0; LANES]; 2],
            taps: TapLanes::default(),
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
    /// Shades the tile of image rows from `row0` on whose visibility buffer is `index`
    /// (positions in `tile.bin`, replaced here by set-up ids) into `out`.
    ///
    /// On x86-64 CPUs with AVX-512 or AVX2 the pass is compiled again for their wide vectors and
    /// chosen at run time ([`with_simd`]); Rust never fuses or reorders floating-point
    /// operations, so the results are identical.
    pub(crate) fn shade_tile(
        &self,
        block: &mut Block,
        row0: usize,
        tile: TileSetups<'_>,
        index: &mut [u32],
        out: Rows<'_>,
    ) {
        with_simd(
            #[inline(always)]
            || self.shade_tile_inline(block, row0, tile, index, out),
        )
    }

    #[inline(always)]
    fn shade_tile_inline(
        &self,
        block: &mut Block,
        row0: usize,
        tile: TileSetups<'_>,
        index: &mut [u32],
        out: Rows<'_>,
    ) {
        let w = self.intrinsics.width as usize;
        // Rows of the optional buffers, or empty rows when a buffer is not wanted.
        let mut t_rows = out.triangle.chunks_mut(w);
        let mut b_rows = out.bary.chunks_mut(w);
        for (r, ((setups, color), depth)) in index
            .chunks_mut(w)
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
            self.shade_row(block, row0 + r, &tile, setups, row);
        }
        // The background's streaming stores reach memory before the tile is handed back.
        stream::fence();
    }

    /// Shades row `y` whose visibility buffer row is `setups` into `row` (one image row; the
    /// visible triangle and barycentrics only where those buffers are not empty).
    #[inline(always)]
    fn shade_row(
        &self,
        block: &mut Block,
        y: usize,
        tile: &TileSetups<'_>,
        setups: &mut [u32],
        row: Rows<'_>,
    ) {
        let Rows {
            color: c_row,
            depth: d_row,
            triangle: t_row,
            bary: b_row,
        } = row;
        let k = &self.intrinsics;
        let yf = y as f64;
        let yr = (yf - k.cy) * (1.0 / k.fy);
        let yr2_plus_1 = yr * yr + 1.0;
        let w = c_row.len();
        let mut x = 0;
        while x < w {
            let s = setups[x];
            // (`NO_TRIANGLE` lies past the end of every bin.)
            let Some((&id, sp)) = tile.bin.get(s as usize).zip(tile.planes.get(s as usize)) else {
                let end = run_end(setups, x);
                fill_color(&mut c_row[x..end], self.background);
                stream::fill(&mut d_row[x..end], 0.0);
                if let Some(t) = t_row.get_mut(x..end) {
                    t.fill(NO_TRIANGLE);
                }
                if let Some(b) = b_row.get_mut(x..end) {
                    b.fill([0.0; 3]);
                }
                x = end;
                continue;
            };
            // The visibility buffer gets the set-up id in place of the position in the bin.
            setups[x] = id;
            // The set-up itself only for the optional buffers: the planes hold the rest.
            if !(t_row.is_empty() && b_row.is_empty()) {
                let st = &tile.chunks[(id >> 16) as usize][(id & 0xffff) as usize];
                if let Some(t) = t_row.get_mut(x) {
                    *t = st.triangle();
                }
                if let Some(b) = b_row.get_mut(x) {
                    // Exactly as the depth renderer computes them.
                    let (wt, _) = st.corner_weights(&st.rows(yf), x as f64);
                    *b = st.mesh_bary(&wt).map(|v| v as f32);
                }
            }
            if block.len == LANES {
                self.flush(block, yr, yr2_plus_1, c_row, d_row);
            }
            // Step 7: every plane at this pixel (integers far below 2⁵³, converted exactly),
            // divided at flush, lane-parallel (one division per pixel, and square roots only
            // for ray depth, were the bottleneck here).
            let u = (x as i64 - sp.origin[0] as i64) as f64;
            let v = (y as i64 - sp.origin[1] as i64) as f64;
            let at = sp.at(u, v);
            let l = block.len;
            block.column[l] = x as u32;
            block.edge_sum[l] = sp.edge_sum;
            block.planes[l] = at;
            block.len += 1;
            x += 1;
        }
        self.flush(block, yr, yr2_plus_1, c_row, d_row);
    }

    /// Step 7's divisions for the first `m` pixels of `block`: depth-buffer value, ray
    /// coordinate, normal (not yet normalised) and albedo source from `ΣE` and the planes'
    /// values (`z = ΣE / D`, attribute `= numerator / D`). `yr2_plus_1` is the row's `y'² + 1`.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // `l` indexes several lane arrays
    fn divide(&self, block: &mut Block, m: usize, yr2_plus_1: f64) {
        let m = m.min(LANES);
        let k = &self.intrinsics;
        let inv_fx = 1.0 / k.fx;
        let planes = &block.planes;
        let mut inv_d = [0.0; LANES];
        let mut z = [0.0; LANES];
        let mut xr = [0.0; LANES];
        for l in 0..m {
            inv_d[l] = 1.0 / planes[l][0];
            z[l] = block.edge_sum[l] * inv_d[l];
            xr[l] = (block.column[l] as f64 - k.cx) * inv_fx;
            block.ray_x[l] = xr[l] as f32;
        }
        // One loop per depth kind: the square root only where it is needed.
        match self.kind {
            DepthKind::Z => {
                for l in 0..m {
                    block.depth[l] = z[l] as f32;
                }
            }
            DepthKind::Ray => {
                for l in 0..m {
                    block.depth[l] = (z[l] * (xr[l] * xr[l] + yr2_plus_1).sqrt()) as f32;
                }
            }
        }
        let s = &mut block.surface;
        for (c, normal) in s.normal.iter_mut().enumerate() {
            for l in 0..m {
                normal[l] = (planes[l][NORMAL + c] * inv_d[l]) as f32;
            }
        }
        match self.albedo {
            Albedo::Texture { .. } => {
                for (c, texel) in block.texel.iter_mut().enumerate() {
                    for l in 0..m {
                        texel[l] = planes[l][ALBEDO + c] * inv_d[l];
                    }
                }
            }
            Albedo::VertexColors => {
                for (c, albedo) in s.albedo.iter_mut().enumerate() {
                    for l in 0..m {
                        albedo[l] = (planes[l][ALBEDO + c] * inv_d[l]) as f32;
                    }
                }
            }
            Albedo::Constant(color) => {
                for (albedo, value) in s.albedo.iter_mut().zip(color) {
                    albedo[..m].fill(value);
                }
            }
        }
    }

    /// Shades the pixels of `block` into `c_row` and `d_row` and empties it. `yr` and
    /// `yr2_plus_1` are the row's ray coordinate `y'` and `y'² + 1`.
    #[inline(always)]
    fn flush(
        &self,
        block: &mut Block,
        yr: f64,
        yr2_plus_1: f64,
        c_row: &mut [[f32; 3]],
        d_row: &mut [f32],
    ) {
        let m = block.len.min(LANES);
        if m == 0 {
            return;
        }
        self.divide(block, m, yr2_plus_1);
        let s = &mut block.surface;
        let (yr, yr2_plus_1) = (yr as f32, yr2_plus_1 as f32);
        if let Albedo::Texture { texture, wrap } = self.albedo {
            texture.sample_rgb_lanes(&block.texel, m, wrap, &mut block.taps, &mut s.albedo);
        }
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
        let [r, g, b] = &s.albedo;
        let first = block.column[0] as usize;
        let contiguous = block.column[m - 1] as usize == first + m - 1;
        match (
            c_row.get_mut(first..first + m),
            d_row.get_mut(first..first + m),
        ) {
            // Contiguous columns (no background in between, the usual case): one interleaving
            // copy, which vectorises, and one plain copy.
            (Some(out), Some(depth)) if contiguous => {
                for (k, out) in out.iter_mut().enumerate() {
                    *out = [r[k], g[k], b[k]];
                }
                depth.copy_from_slice(&block.depth[..m]);
            }
            _ => {
                for (k, &x) in block.column[..m].iter().enumerate() {
                    c_row[x as usize] = [r[k], g[k], b[k]];
                    d_row[x as usize] = block.depth[k];
                }
            }
        }
        block.len = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_end_finds_the_end_of_every_run() {
        // Runs of every length from 1 to 40 (across and within chunks), ending at the row's end.
        let mut row = Vec::new();
        for (k, len) in (1..=40).chain([3, 1]).enumerate() {
            row.extend(std::iter::repeat_n(k as u32 % 3, len));
        }
        let mut start = 0;
        while start < row.len() {
            let expected = start
                + row[start..]
                    .iter()
                    .take_while(|&&t| t == row[start])
                    .count();
            for x in start..expected {
                assert_eq!(run_end(&row, x), expected, "from {x}");
            }
            start = expected;
        }
    }
}
