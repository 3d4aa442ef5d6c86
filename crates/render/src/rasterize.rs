//! Tile-parallel scan conversion with a z-buffer: steps 1–2, 5–7 and 10 of Algorithm 3.
//!
//! Pipeline per frame:
//! 1. every vertex goes to camera space (`[R t]·M`) and clip space (`P·F`, Eq. (6.1)), gets its
//!    frustum outcode, and is divided by `w` and mapped by the viewport;
//! 2. every triangle is trivially rejected against the frustum or clipped against the near/far
//!    planes ([`crate::clip`]; new corners are divided and mapped then), and set up as a
//!    [`ScreenTriangle`] (edge functions, `1/w` at the corners, bounding box);
//! 3. the set-ups are binned into horizontal tiles of [`TILE_ROWS`] image rows; tiles are
//!    rasterised in parallel (rayon), each owning its slice of the visibility buffer and
//!    scanned into its worker thread's tile-sized z-buffer.
//!
//! The result is a *visibility buffer*: per pixel the camera `z` of the nearest surface and the
//! set-up that produced it. Attributes (exact depth, barycentrics, normals, UVs) are reconstructed
//! once per visible pixel afterwards ([`Rasterizer::fragment`]), so overdraw costs only the depth
//! test. Depth ties are won by the lower triangle index, independently of the thread schedule.

use std::cell::RefCell;

use rayon::prelude::*;

use crate::camera::Camera;
use crate::clip::{clip_triangle, far_distance, near_distance, ClipVertex};
use crate::edge::{signed_area2, Edge};
use crate::mat4::Mat4;
use crate::plane::Plane;
use crate::projection::viewport;
use crate::simd::with_simd;
use crate::RenderError;

/// Image rows per tile: the unit of parallel work and of visibility-buffer ownership.
pub const TILE_ROWS: usize = 16;

/// Vertices per parallel task of the vertex transforms.
const VERTEX_CHUNK: usize = 4096;

/// Triangles per parallel set-up task (at least; grows for huge meshes so that the chunk count
/// fits the 16-bit half of a set-up id).
const SETUP_CHUNK: usize = 2048;

/// Set-up ids are `chunk << 16 | index in chunk`; a chunk holds at most 3 set-ups per triangle.
const MAX_CHUNK_TRIANGLES: usize = 0xffff / 3;

/// Index stored in the visibility buffer for background pixels.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// Which triangles to discard by orientation.
///
/// A triangle `(v₀, v₁, v₂)` is *front-facing* when its normal `(v₁ − v₀) × (v₂ − v₀)` points
/// towards the camera, i.e. it runs counter-clockwise on screen (the OpenGL default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CullMode {
    /// Draw every triangle (open meshes such as a reconstructed face are seen from both sides).
    #[default]
    None,
    /// Discard triangles facing away from the camera.
    Back,
    /// Discard triangles facing the camera.
    Front,
}

/// A triangle ready for scan conversion, in pixel coordinates, oriented so that its interior has
/// `E > 0` on all three edges. One mesh triangle yields up to three of these after clipping.
#[derive(Clone, Copy, Debug)]
pub struct ScreenTriangle {
    /// `edges[i]` is opposite corner `i`: `E_i(p) ∝ λ_i(p)`, the screen-space barycentric.
    edges: [Edge; 3],
    /// `1/w = 1/z_camera` at the corners.
    inv_w: [f64; 3],
    /// Barycentric coordinates of the corners in the original mesh triangle (`f32`: they only
    /// weight attributes; depth comes from `inv_w` in `f64`).
    bary: [[f32; 3]; 3],
    /// When the corners are the mesh triangle's vertices (`bary` a permutation of the identity,
    /// as for every unclipped set-up): for each vertex `j`, its corner `i` (`bary[i] = e_j`).
    vertex_corners: Option<[u8; 3]>,
    /// Inclusive pixel bounding box, already clamped to the image.
    x0: i32,
    x1: i32,
    y0: i32,
    y1: i32,
    /// Index of the mesh triangle.
    triangle: u32,
    front_facing: bool,
}

/// A visible surface sample at a pixel centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// Index of the mesh triangle.
    pub triangle: u32,
    /// Camera-space depth `z` in metres, exact to `f64` rounding (interpolated as `1/z`, which is
    /// affine in screen space).
    pub z: f64,
    /// Perspective-correct barycentric coordinates in the mesh triangle (sum to 1): the surface
    /// point is `Σ bary[i] · v_i`.
    pub bary: [f64; 3],
    /// Whether the triangle faces the camera (see [`CullMode`]).
    pub front_facing: bool,
}

/// Reusable rasteriser state: per-vertex transforms, triangle set-ups, tile bins and the
/// visibility buffer. Create once, call [`Rasterizer::rasterize`] per frame (no allocation once
/// the buffers, and each worker thread's tile z-buffer, have grown to the frame's size).
#[derive(Debug, Default)]
pub struct Rasterizer {
    width: u32,
    height: u32,
    camera_positions: Vec<[f64; 3]>,
    vertices: Vec<ProjectedVertex>,
    setup_chunks: Vec<Vec<ScreenTriangle>>,
    /// Per set-up chunk and tile, the ids of the chunk's set-ups that overlap the tile.
    chunk_bins: Vec<Vec<Vec<u32>>>,
    /// Per tile, the ids of the set-ups that overlap it, in triangle order.
    bins: Vec<Vec<u32>>,
    index: Vec<u32>,
}

impl Rasterizer {
    /// An empty rasteriser; buffers grow on first use.
    pub fn new() -> Rasterizer {
        Rasterizer::default()
    }

    /// Image width of the last frame, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height of the last frame, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Camera-space vertex positions of the last frame (`[R t] · M · v`, metres), #V × 3.
    pub fn camera_positions(&self) -> &[[f64; 3]] {
        &self.camera_positions
    }

    /// Rasterises `triangles` over `positions` (object space, #V × 3) seen through `camera`
    /// after the model transform `model` (object → world, an affine 4×4 `M_k` of Eq. (6.1)).
    ///
    /// # Errors
    /// A triangle index out of range, a non-finite position, a non-affine or non-finite `model`,
    /// an invalid camera. Nothing panics on bad input.
    pub fn rasterize(
        &mut self,
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        model: &Mat4,
        camera: &Camera,
        cull: CullMode,
    ) -> Result<(), RenderError> {
        camera.validate()?;
        crate::validate::check_model(model)?;
        crate::validate::check_positions(positions)?;
        crate::validate::check_triangles(triangles, positions.len())?;
        self.rasterize_valid(positions, triangles, model, camera, cull)
    }

