//! SIFT keypoints of a sequence's first colour frame as extra vertices of the image-plane mesh:
//! the paper's "semantic anchors" (§3), samples where the image shows detail. Used by
//! [`crate::Method::StreamingSiftAnchors`], an experiment kept out of the default method list.

use visage_keypoints::{GrayImage, Sift, SiftOptions};
use visage_mesh::color::linear_to_srgb_u8;

use crate::{EvalError, SyntheticSequence};

/// The SIFT settings of the anchors (the rest are [`SiftOptions::default`]'s).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct SiftAnchorOptions {
    /// Double the image first, for more and smaller keypoints ([`SiftOptions::upsample`]).
    pub upsample: bool,
    /// Keep at most this many keypoints, the strongest (`None`: all).
    pub max_keypoints: Option<usize>,
}

impl Default for SiftAnchorOptions {
    fn default() -> Self {
        let s = SiftOptions::default();
        SiftAnchorOptions {
            upsample: s.upsample,
            max_keypoints: s.max_keypoints,
        }
    }
}

/// How many anchors a sequence had, for the record.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct SiftAnchorInfo {
    /// Keypoints SIFT found on the first frame's render.
    pub keypoints: usize,
    /// Of those, the ones that became vertices (inside the domain, clear of other samples).
    pub vertices_added: usize,
}

/// Keypoint positions `(u, v)` (pixels) of frame `index` of `seq`: its shaded render
/// ([`SyntheticSequence::render_color`], linear RGB) encoded as 8-bit sRGB, turned grey
/// ([`GrayImage::from_rgb8`], BT.601) and run through [`Sift`] with `options`. Several
/// keypoints can share a position (one per dominant orientation).
///
/// # Errors
/// A failing render.
pub fn sift_anchors(
    seq: &SyntheticSequence,
    index: usize,
    options: &SiftAnchorOptions,
) -> Result<Vec<[f64; 2]>, EvalError> {
    let rgb = seq.render_color(index)?;
    let bytes: Vec<u8> = rgb.iter().flat_map(|p| p.map(linear_to_srgb_u8)).collect();
    let (w, h) = (seq.k.width as usize, seq.k.height as usize);
    let image = GrayImage::from_rgb8(w, h, &bytes).ok_or(EvalError::InvalidConfig {
        name: "render",
        value: format!("{} pixels", rgb.len()),
        reason: "the colour render does not match the camera's size",
    })?;
    let mut sift = Sift::new(SiftOptions {
        upsample: options.upsample,
        max_keypoints: options.max_keypoints,
        ..SiftOptions::default()
    });
    Ok(sift
        .detect_and_compute(&image)
        .keypoints
        .iter()
        .map(|k| [f64::from(k.x), f64::from(k.y)])
        .collect())
}
