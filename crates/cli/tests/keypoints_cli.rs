//! `visage keypoints` and `visage match` through the real binary, on a synthetic texture made
//! here: the keypoints file has OpenCV's fields and sane values, the flags change what they
//! say, matches between the texture and a shifted copy agree with the shift, keypoints files
//! match like their images, and bad input is an error (exit 2) that names the file.

mod common;

use std::path::Path;
use std::process::Output;

use common::{s, visage};
use image::RgbImage;
use serde_json::Value;

const WIDTH: u32 = 200;
const HEIGHT: u32 = 160;

/// A 200 × 160 texture: sums of sines with incommensurate frequencies and directions, a few
/// Gaussian blobs of several sizes and a sprinkle of pixel-sized dots, slightly coloured.
fn texture() -> RgbImage {
    const BLOBS: [(f32, f32, f32, f32); 8] = [
        (40.0, 35.0, 6.0, 70.0),
        (150.0, 30.0, 4.0, -60.0),
        (100.0, 80.0, 9.0, 80.0),
        (30.0, 120.0, 5.0, -70.0),
        (170.0, 125.0, 7.0, 65.0),
        (75.0, 140.0, 3.5, 60.0),
        (125.0, 55.0, 3.0, -55.0),
        (60.0, 75.0, 4.5, -65.0),
    ];
    RgbImage::from_fn(WIDTH, HEIGHT, |x, y| {
        let (x, y) = (x as f32, y as f32);
        let mut v = 128.0
            + 28.0 * (0.21 * x + 0.07 * y).sin()
            + 22.0 * (0.05 * x - 0.17 * y + 1.0).sin()
            + 18.0 * (0.013 * x * y / 7.0 + 0.3).sin()
            + 14.0 * (0.31 * y + 0.4 * (0.05 * x).sin() * 6.0).cos();
        for (cx, cy, sigma, amplitude) in BLOBS {
            let r2 = (x - cx).powi(2) + (y - cy).powi(2);
            v += amplitude * (-r2 / (2.0 * sigma * sigma)).exp();
        }
        // Dots about a pixel wide on a jittered 20-pixel grid: keypoints only the doubled
        // image finds.
        let (i, j) = ((x / 20.0).floor(), (y / 20.0).floor());
        let jitter = |k: f32| (k * 12.9898 + 78.233).sin().abs() * 10.0 + 5.0;
        let (cx, cy) = (
            20.0 * i + jitter(i + 31.0 * j),
            20.0 * j + jitter(j + 17.0 * i),
        );
        let sign = if (i + j) % 2.0 == 0.0 { 1.0 } else { -1.0 };
        v += sign * 60.0 * (-((x - cx).powi(2) + (y - cy).powi(2)) / 2.0).exp();
        let byte = |v: f32| v.round().clamp(0.0, 255.0) as u8;
        image::Rgb([byte(v), byte(0.9 * v + 10.0), byte(0.8 * v + 20.0)])
    })
}

/// `image` moved by (`dx`, `dy`) whole pixels: `out(x, y) = image(x − dx, y − dy)`, the
/// uncovered pixels a constant grey.
fn shifted(image: &RgbImage, dx: i64, dy: i64) -> RgbImage {
    RgbImage::from_fn(image.width(), image.height(), |x, y| {
        let (sx, sy) = (i64::from(x) - dx, i64::from(y) - dy);
        if (0..i64::from(image.width())).contains(&sx)
            && (0..i64::from(image.height())).contains(&sy)
        {
            *image.get_pixel(sx as u32, sy as u32)
        } else {
            image::Rgb([128, 128, 128])
        }
    })
}