    /// [`Rasterizer::rasterize`] of geometry validated by the caller (finite positions, vertex
    /// indices in range), which is not checked again.
    pub(crate) fn rasterize_valid(
        &mut self,
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        model: &Mat4,
        camera: &Camera,
        cull: CullMode,
    ) -> Result<(), RenderError> {
        self.set_up(positions, triangles, model, camera, cull)?;
        let n_tiles = self.bins.len();
        self.scan_tiles((0..n_tiles).into_par_iter(), |_, _, _, bin, index| {
            positions_to_ids(bin, index)
        });
        Ok(())
    }

    /// The first half of [`Rasterizer::rasterize`]: vertex transforms, triangle set-ups and
    /// binning into tiles ([`Rasterizer::setup_chunks`] is ready afterwards).
    ///
    /// # Panics
    /// If a vertex index is out of range: the callers validate the geometry (positions finite,
    /// indices in range) once per frame, before anything else is computed.
    pub(crate) fn set_up(
        &mut self,
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        model: &Mat4,
        camera: &Camera,
        cull: CullMode,
    ) -> Result<(), RenderError> {
        camera.validate()?;
        crate::validate::check_model(model)?;

        let k = &camera.intrinsics;
        let (width, height) = (k.width, k.height);
        self.width = width;
        self.height = height;

        // Step 1–2 of Algorithm 3: per-vertex transforms.
        let model_view = Mat4::from_rigid(&camera.pose).mul(model);
        let to_clip = camera.camera_to_clip();
        self.camera_positions.resize(positions.len(), [0.0; 3]);
        self.vertices
            .resize(positions.len(), ProjectedVertex::default());
        positions
            .par_chunks(VERTEX_CHUNK)
            .zip(self.camera_positions.par_chunks_mut(VERTEX_CHUNK))
            .zip(self.vertices.par_chunks_mut(VERTEX_CHUNK))
            .for_each(|((positions, camera), vertices)| {
                with_simd(
                    #[inline(always)]
                    || {
                        let size = [width, height];
                        project_vertices(positions, &model_view, &to_clip, camera, vertices, size)
                    },
                )
            });

        // Triangle set-up, in parallel over chunks; chunk order keeps triangle order.
        let chunk_len = SETUP_CHUNK.max(triangles.len().div_ceil(0xffff));
        if chunk_len > MAX_CHUNK_TRIANGLES {
            return Err(RenderError::Parameter {
                field: "triangle count",
                value: triangles.len() as f64,
                reason: "more triangles than the rasteriser can index (about 1.4 billion)",
            });
        }
        let n_chunks = triangles.len().div_ceil(chunk_len);
        let n_tiles = (height as usize).div_ceil(TILE_ROWS);
        self.setup_chunks.resize_with(n_chunks, Vec::new);
        self.chunk_bins.resize_with(n_chunks, Vec::new);
        let vertices = &self.vertices;
        triangles
            .par_chunks(chunk_len)
            .zip(self.setup_chunks.par_iter_mut())
            .zip(self.chunk_bins.par_iter_mut())
            .enumerate()
            .for_each(|(c, ((chunk, out), bins))| {
                out.clear();
                bins.resize_with(n_tiles, Vec::new);
                bins.iter_mut().for_each(Vec::clear);
                let first = (c * chunk_len) as u32;
                with_simd(
                    #[inline(always)]
                    || set_up_triangles(vertices, chunk, first, [width, height], cull, out),
                );
                // Binning into row tiles, while the chunk's set-ups are in cache.
                for (k, st) in out.iter().enumerate() {
                    let id = (c << 16 | k) as u32;
                    let tiles = st.y0 as usize / TILE_ROWS..=st.y1 as usize / TILE_ROWS;
                    bins[tiles].iter_mut().for_each(|bin| bin.push(id));
                }
            });
        // Each tile's bin: those of the chunks, in chunk (so triangle) order.
        let chunk_bins = &self.chunk_bins;
        self.bins.resize_with(n_tiles, Vec::new);
        self.bins
            .par_iter_mut()
            .enumerate()
            .for_each(|(tile, bin)| {
                bin.clear();
                for bins in chunk_bins {
                    bin.extend_from_slice(&bins[tile]);
                }
            });
        Ok(())
    }

    /// The second half of [`Rasterizer::rasterize`]: tile-parallel scan conversion with depth
    /// test. Right after scanning tile `t` (rows `t · TILE_ROWS ..`), while its part of the
    /// visibility buffer is still in cache, calls `then(item, row0, setup_chunks, bin, index)`
    /// with the `t`-th of `per_tile` (one item per tile), the tile's first row, the ids of the
    /// set-ups that overlap the tile (in triangle order) and its rows of the visibility buffer
    /// — which at that point hold *positions in `bin`* ([`NO_TRIANGLE`] for background), so
    /// that per-tile data can be kept in a dense array. `then` must replace them by the set-up
    /// ids (`bin[k]`, see [`positions_to_ids`]).
    pub(crate) fn scan_tiles<T: Send>(
        &mut self,
        per_tile: impl IndexedParallelIterator<Item = T>,
        then: impl Fn(T, usize, &[Vec<ScreenTriangle>], &[u32], &mut [u32]) + Sync,
    ) {
        let width = self.width as usize;
        let n_pixels = width * self.height as usize;
        self.index.resize(n_pixels, NO_TRIANGLE);
        let tile_len = TILE_ROWS * width;
        let (chunks, bins) = (&self.setup_chunks, &self.bins);
        self.index
            .par_chunks_mut(tile_len)
            .zip(per_tile)
            .enumerate()
            .for_each(|(tile, (index, item))| {
                let row0 = tile * TILE_ROWS;
                let bin = &bins[tile];
                TILE_DEPTH.with_borrow_mut(|depth| {
                    depth.resize(tile_len, f32::INFINITY);
                    let depth = &mut depth[..index.len()];
                    scan_tile(chunks, bin, row0 as i32, width, depth, index);
                });
                then(item, row0, chunks, bin, index);
            });
    }

