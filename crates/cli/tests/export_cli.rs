//! The files people open: the point cache holds the PLYs' surfaces in mesh.obj's axes, the glb
//! plays them back (morph targets and head motion) within a fraction of a millimetre and passes
//! the Khronos validator, the charts are there as SVG and PNG, `visage export` remakes them from
//! the folder, and a folder that is not a run's is a clear error.

mod common;

use common::{run_ok, s, visage};

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// A 30-frame run with PLYs and the exports (but the preview), into `out`.
fn run_with_exports(out: &Path) {
    let models = visage_testdata::require(visage_testdata::models_dir());
    let clip =
        visage_testdata::require(visage_testdata::shared_dir().join("data/video/lp_d18.mp4"));
    run_ok(&[
        "run",
        s(&clip),
        "--out",
        s(out),
        "--max-frames",
        "30",
        "--ply",
        "--glb",
        "--report",
        "--models",
        s(&models),
    ]);
}

/// A glb's JSON and binary chunks.
fn read_glb(path: &Path) -> (Value, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..4], b"glTF");
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    assert_eq!(word(4), 2, "glTF version");
    assert_eq!(word(8), bytes.len(), "declared length");
    let json_len = word(12);
    assert_eq!(&bytes[16..20], b"JSON");
    let json: Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
    let bin = bytes[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec();
    (json, bin)
}

/// An accessor's floats (tightly packed float accessors only, as visage writes them).
fn floats(json: &Value, bin: &[u8], accessor: usize) -> Vec<f32> {
    let a = &json["accessors"][accessor];
    assert_eq!(a["componentType"], 5126);
    let width = match a["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        t => panic!("{t}"),
    };
    let view = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let n = a["count"].as_u64().unwrap() as usize * width;
    bin[start..start + 4 * n]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect()
}

