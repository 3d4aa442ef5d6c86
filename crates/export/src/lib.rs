//! What people open after a run, made from its output folder ([`Capture`]): the animated glTF
//! (`sequence.glb`), the face texture fused from the frames (`texture.png`, also named by
//! `mesh.mtl`), the per-frame charts (`plots/*.svg` and `*.png`), the offline report with its
//! 3-D viewer (`report.html`), the preview video (`preview.mp4`), and the list of what was
//! written with sizes and times (`export.json`).
//!
//! `visage run --glb --report --preview` calls [`export`] on the folder it has just written;
//! `visage export OUT` does the same for any earlier run's folder.

#![forbid(unsafe_code)]

mod arkit_targets;
mod capture;
mod error;
mod frame_renders;
mod glb;
mod moments;
mod morph_animation;
mod plots;
mod preview;
mod report;
mod texture_fusion;

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use visage_run_folder::{file_names, CACHE_MATERIAL};
use visage_video::{Frame, FrameSource};

pub use capture::{Blendshapes, Capture, CaptureFrame};
pub use error::ExportError;
pub use glb::write_glb;
pub use morph_animation::{
    MorphAnimation, NamedTargets, MAX_RESIDUAL_TARGETS, RESIDUAL_TOLERANCE_M,
};
pub use plots::{run_plots, Plot};
pub use preview::{write_preview, PreviewSummary};
pub use report::{report_html, Render, VIEWER_JS};
pub use texture_fusion::{fuse_texture, FusedTexture, TextureView};

/// The texture's side in texels: the smallest power of two that gives the face as many texels
/// as it has pixels in the video (the face's size in pixels over the share of the texture its
/// UV layout spans), within these bounds. Finer would only interpolate the video.
pub const TEXTURE_SIZE_RANGE: (usize, usize) = (256, 2048);
/// Frames the texture is fused from, at most: evenly spaced over the meshed frames of the first
/// [`TEXTURE_SECONDS`] (the input is decoded again only that far).
pub const TEXTURE_FRAMES: usize = 8;
/// Seconds of the input the texture is fused from.
pub const TEXTURE_SECONDS: f64 = 2.0;

/// What to export.
#[derive(Clone, Copy, Debug, Default)]
pub struct ExportOptions {
    /// `sequence.glb`.
    pub glb: bool,
    /// `texture.png` (and `mesh.mtl` naming it); the glb uses it.
    pub texture: bool,
    /// `plots/*.svg` and `plots/*.png`.
    pub plots: bool,
    /// `report.html` (with the glb, the texture and the plots).
    pub report: bool,
    /// `preview.mp4`.
    pub preview: bool,
}

impl ExportOptions {
    /// Whether any export is asked for.
    pub fn any(&self) -> bool {
        self.glb || self.texture || self.plots || self.report || self.preview
    }
}

/// One file written.
#[derive(Clone, Debug, Serialize)]
pub struct ExportedFile {
    pub file: String,
    pub bytes: u64,
    /// Time to make and write it.
    pub ms: f64,
}

/// What an export wrote, and the figures of its encodings (`export.json`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ExportSummary {
    pub files: Vec<ExportedFile>,
    /// The glb's morph targets: named (ARKit) and residual.
    pub named_targets: usize,
    pub residual_targets: usize,
    /// The share of the surfaces' deformation the ARKit targets and curves explain.
    pub named_explained: Option<f64>,
    /// The glb's vertex error against the point cache, metres.
    pub glb_rms_error_m: Option<f64>,
    pub glb_max_error_m: Option<f64>,
    /// Frames the texture was fused from, and the share of the UV area they saw.
    pub texture_frames: usize,
    pub texture_coverage: Option<f64>,
    /// Wall time of the whole export.
    pub total_ms: f64,
}

