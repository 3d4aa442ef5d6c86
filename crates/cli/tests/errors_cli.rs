//! The bad inputs of `docs/errors.md`, each run through the real binary: the exit code and the
//! message the table shows, and that every message names the file once, in words (no Rust
//! debug formatting, no cause printed twice). The table and these cases are checked against
//! each other, so neither can drift.

mod common;

use std::path::Path;

use common::s;

/// One row of `docs/errors.md`.
struct Case {
    /// The table's first column: the bad input, in words.
    what: &'static str,
    /// The arguments after `visage` (`{dir}` is the test's folder of bad files).
    args: &'static [&'static str],
    exit: i32,
    /// What the message must contain (as the table quotes it, `{dir}/` removed).
    says: &'static str,
    /// Whether the case needs the model files.
    models: bool,
}

const CASES: &[Case] = &[
    Case {
        what: "a missing input",
        args: &["run", "{dir}/missing.mp4", "--out", "{dir}/o1"],
        exit: 2,
        says: "missing.mp4: cannot read the input",
        models: false,
    },
    Case {
        what: "intrinsics that are not JSON",
        args: &["render", "{dir}/tri.obj", "--intrinsics", "{dir}/broken.json"],
        exit: 2,
        says: "broken.json: not a valid intrinsics file: EOF while parsing an object at line 1 column 1",
        models: false,
    },
    Case {
        what: "a focal length of 0",
        args: &["render", "{dir}/tri.obj", "--intrinsics", "{dir}/fx0.json"],
        exit: 2,
        says: "fx0.json: invalid intrinsics: fx = 0 (must be positive and finite)",
        models: false,
    },
    Case {
        what: "an image size beyond the limits",
        args: &["render", "{dir}/tri.obj", "--intrinsics", "{dir}/huge.json"],
        exit: 2,
        says: "huge.json: invalid intrinsics: width = 100000 (is more than the 16384 pixels visage accepts)",
        models: false,
    },
    Case {
        what: "a principal point outside the image",
        args: &["render", "{dir}/tri.obj", "--intrinsics", "{dir}/cx.json"],
        exit: 2,
        says: "cx.json: invalid intrinsics: cx = 99999 (puts the principal point outside the image)",
        models: false,
    },
    Case {
        what: "a field of view over 170°",
        args: &["render", "{dir}/tri.obj", "--intrinsics", "{dir}/wide.json"],
        exit: 2,
        says: "wide.json: invalid intrinsics: fx = 10 (gives a field of view wider than 170 degrees)",
        models: false,
    },
    Case {
        what: "a corrupt PNG",
        args: &["keypoints", "{dir}/corrupt.png", "--out", "{dir}/k.json"],
        exit: 2,
        says: "corrupt.png: cannot decode the image: the PNG data is damaged or truncated",
        models: false,
    },
    Case {
        what: "a mesh file that is not a mesh",
        args: &["render", "{dir}/garbage.ply", "--intrinsics", "{dir}/cam.json"],
        exit: 2,
        says: "garbage.ply:1: not a PLY file: the first line is \"this is not a mesh\", expected \"ply\"",
        models: false,
    },
    Case {
        what: "a field of view out of range",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o2", "--fov-deg", "200"],
        exit: 2,
        says: "--fov-deg 200: must lie between 5 and 170 degrees",
        models: true,
    },
    Case {
        what: "an output folder that is not empty",
        args: &["run", "{dir}/face.png", "--out", "{dir}/full"],
        exit: 2,
        says: "full: the output folder is not empty; it holds other files notes.txt",
        models: false,
    },
    Case {
        what: "`--overwrite` of a folder no run wrote to",
        args: &["run", "{dir}/face.png", "--out", "{dir}/full", "--overwrite"],
        exit: 2,
        says: "full: --overwrite replaces a previous visage run, and this folder does not hold one; it holds notes.txt. Nothing was removed: choose another folder, or remove these yourself",
        models: false,
    },
    Case {
        what: "a weight too large for double precision",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o20", "--lambda", "1e308"],
        exit: 2,
        says: "invalid weight lambda = 1e308: must lie between 0 and 1e6 (larger leaves the data term no weight in double precision)",
        models: true,
    },
    Case {
        what: "a huge number",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o21", "--fov-deg", "1e300"],
        exit: 2,
        says: "--fov-deg 1e300: must lie between 5 and 170 degrees",
        models: false,
    },
    Case {
        what: "a negative number",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o22", "--fov-deg", "-5"],
        exit: 2,
        says: "--fov-deg -5: must lie between 5 and 170 degrees",
        models: false,
    },
    Case {
        what: "a file that is not a mesh by its name",
        args: &["render", "{dir}/full/notes.txt", "--intrinsics", "{dir}/cam.json"],
        exit: 2,
        says: "full/notes.txt: not a mesh file visage reads: the name ends in .txt; a mesh is a .obj or .ply file",
        models: false,
    },
    Case {
        what: "`visage export` of a folder that is not a run",
        args: &["export", "{dir}/full"],
        exit: 2,
        says: "full: not a visage run folder (it has no metrics.json): `visage run INPUT --out` into it makes one, then export",
        models: false,
    },
    Case {
        what: "`visage batch status` of a missing folder",
        args: &["batch", "status", "{dir}/nothere"],
        exit: 2,
        says: "nothere: no such folder (a batch folder is the --out of `visage batch`)",
        models: false,
    },
    Case {
        what: "an output folder under a file",
        args: &["run", "{dir}/face.png", "--out", "{dir}/tri.obj/out"],
        exit: 2,
        says: "cannot write",
        models: true,
    },
    Case {
        what: "a depth network that is missing",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o4", "--depth", "{dir}/missing.onnx"],
        exit: 2,
        says: "cannot use --depth: missing.onnx: No such file or directory (os error 2)",
        models: false,
    },
    Case {
        what: "a depth network that is not ONNX",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o5", "--depth", "{dir}/garbage.onnx"],
        exit: 2,
        says: "cannot use --depth: garbage.onnx: not an ONNX model: failed to decode Protobuf message",
        models: false,
    },
    Case {
        what: "a depth network whose input is not one image",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o6", "--depth", "{dir}/rank3_input.onnx"],
        exit: 2,
        says: "cannot use --depth: rank3_input.onnx: input 'image' has rank 3 (shape [3, 64, 64]); a depth network takes one image, 1×3×H×W",
        models: false,
    },
    Case {
        what: "a depth network with an operator visage cannot run",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o7", "--depth", "{dir}/unsupported_op.onnx"],
        exit: 2,
        says: "cannot use --depth: unsupported_op.onnx: the network uses operators visage's ONNX runtime (tract) does not implement: MaxUnpool",
        models: false,
    },
    Case {
        what: "a depth network whose output is not a depth map of the input's shape",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o8", "--depth", "{dir}/wrong_output.onnx"],
        exit: 2,
        says: "cannot use --depth: wrong_output.onnx: the output is 48×16 (shape [1, 1, 16, 48]) for a 64×64 input; a depth map must have the input's aspect ratio",
        models: false,
    },
    Case {
        what: "a folder that is not an RGB-D recording",
        args: &["run", "--rgbd", "{dir}/full", "--out", "{dir}/o9"],
        exit: 2,
        says: "cannot use --rgbd: full: not an RGB-D recording: expected rgb.txt and depth.txt (TUM RGB-D) or the folders rgb/ and depth/",
        models: false,
    },
    Case {
        what: "a field of view so wide that the fit puts the face behind the camera",
        args: &["run", "{dir}/face.png", "--out", "{dir}/o4", "--fov-deg", "160"],
        exit: 3,
        says: "face.png: nothing to mesh (metrics.json is in o4): a face was found in 1 of the 1 frames, but its metric fit failed (the metric face fit placed the face behind the camera); the camera's intrinsics (--fov-deg, --intrinsics) are the likely cause",
        models: true,
    },
    Case {
        what: "no face in any frame",
        args: &["run", "{dir}/grey.png", "--out", "{dir}/o3"],
        exit: 3,
        says: "no face was found in any of the 1 frames",
        models: true,
    },
];