/// Rotates `v` by the unit quaternion `[x, y, z, w]` (glTF's order).
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let m = visage_camera::quaternion_to_matrix([q[3], q[0], q[1], q[2]]);
    std::array::from_fn(|i| (0..3).map(|j| m[i][j] * v[j]).sum())
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn the_point_cache_and_the_glb_play_the_fused_surfaces() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    run_with_exports(&out);

    // Point cache: each frame's PLY in the y-up axes (x, −y, −z) of mesh.obj (frame 0).
    let cache = visage_mesh::io::read_pc2(&out.join("sequence.pc2")).unwrap();
    assert_eq!(cache.samples(), 30);
    let plys: Vec<Vec<[f64; 3]>> = (0..30)
        .map(|i| {
            visage_mesh::io::read_ply(&out.join(format!("meshes/{i:06}.ply")))
                .unwrap()
                .vertices
        })
        .collect();
    for (k, ply) in plys.iter().enumerate() {
        for (p, c) in ply.iter().zip(cache.sample(k).chunks_exact(3)) {
            let y_up = [p[0], -p[1], -p[2]];
            for i in 0..3 {
                assert!((y_up[i] - c[i] as f64).abs() < 1e-6, "frame {k}");
            }
        }
    }
    let obj = visage_mesh::io::read_obj(&out.join("mesh.obj")).unwrap();
    assert_eq!(obj.vertices.len(), plys[0].len());
    assert_eq!(obj.uvs.len(), obj.vertices.len());
    assert!((obj.vertices[1][1] + plys[0][1][1]).abs() < 1e-6);
    let mtl = std::fs::read_to_string(out.join("mesh.mtl")).unwrap();
    assert!(mtl.contains("map_Kd texture.png"), "{mtl}");
    let texture = image::open(out.join("texture.png")).unwrap().to_rgb8();
    assert!(texture.width() >= 256 && texture.width() == texture.height());

    // The charts (`--report` makes them), each as SVG and as PNG: 1280 × 800 pixels and the
    // legend's column.
    let files: Vec<String> = std::fs::read_dir(out.join("plots"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    let charts: Vec<&str> = files
        .iter()
        .filter_map(|f| f.strip_suffix(".svg"))
        .collect();
    assert!(
        charts.contains(&"blendshapes") && charts.len() >= 6,
        "{files:?}"
    );
    assert_eq!(files.len(), 2 * charts.len(), "{files:?}");
    for chart in charts {
        let png = image::open(out.join(format!("plots/{chart}.png")))
            .unwrap()
            .to_rgb8();
        assert!(
            png.height() == 800 && png.width() > 1280,
            "{chart}: {:?}",
            png.dimensions()
        );
    }

    // The glb: base + Σ wᵢ targetᵢ, then the node's rotation and translation, is each frame's
    // surface in glTF's axes (x, −y, −z).
    let (json, bin) = read_glb(&out.join("sequence.glb"));
    let primitive = &json["meshes"][0]["primitives"][0];
    let targets = primitive["targets"].as_array().unwrap();
    let names = json["meshes"][0]["extras"]["targetNames"]
        .as_array()
        .unwrap();
    assert_eq!(names.len(), targets.len());
    assert!(!targets.is_empty() && targets.len() <= 64 + 52);
    let base = floats(
        &json,
        &bin,
        primitive["attributes"]["POSITION"].as_u64().unwrap() as usize,
    );
    let deltas: Vec<Vec<f32>> = targets
        .iter()
        .map(|t| floats(&json, &bin, t["POSITION"].as_u64().unwrap() as usize))
        .collect();
    let animation = &json["animations"][0];
    let sampler = |path: &str| {
        let channel = animation["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["target"]["path"] == path)
            .unwrap();
        let s = &animation["samplers"][channel["sampler"].as_u64().unwrap() as usize];
        (
            floats(&json, &bin, s["input"].as_u64().unwrap() as usize),
            floats(&json, &bin, s["output"].as_u64().unwrap() as usize),
        )
    };
    let (times, weights) = sampler("weights");
    let (_, translations) = sampler("translation");
    let (_, rotations) = sampler("rotation");
    assert_eq!(times.len(), 30);
    assert!(
        (times[7] as f64 - 7.0 / 30.0).abs() < 1e-3,
        "frame times {times:?}"
    );
    let t = deltas.len();
    let mut worst = 0.0f64;
    for (k, ply) in plys.iter().enumerate() {
        let q = std::array::from_fn(|i| rotations[4 * k + i] as f64);
        for (v, p) in ply.iter().enumerate() {
            let mut local: [f64; 3] = std::array::from_fn(|c| base[3 * v + c] as f64);
            for (j, d) in deltas.iter().enumerate() {
                for c in 0..3 {
                    local[c] += weights[t * k + j] as f64 * d[3 * v + c] as f64;
                }
            }
            let r = rotate(q, local);
            let played: [f64; 3] = std::array::from_fn(|c| r[c] + translations[3 * k + c] as f64);
            let expected = [p[0], -p[1], -p[2]];
            let e = (0..3)
                .map(|c| (played[c] - expected[c]).powi(2))
                .sum::<f64>()
                .sqrt();
            worst = worst.max(e);
        }
    }
    assert!(
        worst < 1e-3,
        "the glb plays the surfaces back within {worst} m"
    );
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("export.json")).unwrap()).unwrap();
    assert!((summary["glb_max_error_m"].as_f64().unwrap() - worst).abs() < 1e-4);

    // `visage export` remakes them from the folder alone (decoding the input again).
    let glb_before = std::fs::metadata(out.join("sequence.glb")).unwrap().len();
    std::fs::remove_file(out.join("sequence.glb")).unwrap();
    run_ok(&["export", s(&out), "--glb", "--quiet"]);
    assert!(out.join("sequence.glb").is_file());
    let glb_after = std::fs::metadata(out.join("sequence.glb")).unwrap().len();
    assert!(
        glb_after.abs_diff(glb_before) < glb_before / 10,
        "{glb_before} vs {glb_after}"
    );
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg, web_tools)),
    ignore = "needs ../shared, the model files, FFmpeg and web/viewer built (scripts/setup.sh)"
)]
fn the_glb_validates_and_the_report_plays_offline_in_chromium() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    run_with_exports(&out);
    let web = visage_testdata::web_dir();
    let node = |args: &[&Path]| {
        let o = Command::new("node").args(args).output().unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{args:?}: {stdout}{stderr}");
        serde_json::from_str::<Value>(stdout.trim()).unwrap()
    };
    // The Khronos validator: no errors, no warnings, no hints (every morph target's positions
    // marked as vertex data, as the base positions are).
    let report = node(&[
        &web.join("test/validate_gltf.mjs"),
        &out.join("sequence.glb"),
    ]);
    assert_eq!(report["numErrors"], 0, "{report}");
    assert_eq!(report["numWarnings"], 0, "{report}");
    assert_eq!(report["numHints"], 0, "{report}");
    // report.html from file:// in headless Chromium: no console errors, a canvas that is not
    // blank and changes as the animation plays. The screenshot stays as a test artefact.
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        !html.contains("src=\"http") && !html.contains("href=\"http"),
        "no network"
    );
    let artefacts = visage_testdata::workspace_root().join("target/test-artifacts");
    std::fs::create_dir_all(&artefacts).unwrap();
    let shot = artefacts.join("report.png");
    let check = node(&[
        &web.join("test/check_report.mjs"),
        &out.join("report.html"),
        &shot,
    ]);
    assert_eq!(check["consoleErrors"], serde_json::json!([]), "{check}");
    assert!(check["variance"].as_f64().unwrap() > 25.0, "{check}");
    assert!(check["difference"].as_f64().unwrap() > 0.5, "{check}");
    assert!(shot.is_file());
}

