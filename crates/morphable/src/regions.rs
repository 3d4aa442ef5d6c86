//! Vertex regions of the ICT-FaceKit topology and its unit.

use std::ops::Range;

/// Centimetres (the OBJ files' unit) to metres.
pub const CM_TO_M: f64 = 0.01;

/// Contiguous vertex ranges of the ICT-FaceKit topology (26,719 vertices), from the
/// repository's README (`../shared/data/ict-facekit/SOURCE.md` quotes the first two).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Region {
    /// The face, vertices 0–9408: the region every benchmark metric is computed over.
    Face,
    /// The narrow face area, vertices 0–6705 (a subset of [`Region::Face`]).
    NarrowFace,
    /// Back of the head and neck, vertices 9409–11247.
    HeadAndNeck,
    /// Mouth socket, eye sockets, gums, tongue, teeth and eyeballs, vertices 11248–24590: the
    /// interior surfaces visible through the open mouth and the eye openings.
    Interior,
    /// Lacrimal fluid, eye blend and occlusion shells and eyelashes, vertices 24591–26718:
    /// semi-transparent render helpers that a depth sensor would not see.
    Overlays,
}

impl Region {
    /// The half-open vertex range of the region.
    pub const fn range(self) -> Range<usize> {
        match self {
            Region::Face => 0..9409,
            Region::NarrowFace => 0..6706,
            Region::HeadAndNeck => 9409..11248,
            Region::Interior => 11248..24591,
            Region::Overlays => 24591..26719,
        }
    }

    /// Whether vertex `i` belongs to the region.
    pub const fn contains(self, i: usize) -> bool {
        let r = self.range();
        i >= r.start && i < r.end
    }
}

/// Vertices `0..SOLID_SURFACE_END` form the opaque surfaces a depth camera sees (face, head,
/// neck, mouth and eye interiors); the [`Region::Overlays`] after them are left out of
/// ground-truth renders.
pub const SOLID_SURFACE_END: usize = 24591;
