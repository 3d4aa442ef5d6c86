//! `visage run` and `visage bench` as a user runs them, on a real clip: outputs per frame, both
//! mesh designs, clip mode, and bad inputs (missing input, truncated video, a
//! frame without a face, intrinsics for another size, unwritable output). Most need the model
//! files (`scripts/setup.sh`), FFmpeg and `../shared`, and are ignored without them.

mod common;

use common::{inputs, json, run_ok, s, spawn_until, visage};

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// `visage run` on the first 5 frames of `clip` into `out`, with `extra` options.
fn run_five_frames(clip: &Path, models: &Path, out: &Path, extra: &[&str]) {
    let mut args = vec![
        "run",
        s(clip),
        "--out",
        s(out),
        "--max-frames",
        "5",
        "--quiet",
        "--ply",
        "--models",
        s(models),
    ];
    args.extend(extra);
    run_ok(&args);
}

fn ply_count(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |d| {
        d.filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "ply"))
        })
        .count()
    })
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_short_clip_gives_a_mesh_landmarks_and_metrics_per_frame() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    run_ok(&[
        "run",
        s(&clip),
        "--out",
        s(&out),
        "--max-frames",
        "8",
        "--save-raw",
        "--quiet",
        "--ply",
        "--models",
        s(&models),
    ]);
    assert_eq!(ply_count(&out.join("meshes")), 8);
    assert_eq!(ply_count(&out.join("raw")), 8);
    let mesh = visage_mesh::io::read_ply(&out.join("meshes/000007.ply")).unwrap();
    // Metres in camera coordinates: a face 0.2–2 m in front of the camera.
    let z = mesh.vertices.iter().map(|v| v[2]).sum::<f64>() / mesh.vertices.len() as f64;
    assert!((0.2..2.0).contains(&z), "mean z {z}");
    let lm = json(&out.join("landmarks.json"));
    assert_eq!(lm["frames"].as_array().unwrap().len(), 8);
    assert_eq!(
        lm["frames"][3]["faces"][0]["landmarks"]
            .as_array()
            .unwrap()
            .len(),
        468
    );
    let m = json(&out.join("metrics.json"));
    assert_eq!(m["status"], "complete");
    // The camera the meshes are in, readable by `visage render --intrinsics`.
    let k = visage_camera::Intrinsics::load_json(&out.join("camera.json")).unwrap();
    assert_eq!(
        (k.width, k.height),
        (
            m["intrinsics"]["width"].as_u64().unwrap() as u32,
            m["intrinsics"]["height"].as_u64().unwrap() as u32
        )
    );
    let frames = m["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 8);
    for f in frames {
        assert_eq!(f["status"], "solved");
        for stage in ["decode", "track", "fit", "depth", "fuse", "write"] {
            assert!(f["ms"][stage].as_f64().unwrap() >= 0.0, "{stage}");
        }
        assert!(f["relative_residual"].as_f64().unwrap() < 1e-6);
        assert!(f["pose"]["yaw_deg"].is_number());
        assert!(f["roughness"].as_f64().unwrap() > 0.0);
    }
    let summary = &m["summary"];
    assert_eq!(summary["frames"], 8);
    assert!(summary["fps"].as_f64().unwrap() > 0.0);
    assert!(summary["stages"]["track"]["p95_ms"].as_f64().unwrap() > 0.0);
    let q = &summary["quality"];
    assert_eq!(q["pairs"], 7);
    let (fused, raw) = (
        q["vertex_jitter_mm"]["fused"].as_f64().unwrap(),
        q["vertex_jitter_mm"]["raw"].as_f64().unwrap(),
    );
    assert!(fused > 0.0 && fused < raw, "fused {fused} raw {raw}");
    assert!(q["reprojection_px"]["fused"].as_f64().unwrap() < 5.0);
    // The face-model fit's outputs: a Live Link Face row per frame (61 values after the
    // timecode and the count), the same in JSON with timestamps, the fitted neutral face.
    let csv = std::fs::read_to_string(out.join("blendshapes.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 9, "a header and 8 rows");
    assert!(rows[0].starts_with("Timecode,BlendShapeCount,EyeBlinkLeft,"));
    assert_eq!(rows[1].split(',').count(), 63);
    assert!(rows[1].starts_with("00:00:00:00.000,61,"), "{}", rows[1]);
    let b = json(&out.join("blendshapes.json"));
    assert_eq!(b["frames"].as_array().unwrap().len(), 8);
    assert!((b["fps"].as_f64().unwrap() - 30.0).abs() < 0.5);
    let t7 = b["frames"][7]["timestamp_s"].as_f64().unwrap();
    assert!((t7 - 7.0 / 30.0).abs() < 0.01, "{t7}");
    let identity = visage_mesh::io::read_obj(&out.join("identity.obj")).unwrap();
    assert_eq!(identity.uvs.len(), identity.vertices.len());
    assert_eq!(json(&out.join("identity.json"))["frames"], 8);
    for f in frames {
        assert!(f["model_fit_px"].as_f64().unwrap() < 5.0);
        assert!(f["time_s"].as_f64().unwrap() >= 0.0);
    }
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn image_mesh_and_clip_mode_run() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    for (name, extra) in [("image", ["--mesh", "image"]), ("clip", ["--mode", "clip"])] {
        let out = tmp.path().join(name);
        run_five_frames(&clip, &models, &out, &extra);
        assert_eq!(ply_count(&out.join("meshes")), 5, "{name}");
        let m = json(&out.join("metrics.json"));
        assert_eq!(m["status"], "complete", "{name}");
        let lj = &m["summary"]["quality"]["landmark_jitter_mm"];
        assert!(lj["fused"].as_f64().unwrap() > 0.0, "{name}: {lj}");
    }
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn bench_prints_stage_percentiles_and_the_kernels_it_ran() {
    let (models, clip) = inputs();
    let o = visage(&[
        "bench",
        s(&clip),
        "--max-frames",
        "4",
        "--quiet",
        "--models",
        s(&models),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["frames"], 4);
    assert_eq!(j["writes_meshes"], false);
    assert!(j["stages_ms"]["fuse"]["median_ms"].as_f64().unwrap() > 0.0);
    assert!(j["peak_rss_mib"].as_f64().unwrap() > 1.0);
    let kernels = j["network_kernels"].as_str().unwrap();
    assert!(
        ["avx512", "avx2+fma", "portable"].contains(&kernels),
        "{kernels}"
    );
    // The AVX-512 kernels switched off, as on a machine with AVX2 only.
    let o = Command::new(env!("CARGO_BIN_EXE_visage"))
        .args(["bench", s(&clip), "--max-frames", "2", "--quiet"])
        .args(["--models", s(&models)])
        .env("VISAGE_NO_AVX512", "1")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_ne!(j["network_kernels"], "avx512");
}

#[test]
fn a_missing_input_is_exit_2_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("nope.mp4");
    let o = visage(&["run", s(&missing), "--out", s(&tmp.path().join("o"))]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nope.mp4"));
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_truncated_video_keeps_the_readable_frames_and_names_the_break() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let cut = common::truncated_clip(tmp.path(), &clip);
    let out = tmp.path().join("out");
    let o = visage(&[
        "run",
        s(&cut),
        "--out",
        s(&out),
        "--quiet",
        "--ply",
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cut.mp4") && err.contains("broke at frame"),
        "{err}"
    );
    let m = json(&out.join("metrics.json"));
    assert_eq!(m["status"], "failed");
    assert!(m["error"].as_str().unwrap().contains("broke at frame"));
    let done = m["frames"].as_array().unwrap().len();
    assert!(done > 0 && done < 24, "{done} frames");
    assert_eq!(ply_count(&out.join("meshes")), done);
    assert_eq!(
        json(&out.join("landmarks.json"))["frames"]
            .as_array()
            .unwrap()
            .len(),
        done
    );
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_frame_without_a_face_gets_no_mesh_and_tracking_reacquires() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("frames");
    std::fs::create_dir(&dir).unwrap();
    let source = visage_video::FrameSource::open(&clip).unwrap();
    for (i, frame) in source.take(4).enumerate() {
        let image = frame.unwrap().image;
        image.save(dir.join(format!("f{i}.png"))).unwrap();
        if i == 1 {
            let black = image::RgbImage::new(image.width(), image.height());
            black.save(dir.join("f1_black.png")).unwrap();
        }
    }
    let out = tmp.path().join("out");
    run_ok(&[
        "run",
        s(&dir),
        "--out",
        s(&out),
        "--quiet",
        "--ply",
        "--models",
        s(&models),
    ]);
    let m = json(&out.join("metrics.json"));
    let status: Vec<&str> = m["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["status"].as_str().unwrap())
        .collect();
    assert_eq!(status, ["solved", "solved", "no_face", "solved", "solved"]);
    assert_eq!(m["summary"]["no_face"], 1);
    assert!(!out.join("meshes/000002.ply").exists());
    assert!(out.join("meshes/000003.ply").exists());
    // The point cache has a sample for every frame: the faceless one holds the one before.
    let cache = visage_mesh::io::read_pc2(&out.join("sequence.pc2")).unwrap();
    assert_eq!(cache.samples(), 5);
    assert_eq!(cache.sample(2), cache.sample(1));
    assert_ne!(cache.sample(3), cache.sample(2));
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn intrinsics_for_another_size_are_exit_2_naming_the_file() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let cam = tmp.path().join("cam.json");
    std::fs::write(
        &cam,
        r#"{"width": 640, "height": 480, "fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5}"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = visage(&[
        "run",
        s(&clip),
        "--out",
        s(&out),
        "--intrinsics",
        s(&cam),
        "--models",
        s(&models),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("cam.json") && err.contains("480"), "{err}");
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn an_unwritable_output_folder_is_exit_2() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("a_file");
    std::fs::write(&file, b"x").unwrap();
    let out = file.join("out");
    let o = visage(&["run", s(&clip), "--out", s(&out), "--models", s(&models)]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("a_file"), "{err}");
}

/// The fitted face model as the mesh and as the depth: every frame meshed on the model's face
/// region with its UVs, the fused surface near the tracked landmarks; clip mode on it too.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn the_model_mesh_and_the_model_depth_run() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let runs: [(&str, &[&str]); 4] = [
        ("model_model", &["--mesh", "model", "--depth", "model"]),
        ("model_face", &["--mesh", "model", "--depth", "face"]),
        ("face_model", &["--mesh", "face", "--depth", "model"]),
        ("model_clip", &["--mesh", "model", "--mode", "clip"]),
    ];
    for (name, extra) in runs {
        let out = tmp.path().join(name);
        run_five_frames(&clip, &models, &out, extra);
        assert_eq!(ply_count(&out.join("meshes")), 5, "{name}");
        let m = json(&out.join("metrics.json"));
        assert_eq!(m["status"], "complete", "{name}");
        let reprojection = m["summary"]["quality"]["reprojection_px"]["fused"]
            .as_f64()
            .unwrap();
        assert!(reprojection < 4.0, "{name}: {reprojection} px");
        let mesh = visage_mesh::io::read_ply(&out.join("meshes/000004.ply")).unwrap();
        if name.starts_with("model") {
            assert_eq!(mesh.vertices.len(), 9409, "{name}");
        }
        assert_eq!(mesh.uvs.len(), mesh.vertices.len(), "{name}: UVs");
        assert!(mesh.uvs.iter().flatten().all(|c| (0.0..=1.0).contains(c)));
    }
}

/// Ctrl-C (SIGINT) stops the run after the current frame: what was done is written and
/// consistent — metrics.json says "interrupted", the point cache has one sample per listed
/// frame, landmarks.json is valid JSON, no temporary file is left — and the exit code is 130.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn ctrl_c_stops_after_a_frame_and_keeps_the_work() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let child = spawn_until(
        &[
            "run",
            s(&clip),
            "--out",
            s(&out),
            "--ply",
            "--models",
            s(&models),
        ],
        &out.join("meshes/000003.ply"),
        std::process::Stdio::piped(),
    );
    interrupt(&child);
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted after"), "{err}");
    let m = json(&out.join("metrics.json"));
    assert_eq!(m["status"], "interrupted");
    let frames = m["frames"].as_array().unwrap().len();
    assert!((4..216).contains(&frames), "{frames} frames");
    let cache = visage_mesh::io::read_pc2(&out.join("sequence.pc2")).unwrap();
    assert_eq!(cache.samples(), frames);
    assert_eq!(
        json(&out.join("landmarks.json"))["frames"]
            .as_array()
            .unwrap()
            .len(),
        frames
    );
    assert!(out.join("camera.json").is_file());
    assert!(tmp_files(&out).is_empty(), "{:?}", tmp_files(&out));

    // --resume goes on after the last frame (here with a frame limit four frames further).
    let limit = (frames + 4).to_string();
    let o = visage(&[
        "run",
        s(&clip),
        "--out",
        s(&out),
        "--ply",
        "--max-frames",
        &limit,
        "--resume",
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let m = json(&out.join("metrics.json"));
    assert_eq!(m["resumed"]["previous_status"], "interrupted");
    // The last frame was given out without the smoother's look-ahead: done again.
    assert_eq!(m["resumed"]["after_frame"], frames - 2);
    // Every frame the files hold, the kept ones first.
    assert_eq!(m["frames"].as_array().unwrap().len(), frames + 4);
    assert_whole_run(&out, frames + 4);
}

fn tmp_files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "tmp"))
        .collect()
}

/// `out` holds a finished run over the input's first `frames` frames: every stream has every
/// frame once, in order, and no file is left under a temporary name.
#[track_caller]
fn assert_whole_run(out: &Path, frames: usize) {
    assert_eq!(ply_count(&out.join("meshes")), frames);
    assert_whole_run_without_plys(out, frames);
}

/// [`assert_whole_run`] of a run without `--ply`.
#[track_caller]
fn assert_whole_run_without_plys(out: &Path, frames: usize) {
    let indices = |v: &Value| -> Vec<u64> {
        v["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["index"].as_u64().unwrap())
            .collect()
    };
    let all: Vec<u64> = (0..frames as u64).collect();
    assert_eq!(indices(&json(&out.join("landmarks.json"))), all);
    assert_eq!(indices(&json(&out.join("blendshapes.json"))), all);
    let csv = std::fs::read_to_string(out.join("blendshapes.csv")).unwrap();
    assert_eq!(csv.lines().count(), frames + 1);
    assert_eq!(
        visage_mesh::io::read_pc2(&out.join("sequence.pc2"))
            .unwrap()
            .samples(),
        frames
    );
    let metrics = json(&out.join("metrics.json"));
    assert_eq!(metrics["status"], "complete");
    // metrics.json lists every frame the files hold, in order.
    assert_eq!(indices(&metrics), all, "metrics.json's frames");
    assert!(out.join("identity.json").is_file());
    assert!(tmp_files(out).is_empty(), "{:?}", tmp_files(out));
}

/// Sends SIGINT to `child`.
fn interrupt(child: &std::process::Child) {
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
}

/// Ctrl-C in clip mode: the message does not advise `--resume`, which a clip-mode run cannot
/// do, and says why; a second Ctrl-C stops at once and says so, and what it left.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn ctrl_c_says_what_the_run_can_do_next_and_a_second_one_is_not_silent() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("clip");
    let args = ["run", s(&clip), "--out", s(&out), "--models", s(&models)];
    let child = spawn_until(
        &[&args[..], &["--mode", "clip"]].concat(),
        &out.join("metrics.json"),
        std::process::Stdio::piped(),
    );
    std::thread::sleep(std::time::Duration::from_millis(1500));
    interrupt(&child);
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted after")
            && err.contains("cannot be resumed: a clip-mode run")
            && !err.contains("--resume goes on"),
        "{err}"
    );

    let out = tmp.path().join("twice");
    let args = ["run", s(&clip), "--out", s(&out), "--models", s(&models)];
    let child = spawn_until(
        &args,
        &out.join("metrics.json"),
        std::process::Stdio::piped(),
    );
    std::thread::sleep(std::time::Duration::from_millis(500));
    interrupt(&child);
    std::thread::sleep(std::time::Duration::from_millis(20));
    interrupt(&child);
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("stopped at once by a second Ctrl-C") && err.contains("--resume"),
        "{err}"
    );
}