    /// The visible fragment at pixel `(x, y)`, or `None` for background or outside the image.
    pub fn fragment(&self, x: u32, y: u32) -> Option<Fragment> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let s = *self
            .index
            .get(y as usize * self.width as usize + x as usize)?;
        Some(self.setup(s)?.fragment(x as f64, y as f64))
    }

    /// The set-up with id `s` (`chunk << 16 | index`).
    #[inline(always)]
    pub(crate) fn setup(&self, s: u32) -> Option<&ScreenTriangle> {
        self.setup_chunks
            .get((s >> 16) as usize)?
            .get((s & 0xffff) as usize)
    }

    /// Row `y` of the visibility buffer (set-up indices, [`NO_TRIANGLE`] for background).
    ///
    /// # Panics
    /// If `y` is not a row of the last frame.
    #[inline]
    pub(crate) fn visibility_row(&self, y: usize) -> &[u32] {
        let w = self.width as usize;
        &self.index[y * w..(y + 1) * w]
    }

    /// The set-ups of the last frame, in triangle order (for coverage tests and custom passes).
    pub fn screen_triangles(&self) -> impl Iterator<Item = &ScreenTriangle> {
        self.setup_chunks.iter().flatten()
    }
}

impl ScreenTriangle {
    /// Index of the mesh triangle this set-up came from.
    pub fn triangle(&self) -> u32 {
        self.triangle
    }

    /// Calls `f(x, y)` for every pixel centre the triangle covers under the fill rule, without
    /// depth test.
    pub fn for_each_pixel(&self, mut f: impl FnMut(u32, u32)) {
        scan(self, self.y0, self.y1, |x, y, _| f(x as u32, y as u32));
    }

    /// Perspective-correct reconstruction at pixel centre `(x, y)` (assumed covered).
    #[inline(always)]
    fn fragment(&self, x: f64, y: f64) -> Fragment {
        let (w, z) = self.corner_weights(&self.rows(y), x);
        Fragment {
            triangle: self.triangle,
            z,
            bary: self.mesh_bary(&w),
            front_facing: self.front_facing,
        }
    }

    /// The row-constant parts of the three edge functions at pixel row `y` (hoisted out of a
    /// span of pixels; [`ScreenTriangle::corner_weights`] takes them).
    #[inline(always)]
    pub(crate) fn rows(&self, y: f64) -> [f64; 3] {
        std::array::from_fn(|i| self.edges[i].row(y))
    }

    /// Perspective-correct weights of this set-up's three corners at pixel centre `(x, y)`
    /// (`rows = self.rows(y)`, the centre assumed covered), and the camera depth `z` there.
    ///
    /// The same operations in the same order as [`Rasterizer::fragment`], so depth and
    /// barycentrics are bit-identical between it, the depth renderer and the colour renderer's
    /// barycentric buffer. (The colour renderer interpolates depth and attributes with the
    /// planes of [`ScreenTriangle::perspective_planes`]; its depth agrees to ~10⁻¹³ relative.)
    #[inline(always)]
    pub(crate) fn corner_weights(&self, rows: &[f64; 3], x: f64) -> ([f64; 3], f64) {
        let e: [f64; 3] = std::array::from_fn(|i| self.edges[i].eval(rows[i], x));
        // λ_i = e_i / Σe; 1/z = Σ λ_i / w_i; perspective-correct weights (λ_i / w_i) · z.
        let sum = e[0] + e[1] + e[2];
        let q: [f64; 3] = std::array::from_fn(|i| e[i] * self.inv_w[i]);
        let inv_s = 1.0 / (q[0] + q[1] + q[2]);
        let w: [f64; 3] = std::array::from_fn(|i| q[i] * inv_s);
        (w, sum * inv_s)
    }

    /// Barycentrics in the mesh triangle from corner weights `w` (see
    /// [`ScreenTriangle::corner_weights`]).
    #[inline(always)]
    pub(crate) fn mesh_bary(&self, w: &[f64; 3]) -> [f64; 3] {
        let b = &self.bary;
        std::array::from_fn(|j| {
            w[0] * b[0][j] as f64 + w[1] * b[1][j] as f64 + w[2] * b[2][j] as f64
        })
    }

    /// Barycentric coordinates of the set-up's corners in the mesh triangle: row `i` is corner
    /// `i` (identity rows up to order unless the triangle was clipped).
    #[inline(always)]
    pub(crate) fn corner_bary(&self) -> &[[f32; 3]; 3] {
        &self.bary
    }

    /// For a set-up whose corners are the mesh triangle's vertices, the corner of each vertex
    /// (`corner_bary()[corner[j]] = e_j`); `None` when clipping made new corners.
    #[inline(always)]
    pub(crate) fn vertex_corners(&self) -> Option<[u8; 3]> {
        self.vertex_corners
    }

    /// The top-left pixel `(x₀, y₀)` of the bounding box: the origin of
    /// [`ScreenTriangle::perspective_planes`].
    pub(crate) fn origin(&self) -> [i32; 2] {
        [self.x0, self.y0]
    }

    /// `q_i = E_i / w_i` for the three corners as affine functions of the pixel centre about
    /// [`ScreenTriangle::origin`], and `ΣE_i` there (twice the screen area).
    ///
    /// `E_i` is proportional to the screen-space barycentric `λ_i` and `1/w` is affine in
    /// screen space, so each `q_i` is: `1/z = Σq_i / ΣE_i` and the perspective-correct weight
    /// of corner `i` is `q_i / Σq_i` ([`crate::interpolation`]).
    #[inline(always)]
    pub(crate) fn perspective_planes(&self) -> ([Plane; 3], f64) {
        let (x, y) = (self.x0 as f64, self.y0 as f64);
        let [e0, e1, e2] = &self.edges;
        let e = [e0.plane_at(x, y), e1.plane_at(x, y), e2.plane_at(x, y)];
        let planes = std::array::from_fn(|i| Plane {
            c: e[i][0] * self.inv_w[i],
            dx: e[i][1] * self.inv_w[i],
            dy: e[i][2] * self.inv_w[i],
        });
        (planes, e[0][0] + e[1][0] + e[2][0])
    }

    /// [`ScreenTriangle::perspective_planes`] with each plane in the lanes `(c, dx, dy, 0)` of
    /// one AVX register: the same operations.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    #[target_feature(enable = "avx")]
    pub(crate) fn perspective_planes_x4(&self) -> ([std::arch::x86_64::__m256d; 3], f64) {
        use std::arch::x86_64::*;
        let (x, y) = (self.x0 as f64, self.y0 as f64);
        let [e0, e1, e2] = &self.edges;
        let e = [e0.plane_at(x, y), e1.plane_at(x, y), e2.plane_at(x, y)];
        let plane = |[c, dx, dy]: [f64; 3], inv_w: f64| {
            _mm256_mul_pd(_mm256_setr_pd(c, dx, dy, 0.0), _mm256_set1_pd(inv_w))
        };
        let planes = [
            plane(e[0], self.inv_w[0]),
            plane(e[1], self.inv_w[1]),
            plane(e[2], self.inv_w[2]),
        ];
        (planes, e[0][0] + e[1][0] + e[2][0])
    }
}

