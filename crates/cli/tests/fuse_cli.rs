//! `visage fuse` driven as a user would: the real binary on generated depth sequences.

mod common;

use common::{s, visage};

use std::path::{Path, PathBuf};
use std::process::Output;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use visage_camera::{write_depth_png, DepthKind, DepthMap, Intrinsics};
use visage_mesh::io::read_ply;

const W: u32 = 96;
const H: u32 = 72;

fn camera() -> Intrinsics {
    Intrinsics::new(W, H, 100.0, 100.0, 47.5, 35.5).unwrap()
}

/// Noise-free surface: z as a function of normalised image coordinates (a still scene; the
/// frame index is kept so that moving scenes can be added).
fn surface(xn: f64, yn: f64, _frame: usize) -> f64 {
    0.6 + 0.05 * (2.5 * xn).cos() * (2.0 * yn).cos()
}

/// Writes `frames` depth PNGs: the surface plus 4 mm Gaussian-ish noise and a moving hole.
fn write_sequence(dir: &Path, frames: usize, empty_frame: Option<usize>) {
    std::fs::create_dir_all(dir).unwrap();
    let k = camera();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for f in 0..frames {
        let mut d = DepthMap::empty(W, H, DepthKind::Z);
        for v in 0..H {
            for u in 0..W {
                let (xn, yn) = ((u as f64 - k.cx) / k.fx, (v as f64 - k.cy) / k.fy);
                let noise: f64 =
                    (0..4).map(|_| rng.random_range(-0.004..0.004)).sum::<f64>() * 0.85;
                let hole = (u as i64 - 30 - 3 * f as i64).pow(2) + (v as i64 - 36).pow(2) < 36;
                if !hole && Some(f) != empty_frame {
                    d.data[(v * W + u) as usize] = (surface(xn, yn, f) + noise) as f32;
                }
            }
        }
        write_depth_png(&dir.join(format!("depth_{f:03}.png")), &d, 1000.0).unwrap();
    }
}

/// RMS distance along the line of sight between mesh vertices and the noise-free surface (m).
fn surface_error(path: &Path, frame: usize) -> f64 {
    let mesh = read_ply(path).unwrap();
    assert!(!mesh.triangles.is_empty());
    let sum: f64 = mesh
        .vertices
        .iter()
        .map(|p| {
            assert!(p.iter().all(|c| c.is_finite()));
            let (xn, yn) = (p[0] / p[2], p[1] / p[2]);
            (p[2] - surface(xn, yn, frame)).powi(2)
        })
        .sum();
    (sum / mesh.vertices.len() as f64).sqrt()
}

fn setup_dir(frames: usize, empty: Option<usize>) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let depth = tmp.path().join("depth");
    write_sequence(&depth, frames, empty);
    let cam = tmp.path().join("cam.json");
    camera().save_json(&cam).unwrap();
    (tmp, depth, cam)
}

#[test]
fn fuse_beats_raw_back_projection_in_both_modes() {
    let (tmp, depth, cam) = setup_dir(6, None);
    for mode in ["streaming", "clip"] {
        let out = tmp.path().join(mode);
        let o = visage(&[
            "fuse",
            "--depth",
            s(&depth),
            "--intrinsics",
            s(&cam),
            "--out",
            s(&out),
            "--mode",
            mode,
            "--save-raw",
            "--quiet",
        ]);
        assert!(
            o.status.success(),
            "{mode}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let (mut fused, mut raw) = (0.0, 0.0);
        for f in 0..6 {
            let name = format!("{f:06}.ply");
            fused += surface_error(&out.join("meshes").join(&name), f);
            raw += surface_error(&out.join("raw").join(&name), f);
        }
        assert!(
            fused < 0.7 * raw,
            "{mode}: fused error {fused} vs raw {raw}"
        );
        let metrics: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap())
                .unwrap();
        assert_eq!(metrics["status"], "complete");
        assert_eq!(metrics["frames"].as_array().unwrap().len(), 6);
        assert!(metrics["solver"]["factor_nnz"].as_u64().unwrap() > 0);
        let frame = &metrics["frames"][3];
        assert!(frame["relative_residual"].as_f64().unwrap() < 1e-7);
        assert!(frame["curvature_improvement"].as_f64().unwrap() > 1.0);
        assert!(frame["roughness"].as_f64().unwrap() < frame["roughness_raw"].as_f64().unwrap());
        assert!(!out.join("meshes").read_dir().unwrap().any(|e| e
            .unwrap()
            .path()
            .extension()
            .unwrap()
            == "tmp"));
    }
}