/// SIGKILL part-way, then `--resume`: the files are cut back to the last frame they all hold
/// and the run goes on after it, so that the folder ends as a run over every frame; a second
/// `--resume` has nothing to do; other options are refused, naming what differs.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_killed_run_resumes_where_it_stopped() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let args = [
        "run",
        s(&clip),
        "--out",
        s(&out),
        "--ply",
        "--max-frames",
        "60",
        "--models",
        s(&models),
    ];
    let mut child = spawn_until(
        &args,
        &out.join("meshes/000008.ply"),
        std::process::Stdio::null(),
    );
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(json(&out.join("metrics.json"))["status"], "running");

    let resume = [&args[..], &["--resume"]].concat();
    let o = visage(&resume);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("continuing after frame"), "{err}");
    let m = json(&out.join("metrics.json"));
    let after = m["resumed"]["after_frame"].as_u64().unwrap() as usize;
    // Frame 8's PLY was written after its landmarks record, which may not have reached the
    // disk whole; frame 7's record did, and is done again.
    assert!(after >= 6, "resumed after frame {after}");
    assert_eq!(m["resumed"]["previous_status"], "running");
    assert_eq!(m["resumed"]["frames"], after + 1);
    assert_eq!(m["frames"].as_array().unwrap().len(), 60);
    assert_whole_run(&out, 60);

    let o = visage(&resume);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("nothing to resume"), "{err}");

    let other = [&resume[..], &["--lambda", "5"]].concat();
    let o = visage(&other);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cannot resume") && err.contains("weights"),
        "{err}"
    );
    assert_whole_run(&out, 60);
}

