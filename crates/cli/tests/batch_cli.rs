//! `visage batch` as an array job's workers run it: shards over short clips cut from a shared
//! video, one worker SIGKILLed in the middle of a clip and started again, failed clips that
//! leave the others to finish, `visage batch status`, and bad invocations.

mod common;

use common::{inputs, json, s, visage};

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

/// `n` clips of `frames` frames each, cut from `video` at different times into `dir`
/// (`dir/day{i % 3}/clip{i}.mp4`, downscaled so that the tests stay quick); the manifest
/// `dir/manifest.txt` lists them.
fn cut_clips(video: &Path, dir: &Path, n: usize, frames: usize) -> PathBuf {
    let mut lines = String::from("# short clips cut from the sample video\n");
    for i in 0..n {
        let rel = format!("day{}/clip{i:02}.mp4", i % 3);
        let path = dir.join(&rel);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        let status = Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-ss"])
            .arg(format!("{:.2}", 0.2 * i as f64))
            .arg("-i")
            .arg(video)
            .args(["-frames:v", &frames.to_string(), "-vf", "scale=240:240"])
            .args([
                "-c:v",
                "libx264",
                "-preset",
                "ultrafast",
                "-pix_fmt",
                "yuv420p",
            ])
            .arg(&path)
            .status()
            .unwrap();
        assert!(status.success(), "ffmpeg cutting {rel}");
        lines += &rel;
        lines.push('\n');
    }
    let manifest = dir.join("manifest.txt");
    std::fs::write(&manifest, lines).unwrap();
    manifest
}

/// Every file of each clip's folder but `metrics.json` and `done.json` (which hold timings),
/// by path, with contents.
fn outputs(out: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![out.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(out).unwrap().to_string_lossy().into_owned();
            if p.is_dir() {
                stack.push(p);
            } else if !["metrics.json", "done.json", "batch.json"]
                .iter()
                .any(|n| rel.ends_with(n))
            {
                files.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    files
}

/// The clip folders under `out` holding a `done.json`, by id.
fn done_ids(out: &Path) -> Vec<String> {
    let mut ids = Vec::new();
    let mut stack = vec![out.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.join("done.json").is_file() {
                ids.push(p.strip_prefix(out).unwrap().to_string_lossy().into_owned());
            } else if p.is_dir() {
                stack.push(p);
            }
        }
    }
    ids.sort();
    ids
}

fn batch(manifest: &Path, out: &Path, extra: &[&str], models: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_visage"));
    c.args(["batch", s(manifest), "--out", s(out)])
        .args(extra)
        .args(["--", "--models", s(models)]);
    c
}

/// Four shard workers over 20 clips, one SIGKILLed while a clip of its shard is half written
/// and started again: every clip is done exactly once, nothing unfinished stays visible, and
/// the outputs are byte for byte those of one worker over the whole manifest.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn four_shards_with_one_killed_and_restarted_do_every_clip_once() {
    let (models, video) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let manifest = cut_clips(&video, &tmp.path().join("clips"), 20, 10);
    let single = tmp.path().join("single");
    let o = batch(&manifest, &single, &[], &models).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let summary: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["done"], 20, "{summary}");
    assert_eq!(summary["frames"], 200, "{summary}");
    assert!(summary["frames_per_hour_per_core"].as_f64().unwrap() > 0.0);

    let out = tmp.path().join("sharded");
    let spawn = |i: usize| {
        batch(
            &manifest,
            &out,
            &["--shard-index", &i.to_string(), "--shard-count", "4"],
            &models,
        )
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
    };
    let mut workers: Vec<_> = (0..4).map(spawn).collect();
    // Kill shard 1's worker once it has finished a clip and the next one's run is part-way:
    // its point cache has frames but is still under its temporary name.
    let shard1: Vec<String> = {
        let text = std::fs::read_to_string(&manifest).unwrap();
        text.lines()
            .filter(|l| !l.starts_with('#'))
            .map(|l| l.trim_end_matches(".mp4").to_owned())
            .filter(|id| fnv1a64(id.as_bytes()) % 4 == 1)
            .collect()
    };
    assert!(shard1.len() >= 2, "shard 1 holds {shard1:?}");
    let partial = out.join(".partial");
    let pid = workers[1].id();
    let started = Instant::now();
    loop {
        let half_written = std::fs::read_dir(&partial).ok().and_then(|d| {
            d.filter_map(|e| e.ok()).find(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                name.split('.').nth(1) == Some(&pid.to_string())
                    && std::fs::metadata(e.path().join("sequence.pc2.tmp"))
                        .is_ok_and(|m| m.len() > 0)
            })
        });
        let one_done = shard1
            .iter()
            .any(|id| out.join(id).join("done.json").is_file());
        if one_done && half_written.is_some() {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(300),
            "shard 1 wrote no point cache in five minutes"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    workers[1].kill().unwrap();
    workers[1].wait().unwrap();
    for (i, w) in workers.into_iter().enumerate() {
        if i == 1 {
            continue;
        }
        let o = w.wait_with_output().unwrap();
        assert!(
            o.status.success(),
            "shard {i}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // The killed clip is not done, and `status` says shard 1 is missing clips.
    let o = visage(&["batch", "status", s(&out)]);
    let table = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(4), "{table}");
    assert!(table.contains("missing (shard 1)"), "{table}");

    let o = spawn(1).wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("removed 1 unfinished folder"), "{err}");
    let again: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(again["skipped"].as_u64().unwrap() >= 1, "{again}");
    assert_eq!(
        again["skipped"].as_u64().unwrap() + again["done"].as_u64().unwrap(),
        shard1.len() as u64
    );

    assert_eq!(done_ids(&out).len(), 20);
    assert_eq!(done_ids(&out), done_ids(&single));
    assert!(!partial.exists(), "{partial:?} is left");
    let (a, b) = (outputs(&single), outputs(&out));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (k, v) in &a {
        assert!(b[k] == *v, "{k} differs from the single worker's");
    }
    let done = json(&out.join("day0/clip00/done.json"));
    assert_eq!(done["clip"], "day0/clip00");
    assert_eq!(done["input_file"]["sha256"].as_str().unwrap().len(), 64);
    assert!(done["outputs"]["sequence.pc2"]["bytes"].as_u64().unwrap() > 0);
    let o = visage(&["batch", "status", s(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    // A worker over a finished shard skips every clip.
    let o = batch(
        &manifest,
        &out,
        &["--shard-index", "2", "--shard-count", "4"],
        &models,
    )
    .output()
    .unwrap();
    let again: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(again["done"], 0);
    assert_eq!(again["skipped"], again["clips"]);
}

/// A missing file, a corrupt video and a clip without a face fail with their own
/// `error.json`; the good clips finish; the exit code is 3, and stays so on a rerun, which
/// keeps the failed clips (and runs them again with --retry-failed).
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn failed_clips_say_why_and_the_others_finish() {
    let (models, video) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("clips");
    let manifest = cut_clips(&video, &dir, 2, 4);
    std::fs::write(dir.join("corrupt.mp4"), b"this is not a video").unwrap();
    let status = Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-y",
            "-f",
            "lavfi",
            "-i",
            "color=gray:s=160x120:d=0.2",
        ])
        .args([
            "-c:v",
            "libx264",
            "-preset",
            "ultrafast",
            "-pix_fmt",
            "yuv420p",
        ])
        .arg(dir.join("noface.mp4"))
        .status()
        .unwrap();
    assert!(status.success());
    let mut text = std::fs::read_to_string(&manifest).unwrap();
    text += "missing.mp4\ncorrupt.mp4\nnoface.mp4\n";
    std::fs::write(&manifest, text).unwrap();
    let out = tmp.path().join("out");
    let o = batch(&manifest, &out, &[], &models).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(err.contains("3 of 5 clips of shard 0 failed"), "{err}");
    let why = |id: &str| {
        let e = json(&out.join(id).join("error.json"));
        (
            e["exit_code"].as_u64().unwrap(),
            e["error"].as_str().unwrap().to_owned(),
        )
    };
    let (code, msg) = why("missing");
    assert_eq!(code, 2);
    assert!(
        msg.contains("missing.mp4") && msg.contains("cannot read"),
        "{msg}"
    );
    let (code, msg) = why("corrupt");
    assert_eq!(code, 2);
    assert!(msg.contains("corrupt.mp4"), "{msg}");
    let (code, msg) = why("noface");
    assert_eq!(code, 3);
    assert!(msg.contains("no face"), "{msg}");
    assert_eq!(done_ids(&out), ["day0/clip00", "day1/clip01"]);
    assert!(!out.join("missing/done.json").exists());

    let o = visage(&["batch", "status", s(&out)]);
    let table = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(3), "{table}");
    assert!(table.contains("failed  (shard 0) noface"), "{table}");

    let o = batch(&manifest, &out, &[], &models).output().unwrap();
    assert_eq!(o.status.code(), Some(3));
    let again: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (again["skipped"].as_u64(), again["failed"].as_u64()),
        (Some(2), Some(3))
    );
    assert_eq!(again["failed_before"], 3);
    assert!(String::from_utf8_lossy(&o.stderr).contains("failed before"));
    let o = batch(&manifest, &out, &["--retry-failed"], &models)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("failed before"));
}

