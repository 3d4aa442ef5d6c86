//! `visage render` through the real binary: the depth it writes is what `visage fuse` reads,
//! projective texturing from the same camera gives the texture image back, and bad inputs are
//! errors (exit 2) that name the file.

mod common;

use std::path::Path;

use common::{s, visage};
use visage_camera::{read_depth_png, DepthKind, Intrinsics};

/// `visage render MESH --intrinsics DIR/cam.json --out DIR/c.png --depth-out DIR/d.png EXTRA…`.
fn render(dir: &Path, mesh: &str, extra: &[&str]) -> std::process::Output {
    let (mesh, cam) = (dir.join(mesh), dir.join("cam.json"));
    let (color, depth) = (dir.join("c.png"), dir.join("d.png"));
    let mut args = vec!["render", s(&mesh), "--intrinsics", s(&cam)];
    args.extend(["--out", s(&color), "--depth-out", s(&depth)]);
    args.extend(extra);
    visage(&args)
}

#[test]
fn renders_depth_that_fuse_reads_and_colours_projectively() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let k = Intrinsics::new(32, 24, 30.0, 30.0, 15.5, 11.5).unwrap();
    k.save_json(&d.join("cam.json")).unwrap();
    // A plane at z = 0.8 m filling the view.
    std::fs::write(
        d.join("plane.obj"),
        "v -1 -1 0.8\nv 1 -1 0.8\nv 1 1 0.8\nv -1 1 0.8\nf 1 2 3 4\n",
    )
    .unwrap();
    assert!(render(d, "plane.obj", &[]).status.success());
    let depth = read_depth_png(&d.join("d.png"), 1000.0, DepthKind::Z).unwrap();
    assert!(
        depth.data.iter().all(|&z| (z - 0.8).abs() < 1e-6),
        "800 mm everywhere"
    );
    // Projective texturing from the same camera reproduces the texture image.
    let mut img = image::RgbImage::new(32, 24);
    for (x, y, p) in img.enumerate_pixels_mut() {
        *p = image::Rgb([(x * 8) as u8, (y * 10) as u8, 77]);
    }
    let frame = d.join("frame.png");
    img.save(&frame).unwrap();
    let o = render(
        d,
        "plane.obj",
        &["--texture", s(&frame), "--projective", "--unlit"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let back = image::open(d.join("c.png")).unwrap().to_rgb8();
    for (p, q) in back.pixels().zip(img.pixels()) {
        for c in 0..3 {
            assert!((p.0[c] as i32 - q.0[c] as i32).abs() <= 1, "{p:?} vs {q:?}");
        }
    }
}

#[test]
fn a_turntable_does_not_show_an_open_surface_from_behind() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let k = Intrinsics::new(32, 24, 30.0, 30.0, 15.5, 11.5).unwrap();
    k.save_json(&d.join("cam.json")).unwrap();
    // A small open square facing the camera (wound as visage's face meshes are), seen from the
    // front and, half a turn later, from behind.
    std::fs::write(
        d.join("square.obj"),
        "v -0.1 -0.1 0.8\nv 0.1 -0.1 0.8\nv 0.1 0.1 0.8\nv -0.1 0.1 0.8\nf 1 4 3 2\n",
    )
    .unwrap();
    let o = render(d, "square.obj", &["--views", "turntable:2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let drawn = |view: usize| {
        let png = d.join(format!("c_{view:03}.png"));
        let image = image::open(&png).unwrap().to_rgb8();
        image.pixels().filter(|p| p.0 != [0, 0, 0]).count()
    };
    let (front, back) = (drawn(0), drawn(1));
    assert!(
        front > 0 && back == 0,
        "pixels drawn: front {front}, back {back}"
    );
}

#[test]
fn bad_inputs_are_errors_that_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    Intrinsics::new(8, 8, 8.0, 8.0, 3.5, 3.5)
        .unwrap()
        .save_json(&d.join("cam.json"))
        .unwrap();
    let fails_with = |mesh: &str, text: &[&str]| {
        let o = render(d, mesh, &[]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(text.iter().all(|t| err.contains(t)), "{err}");
    };
    std::fs::write(d.join("bad.obj"), "v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 7\n").unwrap();
    fails_with("bad.obj", &["bad.obj:4"]);
    std::fs::write(d.join("empty.obj"), "# no geometry\n").unwrap();
    fails_with("empty.obj", &["empty"]);
    std::fs::write(d.join("ok.obj"), "v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\n").unwrap();
    std::fs::write(
        d.join("cam.json"),
        r#"{"width": 8, "height": 8, "fx": 0, "fy": 8, "cx": 3.5, "cy": 3.5}"#,
    )
    .unwrap();
    fails_with("ok.obj", &["cam.json", "fx"]);
    // A malformed file: its parser's message once, not once per layer of the error chain.
    std::fs::write(d.join("cam.json"), r#"{"width": 8, "height": "#).unwrap();
    let o = render(d, "ok.obj", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("cam.json"), "{err}");
    assert_eq!(err.matches("EOF while parsing").count(), 1, "{err}");
}