/// SIGKILL leaves no half-written file under a final name (every file that looks complete
/// parses; metrics.json says "running"); a re-run into the folder is refused, saying what it
/// found, and `--overwrite` replaces the killed run's files but keeps the user's.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_killed_run_leaves_complete_files_and_a_rerun_must_choose() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let mut child = spawn_until(
        &[
            "run",
            s(&clip),
            "--out",
            s(&out),
            "--ply",
            "--models",
            s(&models),
        ],
        &out.join("meshes/000005.ply"),
        std::process::Stdio::null(),
    );
    child.kill().unwrap();
    child.wait().unwrap();
    assert_eq!(json(&out.join("metrics.json"))["status"], "running");
    assert_eq!(json(&out.join("camera.json"))["width"], 480);
    for entry in std::fs::read_dir(out.join("meshes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|x| x == "ply") {
            visage_mesh::io::read_ply(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
        }
    }
    if out.join("mesh.obj").exists() {
        visage_mesh::io::read_obj(&out.join("mesh.obj")).unwrap();
    }
    assert!(!out.join("landmarks.json").exists() && out.join("landmarks.json.tmp").exists());
    std::fs::write(out.join("notes.txt"), b"mine").unwrap();

    let o = visage(&["run", s(&clip), "--out", s(&out), "--models", s(&models)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("not empty") && err.contains("killed") && err.contains("--overwrite"),
        "{err}"
    );

    run_five_frames(&clip, &models, &out, &["--overwrite"]);
    assert_eq!(ply_count(&out.join("meshes")), 5, "stale meshes were left");
    assert_eq!(json(&out.join("metrics.json"))["status"], "complete");
    assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"mine");
    assert!(tmp_files(&out).is_empty(), "{:?}", tmp_files(&out));

    let o = visage(&[
        "run",
        s(&clip),
        "--out",
        s(&out),
        "--max-frames",
        "2",
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("\"complete\" over 5 frames"), "{err}");
}

/// A write that fails part-way, here past a file-size limit: the run stops with exit 2 naming
/// the file, metrics.json says "failed" with the cause, no streamed file appears under its
/// final name (each may end inside a record), and `--resume` goes on once there is room, to
/// the files an uninterrupted run writes.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_full_disk_stops_the_run_naming_the_file_and_resume_goes_on() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let args = [
        "run",
        s(&clip),
        "--out",
        s(&out),
        "--max-frames",
        "40",
        "--models",
        s(&models),
    ];
    // 400 KiB per file: room for mesh.obj (~300 KB), not for 40 frames of landmarks (~20 KB
    // each). SIGXFSZ is ignored, so a write past the limit fails with EFBIG.
    let o = Command::new("bash")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 400; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_visage"))
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cannot write") && err.contains(s(&out)) && err.contains("too large"),
        "{err}"
    );
    let m = json(&out.join("metrics.json"));
    assert_eq!(m["status"], "failed");
    assert!(m["error"].as_str().unwrap().contains("too large"), "{m}");
    let frames = m["frames"].as_array().unwrap().len();
    assert!((2..40).contains(&frames), "{frames} frames");
    assert!(
        err.contains("temporary names") && err.contains("--resume"),
        "{err}"
    );
    for name in STREAMED {
        assert!(!out.join(name).exists(), "{name} under its final name");
    }

    let resume = [&args[..], &["--resume"]].concat();
    let o = visage(&resume);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(
        json(&out.join("metrics.json"))["resumed"]["previous_status"],
        "failed"
    );
    assert_whole_run_without_plys(&out, 40);
    let whole = tmp.path().join("whole");
    run_ok(&[&args[..2], &["--out", s(&whole)], &args[4..], &["--quiet"]].concat());
    for name in ["sequence.pc2", "blendshapes.csv"] {
        assert!(
            std::fs::read(out.join(name)).unwrap() == std::fs::read(whole.join(name)).unwrap(),
            "{name} differs from the uninterrupted run's"
        );
    }
}

