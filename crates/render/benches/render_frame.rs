//! Speed of Algorithm 3 on a 1280×720 frame of a 30k-triangle textured, shaded mesh (target:
//! ≤ 10 ms on the 2-core build machine), and of the depth-only ground-truth path.
//!
//! The mesh is a bumpy, face-like height field (124 × 123 vertices, 30 012 triangles) seen from
//! 0.5 m, covering about half of the frame; texture 1024², default material and light.
//! Each benchmark reports how much CPU time the host's hypervisor took while it ran (steal): on
//! a shared virtual machine, a figure measured under steal is not the machine's own speed.

use criterion::{criterion_group, criterion_main, Criterion};
use visage_camera::{DepthKind, Intrinsics};
use visage_render::{
    render_depth_with, Albedo, Camera, CullMode, Frame, Mat4, Rasterizer, Renderer, Scene, Wrap,
};

#[path = "common/scene.rs"]
mod scene;
#[path = "common/steal.rs"]
mod steal;

use scene::{face_like_mesh, texture};

fn bench(c: &mut Criterion) {
    let k = Intrinsics::new(1280, 720, 1000.0, 1000.0, 639.5, 359.5).expect("valid intrinsics");
    let camera = Camera::new(k).expect("valid camera");
    let mesh = face_like_mesh();
    assert_eq!(mesh.triangles.len(), 30_012);
    let tex = texture();
    let scene = Scene {
        albedo: Albedo::Texture {
            texture: &tex,
            wrap: Wrap::Clamp,
        },
        ..Scene::default()
    };
    let mut renderer = Renderer::new();
    let mut frame = Frame::new(k.width, k.height, DepthKind::Z);
    renderer
        .render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut frame)
        .expect("renders");
    let covered = frame.depth.valid_count();
    eprintln!(
        "render_frame: {} triangles, {covered} of {} pixels covered ({:.0}%), {} rayon threads",
        mesh.triangles.len(),
        frame.color.len(),
        100.0 * covered as f64 / frame.color.len() as f64,
        rayon::current_num_threads()
    );
    // Headline: colour + depth images (what `visage render` writes).
    let mut images = Frame::color_and_depth(k.width, k.height, DepthKind::Z);
    let mut c = steal::Reporting(c);
    c.bench_function("textured_shaded_1280x720_30k_tris", |b| {
        b.iter(|| {
            renderer
                .render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut images)
                .expect("renders")
        })
    });
    // Every buffer: adds triangle ids and barycentrics.
    c.bench_function("textured_shaded_all_buffers_1280x720_30k_tris", |b| {
        b.iter(|| {
            renderer
                .render(&mesh, &camera, &Mat4::IDENTITY, &scene, &mut frame)
                .expect("renders")
        })
    });
    let mut rasterizer = Rasterizer::new();
    c.bench_function("depth_only_1280x720_30k_tris", |b| {
        b.iter(|| {
            render_depth_with(
                &mut rasterizer,
                &mesh,
                &camera,
                &Mat4::IDENTITY,
                DepthKind::Z,
                CullMode::None,
            )
            .expect("renders")
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
