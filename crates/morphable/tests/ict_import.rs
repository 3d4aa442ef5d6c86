//! Import of the ICT-FaceKit subset in ../shared: counts, units, modes, landmarks, the repository
//! layout, a full-size checkout (100 identities), and errors that name the file.

use std::path::{Path, PathBuf};

use visage_mesh::io::{read_obj_with, ObjReadOptions};
use visage_morphable::{IctModel, ImportOptions, MorphableError, Region, LANDMARK_COUNT};

/// The ICT-FaceKit subset in `../shared` (tests using it are ignored without it).
#[track_caller]
fn shared_model() -> PathBuf {
    let dir = visage_testdata::shared_dir().join("data/ict-facekit/FaceXModel");
    visage_testdata::require(dir.join("generic_neutral_mesh.obj"));
    dir
}

fn small() -> ImportOptions {
    ImportOptions {
        max_identities: Some(2),
        expressions: Some(vec!["jawOpen".into(), "eyeBlink_L".into()]),
    }
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
fn imports_the_shared_subset_in_metres_with_triangulated_quads() {
    let dir = shared_model();
    let model = IctModel::load_with(&dir, &small()).unwrap();
    assert_eq!(model.vertex_count(), 26_719);
    // 26,384 polygons, mostly quads: each quad gives two triangles.
    let polygons = model.triangle_polygon.last().map_or(0, |&p| p as usize + 1);
    assert_eq!(polygons, 26_384);
    assert!(model.triangles.len() > 50_000 && model.triangles.len() <= 2 * 26_384);
    // Metres: a head is ~15–30 cm across, not 15–30 units.
    let face = &model.neutral[Region::Face.range()];
    let span = |c: usize| {
        let (lo, hi) = face.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
            (lo.min(p[c]), hi.max(p[c]))
        });
        hi - lo
    };
    assert!(
        (0.1..0.35).contains(&span(0)) && (0.1..0.4).contains(&span(1)),
        "{} {}",
        span(0),
        span(1)
    );
    assert_eq!(model.identity_names, ["identity000", "identity001"]);
    assert_eq!(model.expression_names, ["jawOpen", "eyeBlink_L"]);
    // jawOpen moves the chin by centimetres, not metres, and leaves the back of the head alone.
    let jaw = &model.expression_modes[0];
    let max_move = jaw
        .iter()
        .map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt())
        .fold(0.0, f64::max);
    assert!((0.005..0.1).contains(&max_move), "{max_move}");
    // Landmarks are face vertices.
    assert_eq!(model.landmarks.len(), LANDMARK_COUNT);
    assert!(model
        .landmarks
        .iter()
        .all(|&i| Region::Face.contains(i as usize)));
    // shape() with zero weights is the neutral mesh; with a unit weight it is the mode's mesh.
    let mut s = Vec::new();
    model.shape(&[0.0, 0.0], &[0.0, 0.0], &mut s).unwrap();
    assert_eq!(s, model.neutral);
    model.shape(&[0.0, 0.0], &[1.0, 0.0], &mut s).unwrap();
    let file = read_obj_with(&dir.join("jawOpen.obj"), &ObjReadOptions::POSITIONS).unwrap();
    assert_eq!(file.mesh.vertices.len(), s.len());
    for (p, q) in s.iter().zip(&file.mesh.vertices) {
        for c in 0..3 {
            assert!((p[c] - q[c] * 0.01).abs() < 1e-12);
        }
    }
    assert!(matches!(
        model.shape(&[0.0], &[0.0, 0.0], &mut s),
        Err(MorphableError::WeightCount {
            what: "identity",
            ..
        })
    ));
}

/// Stems of the `.obj` files in `dir` other than the neutral mesh, sorted.
fn mode_files(dir: &Path) -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter_map(|name| name.strip_suffix(".obj").map(str::to_owned))
        .filter(|stem| stem != "generic_neutral_mesh")
        .collect();
    stems.sort();
    stems
}