/// Chooses, as an input is decoded, the frames the texture is fused from: every n-th of the
/// first [`TEXTURE_SECONDS`], so that about [`TEXTURE_FRAMES`] are kept (`fps` the input's rate,
/// 30 when unknown). For the `visage` crate's `Input::keep_copies`, so a run keeps them for [`export`].
pub fn texture_frames(fps: Option<f64>) -> impl FnMut(&Frame) -> bool + Send + 'static {
    let fps = fps.filter(|f| f.is_finite() && *f > 0.0).unwrap_or(30.0);
    let step = ((fps * TEXTURE_SECONDS / TEXTURE_FRAMES as f64).round() as usize).max(1);
    let mut seen = 0usize;
    let mut first: Option<f64> = None;
    move |frame: &Frame| {
        let t = frame.timestamp_s.unwrap_or(frame.index as f64 / fps);
        let t0 = *first.get_or_insert(t);
        seen += 1;
        t <= t0 + TEXTURE_SECONDS && (seen - 1).is_multiple_of(step)
    }
}

/// Exports the run in `dir`. `frames`: input frames kept during the run (see
/// [`texture_frames`]); without them the texture's frames are decoded again from the input.
///
/// # Errors
/// The folder is not a complete run's, an input frame cannot be read back, or a file cannot
/// be written.
pub fn export(
    dir: &Path,
    options: &ExportOptions,
    frames: Option<&[Frame]>,
) -> Result<ExportSummary, ExportError> {
    let start = Instant::now();
    let capture = Capture::open(dir)?;
    let mut summary = ExportSummary::default();
    let glb_wanted = options.glb || options.report;
    let mut texture_image = None;
    let texture_png = if options.texture || glb_wanted {
        let t = Instant::now();
        match make_texture(&capture, frames)? {
            Some((texture, png)) => {
                write_file(&dir.join(file_names::TEXTURE), &png)?;
                visage_mesh::io::write_mtl(
                    &dir.join(file_names::CACHE_MATERIAL_FILE),
                    CACHE_MATERIAL,
                    Some(file_names::TEXTURE),
                )?;
                summary.texture_frames = texture.frames_used;
                summary.texture_coverage = Some(texture.coverage);
                summary.files.push(file_entry(dir, file_names::TEXTURE, t));
                texture_image = Some(texture.image);
                Some(png)
            }
            None => None,
        }
    } else {
        None
    };
    // The glb and the plots are independent: each on a core.
    let (glb, plots) = rayon::join(
        || {
            glb_wanted
                .then(|| make_glb(&capture, dir, texture_png.as_deref()))
                .transpose()
        },
        || {
            (options.plots || options.report)
                .then(|| make_plots(&capture, dir))
                .transpose()
        },
    );
    let glb = match glb? {
        Some((bytes, animation, file)) => {
            summary.named_targets = animation.named_targets;
            summary.named_explained = animation.named_explained;
            summary.residual_targets = animation.targets.len() - animation.named_targets;
            summary.glb_rms_error_m = Some(animation.rms_error_m);
            summary.glb_max_error_m = Some(animation.max_error_m);
            summary.files.push(file);
            Some(bytes)
        }
        None => None,
    };
    let plots = match plots? {
        Some((plots, file)) => {
            summary.files.push(file);
            plots
        }
        None => Vec::new(),
    };
    // The preview before the report, so that the report's table of files lists it.
    if options.preview {
        let t = Instant::now();
        write_preview(&capture, &dir.join(file_names::PREVIEW))?;
        summary.files.push(file_entry(dir, file_names::PREVIEW, t));
    }
    if options.report {
        let t = Instant::now();
        let renders = frame_renders::frame_renders(&capture, texture_image.as_ref())?;
        let viewer = VIEWER_JS.zip(glb.as_deref());
        let html = report_html(&capture, &summary, &plots, &renders, viewer);
        write_file(&dir.join(file_names::REPORT), html.as_bytes())?;
        summary.files.push(file_entry(dir, file_names::REPORT, t));
    }
    summary.total_ms = start.elapsed().as_secs_f64() * 1e3;
    let text =
        serde_json::to_string_pretty(&summary).map_err(|e| ExportError::Internal(e.to_string()))?;
    write_file(&dir.join(file_names::EXPORT), text.as_bytes())?;
    Ok(summary)
}

