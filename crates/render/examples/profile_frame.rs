//! Renders the benchmark scene of `benches/render_frame.rs` a given number of times, for
//! instruction-count profiling (`valgrind --tool=callgrind`), which criterion's timing loop does
//! not suit: `cargo run --release -p visage-render --example profile_frame -- 5` (colour frames)
//! or `-- 5 depth` (the depth-only ground-truth path, `render_depth_with`).

use visage_camera::{DepthKind, Intrinsics};
use visage_render::{
    render_depth_with, Albedo, Camera, CullMode, Frame, Mat4, Rasterizer, Renderer, Scene, Wrap,
};

#[path = "../benches/common/scene.rs"]
mod scene;

use scene::{face_like_mesh, texture};

fn main() {
    let frames: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1);
    let k = Intrinsics::new(1280, 720, 1000.0, 1000.0, 639.5, 359.5).expect("valid intrinsics");
    let camera = Camera::new(k).expect("valid camera");
    let mesh = face_like_mesh();
    let tex = texture();
    let scene = Scene {
        albedo: Albedo::Texture {
            texture: &tex,
            wrap: Wrap::Clamp,
        },
        ..Scene::default()
    };
    if std::env::args().nth(2).as_deref() == Some("depth") {
        let mut rasterizer = Rasterizer::new();
        let start = std::time::Instant::now();
        let mut valid = 0;
        for _ in 0..frames {
            let r = render_depth_with(
                &mut rasterizer,
                &mesh,
                &camera,
                &Mat4::IDENTITY,
                DepthKind::Z,
                CullMode::None,
            )
            .expect("renders");
            valid = r.depth.valid_count();
        }
        eprintln!(
            "{frames} depth frames, {:.2} ms/frame wall, {valid} pixels",
            start.elapsed().as_secs_f64() * 1e3 / frames as f64
        );
        return;
    }
    let mut renderer = Renderer::new();
    let mut images = Frame::color_and_depth(k.width, k.height, DepthKind::Z);
    let start = std::time::Instant::now();
    for _ in 0..frames {
        renderer
            .render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut images)
            .expect("renders");
    }
    let checksum: f64 = images
        .color
        .iter()
        .flatten()
        .map(|&c| c as f64)
        .sum::<f64>()
        + images.depth.data.iter().map(|&d| d as f64).sum::<f64>();
    eprintln!(
        "{frames} frames, {:.2} ms/frame wall, checksum {checksum:.6}",
        start.elapsed().as_secs_f64() * 1e3 / frames as f64
    );
}