/// The files a run streams frame by frame.
const STREAMED: [&str; 4] = [
    "sequence.pc2",
    "landmarks.json",
    "blendshapes.csv",
    "blendshapes.json",
];

/// A really full disk (a 600 KiB tmpfs, in a mount namespace of its own: needs root): the
/// message names the write that failed first — not metrics.json, which cannot be written
/// either and is said to be so —, nothing streamed is under a final name, and the folder,
/// moved where there is room, resumes to an uninterrupted run's files.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_full_disk_names_the_first_failed_write_and_the_frames_resume() {
    let (models, clip) = inputs();
    let namespaces = Command::new("unshare").args(["-m", "true"]).output();
    if !namespaces.is_ok_and(|o| o.status.success()) {
        // Without root a tmpfs cannot be mounted; the test above covers the failing write.
        let root = std::env::var("USER").is_ok_and(|u| u == "root");
        assert!(
            !(root && std::env::var("CI").is_ok_and(|v| v == "true")),
            "unshare -m failed as root under CI"
        );
        eprintln!("skipped: cannot make a mount namespace (needs root)");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let (disk, moved) = (tmp.path().join("disk"), tmp.path().join("moved"));
    std::fs::create_dir(&disk).unwrap();
    let args = ["--max-frames", "40", "--models", s(&models)];
    let o = Command::new("unshare")
        .args(["-m", "bash", "-c"])
        .arg(
            "disk=$1; moved=$2; shift 2; mount -t tmpfs -o size=600k tmpfs \"$disk\" || exit 99; \
             \"$@\"; code=$?; cp -a \"$disk/r\" \"$moved\"; exit $code",
        )
        .args([
            "sh",
            s(&disk),
            s(&moved),
            env!("CARGO_BIN_EXE_visage"),
            "run",
        ])
        .arg(&clip)
        .args(["--out", &format!("{}/r", s(&disk))])
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_ne!(o.status.code(), Some(99), "cannot mount a tmpfs: {err}");
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("No space left on device"), "{err}");
    assert!(
        err.contains("metrics.json could not be written either"),
        "{err}"
    );
    let first = err.trim_end().rsplit("cannot write ").next().unwrap();
    assert!(
        !first.contains("metrics.json"),
        "the first failure: {first}"
    );
    for name in STREAMED {
        assert!(!moved.join(name).exists(), "{name} under its final name");
    }
    // `cp -a` above kept the folder as the full disk left it.
    let resume = [
        &["run", s(&clip), "--out", s(&moved)][..],
        &args,
        &["--resume", "--quiet"],
    ]
    .concat();
    run_ok(&resume);
    assert_whole_run_without_plys(&moved, 40);
    let whole = tmp.path().join("whole");
    run_ok(
        &[
            &["run", s(&clip), "--out", s(&whole)][..],
            &args,
            &["--quiet"],
        ]
        .concat(),
    );
    for name in ["sequence.pc2", "blendshapes.csv"] {
        assert!(
            std::fs::read(moved.join(name)).unwrap() == std::fs::read(whole.join(name)).unwrap(),
            "{name} differs from the uninterrupted run's"
        );
    }
}

