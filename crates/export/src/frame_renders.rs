//! Renders of a few frames for the report: the fused surface seen by the video's camera,
//! shaded, and with the fused texture.

use image::RgbImage;
use visage_mesh::TriMesh;
use visage_render::{Albedo, Camera, Frame, Mat4, Renderer, Scene, Texture, Wrap};

use crate::capture::Capture;
use crate::report::Render;
use crate::ExportError;

/// Frames rendered: the first, middle and last meshed ones.
const RENDERED_FRAMES: usize = 3;

/// Shaded and textured renders of the first, middle and last meshed frames (PNG), cropped to
/// the face with a margin.
pub fn frame_renders(
    capture: &Capture,
    texture: Option<&RgbImage>,
) -> Result<Vec<Render>, ExportError> {
    let meshed: Vec<usize> = capture.meshed().map(|(k, _)| k).collect();
    if meshed.is_empty() {
        return Ok(Vec::new());
    }
    let picks: Vec<usize> = (0..RENDERED_FRAMES)
        .map(|i| meshed[i * (meshed.len() - 1) / (RENDERED_FRAMES - 1).max(1)])
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();
    let k = capture.intrinsics;
    let camera = Camera::new(k)?;
    let texture =
        texture.map(|t| Texture::from_rgba8(&image::DynamicImage::ImageRgb8(t.clone()).to_rgba8()));
    let mut renderer = Renderer::new();
    let mut frame = Frame::color_and_depth(k.width, k.height, visage_camera::DepthKind::Z);
    let mut out = Vec::new();
    for &f in &picks {
        let mut mesh = TriMesh::new(capture.surface_points(f), capture.mesh.triangles.clone());
        mesh.uvs = capture.mesh.uvs.clone();
        let time = capture.frames[f].time_s;
        let mut albedos = vec![("shaded", Albedo::Constant([0.8; 3]))];
        if let Some(t) = &texture {
            albedos.push((
                "textured",
                Albedo::Texture {
                    texture: t,
                    wrap: Wrap::Clamp,
                },
            ));
        }
        for (kind, albedo) in albedos {
            let scene = Scene {
                albedo,
                background: [0.02; 3],
                ..Scene::default()
            };
            renderer.render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut frame)?;
            out.push(Render {
                caption: format!("frame {} ({time:.2} s), {kind}", capture.frames[f].index),
                png: crop_png(&frame, k.width, k.height)?,
            });
        }
    }
    Ok(out)
}

/// The frame's colour as an sRGB PNG, cropped to the rendered surface plus a 15 % margin.
fn crop_png(frame: &Frame, width: u32, height: u32) -> Result<Vec<u8>, ExportError> {
    let (mut lo, mut hi) = ([u32::MAX; 2], [0u32; 2]);
    for y in 0..height {
        for x in 0..width {
            if frame.depth.data[(y * width + x) as usize] > 0.0 {
                lo = [lo[0].min(x), lo[1].min(y)];
                hi = [hi[0].max(x), hi[1].max(y)];
            }
        }
    }
    if lo[0] > hi[0] {
        (lo, hi) = ([0, 0], [width - 1, height - 1]);
    }
    let margin = ((hi[0] - lo[0]).max(hi[1] - lo[1]) as f64 * 0.15) as u32;
    let (x0, y0) = (lo[0].saturating_sub(margin), lo[1].saturating_sub(margin));
    let (x1, y1) = (
        (hi[0] + margin).min(width - 1),
        (hi[1] + margin).min(height - 1),
    );
    let image = RgbImage::from_fn(x1 - x0 + 1, y1 - y0 + 1, |x, y| {
        let c = frame.color[((y + y0) * width + x + x0) as usize];
        image::Rgb([0, 1, 2].map(|i| visage_mesh::color::linear_to_srgb_u8(c[i])))
    });
    crate::png_bytes(&image)
}