/// Writes the bad (and the good) files the cases use into `dir`.
fn make_files(dir: &Path) {
    let write = |name: &str, bytes: &[u8]| std::fs::write(dir.join(name), bytes).unwrap();
    write("tri.obj", b"v 0 0 0.5\nv 0.1 0 0.5\nv 0 0.1 0.5\nf 1 2 3\n");
    write("broken.json", b"{");
    let k = |w: u32, fx: f64, cx: f64| {
        format!(
            r#"{{"width": {w}, "height": 480, "fx": {fx}, "fy": 500, "cx": {cx}, "cy": 239.5}}"#
        )
    };
    write("fx0.json", k(640, 0.0, 319.5).as_bytes());
    write(
        "huge.json",
        br#"{"width": 100000, "height": 100000, "fx": 50000, "fy": 50000, "cx": 50000, "cy": 50000}"#,
    );
    write("cx.json", k(640, 500.0, 99999.0).as_bytes());
    write("wide.json", k(640, 10.0, 319.5).as_bytes());
    write("cam.json", k(640, 500.0, 319.5).as_bytes());
    let mut png = Vec::new();
    image::RgbImage::new(64, 48)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let half = png.len() / 2;
    png[half..].fill(0x5a);
    write("corrupt.png", &png);
    write("garbage.ply", b"this is not a mesh\n");
    write(
        "cam.json",
        br#"{"width": 64, "height": 48, "fx": 60, "fy": 60, "cx": 31.5, "cy": 23.5}"#,
    );
    image::RgbImage::from_pixel(320, 240, image::Rgb([128, 128, 128]))
        .save(dir.join("grey.png"))
        .unwrap();
    let face = visage_testdata::shared_dir().join("data/images/astronaut.png");
    if face.is_file() {
        std::fs::copy(face, dir.join("face.png")).unwrap();
    } else {
        std::fs::copy(dir.join("grey.png"), dir.join("face.png")).unwrap();
    }
    std::fs::create_dir(dir.join("full")).unwrap();
    write("full/notes.txt", b"mine");
    let networks = visage_testdata::workspace_root().join("crates/depth/tests/data");
    for name in [
        "rank3_input.onnx",
        "unsupported_op.onnx",
        "wrong_output.onnx",
    ] {
        std::fs::copy(networks.join(name), dir.join(name)).unwrap();
    }
    write("garbage.onnx", b"not a network\n");
}

