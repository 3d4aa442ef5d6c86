//! The output folder as one writer's: a second run (or an `--overwrite`, or an export) into a
//! folder in use is refused at once naming the first, and `--overwrite` removes nothing from a
//! folder that no run wrote to.

mod common;

use std::path::Path;
use std::process::Command;

use common::{inputs, s, visage};
use visage::run_folder::FolderLock;

/// Every file under `dir`, relative, sorted.
fn files(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.push(p.strip_prefix(root).unwrap().to_string_lossy().into_owned());
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// A folder of the user's whose names are a run's: `--overwrite` used to delete them all.
fn users_folder(dir: &Path) {
    for (name, text) in [
        ("mesh.obj", "v 0 0 0\n"),
        ("camera.json", "{\"mine\": true}"),
        ("texture.png", "not a png"),
        ("meshes/scan_final.ply", "ply\n"),
        ("plots/figure.svg", "<svg/>"),
        ("notes.txt", "mine"),
    ] {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
}

#[test]
fn overwrite_removes_nothing_from_a_folder_no_run_wrote_to() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("work");
    users_folder(&out);
    let before = files(&out);
    // The folder is judged before the input is opened: any file will do.
    let input = tmp.path().join("clip.mp4");
    std::fs::write(&input, b"x").unwrap();
    let o = visage(&["run", s(&input), "--out", s(&out), "--overwrite"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("does not hold one")
            && err.contains("mesh.obj")
            && err.contains("meshes/")
            && err.contains("Nothing was removed"),
        "{err}"
    );
    // Every file is still there, and nothing marks the folder as a run's: a second try is
    // refused the same way.
    assert_eq!(files(&out), before);
    let o = visage(&["run", s(&input), "--out", s(&out), "--overwrite"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(files(&out), before);
}

#[test]
fn a_folder_in_use_is_refused_at_once_naming_its_user() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let input = tmp.path().join("clip.mp4");
    std::fs::write(&input, b"x").unwrap();
    // This test process holds the folder, as a run would.
    let lock = FolderLock::acquire(&out).unwrap();
    let me = format!("pid {}", std::process::id());
    for extra in [&[][..], &["--overwrite"], &["--resume"]] {
        let mut args = vec!["run", s(&input), "--out", s(&out)];
        args.extend_from_slice(extra);
        let o = visage(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.contains("in use") && err.contains(&me),
            "{extra:?}: {err}"
        );
    }
    // Once it lets go, the folder is free (an empty folder: the run goes on to the input).
    drop(lock);
    let o = visage(&["run", s(&input), "--out", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("in use"), "{err}");
}

/// Two real runs into one folder: the second is refused at once, naming the first by its
/// process id, and the first's files are untouched by it; a killed run's lock goes with it.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_second_run_into_the_same_folder_is_refused_naming_the_first() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let run = |extra: &[&str]| {
        let mut args = vec!["run", s(&clip), "--out", s(&out), "--models", s(&models)];
        args.extend_from_slice(extra);
        args.iter().map(|a| a.to_string()).collect::<Vec<_>>()
    };
    // Started, it holds the folder; wait until it has written a frame.
    let args = run(&["--ply"]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let mut first = common::spawn_until(
        &args,
        &out.join("meshes/000002.ply"),
        std::process::Stdio::null(),
    );
    let pid = format!("pid {}", first.id());
    for extra in [&[][..], &["--overwrite"]] {
        let args = run(extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = visage(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.contains("in use") && err.contains(&pid),
            "{extra:?}: {err}"
        );
    }
    let o = visage(&["export", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("in use") && err.contains(&pid), "{err}");
    // The first run is still writing: it was not disturbed.
    assert!(first.try_wait().unwrap().is_none(), "the first run stopped");
    first.kill().unwrap();
    first.wait().unwrap();
    // Killed, it holds nothing: --overwrite replaces its files.
    let args = run(&["--overwrite", "--max-frames", "3", "--quiet"]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = visage(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        common::json(&out.join("metrics.json"))["status"],
        "complete"
    );
}

/// A run stopped at its frame limit and resumed further lists every frame in metrics.json,
/// so the exports work, and they equal an uninterrupted run's byte for byte.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_resumed_run_exports_as_the_uninterrupted_one() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let (resumed, whole) = (tmp.path().join("resumed"), tmp.path().join("whole"));
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "run",
            s(&clip),
            "--out",
            s(out),
            "--models",
            s(&models),
            "--quiet",
        ];
        args.extend_from_slice(extra);
        common::run_ok(&args);
    };
    run(&resumed, &["--max-frames", "10"]);
    run(&resumed, &["--resume", "--max-frames", "30"]);
    run(&whole, &["--max-frames", "30"]);
    let metrics = common::json(&resumed.join("metrics.json"));
    let indices: Vec<u64> = metrics["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["index"].as_u64().unwrap())
        .collect();
    assert_eq!(indices, (0..30).collect::<Vec<u64>>());
    for out in [&resumed, &whole] {
        common::run_ok(&["export", s(out), "--glb", "--quiet"]);
    }
    for file in ["sequence.pc2", "blendshapes.csv", "sequence.glb"] {
        assert!(
            std::fs::read(resumed.join(file)).unwrap() == std::fs::read(whole.join(file)).unwrap(),
            "{file} differs from the uninterrupted run's"
        );
    }
}

/// A killed run resumed lists every frame (the kept ones' records rebuilt), and a resume with
/// a frame limit below what the folder holds is refused instead of leaving the files and
/// metrics.json disagreeing.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_killed_run_resumes_to_a_folder_whose_files_agree() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    let args = |extra: &[&str]| {
        let mut a = vec![
            "run",
            s(&clip),
            "--out",
            s(&out),
            "--models",
            s(&models),
            "--ply",
        ];
        a.extend_from_slice(extra);
        a.iter().map(|x| x.to_string()).collect::<Vec<_>>()
    };
    let a = args(&[]);
    let mut child = common::spawn_until(
        &a.iter().map(String::as_str).collect::<Vec<_>>(),
        &out.join("meshes/000012.ply"),
        std::process::Stdio::null(),
    );
    child.kill().unwrap();
    child.wait().unwrap();
    let held = std::fs::read_dir(out.join("meshes")).unwrap().count();

    let a = args(&["--resume", "--max-frames", "3"]);
    let o = visage(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("already holds") && err.contains("--max-frames 3"),
        "{err}"
    );
    assert_eq!(std::fs::read_dir(out.join("meshes")).unwrap().count(), held);

    let a = args(&["--resume", "--max-frames", "40", "--quiet"]);
    common::run_ok(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let metrics = common::json(&out.join("metrics.json"));
    assert_eq!(metrics["status"], "complete");
    assert_eq!(metrics["frames"].as_array().unwrap().len(), 40);
    common::run_ok(&["export", s(&out), "--glb", "--quiet"]);
}

/// The input is the file's content, not the path as typed: a resume may name it relative
/// where the run named it absolute, `visage export` works from any working folder, and
/// another clip of the same size at the same path is refused.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn an_input_is_known_by_its_content_not_the_path_typed() {
    let (models, clip) = inputs();
    let tmp = tempfile::tempdir().unwrap();
    let copy = tmp.path().join("clip.mp4");
    std::fs::copy(&clip, &copy).unwrap();
    let out = tmp.path().join("run");
    let in_dir = |dir: &Path, args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_visage"))
            .current_dir(dir)
            .args(args)
            .output()
            .unwrap()
    };
    let ok = |o: std::process::Output| {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let base = ["--out", s(&out), "--models", s(&models), "--quiet"];
    ok(in_dir(
        tmp.path(),
        &[&["run", "clip.mp4", "--max-frames", "5"], &base[..]].concat(),
    ));
    ok(in_dir(
        Path::new("/"),
        &[
            &["run", s(&copy), "--resume", "--max-frames", "8"],
            &base[..],
        ]
        .concat(),
    ));
    ok(in_dir(
        Path::new("/"),
        &["export", s(&out), "--glb", "--quiet"],
    ));
    assert_eq!(
        common::json(&out.join("metrics.json"))["frames"]
            .as_array()
            .unwrap()
            .len(),
        8
    );

    // The same size, other bytes.
    let mut bytes = std::fs::read(&copy).unwrap();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0xff;
    std::fs::write(&copy, &bytes).unwrap();
    let o = in_dir(
        tmp.path(),
        &[
            &["run", "clip.mp4", "--resume", "--max-frames", "12"],
            &base[..],
        ]
        .concat(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("another file's content"), "{err}");
}