#[test]
fn a_frame_without_depth_is_carried_and_counted() {
    let (tmp, depth, cam) = setup_dir(4, Some(2));
    let out = tmp.path().join("out");
    let o = visage(&[
        "fuse",
        "--depth",
        s(&depth),
        "--intrinsics",
        s(&cam),
        "--out",
        s(&out),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("depth_002.png"));
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["summary"]["carried"], 1);
    assert_eq!(metrics["frames"][2]["status"], "carried");
    let a = read_ply(&out.join("meshes/000001.ply")).unwrap();
    let b = read_ply(&out.join("meshes/000002.ply")).unwrap();
    assert_eq!(a.vertices, b.vertices);
}

fn assert_bad_input(o: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(needle), "expected {needle:?} in: {err}");
}

#[test]
fn bad_input_is_reported_with_the_file_and_exit_code_2() {
    let (tmp, depth, cam) = setup_dir(2, None);
    let out = tmp.path().join("out");
    let base = |d: &Path, c: &Path| {
        vec![
            "fuse".to_string(),
            "--depth".into(),
            s(d).into(),
            "--intrinsics".into(),
            s(c).into(),
            "--out".into(),
            s(&out).into(),
            "--quiet".into(),
        ]
    };
    let run = |args: Vec<String>| visage(&args.iter().map(String::as_str).collect::<Vec<_>>());

    // Missing folder.
    let missing = tmp.path().join("nowhere");
    assert_bad_input(&run(base(&missing, &cam)), "nowhere");
    // Intrinsics for another image size.
    let other = tmp.path().join("other.json");
    Intrinsics::from_fov(640, 480, 60.0)
        .unwrap()
        .save_json(&other)
        .unwrap();
    assert_bad_input(&run(base(&depth, &other)), "640×480");
    // Non-positive focal length.
    let bad = tmp.path().join("bad.json");
    std::fs::write(
        &bad,
        r#"{"width": 96, "height": 72, "fx": 0, "fy": 100, "cx": 47.5, "cy": 35.5}"#,
    )
    .unwrap();
    assert_bad_input(&run(base(&depth, &bad)), "fx");
    // Negative λ.
    let mut args = base(&depth, &cam);
    args.extend(["--lambda".into(), "-1".into()]);
    assert_bad_input(&run(args), "lambda");
    let mut args = base(&depth, &cam);
    args.extend(["--mu=nan".into()]);
    assert_bad_input(&run(args), "mu");
    // A frame of another size, and an 8-bit frame: named, and nothing written.
    let mixed = tmp.path().join("mixed");
    write_sequence(&mixed, 2, None);
    write_depth_png(
        &mixed.join("depth_005.png"),
        &DepthMap::empty(10, 10, DepthKind::Z),
        1000.0,
    )
    .unwrap();
    assert_bad_input(&run(base(&mixed, &cam)), "depth_005.png");
    assert!(!out.join("metrics.json").exists());
    std::fs::remove_file(mixed.join("depth_005.png")).unwrap();
    image::GrayImage::new(W, H)
        .save(mixed.join("depth_006.png"))
        .unwrap();
    assert_bad_input(&run(base(&mixed, &cam)), "depth_006.png");
    // A folder without frames.
    let empty = tmp.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    assert_bad_input(&run(base(&empty, &cam)), "no PNG depth frames");
}