/// The table rows of `docs/errors.md`: (first column, exit code column, message column).
fn table() -> Vec<(String, String, String)> {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/errors.md"))
        .expect("docs/errors.md");
    doc.lines()
        .skip_while(|l| !l.starts_with("| Bad input"))
        .skip(2)
        .take_while(|l| l.starts_with("| "))
        .map(|l| {
            let cells: Vec<String> = l
                .trim_matches('|')
                .split(" | ")
                .map(|c| c.trim().to_owned())
                .collect();
            assert_eq!(cells.len(), 4, "{l}");
            (cells[0].clone(), cells[2].clone(), cells[3].clone())
        })
        .collect()
}

#[test]
fn the_table_lists_every_case_and_only_them() {
    let rows = table();
    for case in CASES {
        let row = rows
            .iter()
            .find(|r| r.0 == case.what)
            .unwrap_or_else(|| panic!("docs/errors.md has no row for {:?}", case.what));
        assert_eq!(row.1, case.exit.to_string(), "{}", case.what);
        assert!(
            row.2.contains(case.says),
            "{}: the table says {:?}, the test expects {:?}",
            case.what,
            row.2,
            case.says
        );
    }
    let tested: Vec<&str> = CASES
        .iter()
        .map(|c| c.what)
        .chain(OTHER_TESTS.iter().map(|t| t.0))
        .collect();
    for row in &rows {
        assert!(
            tested.contains(&row.0.as_str()),
            "no test for the row {:?}",
            row.0
        );
    }
}