#[test]
fn a_folder_that_is_not_a_run_is_exit_2_saying_what_it_is() {
    let tmp = tempfile::tempdir().unwrap();
    let o = visage(&["export", s(tmp.path())]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("not a visage run folder") && err.contains("metrics.json"),
        "{err}"
    );
    let missing: PathBuf = tmp.path().join("nothing_here");
    let o = visage(&["export", s(&missing)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("nothing_here: no such folder"), "{err}");
}

/// The streams of a media file, as `ffprobe` lists them: (codec type, duration in seconds).
fn streams(path: &Path) -> Vec<(String, f64)> {
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-show_entries", "stream=codec_type,duration"])
        .args(["-of", "csv=p=0"])
        .arg(path)
        .output()
        .unwrap();
    assert!(out.status.success(), "ffprobe {}", path.display());
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|l| {
            let (kind, duration) = l.split_once(',')?;
            Some((kind.to_string(), duration.parse().ok()?))
        })
        .collect()
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn the_preview_keeps_the_inputs_sound_in_step_with_the_frames_and_the_report_lists_it() {
    let models = visage_testdata::require(visage_testdata::models_dir());
    let video = visage_testdata::shared_dir().join("data/video");
    let tmp = tempfile::tempdir().unwrap();
    // lp_d18 has a sound track, lp_d13 none.
    for (clip, sound) in [("lp_d18.mp4", true), ("lp_d13.mp4", false)] {
        let clip = visage_testdata::require(video.join(clip));
        let out = tmp.path().join(clip.file_stem().unwrap());
        run_ok(&[
            "run",
            s(&clip),
            "--out",
            s(&out),
            "--every",
            "2",
            "--max-frames",
            "15",
            "--preview",
            "--report",
            "--models",
            s(&models),
        ]);
        // The report's table of files lists the preview, written before it.
        let report = std::fs::read_to_string(out.join("report.html")).unwrap();
        assert!(
            report.contains("<a href=\"preview.mp4\">"),
            "the report's table of files misses the preview"
        );
        let streams = streams(&out.join("preview.mp4"));
        let duration = |kind: &str| streams.iter().find(|s| s.0 == kind).map(|s| s.1);
        let video = duration("video").expect("a video stream");
        assert!(
            (video - 1.0).abs() < 0.05,
            "every second frame of 30: {video} s"
        );
        match duration("audio") {
            Some(audio) => {
                assert!(sound, "{}: sound the input does not have", clip.display());
                assert!(
                    (audio - video).abs() < 0.1,
                    "sound {audio} s, video {video} s"
                );
            }
            None => assert!(!sound, "{}: the input's sound was dropped", clip.display()),
        }
    }
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn the_reports_contact_sheet_shows_the_sample_clips_two_blinks() {
    let models = visage_testdata::require(visage_testdata::models_dir());
    let clip =
        visage_testdata::require(visage_testdata::shared_dir().join("data/video/lp_d18.mp4"));
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    run_ok(&[
        "run",
        s(&clip),
        "--out",
        s(&out),
        "--report",
        "--models",
        s(&models),
    ]);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // The subject closes both eyes over frames 94–98 and 185–188 (checked by eye).
    // Each caption is written twice (the picture's alt text and its caption).
    let mut blinks: Vec<usize> = html
        .match_indices("blink · frame ")
        .filter_map(|(at, m)| {
            let rest = &html[at + m.len()..];
            rest[..rest.find(' ')?].parse().ok()
        })
        .collect();
    blinks.dedup();
    assert_eq!(blinks.len(), 2, "{blinks:?}");
    assert!((94..=98).contains(&blinks[0]), "{blinks:?}");
    assert!((185..=188).contains(&blinks[1]), "{blinks:?}");
}