/// The animation encoded and written to `sequence.glb`: its bytes, the encoding and the file.
fn make_glb(
    capture: &Capture,
    dir: &Path,
    texture_png: Option<&[u8]>,
) -> Result<(Vec<u8>, MorphAnimation, ExportedFile), ExportError> {
    let t = Instant::now();
    let animation = MorphAnimation::encode(capture, |base| {
        let deltas = arkit_targets::arkit_targets(capture, base)?;
        let curves = capture.blendshapes.as_ref()?;
        let order: Vec<Option<usize>> = visage_rig::ARKIT_BLENDSHAPES
            .iter()
            .map(|a| curves.names.iter().position(|n| n == a))
            .collect();
        Some(NamedTargets {
            names: visage_rig::ARKIT_BLENDSHAPES
                .iter()
                .map(|s| s.to_string())
                .collect(),
            deltas,
            weights: curves
                .weights
                .iter()
                .map(|w| {
                    order
                        .iter()
                        .map(|i| w.as_ref().zip(*i).map_or(0.0, |(w, i)| w[i]))
                        .collect()
                })
                .collect(),
        })
    })?;
    let extras = serde_json::json!({
        "input": capture.input,
        "start_s": animation.start_s,
        "rms_error_m": animation.rms_error_m,
        "max_error_m": animation.max_error_m,
    });
    let bytes = write_glb(
        &animation,
        &capture.mesh.triangles,
        &capture.mesh.uvs,
        &capture.intrinsics,
        texture_png,
        extras,
    )?;
    write_file(&dir.join(file_names::GLB), &bytes)?;
    Ok((bytes, animation, file_entry(dir, file_names::GLB, t)))
}

/// The per-frame charts, written to `plots/` as SVG and PNG.
fn make_plots(capture: &Capture, dir: &Path) -> Result<(Vec<Plot>, ExportedFile), ExportError> {
    let t = Instant::now();
    let landmarks_path = dir.join(file_names::LANDMARKS);
    let landmarks = landmarks_path
        .is_file()
        .then(|| capture::read_json(&landmarks_path))
        .transpose()?;
    let plots = run_plots(capture, landmarks.as_ref());
    let plot_dir = dir.join(file_names::PLOTS_FOLDER);
    std::fs::create_dir_all(&plot_dir).map_err(|source| ExportError::Write {
        path: plot_dir.clone(),
        source,
    })?;
    let mut bytes = 0;
    for p in &plots {
        let png = p.png()?;
        write_file(&plot_dir.join(format!("{}.svg", p.name)), p.svg.as_bytes())?;
        write_file(&plot_dir.join(format!("{}.png", p.name)), &png)?;
        bytes += (p.svg.len() + png.len()) as u64;
    }
    let file = ExportedFile {
        file: format!("{}/", file_names::PLOTS_FOLDER),
        bytes,
        ms: t.elapsed().as_secs_f64() * 1e3,
    };
    Ok((plots, file))
}

/// The texture fused from up to [`TEXTURE_FRAMES`] meshed frames, and its PNG; `None` when the
/// mesh has no UVs.
fn make_texture(
    capture: &Capture,
    frames: Option<&[Frame]>,
) -> Result<Option<(FusedTexture, Vec<u8>)>, ExportError> {
    if capture.mesh.uvs.len() != capture.vertex_count() {
        return Ok(None);
    }
    if let Some(frames) = frames {
        let by_index: std::collections::HashMap<usize, usize> =
            capture.meshed().map(|(k, f)| (f.index, k)).collect();
        let views: Vec<TextureView<'_>> = frames
            .iter()
            .filter_map(|f| {
                by_index.get(&f.index).map(|&k| TextureView {
                    vertices: capture.surface_points(k),
                    image: &f.image,
                })
            })
            .collect();
        let first = by_index.values().min().copied().unwrap_or(0);
        return encode_texture(fuse_texture(
            &capture.mesh,
            &capture.intrinsics,
            &views,
            texture_size(capture, first),
        )?)
        .map(Some);
    }
    let start = capture.meshed().next().map_or(0.0, |(_, f)| f.time_s);
    let meshed: Vec<usize> = capture
        .meshed()
        .filter(|(_, f)| f.time_s <= start + TEXTURE_SECONDS)
        .map(|(k, _)| k)
        .collect();
    let picks: Vec<usize> = if meshed.len() <= TEXTURE_FRAMES {
        meshed
    } else {
        (0..TEXTURE_FRAMES)
            .map(|i| meshed[i * (meshed.len() - 1) / (TEXTURE_FRAMES - 1)])
            .collect()
    };
    let images = read_frames(
        &capture.input,
        picks.iter().map(|&k| capture.frames[k].index),
    )?;
    let views: Vec<TextureView<'_>> = picks
        .iter()
        .zip(&images)
        .map(|(&k, image)| TextureView {
            vertices: capture.surface_points(k),
            image,
        })
        .collect();
    let size = texture_size(capture, picks.first().copied().unwrap_or(0));
    encode_texture(fuse_texture(
        &capture.mesh,
        &capture.intrinsics,
        &views,
        size,
    )?)
    .map(Some)
}

