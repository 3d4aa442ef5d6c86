//! visage-render: a software rasteriser for metric depth, triangle-id, barycentric and shaded
//! colour images of triangle meshes — paper §6, Algorithm 3, with ERRATA 12.
//!
//! It is exact enough to serve as ground truth: the depth stored at a pixel is the intersection
//! of that pixel's ray with the visible triangle (to `f32` rounding of the stored value), and
//! coverage follows a watertight fill rule.
//!
//! # Conventions
//! - **Camera coordinates** (the project's, see `visage_camera`): x right, y down, z forward,
//!   metres. Without a pose the camera sits at the origin looking down +z and mesh coordinates
//!   *are* camera coordinates — what `visage fuse` writes. A pose
//!   ([`visage_camera::RigidTransform`], as a matrix [`Mat4::from_rigid`]) maps world (mesh)
//!   coordinates to camera coordinates: `x_cam = R · x + t`.
//! - **Pixels**: `u` right, `v` down; the centre of pixel `(i, j)` is at `(i, j)`; a point
//!   projects to `(fx·x/z + cx, fy·y/z + cy)` ([`visage_camera::Intrinsics::project`]).
//! - **Coverage**: a pixel belongs to a triangle when its centre is inside the projected
//!   triangle; centres exactly on an edge go to the triangle for which that edge is a top or left
//!   edge (the top-left rule), so a closed mesh or a shared edge is covered exactly once —
//!   no cracks, no double hits. Edge functions are `f64` and computed canonically per edge
//!   ([`edge`]), so this holds bit-exactly.
//! - **Depth**: per pixel, either the camera `z` or the distance along the unit ray
//!   ([`visage_camera::DepthKind`]), in metres; `0` marks background. Nearest surface wins; ties
//!   go to the lower triangle index.
//! - **Transform chain** (Eq. (6.1)): `clip = P · F · [R t] · M · (v, 1)ᵀ` with `M` the model
//!   matrix (object → world), `[R t]` the pose, `F = diag(1, −1, −1, 1)` the change to OpenGL eye
//!   space and `P` the OpenGL projection built from `K` ([`projection_matrix`], ERRATA 12).
//!   Clip-space `w` equals camera `z`. Triangles are clipped against the near and far planes
//!   ([`clip`]); the side planes by rejection and scissoring.
//! - **Orientation**: a triangle is front-facing when `(v₁ − v₀) × (v₂ − v₀)` points towards
//!   the camera (counter-clockwise on screen). Both sides are drawn unless culling is asked for.
//! - **Parallelism**: every per-vertex and per-triangle pass (validation, transforms, normals,
//!   set-up, binning) and scan conversion run on rayon's pool; scan conversion is split into
//!   tiles of [`TILE_ROWS`] image rows, each owning its part of the z-buffer. These passes, the
//!   interpolation planes, the tile scan and the shading pass also have AVX-512 and AVX2 builds
//!   chosen at run time, with identical results (no float contraction or reordering).
//!
//! # Decisions where the paper and the ERRATA are silent
//! - `P` carries `(2cx + 1)/W` instead of ERRATA 12's `2cx/W` because pixel centres sit at
//!   integers here; with it, the chain of Eq. (6.1) reproduces `Intrinsics::project` exactly.
//! - Rasterisation is deferred: a visibility buffer (z, set-up id) first, then one exact
//!   reconstruction and one shading evaluation per visible pixel, so depth is the exact
//!   ray–triangle intersection and overdraw never shades.
//! - Texture coordinates are OBJ/OpenGL (`v` up); textures are linear RGBA stored as 16-bit
//!   values; 8-bit image files are decoded as sRGB. Colour output is linear RGB, written as 8-bit
//!   sRGB PNG.
//! - Default near plane 1 mm, far plane 1 km; both sides of triangles drawn and lit (a
//!   reconstructed face is an open surface); the default light comes from above-left of the
//!   camera. The specular lobe is skipped where it would add less than 10⁻⁵ (linear).
//!
//! # Entry points
//! - [`render_depth`]: depth + triangle-id + barycentric buffers of a [`visage_mesh::TriMesh`]
//!   for a camera with intrinsics and optional pose — the ground-truth renderer.
//! - [`Renderer::render`]: Algorithm 3 — colour (Blinn–Phong, Eq. (6.4), textured by Eq. (6.3)),
//!   depth, triangle-id and barycentric buffers into a caller-owned [`Frame`].
//! - [`Rasterizer`]: reusable state for repeated frames; [`Rasterizer::fragment`] gives exact
//!   per-pixel depth and barycentrics.

// Unsafe code is denied except in the modules marked below: calls into the AVX2 and AVX-512
// builds after the run-time CPU check (`simd`, `interpolation`, `rasterize`), x86-64 intrinsics
// (streaming stores in `stream`, prefetches in `prefetch`, the texel sum in `texture`, plane
// stores in `interpolation`, masked tile loads and stores in `rasterize`) and one unchecked
// float-to-int conversion (`texture`). Each block states the invariant it relies on (`SAFETY:`).
#![deny(unsafe_code)]
#![deny(unsafe_op_in_unsafe_fn, clippy::undocumented_unsafe_blocks)]

mod albedo;
pub mod camera;
pub mod clip;
pub mod color;
mod deferred;
pub mod depth;
pub mod edge;
mod error;
mod frame;
#[allow(unsafe_code)]
mod interpolation;
pub mod mat4;
pub mod normals;
mod plane;
#[allow(unsafe_code)]
mod prefetch;
pub mod projection;
pub mod projective;
#[allow(unsafe_code)]
pub mod rasterize;
pub mod shading;
#[allow(unsafe_code)]
mod simd;
#[allow(unsafe_code)]
mod stream;
#[allow(unsafe_code)]
pub mod texture;
pub mod turntable;
mod uv_raster;
mod validate;

pub use albedo::{Albedo, DEFAULT_ALBEDO};
pub use camera::{Camera, DEFAULT_FAR, DEFAULT_NEAR};
pub use color::write_srgb_png;
pub use depth::{render_depth, render_depth_with, DepthRender};
pub use error::RenderError;
pub use frame::{Frame, Renderer, Scene};
pub use mat4::{Mat3, Mat4};
pub use normals::{normal_matrix, vertex_normals};
pub use projection::{projection_matrix, viewport};
pub use projective::projective_uvs;
pub use rasterize::{CullMode, Fragment, Rasterizer, ScreenTriangle, NO_TRIANGLE, TILE_ROWS};
pub use shading::{blinn_phong, Light, Material, UNLIT};
pub use texture::{Texture, Wrap};
pub use turntable::{turn_about_centre, turntable};
pub use uv_raster::rasterize_uv_triangle;
