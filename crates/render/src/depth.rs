use rayon::prelude::*;
use visage_camera::{DepthKind, DepthMap, Intrinsics, RigidTransform};
use visage_mesh::TriMesh;

use crate::camera::Camera;
use crate::mat4::Mat4;
use crate::rasterize::{CullMode, Rasterizer, NO_TRIANGLE};
use crate::RenderError;

/// Per-pixel geometry buffers of one rendered view, all `width × height`, row-major
/// (`[v · width + u]`).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthRender {
    /// Metric depth of the nearest surface at each pixel centre, of the requested
    /// [`DepthKind`] (`z` or distance along the unit ray, Eq. (2.2)); `0` = background — the
    /// convention of `visage_camera::DepthMap` and `visage fuse`.
    pub depth: DepthMap,
    /// Index of the visible mesh triangle, [`NO_TRIANGLE`] for background.
    pub triangle_id: Vec<u32>,
    /// Perspective-correct barycentric coordinates of the visible point in its triangle
    /// (`Σ = 1`), `[0, 0, 0]` for background.
    pub barycentrics: Vec<[f32; 3]>,
}

/// Renders the depth, triangle-id and barycentric buffers of `mesh` seen by a pinhole camera.
///
/// Conventions (see the crate docs): without `pose` the camera sits at the origin looking down
/// +z and mesh coordinates are camera coordinates (x right, y down, z forward, metres); with
/// `pose`, `x_cam = R · x_mesh + t`. A pixel is covered when its centre `(i, j)` lies inside the
/// projected triangle (top-left rule on edges); the depth stored is the exact ray–triangle
/// intersection at that centre (to `f32` rounding). Both sides of every triangle are drawn;
/// geometry nearer than 1 mm ([`crate::DEFAULT_NEAR`]) is clipped.
///
/// # Errors
/// An empty mesh, out-of-range indices, non-finite vertices, invalid intrinsics or pose.
pub fn render_depth(
    mesh: &TriMesh,
    intrinsics: &Intrinsics,
    pose: Option<&RigidTransform>,
    kind: DepthKind,
) -> Result<DepthRender, RenderError> {
    let mut camera = Camera::new(*intrinsics)?;
    if let Some(pose) = pose {
        camera = camera.with_pose(*pose)?;
    }
    render_depth_with(
        &mut Rasterizer::new(),
        mesh,
        &camera,
        &Mat4::IDENTITY,
        kind,
        CullMode::None,
    )
}

/// [`render_depth`] with full control: a reusable [`Rasterizer`], clipping planes, a model
/// matrix `M` (object → world, Eq. (6.1)) and face culling.
pub fn render_depth_with(
    rasterizer: &mut Rasterizer,
    mesh: &TriMesh,
    camera: &Camera,
    model: &Mat4,
    kind: DepthKind,
    cull: CullMode,
) -> Result<DepthRender, RenderError> {
    crate::validate::check_mesh(mesh)?;
    rasterizer.rasterize_valid(&mesh.vertices, &mesh.triangles, model, camera, cull)?;
    let k = camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    let mut depth = DepthMap::empty(k.width, k.height, kind);
    let mut triangle_id = vec![NO_TRIANGLE; w * h];
    let mut barycentrics = vec![[0.0f32; 3]; w * h];
    let raster = &*rasterizer;
    depth
        .data
        .par_chunks_mut(w)
        .zip(triangle_id.par_chunks_mut(w))
        .zip(barycentrics.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, ((d_row, t_row), b_row))| {
            // In spans of equal set-up id, with the row terms of the edge functions hoisted;
            // the same operations per pixel as `Rasterizer::fragment`.
            let setups = raster.visibility_row(y);
            let yf = y as f64;
            let mut x = 0;
            while x < w {
                let s = setups[x];
                let end = x + setups[x..].iter().take_while(|&&t| t == s).count();
                let st = if s == NO_TRIANGLE {
                    None
                } else {
                    raster.setup(s)
                };
                if let Some(st) = st {
                    let rows = st.rows(yf);
                    for x in x..end {
                        let (wt, z) = st.corner_weights(&rows, x as f64);
                        let value = match kind {
                            DepthKind::Z => z,
                            DepthKind::Ray => z / k.ray(x as f64, yf)[2],
                        };
                        d_row[x] = value as f32;
                        t_row[x] = st.triangle();
                        b_row[x] = st.mesh_bary(&wt).map(|b| b as f32);
                    }
                }
                x = end;
            }
        });
    Ok(DepthRender {
        depth,
        triangle_id,
        barycentrics,
    })
}