/// Two portraits side by side: `--faces largest` meshes one and warns about the other;
/// `--faces all` gives each its own folder (left to right) and lists them in faces.json.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn every_face_gets_its_own_folder_with_faces_all() {
    let models = visage_testdata::models_dir();
    let portrait =
        visage_testdata::require(visage_testdata::shared_dir().join("data/images/astronaut.png"));
    let tmp = tempfile::tempdir().unwrap();
    let one = image::open(portrait).unwrap().to_rgb8();
    let small = image::imageops::resize(&one, 280, 280, image::imageops::FilterType::Triangle);
    let mut two = image::RgbImage::from_pixel(640, 320, image::Rgb([100, 100, 100]));
    image::imageops::replace(&mut two, &small, 10, 30);
    // The right one a little larger: the largest is the right-hand face.
    let larger = image::imageops::resize(&one, 320, 320, image::imageops::FilterType::Triangle);
    image::imageops::replace(&mut two, &larger, 310, 0);
    let input = tmp.path().join("two.png");
    two.save(&input).unwrap();

    let out = tmp.path().join("largest");
    let o = visage(&["run", s(&input), "--out", s(&out), "--models", s(&models)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("2 faces were in view"), "{err}");
    let m = json(&out.join("metrics.json"));
    assert_eq!(m["summary"]["most_faces_seen"], 2);
    let nose_x = |dir: &Path| {
        json(&dir.join("landmarks.json"))["frames"][0]["faces"][0]["landmarks"][1][0]
            .as_f64()
            .unwrap()
    };
    assert!(nose_x(&out) > 320.0, "the largest face is the right one");

    let out = tmp.path().join("all");
    let o = visage(&[
        "run",
        s(&input),
        "--out",
        s(&out),
        "--faces",
        "all",
        "--quiet",
        "--models",
        s(&models),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let faces = json(&out.join("faces.json"));
    let faces = faces["faces"].as_array().unwrap();
    assert_eq!(faces.len(), 2);
    for (i, face) in faces.iter().enumerate() {
        assert_eq!(face["id"], i + 1);
        assert_eq!(face["status"], "complete");
        assert_eq!(face["frames_meshed"], 1);
    }
    let (left, right) = (nose_x(&out.join("face-1")), nose_x(&out.join("face-2")));
    assert!(left < 300.0 && right > 320.0, "{left} {right}");

    // Interrupted while the first face runs: faces.json says what that face's metrics say.
    let folder = tmp.path().join("frames");
    std::fs::create_dir(&folder).unwrap();
    for i in 0..150 {
        std::fs::copy(&input, folder.join(format!("{i:04}.png"))).unwrap();
    }
    let out = tmp.path().join("stopped");
    let child = spawn_until(
        &[
            "run",
            s(&folder),
            "--out",
            s(&out),
            "--faces",
            "all",
            "--models",
            s(&models),
        ],
        &out.join("face-1/metrics.json"),
        std::process::Stdio::piped(),
    );
    std::thread::sleep(std::time::Duration::from_millis(300));
    interrupt(&child);
    let o = child.wait_with_output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let face = &json(&out.join("faces.json"))["faces"][0];
    assert_eq!(face["status"], "interrupted");
    assert_eq!(
        json(&out.join("face-1/metrics.json"))["status"],
        "interrupted"
    );
    let meshed = face["frames_meshed"].as_u64().unwrap();
    assert!((1..150).contains(&meshed), "{meshed}");
}

/// `--mesh image --spacing 1` on a large photo: refused before the mesh is built (it used to
/// grow past 2.4 GB with no limit), naming the spacing that fits; exit 2.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn an_image_plane_mesh_too_fine_for_the_face_is_refused_with_the_spacing_that_fits() {
    let models = visage_testdata::models_dir();
    let portrait =
        visage_testdata::require(visage_testdata::shared_dir().join("data/images/astronaut.png"));
    let tmp = tempfile::tempdir().unwrap();
    let big = tmp.path().join("big.png");
    let img = image::open(portrait).unwrap().to_rgb8();
    image::imageops::resize(&img, 3000, 3000, image::imageops::FilterType::Triangle)
        .save(&big)
        .unwrap();
    let out = tmp.path().join("out");
    let o = visage(&[
        "run",
        s(&big),
        "--out",
        s(&out),
        "--mesh",
        "image",
        "--spacing",
        "1",
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--spacing 1: the mesh over this face's")
            && err.contains("more than the 250000 visage meshes; use --spacing 2 or more"),
        "{err}"
    );
}

/// Two people filmed alike, one after the other (each face cropped to the same place on the
/// same grey background): metrics.json lists a cut where the second starts.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn another_person_filmed_alike_is_listed_as_a_cut() {
    let models = visage_testdata::models_dir();
    let video = visage_testdata::shared_dir().join("data/video");
    let tmp = tempfile::tempdir().unwrap();
    let clip = tmp.path().join("two_people.mp4");
    let place = "scale=300:300,pad=640:480:170:90:gray,setsar=1";
    let filter = format!(
        "[0:v]trim=end_frame=15,setpts=PTS-STARTPTS,crop=330:330:81:120,{place}[a];\
         [1:v]trim=end_frame=15,setpts=PTS-STARTPTS,crop=550:550:93:362,{place}[b];\
         [a][b]concat=n=2:v=1[v]"
    );
    let status = Command::new("ffmpeg")
        .args(["-v", "error", "-y", "-i"])
        .arg(video.join("lp_d18.mp4"))
        .arg("-i")
        .arg(video.join("lp_d13.mp4"))
        .args(["-filter_complex", &filter, "-map", "[v]", "-crf", "16"])
        .arg(&clip)
        .status()
        .unwrap();
    assert!(status.success());
    let out = tmp.path().join("out");
    run_ok(&[
        "run",
        s(&clip),
        "--out",
        s(&out),
        "--models",
        s(&models),
        "--quiet",
    ]);
    let m = json(&out.join("metrics.json"));
    assert_eq!(
        m["summary"]["cuts"],
        serde_json::json!([15]),
        "{}",
        m["summary"]
    );
}

/// `visage run --help` states the weights a run takes when none are given: the help is
/// written from the pipeline's defaults, and a run's metrics.json records what it used.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn the_weights_help_states_the_defaults_a_run_takes() {
    let models = visage_testdata::models_dir();
    let portrait =
        visage_testdata::require(visage_testdata::shared_dir().join("data/images/astronaut.png"));
    let help = visage(&["run", "--help"]);
    let help: String = String::from_utf8_lossy(&help.stdout)
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    run_ok(&[
        "run",
        s(&portrait),
        "--out",
        s(&out),
        "--models",
        s(&models),
        "--quiet",
    ]);
    let weights = &json(&out.join("metrics.json"))["parameters"]["weights"];
    let (lambda, mu) = (
        weights["lambda"].as_f64().unwrap(),
        weights["mu"].as_f64().unwrap(),
    );
    for stated in [
        format!("λ (face and model meshes: mm⁴ of the template face, default {lambda} with the face or model depth"),
        format!("μ (dimensionless; default {mu} with the face or model depth"),
    ] {
        assert!(help.contains(&stated), "{stated:?} not in: {help}");
    }
}
