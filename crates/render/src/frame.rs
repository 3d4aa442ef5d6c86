//! The colour renderer: Algorithm 3 end to end, producing every buffer of a frame.

use std::cell::RefCell;

use rayon::iter::Either;
use rayon::prelude::*;
use visage_camera::{DepthKind, DepthMap};
use visage_mesh::TriMesh;

use crate::albedo::{Albedo, DEFAULT_ALBEDO};
use crate::camera::Camera;
use crate::deferred::{Block, DeferredPass, Rows, TileSetups};
use crate::interpolation::{SetupPlanes, VertexChannels};
use crate::mat4::{Mat3, Mat4};
use crate::normals::{normal_matrix, transform_normal, vertex_normals_into};
use crate::rasterize::{CullMode, Rasterizer, NO_TRIANGLE, TILE_ROWS};
use crate::shading::{BlinnPhong, Light, Material};
use crate::RenderError;

/// Everything besides geometry and camera that decides a frame's colours.
#[derive(Clone, Copy, Debug)]
pub struct Scene<'a> {
    /// Surface reflectances (validated: energy-conserving).
    pub material: Material,
    /// The light, in camera coordinates.
    pub light: Light,
    /// Surface colour source.
    pub albedo: Albedo<'a>,
    /// Linear RGB of pixels that see no surface.
    pub background: [f32; 3],
    /// Flip normals that face away from the viewer before shading, so the back of an open
    /// surface is lit like its front.
    pub two_sided: bool,
    /// Orientation culling.
    pub cull: CullMode,
}

impl Default for Scene<'_> {
    /// Default material and light, light-grey constant albedo, black background, two-sided
    /// lighting, no culling.
    fn default() -> Self {
        Scene {
            material: Material::default(),
            light: Light::default(),
            albedo: Albedo::Constant(DEFAULT_ALBEDO),
            background: [0.0; 3],
            two_sided: true,
            cull: CullMode::None,
        }
    }
}

/// The buffers of one rendered frame, all `width × height`, row-major (`[v · width + u]`).
///
/// `triangle_id` and `barycentrics` may be left empty (see [`Frame::color_and_depth`]): the
/// renderer then skips them, which saves memory traffic when only images are wanted.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Linear RGB radiance (Eq. (6.4)), the background colour where no surface is seen.
    pub color: Vec<[f32; 3]>,
    /// Metric depth of the kind chosen at construction, `0` = background.
    pub depth: DepthMap,
    /// Visible mesh triangle, [`NO_TRIANGLE`] for background (empty: not produced).
    pub triangle_id: Vec<u32>,
    /// Perspective-correct barycentrics in the visible triangle, zero for background (empty: not
    /// produced).
    pub barycentrics: Vec<[f32; 3]>,
}

impl Frame {
    /// Buffers for `width × height` frames whose depth is of kind `kind`.
    pub fn new(width: u32, height: u32, kind: DepthKind) -> Frame {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            color: vec![[0.0; 3]; n],
            depth: DepthMap::empty(width, height, kind),
            triangle_id: vec![NO_TRIANGLE; n],
            barycentrics: vec![[0.0; 3]; n],
        }
    }

    /// Colour and depth buffers only (`triangle_id` and `barycentrics` empty).
    pub fn color_and_depth(width: u32, height: u32, kind: DepthKind) -> Frame {
        Frame {
            triangle_id: Vec::new(),
            barycentrics: Vec::new(),
            ..Frame::new(width, height, kind)
        }
    }
}

/// The renderer of Algorithm 3: reusable scratch (rasteriser, per-vertex normals); one call per
/// frame writes into a caller-owned [`Frame`].
#[derive(Debug, Default)]
pub struct Renderer {
    rasterizer: Rasterizer,
    object_normals: Vec<[f64; 3]>,
    /// Per vertex, the channels interpolated across set-ups (camera-space normal, albedo source).
    channels: VertexChannels,
}

impl Renderer {
    /// A renderer with empty scratch buffers.
    pub fn new() -> Renderer {
        Renderer::default()
    }

    /// The rasteriser state of the last frame (visibility buffer, camera-space positions).
    pub fn rasterizer(&self) -> &Rasterizer {
        &self.rasterizer
    }