/// Saves `image` as `dir/name` (PNG) and returns the path.
fn save(dir: &Path, name: &str, image: &RgbImage) -> std::path::PathBuf {
    let path = dir.join(name);
    image.save(&path).unwrap();
    path
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `visage ARGS…`, fails unless it succeeds, and returns its standard output.
fn ok(args: &[&str]) -> String {
    let o = visage(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    String::from_utf8(o.stdout).unwrap()
}

/// Asserts that `visage ARGS…` exits with 2, without panicking, and returns its stderr.
fn bad_input(args: &[&str]) -> String {
    let o = visage(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    err
}

fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// `visage keypoints IMAGE --out DIR/OUT EXTRA…`: the keypoints file and the stdout summary.
fn keypoints(image: &Path, out: &Path, extra: &[&str]) -> (Value, Value) {
    let mut args = vec!["keypoints", s(image), "--out", s(out)];
    args.extend(extra);
    let stdout = ok(&args);
    let summary = serde_json::from_str(stdout.trim()).unwrap();
    (read_json(out), summary)
}

fn count(file: &Value) -> usize {
    file["keypoints"].as_array().unwrap().len()
}

#[test]
fn keypoints_file_has_opencv_fields_and_sane_values() {
    let dir = tempfile::tempdir().unwrap();
    let image = save(dir.path(), "t.png", &texture());
    let out = dir.path().join("t.json");
    let args = ["keypoints", s(&image), "--out", s(&out), "--repeat", "3"];
    let stdout = ok(&args);
    assert_eq!(stdout.lines().count(), 1, "one line: {stdout}");
    let summary: Value = serde_json::from_str(stdout.trim()).unwrap();
    let file = read_json(&out);

    let mut top: Vec<_> = file.as_object().unwrap().keys().cloned().collect();
    top.sort();
    assert_eq!(top, ["descriptors", "height", "keypoints", "width"]);
    assert_eq!(file["width"], WIDTH);
    assert_eq!(file["height"], HEIGHT);
    let keypoints = file["keypoints"].as_array().unwrap();
    let descriptors = file["descriptors"].as_array().unwrap();
    assert!(keypoints.len() > 20, "{} keypoints", keypoints.len());
    assert_eq!(descriptors.len(), keypoints.len());
    for (k, d) in keypoints.iter().zip(descriptors) {
        let mut fields: Vec<_> = k.as_object().unwrap().keys().cloned().collect();
        fields.sort();
        assert_eq!(
            fields,
            ["angle", "octave", "response", "size", "x", "y"],
            "{k}"
        );
        let f = |name: &str| k[name].as_f64().unwrap();
        assert!((0.0..=f64::from(WIDTH - 1)).contains(&f("x")), "{k}");
        assert!((0.0..=f64::from(HEIGHT - 1)).contains(&f("y")), "{k}");
        assert!((0.0..360.0).contains(&f("angle")), "{k}");
        assert!(f("size") > 0.0 && f("response") > 0.0, "{k}");
        assert!(k["octave"].is_i64(), "{k}");
        let d = d.as_array().unwrap();
        assert_eq!(d.len(), 128);
        assert!(
            d.iter().all(|v| v.as_u64().is_some_and(|v| v <= 255)),
            "{d:?}"
        );
        assert!(
            d.iter().any(|v| v.as_u64() != Some(0)),
            "an all-zero descriptor"
        );
    }

    assert_eq!(summary["keypoints"].as_u64(), Some(keypoints.len() as u64));
    for field in ["ms", "first_ms"] {
        let ms = summary[field].as_f64().unwrap();
        assert!(ms.is_finite() && ms >= 0.0, "{summary}");
    }
}

#[test]
fn keypoints_draw_writes_the_image_with_keypoints_on_it() {
    let dir = tempfile::tempdir().unwrap();
    let input = texture();
    let image = save(dir.path(), "t.png", &input);
    let (out, drawn) = (dir.path().join("t.json"), dir.path().join("drawn.png"));
    keypoints(&image, &out, &["--draw", s(&drawn)]);
    let drawn = image::open(&drawn).unwrap().to_rgb8();
    assert_eq!(drawn.dimensions(), input.dimensions());
    let changed = input
        .pixels()
        .zip(drawn.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(changed > 100, "{changed} pixels drawn");
}

/// Low byte of OpenCV's packed octave: 255 for the doubled image's octave.
fn octave(k: &Value) -> i64 {
    k["octave"].as_i64().unwrap() & 0xff
}

#[test]
fn max_keypoints_no_upsample_and_contrast_threshold_limit_the_keypoints() {
    let dir = tempfile::tempdir().unwrap();
    let image = save(dir.path(), "t.png", &texture());
    let out = dir.path().join("t.json");
    let (all, _) = keypoints(&image, &out, &[]);
    let all_keypoints = all["keypoints"].as_array().unwrap();

    // The five strongest.
    let (five, summary) = keypoints(&image, &out, &["--max-keypoints", "5"]);
    assert_eq!(count(&five), 5);
    assert_eq!(five["descriptors"].as_array().unwrap().len(), 5);
    assert_eq!(summary["keypoints"], 5);
    let mut responses: Vec<f64> = all_keypoints
        .iter()
        .map(|k| k["response"].as_f64().unwrap())
        .collect();
    responses.sort_by(|a, b| b.total_cmp(a));
    for k in five["keypoints"].as_array().unwrap() {
        assert!(all_keypoints.contains(k), "{k} is not among all keypoints");
        assert!(k["response"].as_f64().unwrap() >= responses[4], "{k}");
    }

    // Without the doubled image: fewer, none from its octave and none tiny.
    assert!(all_keypoints.iter().any(|k| octave(k) == 255));
    let (small, _) = keypoints(&image, &out, &["--no-upsample"]);
    assert!(
        0 < count(&small) && count(&small) < count(&all),
        "--no-upsample {} vs {}",
        count(&small),
        count(&all)
    );
    for k in small["keypoints"].as_array().unwrap() {
        assert_ne!(octave(k), 255, "{k}");
        assert!(k["size"].as_f64().unwrap() >= 2.5, "{k}");
    }

    // A higher contrast threshold keeps fewer.
    let (strong, _) = keypoints(&image, &out, &["--contrast-threshold", "0.1"]);
    assert!(
        count(&strong) < count(&all),
        "--contrast-threshold 0.1: {} vs {}",
        count(&strong),
        count(&all)
    );
}

/// The matches of a report whose b − a displacement is (`dx`, `dy`) within half a pixel.
fn agreeing(report: &Value, dx: f64, dy: f64) -> (usize, usize) {
    let matches = report["matches"].as_array().unwrap();
    let good = matches
        .iter()
        .filter(|m| {
            let c = |k: &str, i: usize| m[k][i].as_f64().unwrap();
            (c("b_xy", 0) - c("a_xy", 0) - dx).abs() <= 0.5
                && (c("b_xy", 1) - c("a_xy", 1) - dy).abs() <= 0.5
        })
        .count();
    (good, matches.len())
}

#[test]
fn matches_with_a_shifted_copy_follow_the_shift() {
    let dir = tempfile::tempdir().unwrap();
    let input = texture();
    let (dx, dy) = (7, -5);
    let a = save(dir.path(), "a.png", &input);
    let b = save(dir.path(), "b.png", &shifted(&input, dx, dy));

    // Without --out: the JSON on standard output.
    let report: Value = serde_json::from_str(&ok(&["match", s(&a), s(&b)])).unwrap();
    let (good, total) = agreeing(&report, dx as f64, dy as f64);
    assert!(total >= 20, "{total} matches");
    assert!(good * 5 >= total * 4, "{good} of {total} follow the shift");
    assert!(report["keypoints_a"].as_u64().unwrap() >= total as u64);
    assert!(report["keypoints_b"].as_u64().unwrap() >= total as u64);
    for m in report["matches"].as_array().unwrap() {
        let mut fields: Vec<_> = m.as_object().unwrap().keys().cloned().collect();
        fields.sort();
        assert_eq!(fields, ["a", "a_xy", "b", "b_xy", "distance"], "{m}");
        assert!(m["a"].as_u64().unwrap() < report["keypoints_a"].as_u64().unwrap());
        assert!(m["b"].as_u64().unwrap() < report["keypoints_b"].as_u64().unwrap());
        assert!(m["distance"].as_f64().unwrap() >= 0.0);
    }

    // With --out: the same JSON in the file, nothing on standard output.
    let out = dir.path().join("m.json");
    let stdout = ok(&["match", s(&a), s(&b), "--out", s(&out)]);
    assert!(stdout.trim().is_empty(), "{stdout}");
    assert_eq!(read_json(&out), report);

    // Without the mutual check there are at least as many matches.
    let one_sided: Value =
        serde_json::from_str(&ok(&["match", s(&a), s(&b), "--no-mutual"])).unwrap();
    assert!(one_sided["matches"].as_array().unwrap().len() >= total);
}

#[test]
fn keypoints_files_match_like_their_images_but_cannot_be_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let input = texture();
    let a = save(dir.path(), "a.png", &input);
    let b = save(dir.path(), "b.png", &shifted(&input, 4, 6));
    let (ja, jb) = (dir.path().join("a.json"), dir.path().join("b.json"));
    keypoints(&a, &ja, &[]);
    keypoints(&b, &jb, &[]);

    let from_images: Value = serde_json::from_str(&ok(&["match", s(&a), s(&b)])).unwrap();
    let from_files: Value = serde_json::from_str(&ok(&["match", s(&ja), s(&jb)])).unwrap();
    let n = |r: &Value| r["matches"].as_array().unwrap().len();
    assert!(n(&from_images) >= 20, "{} matches", n(&from_images));
    assert_eq!(n(&from_files), n(&from_images));
    assert_eq!(from_files["keypoints_a"], from_images["keypoints_a"]);
    assert_eq!(from_files["keypoints_b"], from_images["keypoints_b"]);
    // An image against a keypoints file works too.
    let mixed: Value = serde_json::from_str(&ok(&["match", s(&a), s(&jb)])).unwrap();
    assert_eq!(n(&mixed), n(&from_images));

    // Drawing two images side by side.
    let drawn = dir.path().join("m.png");
    ok(&["match", s(&a), s(&b), "--draw", s(&drawn)]);
    let drawn = image::open(&drawn).unwrap().to_rgb8();
    assert_eq!(drawn.dimensions(), (2 * WIDTH, HEIGHT));

    // Drawing needs the images: refused before anything is written.
    let (drawn, out) = (dir.path().join("j.png"), dir.path().join("j.json"));
    let args = ["match", s(&a), s(&jb), "--draw", s(&drawn)];
    let err = bad_input(&[&args[..], &["--out", s(&out)]].concat());
    assert!(err.contains("--draw") && err.contains("image"), "{err}");
    assert!(err.contains("b.json"), "{err}");
    assert!(!drawn.exists() && !out.exists());
    let o = visage(&["match", s(&ja), s(&jb), "--draw", s(&drawn)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("a.json"), "{}", stderr(&o));
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(!drawn.exists());
}

#[test]
fn bad_input_exits_2_and_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let image = save(d, "t.png", &texture());
    let out = d.join("k.json");

    let missing = d.join("missing.png");
    let err = bad_input(&["keypoints", s(&missing), "--out", s(&out)]);
    assert!(err.contains("missing.png"), "{err}");
    // The cause once: the file error already quotes the system's message.
    assert_eq!(err.matches("os error 2").count(), 1, "{err}");
    let err = bad_input(&["match", s(&image), s(&missing)]);
    assert!(err.contains("missing.png"), "{err}");

    // Bytes that are not a PNG, under a PNG's name.
    let corrupt = d.join("x.png");
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let bytes: Vec<u8> = (0..4096)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state as u8
        })
        .collect();
    std::fs::write(&corrupt, bytes).unwrap();
    let err = bad_input(&["keypoints", s(&corrupt), "--out", s(&out)]);
    assert!(err.contains("x.png"), "{err}");
    let err = bad_input(&["match", s(&corrupt), s(&image)]);
    assert!(err.contains("x.png"), "{err}");
    assert!(!out.exists(), "no keypoints file from bad input");

    // A keypoints file whose descriptor is one value short.
    let short = d.join("short.json");
    let descriptor: Vec<u8> = vec![1; 127];
    let file = serde_json::json!({
        "width": 10,
        "height": 10,
        "keypoints": [{"x": 1.0, "y": 2.0, "size": 3.0, "angle": 4.0, "response": 0.1, "octave": 0}],
        "descriptors": [descriptor],
    });
    std::fs::write(&short, file.to_string()).unwrap();
    let err = bad_input(&["match", s(&short), s(&image)]);
    assert!(err.contains("short.json") && err.contains("127"), "{err}");
    // Not a keypoints file at all.
    let other = d.join("other.json");
    std::fs::write(&other, r#"{"frames": []}"#).unwrap();
    let err = bad_input(&["match", s(&image), s(&other)]);
    assert!(err.contains("other.json"), "{err}");

    // Parameters out of range.
    for ratio in ["0", "1.5", "-0.5", "NaN"] {
        let flag = format!("--ratio={ratio}");
        let err = bad_input(&["match", s(&image), s(&image), &flag]);
        assert!(err.contains("ratio"), "{flag}: {err}");
    }
    let err = bad_input(&["keypoints", s(&image), "--out", s(&out), "--repeat", "0"]);
    assert!(err.contains("repeat"), "{err}");
    let err = bad_input(&[
        "keypoints",
        s(&image),
        "--out",
        s(&out),
        "--contrast-threshold=-1",
    ]);
    assert!(err.contains("contrast-threshold"), "{err}");
    assert!(!out.exists(), "no keypoints file from bad parameters");
}