/// The texture and its PNG.
fn encode_texture(texture: FusedTexture) -> Result<(FusedTexture, Vec<u8>), ExportError> {
    let png = png_bytes(&texture.image)?;
    Ok((texture, png))
}

/// The texture's side for the face's size in frame `k` (see [`TEXTURE_SIZE_RANGE`]).
fn texture_size(capture: &Capture, frame: usize) -> usize {
    let k = &capture.intrinsics;
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in capture.surface(frame).chunks_exact(3) {
        if p[2] > 0.0 {
            let px = [
                k.fx * p[0] as f64 / p[2] as f64,
                k.fy * p[1] as f64 / p[2] as f64,
            ];
            for c in 0..2 {
                lo[c] = lo[c].min(px[c]);
                hi[c] = hi[c].max(px[c]);
            }
        }
    }
    let face_px = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);
    let uv = &capture.mesh.uvs;
    let span = |c: usize| {
        let (lo, hi) = uv
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
                (lo.min(t[c]), hi.max(t[c]))
            });
        (hi - lo).clamp(0.05, 1.0)
    };
    let (min, max) = TEXTURE_SIZE_RANGE;
    ((face_px / span(0).max(span(1))).ceil() as usize)
        .next_power_of_two()
        .clamp(min, max)
}

/// The input frames with these indices (increasing), decoded again from `input`.
fn read_frames(
    input: &Path,
    indices: impl Iterator<Item = usize>,
) -> Result<Vec<image::RgbImage>, ExportError> {
    let mut wanted: Vec<usize> = indices.collect();
    wanted.dedup();
    let mut out = Vec::with_capacity(wanted.len());
    let mut next = wanted.iter().peekable();
    for frame in FrameSource::open(input)? {
        let Some(&&index) = next.peek() else { break };
        let frame = frame?;
        if frame.index == index {
            out.push(frame.image);
            next.next();
        }
    }
    if out.len() != wanted.len() {
        return Err(ExportError::Mismatch {
            path: input.to_owned(),
            reason: format!(
                "the run used {} frames that the input no longer has",
                wanted.len() - out.len()
            ),
        });
    }
    Ok(out)
}

/// An RGB image as PNG, compressed for speed (these are a few hundred kilobytes at most).
pub(crate) fn png_bytes(image: &image::RgbImage) -> Result<Vec<u8>, ExportError> {
    use image::ImageEncoder;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut png,
        image::codecs::png::CompressionType::Fast,
        image::codecs::png::FilterType::Adaptive,
    )
    .write_image(
        image.as_raw(),
        image.width(),
        image.height(),
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| ExportError::Internal(format!("PNG encoding: {e}")))?;
    Ok(png)
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), ExportError> {
    let tmp = visage_run_folder::tmp_path(path);
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|source| ExportError::Write {
            path: path.to_owned(),
            source,
        })
}

fn file_entry(dir: &Path, name: &str, since: Instant) -> ExportedFile {
    ExportedFile {
        file: name.to_owned(),
        bytes: std::fs::metadata(dir.join(name)).map_or(0, |m| m.len()),
        ms: since.elapsed().as_secs_f64() * 1e3,
    }
}