thread_local! {
    /// The z-buffer of the tile a thread is scanning ([`Rasterizer::scan_tiles`]): depths are
    /// not needed once a tile is scanned, and one tile-sized buffer per thread stays in cache
    /// where a whole-frame one would come from memory every frame.
    static TILE_DEPTH: RefCell<Vec<f32>> = const { RefCell::new(Vec::new()) };
}

/// Replaces positions in `bin` by the set-up ids there ([`NO_TRIANGLE`] stays: bins are
/// shorter).
pub(crate) fn positions_to_ids(bin: &[u32], index: &mut [u32]) {
    for s in index {
        *s = bin.get(*s as usize).copied().unwrap_or(NO_TRIANGLE);
    }
}

/// Scan-converts the set-ups `bin` (ids into `chunks`) into one tile of the visibility buffer:
/// `depth` and `index` hold whole image rows of `width` pixels from row `row0` on; `index`
/// receives positions in `bin`.
///
/// On x86-64 CPUs with AVX-512 this runs [`scan_avx512`] (eight pixels at a time), else on those
/// with AVX2 [`scan_avx2`] (four), chosen at run time; both perform lane by lane the operations
/// of [`scan`] and Rust never fuses or reorders floating-point operations, so coverage and depth
/// are identical.
fn scan_tile(
    chunks: &[Vec<ScreenTriangle>],
    bin: &[u32],
    row0: i32,
    width: usize,
    depth: &mut [f32],
    index: &mut [u32],
) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx512f") && has!("avx512vl") {
            // SAFETY: `scan_tile_avx512` is compiled for AVX-512 F and VL, which the run-time
            // check just above found on this CPU; its own unsafe blocks state their bounds.
            unsafe { scan_tile_avx512(chunks, bin, row0, width, depth, index) };
            return;
        }
        if has!("avx2") {
            // SAFETY: `scan_tile_avx2` is compiled for AVX2, which the run-time check just
            // above found on this CPU; its own unsafe blocks state their bounds.
            unsafe { scan_tile_avx2(chunks, bin, row0, width, depth, index) };
            return;
        }
    }
    scan_tile_scalar(chunks, bin, row0, width, depth, index);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl")]