/// The `expressions` list of `dir/vertex_indices.json`.
fn listed_expressions(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("vertex_indices.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["expressions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap().to_owned())
        .collect()
}

#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
fn default_import_takes_every_present_file_in_listed_order() {
    let dir = shared_model();
    let model = IctModel::load(&dir).unwrap();

    // What the folder holds: identityNNN.obj files, and expression files listed in
    // vertex_indices.json or not.
    let files = mode_files(&dir);
    let identity_files: Vec<&String> = files.iter().filter(|f| f.starts_with("identity")).collect();
    let listed = listed_expressions(&dir);
    let present: Vec<String> = listed
        .iter()
        .filter(|e| files.contains(e))
        .cloned()
        .collect();
    let unlisted: Vec<String> = files
        .iter()
        .filter(|f| !f.starts_with("identity") && !listed.contains(f))
        .cloned()
        .collect();

    // Every identity file is imported, numbered without a gap from 000.
    let numbered: Vec<String> = (0..identity_files.len())
        .map(|i| format!("identity{i:03}"))
        .collect();
    assert_eq!(model.identity_names, numbered);
    assert_eq!(identity_files, numbered.iter().collect::<Vec<_>>());
    assert_eq!(model.identity_modes.len(), identity_files.len());
    // Every listed expression with a file, in the listed order; unlisted files only on request.
    assert_eq!(model.expression_names, present);
    assert_eq!(model.expression_modes.len(), present.len());
    let n = model.vertex_count();
    assert!(model
        .identity_modes
        .iter()
        .chain(&model.expression_modes)
        .all(|m| m.len() == n));

    // The numbers ../shared/data/ict-facekit/SOURCE.md documents: identities 000–029, all 53
    // listed expressions, and the four shapes the repository ships without listing them.
    assert_eq!(model.identity_modes.len(), 30);
    assert_eq!(listed.len(), 53);
    assert_eq!(model.expression_modes.len(), 53);
    assert_eq!(
        unlisted,
        [
            "PupilDilate_L",
            "PupilDilate_R",
            "cheekRaiser_L",
            "cheekRaiser_R"
        ]
    );
    assert_eq!(
        model
            .expression_index("jawOpen")
            .map(|i| model.expression_names[i].as_str()),
        Some("jawOpen")
    );

    let extra = IctModel::load_with(
        &dir,
        &ImportOptions {
            max_identities: Some(0),
            expressions: Some(unlisted.clone()),
        },
    )
    .unwrap();
    assert!(extra.identity_modes.is_empty());
    assert_eq!(extra.expression_names, unlisted);
}

