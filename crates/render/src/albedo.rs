//! The surface colour source of the colour renderer.

use crate::texture::{Texture, Wrap};

/// Where the surface colour `C_tex` of Eq. (6.4) comes from.
#[derive(Clone, Copy, Debug)]
pub enum Albedo<'a> {
    /// Bilinear samples (Eq. (6.3)) of `texture` at the mesh's interpolated UVs (requires
    /// `mesh.uvs`).
    Texture { texture: &'a Texture, wrap: Wrap },
    /// The mesh's interpolated vertex colours (requires `mesh.colors`).
    VertexColors,
    /// One linear RGB colour for the whole surface.
    Constant([f32; 3]),
}