    /// Renders `mesh` transformed by `model` (object → world, `M_k` of Eq. (6.1)) through
    /// `camera` into `frame`.
    ///
    /// Normals: the mesh's own if present, else area-weighted vertex normals; both are taken to
    /// camera space by the inverse transpose of the model-view's linear part (Eq. (6.2)).
    ///
    /// # Errors
    /// Invalid mesh, camera, model matrix, material or light; `frame` of another size than the
    /// camera's image; an albedo source the mesh lacks (UVs or colours).
    pub fn render(
        &mut self,
        mesh: &TriMesh,
        camera: &Camera,
        model: &Mat4,
        scene: &Scene<'_>,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        crate::validate::check_mesh(mesh)?;
        let shader = BlinnPhong::new(scene.material, scene.light)?;
        let k = camera.intrinsics;
        let n_pixels = k.width as usize * k.height as usize;
        if frame.width != k.width
            || frame.height != k.height
            || frame.depth.width != k.width
            || frame.depth.height != k.height
            || frame.color.len() != n_pixels
            || frame.depth.data.len() != frame.color.len()
            || (!frame.triangle_id.is_empty() && frame.triangle_id.len() != n_pixels)
            || (!frame.barycentrics.is_empty() && frame.barycentrics.len() != n_pixels)
        {
            return Err(RenderError::BufferSize {
                buffer: "frame",
                width: frame.width,
                height: frame.height,
                expected_width: k.width,
                expected_height: k.height,
            });
        }
        match scene.albedo {
            Albedo::Texture { .. } if mesh.uvs.is_empty() => {
                return Err(RenderError::MissingAttribute {
                    attribute: "texture coordinates",
                    needed_by: "a textured render",
                })
            }
            Albedo::VertexColors if mesh.colors.is_empty() => {
                return Err(RenderError::MissingAttribute {
                    attribute: "vertex colours",
                    needed_by: "a vertex-colour render",
                })
            }
            _ => {}
        }
        crate::validate::check_model(model)?;
        let model_view: Mat3 = Mat4::from_rigid(&camera.pose).mul(model).linear();
        let nm = normal_matrix(&model_view)?;

        self.rasterizer
            .set_up(&mesh.vertices, &mesh.triangles, model, camera, scene.cull)?;

        // Step 3 of Algorithm 3: normals to camera space (Eq. (6.2)).
        let object_normals: &[[f64; 3]] = if mesh.normals.is_empty() {
            vertex_normals_into(&mesh.vertices, &mesh.triangles, &mut self.object_normals);
            &self.object_normals
        } else {
            &mesh.normals
        };
        self.channels.fill(
            mesh,
            |v| transform_normal(&nm, object_normals[v]).map(|x| x as f32),
            &scene.albedo,
        );

        let channels = &self.channels;
        // Steps 7–10: one reconstruction and shading evaluation per visible pixel, each tile
        // right after its scan, while its visibility buffer and set-ups are still in cache.
        let pass = DeferredPass {
            shader,
            albedo: scene.albedo,
            background: scene.background,
            two_sided: scene.two_sided,
            intrinsics: k,
            kind: frame.depth.kind,
        };
        let tile_len = TILE_ROWS * k.width as usize;
        let n_tiles = (k.height as usize).div_ceil(TILE_ROWS);
        let tiles = frame
            .color
            .par_chunks_mut(tile_len)
            .zip(frame.depth.data.par_chunks_mut(tile_len))
            .zip(optional_tiles(&mut frame.triangle_id, tile_len, n_tiles))
            .zip(optional_tiles(&mut frame.barycentrics, tile_len, n_tiles))
            .map(|(((color, depth), triangle), bary)| Rows {
                color,
                depth,
                triangle,
                bary,
            });
        self.rasterizer
            .scan_tiles(tiles, |out, row0, chunks, bin, index| {
                TILE_SCRATCH.with_borrow_mut(|TileScratch { planes, block }| {
                    // Step 7's interpolation planes of the tile's set-ups, computed here so
                    // that they are in cache for its pixels (a set-up overlapping two tiles is
                    // done twice; all of them up front were mostly out of cache by their turn).
                    SetupPlanes::of_bin(planes, bin, chunks, &mesh.triangles, channels);
                    let tile = TileSetups {
                        chunks,
                        bin,
                        planes,
                    };
                    pass.shade_tile(block, row0, tile, index, out)
                })
            });
        Ok(())
    }
}

/// A worker thread's scratch for the tiles it shades, kept across tiles and frames so that it
/// stays in cache: one planes buffer per tile was written from memory every frame, and a fresh
/// [`Block`] per tile zeroed its ~12 KiB for nothing (lanes are written before they are read).
#[derive(Default)]
struct TileScratch {
    /// The interpolation planes of the tile's set-ups (in bin order).
    planes: Vec<SetupPlanes>,
    block: Block,
}

thread_local! {
    static TILE_SCRATCH: RefCell<TileScratch> = RefCell::new(TileScratch::default());
}

/// The tiles (`tile_len` elements each) of an optional frame buffer, or `n_tiles` empty tiles
/// when the buffer is not wanted (empty).
fn optional_tiles<T: Send>(
    buffer: &mut [T],
    tile_len: usize,
    n_tiles: usize,
) -> impl IndexedParallelIterator<Item = &mut [T]> {
    if buffer.is_empty() {
        Either::Right((0..n_tiles).into_par_iter().map(|_| &mut [][..]))
    } else {
        Either::Left(buffer.par_chunks_mut(tile_len))
    }
}
