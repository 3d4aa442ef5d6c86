//! The surface colour source of the colour renderer.

use visage_mesh::TriMesh;

use crate::texture::{Texture, Wrap};

/// The light grey (linear RGB) of a surface without colours of its own.
pub const DEFAULT_ALBEDO: [f32; 3] = [0.8; 3];

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

impl<'a> Albedo<'a> {
    /// The colour `mesh` shows by itself: `texture` at its UVs (clamped at the edges) when
    /// given, else its vertex colours when it has them, else [`DEFAULT_ALBEDO`].
    pub fn for_mesh(mesh: &TriMesh, texture: Option<&'a Texture>) -> Albedo<'a> {
        match texture {
            Some(texture) => Albedo::Texture {
                texture,
                wrap: Wrap::Clamp,
            },
            None if !mesh.colors.is_empty() => Albedo::VertexColors,
            None => Albedo::Constant(DEFAULT_ALBEDO),
        }
    }
}
