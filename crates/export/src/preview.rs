//! `preview.mp4`: the run at a glance, three panels side by side — the input frame; the shaded
//! fused mesh over it; the shaded mesh alone, turning slowly — one video frame per processed
//! input frame.
//!
//! The input is decoded again and paired with [`Capture::frames`] by index (frames the run
//! skipped with `--every` are not written; the video's rate is that of the processed frames, so
//! it plays in real time). Each panel is the input scaled to at most [`PANEL_MAX_HEIGHT`] rows
//! (aspect kept, both sides even for H.264), and the meshes are rendered at the panel's size
//! through the run's camera scaled with it, so the overlay registers with the scaled frame.

use std::path::Path;

use image::RgbImage;
use rayon::prelude::*;
use visage_camera::{DepthKind, Intrinsics};
use visage_mesh::color::{linear_to_srgb_u8, srgb_to_linear_u8};
use visage_render::{turn_about_centre, Albedo, Camera, Frame, Mat4, Renderer, Scene};
use visage_video::{AudioTrack, FrameSource, VideoWriter};

use crate::{Capture, ExportError};

/// The panels' height at most, pixels (smaller inputs are not enlarged).
pub const PANEL_MAX_HEIGHT: u32 = 480;
/// Opacity of the shaded mesh over the input frame (middle panel).
pub const OVERLAY_ALPHA: f32 = 0.6;
/// The turning panel swings the mesh this far either way about the vertical axis, degrees…
pub const TURN_AMPLITUDE_DEG: f64 = 35.0;
/// …once in this many seconds (a sine, starting at the camera's view).
pub const TURN_PERIOD_S: f64 = 6.0;
/// Frame rate when the capture's timestamps give none.
const FALLBACK_FPS: f64 = 30.0;
/// The meshes' albedo (linear): light grey.
const ALBEDO: [f32; 3] = [0.75; 3];
/// The turning panel's background (sRGB): near black, a little blue.
const BACKGROUND: [u8; 3] = [22, 24, 30];

/// What [`write_preview`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PreviewSummary {
    /// Video frames (= processed frames).
    pub frames: usize,
    /// Video size, pixels (three panels side by side).
    pub width: u32,
    pub height: u32,
}

/// input | shaded mesh over the input | shaded mesh turning slowly, side by side, with the
/// input's sound.
///
/// Writes an H.264 MP4 to `path` (through a temporary file, see [`VideoWriter`]). Frames
/// without a mesh of their own show the input in the first two panels and an empty third.
///
/// # Errors
/// The capture has no frames; the input cannot be decoded again, has another frame size than
/// the run's camera, or lacks frames the run processed; rendering or encoding fails.
pub fn write_preview(capture: &Capture, path: &Path) -> Result<PreviewSummary, ExportError> {
    if capture.frames.is_empty() {
        return Err(ExportError::Empty {
            path: capture.dir.clone(),
        });
    }
    let k = capture.intrinsics;
    let (pw, ph) = panel_size(k.width, k.height);
    let camera = Camera::new(scaled_intrinsics(&k, pw, ph))?;
    // The input's sound from the first frame on (the preview plays at the frames' own pace,
    // so it stays in sync); an image folder has none.
    let audio = capture.input.is_file().then_some(AudioTrack {
        path: &capture.input,
        start_s: capture.frames[0].time_s,
    });
    let mut writer = VideoWriter::create_with_audio(path, 3 * pw, ph, frame_rate(capture), audio)?;
    let mut mesh = capture.mesh.clone();
    // Per-frame vertices: the OBJ's normals (if any) belong to another frame's.
    mesh.normals.clear();
    let overlay_scene = Scene {
        albedo: Albedo::Constant(ALBEDO),
        ..Scene::default()
    };
    let turn_scene = Scene {
        albedo: Albedo::Constant(ALBEDO),
        background: BACKGROUND.map(srgb_to_linear_u8),
        ..Scene::default()
    };
    let srgb = SrgbTables::new();
    let mut renderer = Renderer::new();
    let mut overlay = Frame::color_and_depth(pw, ph, DepthKind::Z);
    let mut turned = Frame::color_and_depth(pw, ph, DepthKind::Z);
    let mut canvas = RgbImage::new(3 * pw, ph);
    let t0 = capture.frames[0].time_s;

    let mismatch = |reason: String| ExportError::Mismatch {
        path: capture.input.clone(),
        reason,
    };
    let mut wanted = capture.frames.iter().enumerate().peekable();
    for decoded in FrameSource::open(&capture.input)? {
        let Some(&(n, frame)) = wanted.peek() else {
            break;
        };
        let decoded = decoded?;
        if decoded.index < frame.index {
            continue;
        }
        if decoded.index > frame.index {
            return Err(mismatch(format!(
                "the run processed frame {}, which the input does not have",
                frame.index
            )));
        }
        if decoded.image.dimensions() != (k.width, k.height) {
            return Err(mismatch(format!(
                "frame {} is {}×{}, the run's camera is {}×{}",
                frame.index,
                decoded.image.width(),
                decoded.image.height(),
                k.width,
                k.height
            )));
        }
        let input = if (pw, ph) == (k.width, k.height) {
            decoded.image
        } else {
            resize(&decoded.image, pw, ph)
        };
        let rendered = if frame.meshed {
            mesh.vertices = capture.surface_points(n);
            renderer.render(
                &mesh,
                &camera,
                &Mat4::IDENTITY,
                &overlay_scene,
                &mut overlay,
            )?;
            let angle = TURN_AMPLITUDE_DEG.to_radians()
                * (std::f64::consts::TAU * (frame.time_s - t0) / TURN_PERIOD_S).sin();
            let model = turn_about_centre(&mesh.vertices, angle);
            renderer.render(&mesh, &camera, &model, &turn_scene, &mut turned)?;
            Some((&overlay, &turned))
        } else {
            None
        };
        compose(&mut canvas, &input, rendered, &srgb);
        writer.write_frame(&canvas)?;
        wanted.next();
    }
    if let Some((_, frame)) = wanted.peek() {
        return Err(mismatch(format!(
            "the input ends before frame {}, which the run processed",
            frame.index
        )));
    }
    let frames = writer.finish()?;
    Ok(PreviewSummary {
        frames,
        width: 3 * pw,
        height: ph,
    })
}