fn scan_tile_avx512(
    chunks: &[Vec<ScreenTriangle>],
    bin: &[u32],
    row0: i32,
    width: usize,
    depth: &mut [f32],
    index: &mut [u32],
) {
    for_each_setup(
        chunks,
        bin,
        row0,
        width,
        depth,
        index,
        |st, s, y0, y1, depth, index| scan_avx512(st, s, y0, y1, row0, width, depth, index),
    );
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn scan_tile_avx2(
    chunks: &[Vec<ScreenTriangle>],
    bin: &[u32],
    row0: i32,
    width: usize,
    depth: &mut [f32],
    index: &mut [u32],
) {
    for_each_setup(
        chunks,
        bin,
        row0,
        width,
        depth,
        index,
        |st, s, y0, y1, depth, index| scan_avx2(st, s, y0, y1, row0, width, depth, index),
    );
}

/// [`scan_tile`] one pixel at a time, on any CPU.
fn scan_tile_scalar(
    chunks: &[Vec<ScreenTriangle>],
    bin: &[u32],
    row0: i32,
    width: usize,
    depth: &mut [f32],
    index: &mut [u32],
) {
    for_each_setup(
        chunks,
        bin,
        row0,
        width,
        depth,
        index,
        |st, s, y0, y1, depth, index| {
            scan(st, y0, y1, |x, y, z| {
                let p = (y - row0) as usize * width + x as usize;
                // Step 7 of Algorithm 3; strict `<`, so of equal depths the first set-up scanned
                // (the lower triangle index) wins.
                if z < depth[p] {
                    depth[p] = z;
                    index[p] = s;
                }
            })
        },
    );
}

/// Clears the tile (`depth` to `∞`, `index` to [`NO_TRIANGLE`]) and calls
/// `scan_setup(st, k, y0, y1, depth, index)` for the set-ups of `bin` in order, with `k` the
/// position in `bin` (what the tile's visibility buffer stores, see
/// [`Rasterizer::scan_tiles`]) and the rows `y0..=y1` of set-up `st` in the tile.
#[inline(always)]
fn for_each_setup(
    chunks: &[Vec<ScreenTriangle>],
    bin: &[u32],
    row0: i32,
    width: usize,
    depth: &mut [f32],
    index: &mut [u32],
    mut scan_setup: impl FnMut(&ScreenTriangle, u32, i32, i32, &mut [f32], &mut [u32]),
) {
    depth.fill(f32::INFINITY);
    index.fill(NO_TRIANGLE);
    let row1 = row0 + (depth.len() / width) as i32 - 1;
    for (k, &s) in bin.iter().enumerate() {
        let st = &chunks[(s >> 16) as usize][(s & 0xffff) as usize];
        scan_setup(st, k as u32, row0.max(st.y0), row1.min(st.y1), depth, index);
    }
}

/// Steps 5–7 of Algorithm 3 for set-up `st` (id `s`), four pixel centres of a row at a time:
/// coverage under the fill rule, depth and depth test of rows `y0..=y1` in the tile of
/// [`scan_tile`] (`depth` and `index` hold image rows of `width` pixels from row `row0` on).
///
/// Lane by lane the operations of [`scan`] and of the depth test of [`scan_tile_scalar`] (the
/// [`Edge`] twins, then `z = Σe / Σ(e_i / w_i)` in the same order, rounded to `f32`, strict `<`),
/// so coverage, depths and tie-breaking are bit-identical.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
fn scan_avx2(
    st: &ScreenTriangle,
    s: u32,
    y0: i32,
    y1: i32,
    row0: i32,
    width: usize,
    depth: &mut [f32],
    index: &mut [u32],
) {
    use std::arch::x86_64::*;
    let [e0, e1, e2] = &st.edges;
    let [w0, w1, w2] = st.inv_w.map(|w| _mm256_set1_pd(w));
    // Pixel coordinates are integers far below 2⁵³: `x0 + l` and the steps of 4 are exact.
    let x_first = _mm256_add_pd(
        _mm256_set1_pd(st.x0 as f64),
        _mm256_setr_pd(0.0, 1.0, 2.0, 3.0),
    );
    let x_last = _mm256_set1_pd(st.x1 as f64);
    let step = _mm256_set1_pd(4.0);
    // The low 32 bits of each 64-bit lane, to narrow a lane mask of `f64` to one of `f32`.
    let low_halves = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
    let id = _mm_set1_epi32(s as i32);
    // The bounding box is clamped to the image, so `0 ≤ x0 ≤ x1 < width`.
    let (x0, x1) = (st.x0 as usize, st.x1 as usize);
    for y in y0..=y1 {
        let yf = y as f64;
        let (r0, r1, r2) = (e0.row(yf), e1.row(yf), e2.row(yf));
        let (r0, r1, r2) = (_mm256_set1_pd(r0), _mm256_set1_pd(r1), _mm256_set1_pd(r2));
        // The span `x0..=x1` of row `y`.
        let p = (y - row0) as usize * width;
        let (depth, index) = (&mut depth[p + x0..=p + x1], &mut index[p + x0..=p + x1]);
        let mut x = x_first;
        let mut in_run = false;
        for o in (0..depth.len()).step_by(4) {
            let (a, b, c) = (e0.eval_x4(r0, x), e1.eval_x4(r1, x), e2.eval_x4(r2, x));
            // Inside all three edges and the bounding box.
            let covered = _mm256_and_pd(
                _mm256_and_pd(e0.inside_x4(a), e1.inside_x4(b)),
                _mm256_and_pd(e2.inside_x4(c), _mm256_cmp_pd::<_CMP_LE_OQ>(x, x_last)),
            );
            let bits = _mm256_movemask_pd(covered);
            if bits != 0 {
                let sum = _mm256_add_pd(_mm256_add_pd(a, b), c);
                let q = _mm256_add_pd(
                    _mm256_add_pd(_mm256_mul_pd(a, w0), _mm256_mul_pd(b, w1)),
                    _mm256_mul_pd(c, w2),
                );
                // Rounded to nearest like `as f32` (Rust keeps the default rounding mode).
                let z = _mm256_cvtpd_ps(_mm256_div_pd(sum, q));
                let covered = _mm256_castps256_ps128(_mm256_permutevar8x32_ps(
                    _mm256_castpd_ps(covered),
                    low_halves,
                ));
                // SAFETY: `o < depth.len() = index.len()`, and the masked loads and stores touch
                // only covered lanes `o + l`, which lie in the bounding box (`x ≤ x1`), so in
                // the span (`o + l < depth.len()`).
                unsafe {
                    let (d, i) = (depth.as_mut_ptr().add(o), index.as_mut_ptr().add(o));
                    let old = _mm_maskload_ps(d, _mm_castps_si128(covered));
                    let nearer = _mm_castps_si128(_mm_and_ps(_mm_cmplt_ps(z, old), covered));
                    _mm_maskstore_ps(d, nearer, z);
                    _mm_maskstore_epi32(i.cast(), nearer, id);
                }
                // The covered centres of a row are one run (see `scan`): it ends in this group
                // unless the last lane is covered, else at the next group that covers none.
                if bits & 8 == 0 {
                    break;
                }
                in_run = true;
            } else if in_run {
                break;
            }
            x = _mm256_add_pd(x, step);
        }
    }
}

/// [`scan_avx2`] eight pixel centres of a row at a time, with mask registers: the lanes outside
/// the bounding box, the coverage and the depth test are bit masks, and the depth buffer is read
/// and written with masked loads and stores.
///
/// The row-dependent part of the edge functions ([`Edge::row`]) is computed once per row, eight
/// rows at a time, and the column-dependent part ([`Edge::column_x8`]) once per column of the
/// bounding box, by scanning the box in columns of eight pixels, each top to bottom: for the
/// small triangles of a face mesh (boxes at most 8 wide, one column) a row then costs one
/// subtraction and one multiplication per edge before the depth of Step 6. Each pixel is tested
/// at most once per set-up, so the order within a set-up does not change the z-buffer.
///
/// Lane by lane the operations of [`scan`] and of the depth test of [`scan_tile_scalar`], so
/// coverage, depths and tie-breaking are bit-identical. `y0..=y1` are at most [`TILE_ROWS`] rows.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl")]
#[allow(clippy::too_many_arguments)]
fn scan_avx512(
    st: &ScreenTriangle,
    s: u32,
    y0: i32,
    y1: i32,
    row0: i32,
    width: usize,
    depth: &mut [f32],
    index: &mut [u32],
) {
    use std::arch::x86_64::*;
    // The rows of a tile are computed eight at a time.
    const _: () = assert!(TILE_ROWS.is_multiple_of(8));
    let [e0, e1, e2] = &st.edges;
    let [w0, w1, w2] = st.inv_w.map(|w| _mm512_set1_pd(w));
    let id = _mm256_set1_epi32(s as i32);
    // Pixel coordinates are integers far below 2⁵³: `y0 + l` and `x0 + o + l` are exact.
    let lanes = _mm512_setr_pd(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0);
    // `rows[i][j]`: the row part of `E_i` (`Edge::row`) at row `y0 + j`.
    let n_rows = (y1 - y0 + 1) as usize;
    let mut rows = [[0.0; TILE_ROWS]; 3];
    for h in (0..n_rows).step_by(8) {
        let y = _mm512_add_pd(_mm512_set1_pd((y0 + h as i32) as f64), lanes);
        for (e, rows) in [e0, e1, e2].into_iter().zip(&mut rows) {
            let rows = &mut rows[h..h + 8];
            // SAFETY: `rows` is a (bounds-checked) slice of eight `f64`, which the unaligned
            // store writes.
            unsafe { _mm512_storeu_pd(rows.as_mut_ptr(), e.row_x8(y)) };
        }
    }
    let (r0, r1, r2) = (&rows[0][..n_rows], &rows[1][..n_rows], &rows[2][..n_rows]);
    // The bounding box is clamped to the image, so `0 ≤ x0 ≤ x1 < width`.
    let n = (st.x1 - st.x0) as usize + 1;
    for o in (0..n).step_by(8) {
        let x = _mm512_add_pd(_mm512_set1_pd((st.x0 as usize + o) as f64), lanes);
        let (c0, c1, c2) = (e0.column_x8(x), e1.column_x8(x), e2.column_x8(x));
        // The column's pixels in the bounding box: the first `m` lanes of rows `y0..=y1`.
        let m = (n - o).min(8);
        let in_box = (0xff_u32 >> (8 - m)) as __mmask8;
        let first = (y0 - row0) as usize * width + st.x0 as usize + o;
        let last = first + (n_rows - 1) * width + m;
        let (depth, index) = (&mut depth[first..last], &mut index[first..last]);
        for (j, ((&r0, &r1), &r2)) in r0.iter().zip(r1).zip(r2).enumerate() {
            let (r0, r1, r2) = (_mm512_set1_pd(r0), _mm512_set1_pd(r1), _mm512_set1_pd(r2));
            let (a, b, c) = (e0.eval_x8(r0, c0), e1.eval_x8(r1, c1), e2.eval_x8(r2, c2));
            let covered = e2.inside_x8(e1.inside_x8(e0.inside_x8(in_box, a), b), c);
            if covered == 0 {
                continue;
            }
            let sum = _mm512_add_pd(_mm512_add_pd(a, b), c);
            let q = _mm512_add_pd(
                _mm512_add_pd(_mm512_mul_pd(a, w0), _mm512_mul_pd(b, w1)),
                _mm512_mul_pd(c, w2),
            );
            // Rounded to nearest like `as f32` (Rust keeps the default rounding mode).
            let z = _mm512_cvtpd_ps(_mm512_div_pd(sum, q));
            // SAFETY: the masked loads and stores touch only covered lanes `l`, which are in the
            // box (`l < m`), so `j · width + l < depth.len() = index.len()`.
            unsafe {
                let (d, i) = (depth.as_mut_ptr(), index.as_mut_ptr());
                let (d, i) = (d.add(j * width), i.add(j * width));
                let old = _mm256_maskz_loadu_ps(covered, d);
                let nearer = _mm256_mask_cmp_ps_mask::<_CMP_LT_OQ>(covered, z, old);
                _mm256_mask_storeu_ps(d, nearer, z);
                _mm256_mask_storeu_epi32(i.cast(), nearer, id);
            }
        }
    }
}

/// Scan-converts rows `y0..=y1` of `st`, calling `f(x, y, z)` with the camera depth as `f32`.
#[inline]
fn scan(st: &ScreenTriangle, y0: i32, y1: i32, mut f: impl FnMut(i32, i32, f32)) {
    let [e0, e1, e2] = &st.edges;
    let [w0, w1, w2] = st.inv_w;
    for y in y0..=y1 {
        let yf = y as f64;
        let (r0, r1, r2) = (e0.row(yf), e1.row(yf), e2.row(yf));
        // Each edge function is monotone in x (every operation of `Edge::eval` rounds
        // monotonically), so the covered centres of a row are one run: stop at its end.
        let mut in_run = false;
        for x in st.x0..=st.x1 {
            let xf = x as f64;
            let (a, b, c) = (e0.eval(r0, xf), e1.eval(r1, xf), e2.eval(r2, xf));
            if e0.inside(a) & e1.inside(b) & e2.inside(c) {
                in_run = true;
                let z = (a + b + c) / (a * w0 + b * w1 + c * w2);
                f(x, y, z as f32);
            } else if in_run {
                break;
            }
        }
    }
}

/// A mesh vertex after steps 1–2 of Algorithm 3, computed once per vertex rather than once per
/// triangle using it: clip coordinates (Eq. (6.1)), the frustum planes it lies outside of, and
/// its pixel position and `1/w` (what the triangles that need no clipping use).
#[derive(Clone, Copy, Debug, Default)]
struct ProjectedVertex {
    clip: [f64; 4],
    /// Pixel position: perspective divide, then [`viewport`].
    pixel: [f64; 2],
    /// `1/w = 1/z_camera`.
    inv_w: f64,
    /// One bit per frustum plane the vertex is outside of ([`outcode`]).
    outcode: u8,
}

impl ProjectedVertex {
    #[inline(always)]
    fn new(clip: [f64; 4], width: u32, height: u32) -> ProjectedVertex {
        let (pixel, inv_w) = to_screen(&clip, width, height);
        ProjectedVertex {
            clip,
            pixel,
            inv_w,
            outcode: outcode(&clip),
        }
    }
}

/// The frustum planes clip-space point `v` is outside of, one bit each: right, left, top,
/// bottom, near, far (valid in homogeneous space, for trivial rejection).
#[inline(always)]
fn outcode(v: &[f64; 4]) -> u8 {
    ((v[3] - v[0] < 0.0) as u8)
        | ((v[3] + v[0] < 0.0) as u8) << 1
        | ((v[3] - v[1] < 0.0) as u8) << 2
        | ((v[3] + v[1] < 0.0) as u8) << 3
        | ((near_distance(*v) < 0.0) as u8) << 4
        | ((far_distance(*v) < 0.0) as u8) << 5
}

/// The outcode bits of the near and far planes, the ones clipped geometrically.
const NEAR_FAR: u8 = 0b11_0000;

/// Perspective divide and viewport: the pixel position and `1/w` of clip-space point `c`.
#[inline(always)]
fn to_screen(c: &[f64; 4], width: u32, height: u32) -> ([f64; 2], f64) {
    let inv_w = 1.0 / c[3];
    (viewport(width, height, [c[0] * inv_w, c[1] * inv_w]), inv_w)
}

/// Corners of a triangle about to be set up: pixel positions, `1/w`, and barycentric
/// coordinates in the mesh triangle (`f32`: they only weight attributes).
struct Corners {
    pixel: [[f64; 2]; 3],
    inv_w: [f64; 3],
    bary: [[f32; 3]; 3],
}

/// Steps 1–2 of Algorithm 3 for `positions`: their camera-space images under `model_view` into
/// `camera`, and the clip-space images of those under `to_clip`, projected to an image of
/// `size` pixels, into `vertices`.
#[inline(always)]
fn project_vertices(
    positions: &[[f64; 3]],
    model_view: &Mat4,
    to_clip: &Mat4,
    camera: &mut [[f64; 3]],
    vertices: &mut [ProjectedVertex],
    [width, height]: [u32; 2],
) {
    for ((p, cam), v) in positions.iter().zip(camera).zip(vertices) {
        *cam = model_view.transform_point(*p);
        *v = ProjectedVertex::new(to_clip.transform_point4(*cam), width, height);
    }
}

/// [`setup_triangle`] for `triangles`, the first of which has index `first`, in order.
#[inline(always)]
fn set_up_triangles(
    vertices: &[ProjectedVertex],
    triangles: &[[u32; 3]],
    first: u32,
    [width, height]: [u32; 2],
    cull: CullMode,
    out: &mut Vec<ScreenTriangle>,
) {
    for (i, t) in triangles.iter().enumerate() {
        setup_triangle(vertices, *t, first + i as u32, width, height, cull, out);
    }
}

/// Rejects, clips and sets up mesh triangle `t` (index `id`) over the projected `vertices`,
/// appending 0–3 screen triangles.
#[inline(always)]
fn setup_triangle(
    vertices: &[ProjectedVertex],
    t: [u32; 3],
    id: u32,
    width: u32,
    height: u32,
    cull: CullMode,
    out: &mut Vec<ScreenTriangle>,
) {
    let v = [
        &vertices[t[0] as usize],
        &vertices[t[1] as usize],
        &vertices[t[2] as usize],
    ];
    // Trivial rejection: all corners outside one frustum plane.
    let o = [v[0].outcode, v[1].outcode, v[2].outcode];
    if o[0] & o[1] & o[2] != 0 {
        return;
    }
    // Between the near and far planes (almost always) the triangle is its own clipped polygon,
    // with its vertices already projected.
    if (o[0] | o[1] | o[2]) & NEAR_FAR == 0 {
        let corners = Corners {
            pixel: [v[0].pixel, v[1].pixel, v[2].pixel],
            inv_w: [v[0].inv_w, v[1].inv_w, v[2].inv_w],
            bary: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        };
        set_up_corners(corners, true, id, width, height, cull, out);
        return;
    }
    let corner = |k: usize| {
        let mut bary = [0.0; 3];
        bary[k] = 1.0;
        ClipVertex {
            clip: v[k].clip,
            bary,
        }
    };
    let polygon = clip_triangle([corner(0), corner(1), corner(2)]);
    let vs = polygon.vertices();
    // The fan around `vs[0]` (nothing for fewer than 3 vertices).
    let project = |v: &ClipVertex| (to_screen(&v.clip, width, height), v.bary.map(|b| b as f32));
    let first = project(&vs[0]);
    for i in 1..vs.len().saturating_sub(1) {
        let (((p1, w1), b1), ((p2, w2), b2)) = (project(&vs[i]), project(&vs[i + 1]));
        let corners = Corners {
            pixel: [first.0 .0, p1, p2],
            inv_w: [first.0 .1, w1, w2],
            bary: [first.1, b1, b2],
        };
        set_up_corners(corners, false, id, width, height, cull, out);
    }
}

/// Sets up the triangle `c` (inside the near and far planes) for mesh triangle `id`: culling,
/// orientation, edge functions and bounding box; nothing for degenerate or culled triangles and
/// those whose box holds no pixel centre. `unclipped`: the corners are the mesh triangle's
/// vertices in order.
#[inline(always)]
fn set_up_corners(
    c: Corners,
    unclipped: bool,
    id: u32,
    width: u32,
    height: u32,
    cull: CullMode,
    out: &mut Vec<ScreenTriangle>,
) {
    let Corners {
        pixel: mut p,
        mut inv_w,
        mut bary,
    } = c;
    let area = signed_area2(&p);
    if !(area.is_finite() && area != 0.0) {
        return;
    }
    let front_facing = area < 0.0;
    match cull {
        CullMode::Back if !front_facing => return,
        CullMode::Front if front_facing => return,
        _ => {}
    }
    if area < 0.0 {
        p.swap(1, 2);
        inv_w.swap(1, 2);
        bary.swap(1, 2);
    }
    let vertex_corners = match (unclipped, area < 0.0) {
        (true, false) => Some([0, 1, 2]),
        (true, true) => Some([0, 2, 1]),
        // A crossing point can round to a vertex's barycentrics in `f32`.
        (false, _) => corner_of_vertex(&bary),
    };
    // A finite area means finite corners.
    let (x0, x1) = pixel_centres(p.map(|c| c[0]), width);
    let (y0, y1) = pixel_centres(p.map(|c| c[1]), height);
    if x0 > x1 || y0 > y1 {
        return;
    }
    out.push(ScreenTriangle {
        edges: [
            Edge::new(p[1], p[2]),
            Edge::new(p[2], p[0]),
            Edge::new(p[0], p[1]),
        ],
        inv_w,
        bary,
        vertex_corners,
        x0,
        x1,
        y0,
        y1,
        triangle: id,
        front_facing,
    });
}

/// The pixel centres `⌈lo⌉ ..= ⌊hi⌋` of `0..n` (empty when the first exceeds the last) between
/// the least `lo` and the greatest `hi` of the finite coordinates `v`. Clamped to `[0, n]` and
/// `[−1, n − 1]` first (which keeps the result), where truncation is exact and cheap:
/// `f64::ceil` and `floor` are libm calls on baseline x86-64. Minima and maxima by comparison:
/// `f64::min` and `max` also handle NaN (and may differ only in the sign of a zero).
#[inline(always)]
fn pixel_centres(v: [f64; 3], n: u32) -> (i32, i32) {
    let min = |a: f64, b: f64| if b < a { b } else { a };
    let max = |a: f64, b: f64| if b > a { b } else { a };
    let n = n as f64;
    let lo = min(max(min(min(v[0], v[1]), v[2]), 0.0), n);
    let hi = max(min(max(max(v[0], v[1]), v[2]), n - 1.0), -1.0);
    let (first, last) = (lo as i32, hi as i32);
    (
        first + ((first as f64) < lo) as i32,
        last - ((last as f64) > hi) as i32,
    )
}

/// For corners with barycentrics `bc` in the mesh triangle, the corner of each vertex
/// (`corner[j] = i` where `bc[i] = e_j`), or `None` unless the corners are the vertices.
fn corner_of_vertex(bc: &[[f32; 3]; 3]) -> Option<[u8; 3]> {
    let mut corner = [u8::MAX; 3];
    for (i, row) in bc.iter().enumerate() {
        let j = row.iter().position(|&b| b == 1.0)?;
        if row.iter().filter(|&&b| b == 0.0).count() != 2 {
            return None;
        }
        corner[j] = i as u8;
    }
    corner.iter().all(|&i| i < 3).then_some(corner)
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use visage_camera::Intrinsics;

    use super::*;

    /// A soup of small, large, near-clipped and duplicated triangles over a shared-edge grid,
    /// in front of a camera at the origin.
    fn soup(rng: &mut impl Rng) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        let mut push = |corners: [[f64; 3]; 3]| {
            let i = positions.len() as u32;
            positions.extend(corners);
            triangles.push([i, i + 1, i + 2]);
        };
        for k in 0..3000 {
            // Mostly small triangles (a few pixels); a few large ones behind them, and a few
            // crossing the near plane.
            let (size, z) = match k % 100 {
                0 => (1.0, rng.random_range(3.0..4.0)),
                1 => (0.5, 0.3),
                _ => (0.04, rng.random_range(1.0..3.0)),
            };
            let centre = [rng.random_range(-1.1..1.1), rng.random_range(-0.4..0.4), z];
            push(std::array::from_fn(|_| {
                std::array::from_fn(|c| centre[c] + size * rng.random_range(-1.0..1.0))
            }));
        }
        // Duplicates, also with the corners rotated: (nearly) equal depths, won by the lower
        // triangle index.
        let n = triangles.len();
        for t in (0..n).step_by(7) {
            let [a, b, c] = triangles[t];
            triangles.extend([[a, b, c], [b, c, a]]);
        }
        // A grid of shared edges with vertices near pixel centres.
        let base = positions.len() as u32;
        for j in 0..=8 {
            for i in 0..=12 {
                positions.push([-0.9 + 0.15 * i as f64, -0.5 + 0.125 * j as f64, 2.5]);
            }
        }
        for j in 0..8 {
            for i in 0..12 {
                let v = base + j * 13 + i;
                triangles.push([v, v + 1, v + 14]);
                triangles.push([v, v + 14, v + 13]);
            }
        }
        (positions, triangles)
    }

    #[test]
    fn set_up_is_the_same_with_and_without_wide_vectors() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (positions, triangles) = soup(&mut rng);
        let k = Intrinsics::new(333, 101, 150.0, 150.0, 166.0, 50.0).unwrap();
        let camera = Camera::new(k).unwrap();
        let model = Mat4::from_linear_translation(
            crate::Mat3::rotation([0.1, 1.0, 0.2], 0.2),
            [0.01, -0.02, 0.05],
        );
        for cull in [CullMode::None, CullMode::Back] {
            // Through `with_simd` (the AVX-512 or AVX2 build on CPUs that have them) …
            let mut r = Rasterizer::new();
            r.set_up(&positions, &triangles, &model, &camera, cull)
                .unwrap();
            // … and the baseline build of the same functions.
            let n = positions.len();
            let (mut cam, mut vertices) = (vec![[0.0; 3]; n], vec![ProjectedVertex::default(); n]);
            let model_view = Mat4::from_rigid(&camera.pose).mul(&model);
            let size = [k.width, k.height];
            let to_clip = camera.camera_to_clip();
            project_vertices(
                &positions,
                &model_view,
                &to_clip,
                &mut cam,
                &mut vertices,
                size,
            );
            let mut setups = Vec::new();
            set_up_triangles(&vertices, &triangles, 0, size, cull, &mut setups);
            assert_eq!(format!("{:?}", r.vertices), format!("{vertices:?}"));
            assert_eq!(r.camera_positions, cam);
            let all: Vec<_> = r.screen_triangles().collect();
            assert!(all.len() > 1000, "{} set-ups", all.len());
            assert_eq!(
                format!("{all:?}"),
                format!("{:?}", setups.iter().collect::<Vec<_>>())
            );
        }
    }

    /// The tile scan through `scan_tile` (one of the builds below, chosen at run time), through
    /// each vector build the CPU has, and one pixel at a time gives the same visibility buffer
    /// and tile depths, bit for bit.
    #[test]
    fn vector_scans_match_the_scalar_scan_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let (positions, triangles) = soup(&mut rng);
        // Odd width and a partial last tile exercise the ends of spans and of the buffer.
        let k = Intrinsics::new(333, 101, 150.0, 150.0, 166.0, 50.0).unwrap();
        let camera = Camera::new(k).unwrap();
        let mut r = Rasterizer::new();
        r.set_up(
            &positions,
            &triangles,
            &Mat4::IDENTITY,
            &camera,
            CullMode::None,
        )
        .unwrap();
        let width = k.width as usize;
        let n_pixels = width * k.height as usize;
        type ScanTile = fn(&[Vec<ScreenTriangle>], &[u32], i32, usize, &mut [f32], &mut [u32]);
        // The visibility buffer and depths of a frame scanned tile by tile by `scan`.
        let scan_frame = |scan: ScanTile| {
            let (mut depth, mut index) = (vec![0.0; n_pixels], vec![0; n_pixels]);
            let tiles = depth
                .chunks_mut(TILE_ROWS * width)
                .zip(index.chunks_mut(TILE_ROWS * width));
            for (t, (d, i)) in tiles.enumerate() {
                scan(
                    &r.setup_chunks,
                    &r.bins[t],
                    (t * TILE_ROWS) as i32,
                    width,
                    d,
                    i,
                );
            }
            (depth, index)
        };
        let (depth_scalar, index_scalar) = scan_frame(scan_tile_scalar);
        let covered = index_scalar.iter().filter(|&&s| s != NO_TRIANGLE).count();
        assert!(covered > n_pixels / 2, "{covered} of {n_pixels} covered");
        let mut builds: Vec<(&str, ScanTile)> = vec![("dispatched", scan_tile)];
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            if has!("avx2") {
                // SAFETY: the closure is made, and so called, only after the run-time check
                // just above found AVX2, which `scan_tile_avx2` is compiled for.
                builds.push(("AVX2", |c, b, r, w, d, i| unsafe {
                    scan_tile_avx2(c, b, r, w, d, i)
                }));
            } else {
                eprintln!("AVX2 scan not checked: the CPU lacks AVX2");
            }
            if has!("avx512f") && has!("avx512vl") {
                // SAFETY: the closure is made, and so called, only after the run-time check
                // just above found AVX-512 F and VL, which `scan_tile_avx512` is compiled for.
                builds.push(("AVX-512", |c, b, r, w, d, i| unsafe {
                    scan_tile_avx512(c, b, r, w, d, i)
                }));
            } else {
                eprintln!("AVX-512 scan not checked: the CPU lacks AVX-512 F or VL");
            }
        }
        for (name, scan) in builds {
            let (depth, index) = scan_frame(scan);
            for p in 0..n_pixels {
                assert_eq!(index[p], index_scalar[p], "{name}: set-up at pixel {p}");
                assert_eq!(
                    depth[p].to_bits(),
                    depth_scalar[p].to_bits(),
                    "{name}: depth at pixel {p}"
                );
            }
        }
    }
}
