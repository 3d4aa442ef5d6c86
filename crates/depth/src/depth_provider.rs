//! The one interface of the depth maps that come from outside the face fit: a folder of PNGs,
//! an RGB-D recording's associated map, a depth network aligned to the metric face. The
//! pipeline's depth stage asks its provider for each frame's map; a new depth source is a new
//! type that implements [`DepthProvider`].

use image::RgbImage;
use visage_camera::{DepthMap, Intrinsics};

use crate::{Alignment, AlignmentFailure, DepthError};

/// What a provider is given for one frame (one with a tracked face).
#[derive(Debug)]
pub struct DepthRequest<'a> {
    /// The input frame's index (a video's frame number, an image folder's file number).
    pub index: usize,
    /// How errors name the frame (its file, or the video and frame number).
    pub source: &'a str,
    /// The colour frame, when [`DepthProvider::needs_image`].
    pub image: Option<&'a RgbImage>,
    /// The camera: the map is `k.width × k.height`.
    pub k: &'a Intrinsics,
    /// The tracked face's box `[x, y, w, h]`, pixels.
    pub face_box: [f32; 4],
    /// The fitted metric face's z-depth (metres, 0 off the face; the fitted morphable model's
    /// surface when it is fitted, else the rigid face fit's), when
    /// [`DepthProvider::needs_reference`]: what an output known up to scale and shift is
    /// aligned to.
    pub reference: Option<DepthMap>,
    /// Depth beyond this is no depth, metres.
    pub max_depth: f64,
}

/// A frame's depth from a provider.
#[derive(Clone, Debug, PartialEq)]
pub struct ProvidedDepth {
    /// The map, `k.width × k.height`, metres; empty where the source has nothing for the
    /// frame (the fusion then carries the surface through it).
    pub map: DepthMap,
    /// How an output known up to scale and shift was brought to the reference, or why it
    /// could not be (the map is then empty); `None` for a source that is metric as read.
    pub alignment: Option<Result<Alignment, AlignmentFailure>>,
    /// What the user should know about this frame (why its depth was not used).
    pub warning: Option<String>,
}

impl ProvidedDepth {
    /// A map as read, with nothing to report.
    pub fn read(map: DepthMap) -> Self {
        ProvidedDepth {
            map,
            alignment: None,
            warning: None,
        }
    }
}

/// A source of one depth map per input frame (paper §2's `D_k`), asked frame by frame in input
/// order on the depth stage's thread.
pub trait DepthProvider: Send + std::fmt::Debug {
    /// How `metrics.json` names the source (its `depth` parameter): its file or folder.
    fn describe(&self) -> String;

    /// Whether [`DepthRequest::image`] must hold the colour frame (default: no; frames are
    /// then not kept for the depth stage).
    fn needs_image(&self) -> bool {
        false
    }

    /// Whether [`DepthRequest::reference`] must hold the fitted face's depth (default: no; it
    /// costs a render per frame, and keeps the fitted model's surface for it).
    fn needs_reference(&self) -> bool {
        false
    }

    /// Frame `request.index`'s depth map.
    ///
    /// # Errors
    /// What the source cannot read or compute for the frame; each error names the file or the
    /// frame ([`DepthError::on_frame`]).
    fn depth_map(&mut self, request: DepthRequest<'_>) -> Result<ProvidedDepth, DepthError>;
}