/// One video frame: `input` | `overlay` blended over `input` | `turned`, or the input twice and
/// the background without `rendered`.
fn compose(
    canvas: &mut RgbImage,
    input: &RgbImage,
    rendered: Option<(&Frame, &Frame)>,
    srgb: &SrgbTables,
) {
    let pw = input.width() as usize;
    let row_len = 3 * pw;
    let input = input.as_raw();
    canvas
        .par_chunks_mut(3 * row_len)
        .enumerate()
        .for_each(|(y, row)| {
            let src = &input[y * row_len..(y + 1) * row_len];
            let (first, rest) = row.split_at_mut(row_len);
            let (second, third) = rest.split_at_mut(row_len);
            first.copy_from_slice(src);
            second.copy_from_slice(src);
            let Some((overlay, turned)) = rendered else {
                third
                    .chunks_exact_mut(3)
                    .for_each(|p| p.copy_from_slice(&BACKGROUND));
                return;
            };
            for x in 0..pw {
                let i = y * pw + x;
                let px = &mut second[3 * x..3 * x + 3];
                if overlay.depth.data[i] > 0.0 {
                    let c = overlay.color[i];
                    for ch in 0..3 {
                        let under = srgb.to_linear[px[ch] as usize];
                        px[ch] = srgb.encode((1.0 - OVERLAY_ALPHA) * under + OVERLAY_ALPHA * c[ch]);
                    }
                }
                let px = &mut third[3 * x..3 * x + 3];
                if turned.depth.data[i] > 0.0 {
                    let c = turned.color[i];
                    for ch in 0..3 {
                        px[ch] = srgb.encode(c[ch]);
                    }
                } else {
                    px.copy_from_slice(&BACKGROUND);
                }
            }
        });
}

/// Steps of the linear → sRGB table: fine enough that every 8-bit sRGB value survives the
/// round trip through linear (the darkest levels are ~5 steps apart).
const SRGB_STEPS: usize = 1 << 14;

/// sRGB ↔ linear by table: the compositing converts every covered pixel, and `powf` per channel
/// cost as much as both renders together.
struct SrgbTables {
    to_linear: [f32; 256],
    to_srgb: Vec<u8>,
}

impl SrgbTables {
    fn new() -> SrgbTables {
        let last = (SRGB_STEPS - 1) as f32;
        SrgbTables {
            to_linear: std::array::from_fn(|b| srgb_to_linear_u8(b as u8)),
            to_srgb: (0..SRGB_STEPS)
                .map(|i| linear_to_srgb_u8(i as f32 / last))
                .collect(),
        }
    }

