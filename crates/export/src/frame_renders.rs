//! The report's contact sheet: each of the take's moments ([`crate::moments`]) as its source
//! frame beside the fused surface seen by the video's camera (with the fused texture when
//! there is one, shaded otherwise), both cropped to the face.

use image::RgbImage;
use visage_mesh::TriMesh;
use visage_render::{Albedo, Camera, Frame, Mat4, Renderer, Scene, Texture, Wrap};
use visage_video::FrameSource;

use crate::capture::Capture;
use crate::moments::{moments, MomentKind};
use crate::report::Render;
use crate::ExportError;

/// The contact sheet's pictures, in time order: source frame | render, one PNG per moment.
/// A moment whose frame the input no longer gives (a moved or shortened file) shows the
/// render alone.
pub fn frame_renders(
    capture: &Capture,
    texture: Option<&RgbImage>,
) -> Result<Vec<Render>, ExportError> {
    let moments: Vec<_> = moments(capture)
        .into_iter()
        .filter(|m| capture.frames[m.frame].meshed)
        .collect();
    if moments.is_empty() {
        return Ok(Vec::new());
    }
    let sources = source_frames(
        capture,
        moments.iter().map(|m| capture.frames[m.frame].index),
    );
    let k = capture.intrinsics;
    let camera = Camera::new(k)?;
    let texture =
        texture.map(|t| Texture::from_rgba8(&image::DynamicImage::ImageRgb8(t.clone()).to_rgba8()));
    let albedo = match &texture {
        Some(t) => Albedo::Texture {
            texture: t,
            wrap: Wrap::Clamp,
        },
        None => Albedo::Constant([0.8; 3]),
    };
    let scene = Scene {
        albedo,
        background: [0.02; 3],
        ..Scene::default()
    };
    let mut renderer = Renderer::new();
    let mut frame = Frame::color_and_depth(k.width, k.height, visage_camera::DepthKind::Z);
    let mut out = Vec::new();
    for m in &moments {
        let f = &capture.frames[m.frame];
        let mut mesh = TriMesh::new(
            capture.surface_points(m.frame),
            capture.mesh.triangles.clone(),
        );
        mesh.uvs = capture.mesh.uvs.clone();
        renderer.render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut frame)?;
        let source = sources
            .iter()
            .find(|(index, _)| *index == f.index)
            .map(|(_, image)| image);
        let kind = match m.kind {
            MomentKind::Blink => "blink",
            MomentKind::Cut => "cut",
            MomentKind::Expressive => "expression",
        };
        out.push(Render {
            caption: format!("{kind} · frame {} ({:.2} s): {}", f.index, f.time_s, m.note),
            png: side_by_side_png(&frame, source, k.width, k.height)?,
        });
    }
    Ok(out)
}

/// The input's frames with the given indices (in increasing order), decoded once; frames the
/// input cannot give are left out.
fn source_frames(capture: &Capture, wanted: impl Iterator<Item = usize>) -> Vec<(usize, RgbImage)> {
    let mut wanted: Vec<usize> = wanted.collect();
    wanted.sort_unstable();
    wanted.dedup();
    let mut out = Vec::new();
    let Ok(source) = FrameSource::open(&capture.input) else {
        return out;
    };
    let k = capture.intrinsics;
    let mut next = wanted.iter().peekable();
    for decoded in source {
        let Some(&&want) = next.peek() else {
            break;
        };
        let Ok(decoded) = decoded else {
            break;
        };
        if decoded.index < want {
            continue;
        }
        while next.peek().is_some_and(|&&w| w < decoded.index) {
            next.next();
        }
        if next.peek() == Some(&&decoded.index) && decoded.image.dimensions() == (k.width, k.height)
        {
            out.push((decoded.index, decoded.image));
            next.next();
        }
    }
    out
}

/// The source frame (when there is one) and the render side by side as an sRGB PNG, both
/// cropped to the rendered surface plus a 15 % margin.
fn side_by_side_png(
    frame: &Frame,
    source: Option<&RgbImage>,
    width: u32,
    height: u32,
) -> Result<Vec<u8>, ExportError> {
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
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    let panels = if source.is_some() { 2 } else { 1 };
    let image = RgbImage::from_fn(panels * w, h, |x, y| match source {
        Some(source) if x < w => *source.get_pixel(x + x0, y + y0),
        _ => {
            let x = x % w;
            let c = frame.color[((y + y0) * width + x + x0) as usize];
            image::Rgb([0, 1, 2].map(|i| visage_mesh::color::linear_to_srgb_u8(c[i])))
        }
    });
    crate::png_bytes(&image)
}
