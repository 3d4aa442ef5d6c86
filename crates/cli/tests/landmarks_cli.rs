//! `visage landmarks` as a user runs it: JSON on a real portrait, a face-less image, bad input,
//! and the depth maps it writes fused by `visage fuse`. Most need the model files (run
//! `scripts/setup.sh`) and `../shared`, and are ignored without them.

mod common;

use common::{s, visage};

use std::path::PathBuf;

/// The model folder (the tests using it are ignored without it).
#[track_caller]
fn models() -> PathBuf {
    let dir = visage_testdata::models_dir();
    for file in visage_testdata::MODEL_FILES {
        visage_testdata::require(dir.join(file));
    }
    dir
}

/// The astronaut portrait in `../shared` (the tests using it are ignored without it).
#[track_caller]
fn portrait() -> PathBuf {
    visage_testdata::require(visage_testdata::shared_dir().join("data/images/astronaut.png"))
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn landmarks_json_on_a_portrait() {
    let (models, image) = (models(), portrait());
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("lm.json");
    let o = visage(&[
        "landmarks",
        s(&image),
        "--out",
        s(&out),
        "--models",
        s(&models),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let frame = &json["frames"][0];
    let (w, h) = (
        frame["width"].as_f64().unwrap(),
        frame["height"].as_f64().unwrap(),
    );
    let faces = frame["faces"].as_array().unwrap();
    assert_eq!(faces.len(), 1);
    let face = &faces[0];
    assert!(face["score"].as_f64().unwrap() > 0.5 && face["presence"].as_f64().unwrap() > 0.5);
    let landmarks = face["landmarks"].as_array().unwrap();
    assert_eq!(landmarks.len(), 468);
    for p in landmarks {
        let (x, y) = (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
        assert!((0.0..w).contains(&x) && (0.0..h).contains(&y));
    }
    assert!(face["pose"].is_object());
}

#[test]
#[cfg_attr(not(model_files), ignore = "needs the model files (scripts/setup.sh)")]
fn an_image_without_a_face_gives_no_faces_and_exit_3() {
    let models = models();
    let tmp = tempfile::tempdir().unwrap();
    let blank = tmp.path().join("blank.png");
    image::RgbImage::from_pixel(160, 120, image::Rgb([90, 120, 200]))
        .save(&blank)
        .unwrap();
    let out = tmp.path().join("lm.json");
    let o = visage(&[
        "landmarks",
        s(&blank),
        "--out",
        s(&out),
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("no face was found in any of the 1 frames"),
        "{err}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(json["frames"][0]["faces"].as_array().map(Vec::len), Some(0));
}

#[test]
fn missing_models_and_unreadable_images_exit_2_naming_the_file() {
    let tmp = tempfile::tempdir().unwrap();
    let broken = tmp.path().join("broken.png");
    std::fs::write(&broken, b"not a png").unwrap();
    let empty_models = tmp.path().join("no-models");
    std::fs::create_dir_all(&empty_models).unwrap();
    let o = visage(&["landmarks", s(&broken), "--models", s(&empty_models)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("models fetch") || err.contains("broken.png"),
        "{err}"
    );
}

#[test]
#[cfg_attr(not(model_files), ignore = "needs the model files (scripts/setup.sh)")]
fn an_unreadable_image_with_the_models_is_exit_2_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let broken = tmp.path().join("broken.png");
    std::fs::write(&broken, b"not a png").unwrap();
    let o = visage(&["landmarks", s(&broken), "--models", s(&models())]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("broken.png"));
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn landmark_depth_maps_fuse_into_a_metric_face() {
    let (models, image) = (models(), portrait());
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    for i in 0..3 {
        std::fs::copy(&image, frames.join(format!("{i:03}.png"))).unwrap();
    }
    let depth = tmp.path().join("depth");
    let o = visage(&[
        "landmarks",
        s(&frames),
        "--depth-out",
        s(&depth),
        "--models",
        s(&models),
        "--out",
        s(&tmp.path().join("lm.json")),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = tmp.path().join("fused");
    let o = visage(&["fuse", "--depth", s(&depth), "--out", s(&out), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mesh = visage_mesh::io::read_ply(&out.join("meshes/000002.ply")).unwrap();
    assert!(mesh.vertices.len() > 100);
    // Metric: a face about 0.5–1 m from a 60° camera, some 12–20 cm wide.
    let zs: Vec<f64> = mesh.vertices.iter().map(|p| p[2]).collect();
    let xs: Vec<f64> = mesh.vertices.iter().map(|p| p[0]).collect();
    let median_z = {
        let mut z = zs.clone();
        z.sort_by(f64::total_cmp);
        z[z.len() / 2]
    };
    let width =
        xs.iter().cloned().fold(f64::MIN, f64::max) - xs.iter().cloned().fold(f64::MAX, f64::min);
    assert!((0.4..1.2).contains(&median_z), "median depth {median_z} m");
    assert!((0.10..0.25).contains(&width), "face width {width} m");
}

/// A video that breaks part-way: the frames read before the break are written (the JSON lists
/// them), and the message names the break and says so.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_video_that_breaks_part_way_keeps_the_frames_before_the_break() {
    let (models, clip) = common::inputs();
    let tmp = tempfile::tempdir().unwrap();
    let cut = common::truncated_clip(tmp.path(), &clip);
    let out = tmp.path().join("landmarks.json");
    let o = visage(&[
        "landmarks",
        s(&cut),
        "--out",
        s(&out),
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("broke at frame") && err.contains("lists them"),
        "{err}"
    );
    let frames = common::json(&out)["frames"].as_array().unwrap().len();
    assert!((1..24).contains(&frames), "{frames} frames");
    assert!(
        err.contains(&format!("stopped after {frames} frames")),
        "{err}"
    );
}