    /// A linear value → 8-bit sRGB (clamped to `[0, 1]`, NaN → 0).
    #[inline]
    fn encode(&self, c: f32) -> u8 {
        let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
        self.to_srgb[(c * (SRGB_STEPS - 1) as f32 + 0.5) as usize]
    }
}

/// `src` resampled to `width × height`: separable triangle filter, widened to the scale when
/// shrinking so that every source pixel counts (no aliasing), rows in parallel. What
/// `image::imageops::resize` with `FilterType::Triangle` computes (to a level), four to five
/// times faster: 2 ms against 9 ms for 720 × 1280 → 270 × 480 on two cores, where the image
/// crate's took longer than rendering both panels.
fn resize(src: &RgbImage, width: u32, height: u32) -> RgbImage {
    let (sw, sh) = (src.width() as usize, src.height() as usize);
    let xs = resample_taps(sw, width as usize);
    let ys = resample_taps(sh, height as usize);
    let mut out = RgbImage::new(width, height);
    let src = src.as_raw();
    out.par_chunks_mut(3 * width as usize)
        .zip(ys.par_iter())
        .for_each_init(
            || vec![0f32; 3 * sw],
            |column, (row, taps)| {
                column.fill(0.0);
                for &(j, w) in taps {
                    let s = &src[3 * sw * j..3 * sw * (j + 1)];
                    for (c, &v) in column.iter_mut().zip(s) {
                        *c += w * v as f32;
                    }
                }
                for (px, taps) in row.chunks_exact_mut(3).zip(&xs) {
                    let mut acc = [0f32; 3];
                    for &(i, w) in taps {
                        for c in 0..3 {
                            acc[c] += w * column[3 * i + c];
                        }
                    }
                    for c in 0..3 {
                        px[c] = (acc[c] + 0.5).clamp(0.0, 255.0) as u8;
                    }
                }
            },
        );
    out
}

/// Per output sample along one axis (`src` → `dst` samples), the source samples and their
/// weights (summing to 1): a triangle of radius one output pixel, at least one source pixel,
/// centred where the output pixel's centre falls; beyond the edges the edge pixel repeats.
fn resample_taps(src: usize, dst: usize) -> Vec<Vec<(usize, f32)>> {
    let scale = dst as f64 / src as f64;
    let radius = (1.0 / scale).max(1.0);
    (0..dst)
        .map(|i| {
            let centre = (i as f64 + 0.5) / scale - 0.5;
            let mut taps: Vec<(usize, f64)> = Vec::new();
            for j in (centre - radius).floor() as i64..=(centre + radius).ceil() as i64 {
                let w = 1.0 - (j as f64 - centre).abs() / radius;
                if w <= 0.0 {
                    continue;
                }
                let k = j.clamp(0, src as i64 - 1) as usize;
                match taps.last_mut() {
                    Some((last, sum)) if *last == k => *sum += w,
                    _ => taps.push((k, w)),
                }
            }
            let total: f64 = taps.iter().map(|t| t.1).sum();
            taps.into_iter()
                .map(|(k, w)| (k, (w / total) as f32))
                .collect()
        })
        .collect()
}

/// A panel's size: the input's, scaled so that the height is at most [`PANEL_MAX_HEIGHT`],
/// each side rounded to an even number (at least 2).
fn panel_size(width: u32, height: u32) -> (u32, u32) {
    let scale = (PANEL_MAX_HEIGHT as f64 / height as f64).min(1.0);
    let even = |d: u32| (2 * (d as f64 * scale / 2.0).round() as u32).max(2);
    (even(width), even(height))
}

/// `k` for the same view at `width × height`: focal lengths scale with the image; the principal
/// point scales in continuous image coordinates, whose origin is the first pixel's corner, half
/// a pixel before the first pixel's centre (pixel centres are at integers).
fn scaled_intrinsics(k: &Intrinsics, width: u32, height: u32) -> Intrinsics {
    let sx = width as f64 / k.width as f64;
    let sy = height as f64 / k.height as f64;
    Intrinsics {
        width,
        height,
        fx: k.fx * sx,
        fy: k.fy * sy,
        cx: (k.cx + 0.5) * sx - 0.5,
        cy: (k.cy + 0.5) * sy - 0.5,
    }
}

