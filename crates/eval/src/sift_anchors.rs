//! SIFT keypoints of a sequence's colour frames as extra vertices of the image-plane mesh:
//! the paper's "semantic anchors" (§3), samples where the image shows detail. Used by
//! [`crate::Method::StreamingSiftAnchors`], an experiment kept out of the default method list.
//!
//! The colour frames are the benchmark's constant-albedo render by default, or, with
//! [`SiftAnchorOptions::textured`], the same render with a seeded procedural skin texture
//! ([`crate::skin_albedo`]); the depth inputs are the same either way. The keypoints come
//! from the first frame, or with [`SiftAnchorOptions::frame_step`] from every k-th frame
//! (their union, frame 0's first).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use visage_keypoints::{GrayImage, Sift, SiftOptions};
use visage_mesh::color::linear_to_srgb_u8;
use visage_mesh::Mask;

use crate::seed::mix_seed;
use crate::skin_texture::sequence_skin_albedo;
use crate::{EvalError, SyntheticSequence};

/// Salt of the skin texture's seed (`mix_seed(sequence seed ^ TEXTURE_SALT)`).
const TEXTURE_SALT: u64 = 0x5c1_7e47_5eed;

/// Salt of [`SiftAnchorOptions::random_control`]'s seed.
pub const RANDOM_CONTROL_SALT: u64 = 0x00c0_2720_15ee;

/// The SIFT settings of the anchors (the rest are [`SiftOptions::default`]'s).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct SiftAnchorOptions {
    /// Double the image first, for more and smaller keypoints ([`SiftOptions::upsample`]).
    pub upsample: bool,
    /// Keep at most this many keypoints, the strongest (`None`: all), per frame searched.
    pub max_keypoints: Option<usize>,
    /// Render the frames with a seeded procedural skin texture instead of the constant albedo
    /// (default off: the constant albedo, as the depth's ground truth is rendered).
    pub textured: bool,
    /// Search frames 0, k, 2k, … and take the union of their keypoints (`None`: frame 0
    /// only).
    pub frame_step: Option<usize>,
    /// A control for the keypoints' placement: replace the keypoints that fall in the meshing
    /// domain by as many seeded uniformly random points of the domain (the mesh gains about
    /// as many vertices, at no particular feature).
    pub random_control: bool,
}

impl Default for SiftAnchorOptions {
    fn default() -> Self {
        let s = SiftOptions::default();
        SiftAnchorOptions {
            upsample: s.upsample,
            max_keypoints: s.max_keypoints,
            textured: false,
            frame_step: None,
            random_control: false,
        }
    }
}

/// How many anchors a sequence had, for the record.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct SiftAnchorInfo {
    /// Keypoints SIFT found, over the frames searched (with
    /// [`SiftAnchorOptions::random_control`]: the random points that replaced those in the
    /// domain).
    pub keypoints: usize,
    /// Frames searched.
    pub frames: usize,
    /// Of those, the ones that became vertices (inside the domain, clear of other samples).
    pub vertices_added: usize,
}

/// Keypoint positions `(u, v)` (pixels) of frame `index` of `seq`, as
/// [`sequence_sift_anchors`] finds them on one frame.
///
/// # Errors
/// A failing render.
pub fn sift_anchors(
    seq: &SyntheticSequence,
    index: usize,
    options: &SiftAnchorOptions,
) -> Result<Vec<[f64; 2]>, EvalError> {
    AnchorFinder::new(seq, options).find(seq, index)
}

/// Keypoint positions `(u, v)` (pixels) of the frames [`SiftAnchorOptions::frame_step`]
/// selects, in frame order, and how many frames were searched. Each frame: its shaded render
/// ([`SyntheticSequence::render_color_with`], linear RGB; textured when
/// [`SiftAnchorOptions::textured`]) encoded as 8-bit sRGB, turned grey
/// ([`GrayImage::from_rgb8`], BT.601) and run through [`Sift`] with `options`. Several
/// keypoints can share a position (one per dominant orientation).
///
/// # Errors
/// A failing render.
pub fn sequence_sift_anchors(
    seq: &SyntheticSequence,
    options: &SiftAnchorOptions,
) -> Result<(Vec<[f64; 2]>, usize), EvalError> {
    let mut finder = AnchorFinder::new(seq, options);
    let step = options.frame_step.unwrap_or(seq.frames.len()).max(1);
    let mut points = Vec::new();
    let mut frames = 0;
    for index in (0..seq.frames.len()).step_by(step) {
        points.extend(finder.find(seq, index)?);
        frames += 1;
    }
    Ok((points, frames))
}