/// Rows of the table whose test lives with its command's other tests (they need a clip and
/// signals): the row's first column and the test's name.
const OTHER_TESTS: &[(&str, &str)] = &[
    (
        "an output folder another run is writing into",
        "run_folder_cli::a_second_run_into_the_same_folder_is_refused_naming_the_first",
    ),
    (
        "`--resume` with a frame limit below the frames written",
        "run_folder_cli::a_killed_run_resumes_to_a_folder_whose_files_agree",
    ),
    (
        "Ctrl-C or SIGTERM during a run",
        "run_cli::ctrl_c_stops_after_a_frame_and_keeps_the_work",
    ),
    (
        "a run killed with SIGKILL, then run again",
        "run_cli::a_killed_run_leaves_complete_files_and_a_rerun_must_choose",
    ),
    (
        "a full disk during a run",
        "run_cli::a_full_disk_names_the_first_failed_write_and_the_frames_resume",
    ),
    (
        "`--resume` with other options than the run it continues",
        "run_cli::a_killed_run_resumes_where_it_stopped",
    ),
    (
        "an image-plane mesh too fine for the face",
        "run_cli::an_image_plane_mesh_too_fine_for_the_face_is_refused_with_the_spacing_that_fits",
    ),
    (
        "a video that breaks part-way",
        "run_cli::a_truncated_video_keeps_the_readable_frames_and_names_the_break",
    ),
    (
        "a live source that cannot be opened",
        "live_cli::a_source_that_cannot_be_opened_is_exit_2_naming_it",
    ),
    (
        "intrinsics for another image size",
        "run_cli::intrinsics_for_another_size_are_exit_2_naming_the_file",
    ),
];

fn check(case: &Case, dir: &Path) {
    let d = s(dir);
    let args: Vec<String> = case.args.iter().map(|a| a.replace("{dir}", d)).collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_visage"))
        .args(&args)
        .env("VISAGE_MODELS", visage_testdata::models_dir())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(case.exit), "{}: {err}", case.what);
    let message = err.replace(&format!("{d}/"), "");
    assert!(
        message.contains(case.says),
        "{}: expected {:?} in {message:?}",
        case.what,
        case.says
    );
    let line = message
        .lines()
        .find(|l| l.starts_with("error: "))
        .unwrap_or_default();
    assert!(
        !line.contains(" { ") && !line.contains("Os {") && !line.contains("kind:"),
        "{}: debug formatting in {line:?}",
        case.what
    );
    // The first file named in the arguments appears once in the message.
    if let Some(name) = case.args.iter().find_map(|a| a.strip_prefix("{dir}/")) {
        let name = name.split('/').next().unwrap();
        assert!(
            line.matches(name).count() <= 1,
            "{}: {name} named twice in {line:?}",
            case.what
        );
    }
}

#[test]
fn bad_inputs_without_models_give_the_documented_exit_and_message() {
    let tmp = tempfile::tempdir().unwrap();
    make_files(tmp.path());
    for case in CASES.iter().filter(|c| !c.models) {
        check(case, tmp.path());
    }
}

#[test]
#[cfg_attr(not(model_files), ignore = "needs the model files (scripts/setup.sh)")]
fn bad_inputs_with_models_give_the_documented_exit_and_message() {
    let models = visage_testdata::models_dir();
    for file in visage_testdata::MODEL_FILES {
        visage_testdata::require(models.join(file));
    }
    let tmp = tempfile::tempdir().unwrap();
    make_files(tmp.path());
    for case in CASES.iter().filter(|c| c.models) {
        check(case, tmp.path());
    }
}

/// A JSON file that starts with a UTF-8 byte-order mark (Windows editors write one) is read.
#[test]
fn json_with_a_byte_order_mark_is_read() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(
        dir.join("bom.json"),
        "\u{feff}{\"width\": 64, \"height\": 48, \"fx\": 60, \"fy\": 60, \"cx\": 31.5, \"cy\": 23.5}",
    )
    .unwrap();
    std::fs::write(
        dir.join("tri.obj"),
        "v 0 0 1\nv 0.1 0 1\nv 0 0.1 1\nf 1 2 3\n",
    )
    .unwrap();
    let out = dir.join("tri.png");
    let o = common::visage(&[
        "render",
        s(&dir.join("tri.obj")),
        "--intrinsics",
        s(&dir.join("bom.json")),
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.is_file());
}