/// A full checkout has 100 identities (and may have more expressions): nothing caps the counts.
/// Built from tiny meshes in the checkout layout.
#[test]
fn imports_a_full_size_checkout_of_tiny_meshes() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("FaceXModel");
    std::fs::create_dir(&dir).unwrap();
    let mesh = |dx: f64| format!("v {dx} 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\n");
    std::fs::write(dir.join("generic_neutral_mesh.obj"), mesh(0.0)).unwrap();
    for i in 0..100 {
        std::fs::write(dir.join(format!("identity{i:03}.obj")), mesh(i as f64)).unwrap();
    }
    let expressions: Vec<String> = (0..60).map(|j| format!("shape{j}")).collect();
    for name in &expressions {
        std::fs::write(dir.join(format!("{name}.obj")), mesh(-1.0)).unwrap();
    }
    let landmarks: Vec<u32> = (0..68).map(|i| i % 4).collect();
    let json = serde_json::json!({"expressions": expressions, "idx_to_landmark_verts": landmarks});
    std::fs::write(dir.join("vertex_indices.json"), json.to_string()).unwrap();

    let model = IctModel::load(root.path()).unwrap();
    assert_eq!(model.identity_modes.len(), 100);
    assert_eq!(model.identity_names[99], "identity099");
    assert!(
        (model.identity_modes[99][0][0] - 0.99).abs() < 1e-12,
        "cm → m"
    );
    assert_eq!(model.expression_names, expressions);
    let capped = IctModel::load_with(
        root.path(),
        &ImportOptions {
            max_identities: Some(40),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(capped.identity_modes.len(), 40);
}

/// A checkout of the repository has the model in `FaceXModel/`: the importer accepts the
/// checkout's root as well. Built from links to the shared files.
#[test]
#[cfg_attr(not(shared_data), ignore = "needs ../shared beside the checkout")]
fn imports_a_repository_checkout_layout() {
    let dir = shared_model();
    let root = tempfile::tempdir().unwrap();
    let model_dir = root.path().join("FaceXModel");
    std::fs::create_dir(&model_dir).unwrap();
    for name in [
        "generic_neutral_mesh.obj",
        "vertex_indices.json",
        "identity000.obj",
        "jawOpen.obj",
    ] {
        std::os::unix::fs::symlink(dir.join(name), model_dir.join(name)).unwrap();
    }
    let model = IctModel::load(root.path()).unwrap();
    assert_eq!(model.dir, model_dir);
    assert_eq!(model.identity_names, ["identity000"]);
    assert_eq!(model.expression_names, ["jawOpen"]);
}

#[test]
fn missing_and_malformed_files_are_named() {
    let empty = tempfile::tempdir().unwrap();
    let e = IctModel::load(empty.path()).unwrap_err();
    assert!(matches!(e, MorphableError::MissingFile { .. }));
    assert!(e.to_string().contains("generic_neutral_mesh.obj"), "{e}");

    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    std::fs::write(
        p.join("generic_neutral_mesh.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\n",
    )
    .unwrap();
    let e = IctModel::load(p).unwrap_err();
    assert!(e.to_string().contains("vertex_indices.json"), "{e}");

    let landmarks: Vec<u32> = (0..68).map(|i| i % 4).collect();
    let json = serde_json::json!({"expressions": ["jawOpen"], "idx_to_landmark_verts": landmarks});
    std::fs::write(p.join("vertex_indices.json"), json.to_string()).unwrap();
    let model = IctModel::load(p).unwrap();
    assert_eq!(model.triangles, vec![[0, 1, 3], [0, 3, 2]]);
    assert!((model.neutral[1][0] - 0.01).abs() < 1e-15, "cm → m");
    assert!(model.identity_modes.is_empty() && model.expression_modes.is_empty());

    std::fs::write(p.join("jawOpen.obj"), "v 0 0 0\nv 1 0 0\n").unwrap();
    let e = IctModel::load(p).unwrap_err();
    assert!(
        matches!(
            e,
            MorphableError::VertexCount {
                expected: 4,
                got: 2,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("jawOpen.obj"));

    let e = IctModel::load_with(
        p,
        &ImportOptions {
            expressions: Some(vec!["mouthSmile_L".into()]),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("mouthSmile_L"), "{e}");

    let json = serde_json::json!({"expressions": [], "idx_to_landmark_verts": [1, 2]});
    std::fs::write(p.join("vertex_indices.json"), json.to_string()).unwrap();
    std::fs::remove_file(p.join("jawOpen.obj")).unwrap();
    let e = IctModel::load(p).unwrap_err().to_string();
    assert!(
        e.contains("vertex_indices.json") && e.contains("2 entries"),
        "{e}"
    );
    let bad: Vec<u32> = (0..68).map(|i| i + 100).collect();
    let json = serde_json::json!({"expressions": [], "idx_to_landmark_verts": bad});
    std::fs::write(p.join("vertex_indices.json"), json.to_string()).unwrap();
    let e = IctModel::load(p).unwrap_err().to_string();
    assert!(e.contains("landmark vertex 100"), "{e}");
    std::fs::write(p.join("vertex_indices.json"), "{not json").unwrap();
    assert!(matches!(
        IctModel::load(p),
        Err(MorphableError::Indices { .. })
    ));
}