/// Invocations that cannot work stop before any clip with exit code 2, naming the problem.
#[test]
fn bad_invocations_are_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let manifest = tmp.path().join("m.txt");
    let run = |args: &[&str]| {
        let o = visage(args);
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, err) = run(&["batch", s(&manifest), "--out", s(&out)]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("m.txt") && err.contains("cannot read the manifest"),
        "{err}"
    );
    std::fs::write(&manifest, "a.mp4\nb.mp4\n").unwrap();
    let (code, err) = run(&[
        "batch",
        s(&manifest),
        "--out",
        s(&out),
        "--shard-index",
        "4",
        "--shard-count",
        "4",
    ]);
    assert_eq!(code, Some(2));
    assert!(err.contains("not below the shard count 4"), "{err}");
    let (code, err) = run(&[
        "batch",
        s(&manifest),
        "--out",
        s(&out),
        "--",
        "--lambada",
        "1",
    ]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("bad options") && err.contains("--lambada"),
        "{err}"
    );
    let (code, err) = run(&["batch", s(&manifest), "--out", s(&out), "--", "--overwrite"]);
    assert_eq!(code, Some(2));
    assert!(
        err.contains("--overwrite is set by `visage batch`"),
        "{err}"
    );
    std::fs::write(&manifest, "a.mp4\na.mov\n").unwrap();
    let (code, err) = run(&["batch", s(&manifest), "--out", s(&out)]);
    assert_eq!(code, Some(2));
    assert!(err.contains("lines 1 and 2 both name the clip"), "{err}");
    assert!(!out.exists(), "nothing is written before the checks pass");
    let (code, err) = run(&["batch", "status", s(&out)]);
    assert_eq!(code, Some(2));
    assert!(err.contains("no such folder"), "{err}");
    std::fs::create_dir_all(&out).unwrap();
    let (code, err) = run(&["batch", "status", s(&out)]);
    assert_eq!(code, Some(2));
    assert!(err.contains("no batch.json"), "{err}");
}

/// The 64-bit FNV-1a hash (the shard rule, written out here as a user's script would).
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}