/// Keypoint positions `(u, v)` (pixels) of every frame of `seq`, per frame, found as
/// [`sequence_sift_anchors`] finds them ([`SiftAnchorOptions::frame_step`] and
/// [`SiftAnchorOptions::random_control`] play no part): the keypoints of
/// [`crate::Method::FaceAnchoredFairedSift`].
///
/// # Errors
/// A failing render.
pub fn frame_sift_keypoints(
    seq: &SyntheticSequence,
    options: &SiftAnchorOptions,
) -> Result<Vec<Vec<[f64; 2]>>, EvalError> {
    let mut finder = AnchorFinder::new(seq, options);
    (0..seq.frames.len())
        .map(|index| finder.find(seq, index))
        .collect()
}

/// [`SiftAnchorOptions::random_control`]'s points: for each of `points` in `domain` (nearest
/// pixel set), a uniformly random position in a uniformly random pixel of `domain`, seeded
/// by `seed`.
pub fn random_control_points(points: &[[f64; 2]], domain: &Mask, seed: u64) -> Vec<[f64; 2]> {
    let pixels: Vec<[f64; 2]> = (0..domain.height)
        .flat_map(|v| (0..domain.width).map(move |u| (u, v)))
        .filter(|&(u, v)| domain.get(i64::from(u), i64::from(v)))
        .map(|(u, v)| [f64::from(u), f64::from(v)])
        .collect();
    if pixels.is_empty() {
        return Vec::new();
    }
    let inside = points
        .iter()
        .filter(|p| domain.get(p[0].round() as i64, p[1].round() as i64))
        .count();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..inside)
        .map(|_| {
            let p = pixels[rng.random_range(0..pixels.len())];
            [
                p[0] + rng.random_range(-0.5..0.5),
                p[1] + rng.random_range(-0.5..0.5),
            ]
        })
        .collect()
}

/// The detector and, when textured, the sequence's per-vertex albedo, kept across frames.
struct AnchorFinder {
    sift: Sift,
    albedo: Option<Vec<[f32; 3]>>,
}

impl AnchorFinder {
    fn new(seq: &SyntheticSequence, options: &SiftAnchorOptions) -> AnchorFinder {
        AnchorFinder {
            sift: Sift::new(SiftOptions {
                upsample: options.upsample,
                max_keypoints: options.max_keypoints,
                ..SiftOptions::default()
            }),
            albedo: options
                .textured
                .then(|| sequence_skin_albedo(seq, mix_seed(seq.seed ^ TEXTURE_SALT))),
        }
    }

    fn find(&mut self, seq: &SyntheticSequence, index: usize) -> Result<Vec<[f64; 2]>, EvalError> {
        let image = gray_render(seq, index, self.albedo.as_deref())?;
        Ok(self
            .sift
            .detect_and_compute(&image)
            .keypoints
            .iter()
            .map(|k| [f64::from(k.x), f64::from(k.y)])
            .collect())
    }
}

/// Frame `index` of `seq` rendered (with `albedo` per vertex when given), as 8-bit sRGB grey.
///
/// # Errors
/// A failing render.
pub fn gray_render(
    seq: &SyntheticSequence,
    index: usize,
    albedo: Option<&[[f32; 3]]>,
) -> Result<GrayImage, EvalError> {
    let rgb = seq.render_color_with(index, albedo)?;
    let bytes: Vec<u8> = rgb.iter().flat_map(|p| p.map(linear_to_srgb_u8)).collect();
    let (w, h) = (seq.k.width as usize, seq.k.height as usize);
    GrayImage::from_rgb8(w, h, &bytes).ok_or(EvalError::InvalidConfig {
        name: "render",
        value: format!("{} pixels", rgb.len()),
        reason: "the colour render does not match the camera's size",
    })
}
