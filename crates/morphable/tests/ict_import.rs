//! Import of the ICT-FaceKit subset in ../shared: counts, units, modes, landmarks, the repository
//! layout, and errors that name the file.

use std::path::{Path, PathBuf};

use visage_morphable::{IctModel, ImportOptions, MorphableError, Region, LANDMARK_COUNT};

fn shared_model() -> Option<PathBuf> {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/ict-facekit/FaceXModel");
    if dir.join("generic_neutral_mesh.obj").is_file() {
        Some(dir)
    } else {
        println!("SKIPPED: ../shared not found");
        None
    }
}

fn small() -> ImportOptions {
    ImportOptions {
        max_identities: Some(2),
        expressions: Some(vec!["jawOpen".into(), "eyeBlink_L".into()]),
    }
}

#[test]
fn imports_the_shared_subset_in_metres_with_triangulated_quads() {
    let Some(dir) = shared_model() else { return };
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
    let file = visage_morphable::read_obj_positions(&dir.join("jawOpen.obj"), false).unwrap();
    for (p, q) in s.iter().zip(&file.positions) {
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

#[test]
fn default_import_takes_every_present_file_in_listed_order() {
    let Some(dir) = shared_model() else { return };
    let model = IctModel::load(&dir).unwrap();
    assert_eq!(model.identity_modes.len(), 10);
    assert_eq!(model.expression_modes.len(), 16);
    assert_eq!(
        model
            .expression_index("jawOpen")
            .map(|i| model.expression_names[i].as_str()),
        Some("jawOpen")
    );
}

/// A checkout of the repository has the model in `FaceXModel/`: the importer accepts the
/// checkout's root as well. Built from links to the shared files.
#[test]
fn imports_a_repository_checkout_layout() {
    let Some(dir) = shared_model() else { return };
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