/// The rate of the processed frames: one over the median step between their timestamps
/// ([`FALLBACK_FPS`] with fewer than two frames or no positive step).
fn frame_rate(capture: &Capture) -> f64 {
    let mut steps: Vec<f64> = capture
        .frames
        .windows(2)
        .map(|w| w[1].time_s - w[0].time_s)
        .filter(|d| d.is_finite() && *d > 0.0)
        .collect();
    if steps.is_empty() {
        return FALLBACK_FPS;
    }
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    let fps = 1.0 / median;
    if fps.is_finite() && fps > 0.0 {
        fps
    } else {
        FALLBACK_FPS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_are_even_and_at_most_480_rows() {
        assert_eq!(panel_size(480, 480), (480, 480));
        assert_eq!(panel_size(1920, 1080), (854, 480));
        assert_eq!(panel_size(1080, 1920), (270, 480));
        assert_eq!(panel_size(641, 361), (642, 362));
        assert_eq!(panel_size(3, 1), (4, 2));
    }

    #[test]
    fn scaled_intrinsics_keep_the_view() {
        let k = Intrinsics::from_fov(1920, 1080, 60.0).unwrap();
        let s = scaled_intrinsics(&k, 854, 480);
        // The image centre stays the image centre, and a point projects to the same place
        // relative to the image (continuous coordinates scale by the size ratio).
        assert!((s.cx - 0.5 * (854.0 - 1.0)).abs() < 1e-9);
        assert!((s.cy - 0.5 * (480.0 - 1.0)).abs() < 1e-9);
        let p = [0.03, -0.02, 0.4];
        let (u, v) = (k.fx * p[0] / p[2] + k.cx, k.fy * p[1] / p[2] + k.cy);
        let (su, sv) = (s.fx * p[0] / p[2] + s.cx, s.fy * p[1] / p[2] + s.cy);
        assert!(((su + 0.5) / 854.0 - (u + 0.5) / 1920.0).abs() < 1e-12);
        assert!(((sv + 0.5) / 480.0 - (v + 0.5) / 1080.0).abs() < 1e-12);
    }

    #[test]
    fn srgb_tables_round_trip_every_byte_and_stay_within_a_level() {
        let t = SrgbTables::new();
        for b in 0..=255u8 {
            assert_eq!(t.encode(t.to_linear[b as usize]), b);
        }
        for i in 0..=1000 {
            let c = i as f32 / 1000.0;
            assert!(t.encode(c).abs_diff(linear_to_srgb_u8(c)) <= 1, "{c}");
        }
        assert_eq!(
            (t.encode(f32::NAN), t.encode(-1.0), t.encode(2.0)),
            (0, 0, 255)
        );
    }

    #[test]
    fn resizing_keeps_flat_colour_and_matches_the_image_crate() {
        let flat = RgbImage::from_pixel(72, 128, image::Rgb([10, 128, 250]));
        let small = resize(&flat, 28, 48);
        assert!(small.pixels().all(|p| p.0 == [10, 128, 250]));
        let src = RgbImage::from_fn(120, 90, |x, y| {
            image::Rgb([(2 * x) as u8, (3 * y) as u8, ((x * y) % 251) as u8])
        });
        for (w, h) in [(46, 34), (122, 92), (120, 90)] {
            let ours = resize(&src, w, h);
            let theirs = image::imageops::resize(&src, w, h, image::imageops::FilterType::Triangle);
            let diffs: Vec<u8> = ours
                .as_raw()
                .iter()
                .zip(theirs.as_raw())
                .map(|(a, b)| a.abs_diff(*b))
                .collect();
            let mean = diffs.iter().map(|&d| d as f64).sum::<f64>() / diffs.len() as f64;
            assert!(mean < 0.6, "{w}×{h}: mean difference {mean}");
        }
        assert_eq!(resize(&src, 120, 90), src, "the same size is a copy");
    }

    #[test]
    fn the_turn_keeps_the_centre_and_swings_the_sides() {
        let v = [[-0.1, 0.0, 0.5], [0.1, 0.2, 0.7]];
        let m = turn_about_centre(&v, 30f64.to_radians());
        let c = m.transform_point([0.0, 0.1, 0.6]);
        assert!((c[0]).abs() < 1e-12 && (c[1] - 0.1).abs() < 1e-12 && (c[2] - 0.6).abs() < 1e-12);
        let side = m.transform_point([0.1, 0.1, 0.6]);
        assert!((side[2] - 0.6).abs() > 0.04, "a side point moves in depth");
        assert!((side[1] - 0.1).abs() < 1e-12, "…not vertically");
    }
}
