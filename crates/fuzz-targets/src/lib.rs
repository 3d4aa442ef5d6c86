//! The fuzz targets' bodies: each feeds arbitrary bytes to one reader visage owns and checks
//! that it returns a consistent value or an error — never a panic, a hang or a huge
//! allocation. `fuzz/` (cargo-fuzz, libFuzzer, nightly) calls them one per target; the test
//! `tests/replay.rs` (stable, in the test suite) replays the committed seeds and a few
//! thousand deterministic mutations of them through every one ([`mutation`]).

pub mod mutation;

use std::path::Path;

/// A target's body: one input, checked (a failed check panics).
pub type Target = fn(&[u8]);

/// Every target: its name (`fuzz/fuzz_targets/NAME.rs`, `fuzz/seeds/NAME/`) and its body.
pub const TARGETS: [(&str, Target); 15] = [
    ("depth_png", depth_png),
    ("intrinsics_json", intrinsics_json),
    ("rigid_transform_json", rigid_transform_json),
    ("obj", obj),
    ("ply", ply),
    ("pc2", pc2),
    ("tflite", tflite),
    ("exif", exif),
    ("keypoints_json", keypoints_json),
    ("canonical_mesh", canonical_mesh),
    ("network_config", network_config),
    ("tum_list", tum_list),
    ("batch_manifest", batch_manifest),
    ("streamed_records", streamed_records),
    ("image", image),
];

/// `visage_camera::parse_depth_png`: a depth map has `width × height` values.
pub fn depth_png(data: &[u8]) {
    use visage_camera::{parse_depth_png, DepthKind};
    match parse_depth_png(data, Path::new("fuzz.png"), 1000.0, DepthKind::Z) {
        Ok(depth) => assert_eq!(
            depth.data.len() as u64,
            depth.width as u64 * depth.height as u64
        ),
        Err(e) => drop(e.to_string()),
    }
}

/// `Intrinsics::parse_json` (`load_json` reads the file as UTF-8 first): what is accepted
/// passes `validate`.
pub fn intrinsics_json(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match visage_camera::Intrinsics::parse_json(text, Path::new("fuzz.json")) {
        Ok(k) => assert!(k.validate().is_ok(), "accepted invalid intrinsics {k:?}"),
        Err(e) => drop(e.to_string()),
    }
}

/// `RigidTransform::parse_json`: what is accepted passes `validate`.
pub fn rigid_transform_json(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match visage_camera::RigidTransform::parse_json(text, Path::new("pose.json")) {
        Ok(t) => assert!(t.validate().is_ok(), "accepted an invalid transform {t:?}"),
        Err(e) => drop(e.to_string()),
    }
}

/// The checks a mesh read from a file passes: triangles index existing vertices, attributes
/// are absent or one per vertex, positions are finite.
fn check_mesh(m: &visage_mesh::TriMesh) {
    let nv = m.vertices.len();
    assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < nv));
    for len in [m.uvs.len(), m.normals.len(), m.colors.len()] {
        assert!(len == 0 || len == nv, "{len} attributes for {nv} vertices");
    }
    assert!(m.vertices.iter().flatten().all(|c| c.is_finite()));
}

/// `visage_mesh::io::parse_obj`, the first byte choosing the read options: a consistent mesh
/// and one source face per triangle.
pub fn obj(data: &[u8]) {
    use visage_mesh::io::{parse_obj, ObjReadOptions};
    let Some((&flags, file)) = data.split_first() else {
        return;
    };
    let options = ObjReadOptions {
        attributes: flags & 1 == 0,
        faces: flags & 2 == 0,
    };
    match parse_obj(file, Path::new("fuzz.obj"), &options) {
        Ok(obj) => {
            check_mesh(&obj.mesh);
            assert_eq!(obj.triangle_face.len(), obj.mesh.triangles.len());
        }
        Err(e) => drop(e.to_string()),
    }
}

/// `visage_mesh::io::parse_ply` (ASCII and binary, both byte orders): a consistent mesh.
pub fn ply(data: &[u8]) {
    match visage_mesh::io::parse_ply(data, Path::new("fuzz.ply")) {
        Ok(m) => check_mesh(&m),
        Err(e) => drop(e.to_string()),
    }
}

/// `visage_mesh::io::parse_pc2`: every sample can be taken and has `3 × points` values.
pub fn pc2(data: &[u8]) {
    match visage_mesh::io::parse_pc2(data, Path::new("fuzz.pc2")) {
        Ok(cache) => {
            for k in 0..cache.samples() {
                assert_eq!(cache.sample(k).len(), 3 * cache.points);
            }
        }
        Err(e) => drop(e.to_string()),
    }
}

/// Largest input (values) of a compiled network that is run, to keep iterations fast.
const MAX_RUN_INPUT: usize = 1 << 12;

/// `visage_nn::Network::from_tflite` (the flatbuffer reader and the graph compiler): a
/// network that compiles with a small input is also run once.
pub fn tflite(data: &[u8]) {
    match visage_nn::Network::from_tflite(data, "fuzz.tflite") {
        Ok(mut net) => {
            if net.input_mut().len() <= MAX_RUN_INPUT {
                net.input_mut().fill(0.5);
                net.run();
                let mut k = 0;
                while let Some((_, values)) = net.output(k) {
                    std::hint::black_box(values);
                    k += 1;
                }
            }
        }
        Err(e) => drop(e.to_string()),
    }
}

/// `visage_video::focal_length_35mm_in` (the TIFF reader behind EXIF focal lengths): a focal
/// length found is finite and positive.
pub fn exif(data: &[u8]) {
    if let Some(mm) = visage_video::focal_length_35mm_in(data) {
        assert!(mm.is_finite() && mm > 0.0, "focal length {mm}");
    }
}

/// `KeypointsFile::parse_json`: one 128-byte descriptor per keypoint.
pub fn keypoints_json(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match visage_keypoints::KeypointsFile::parse_json(text, Path::new("fuzz.json")) {
        Ok(f) => assert_eq!(f.keypoints.len(), f.descriptors.len()),
        Err(e) => drop(e.to_string()),
    }
}

/// `CanonicalMesh::parse` (the face-geometry protobuf): 468 vertices with UVs, 898 triangles
/// over them and a Procrustes basis.
pub fn canonical_mesh(data: &[u8]) {
    use visage_face::canonical_mesh::{CanonicalMesh, NUM_TRIANGLES};
    use visage_face::NUM_LANDMARKS;
    match CanonicalMesh::parse(data) {
        Ok(m) => {
            assert_eq!(m.vertices.len(), NUM_LANDMARKS);
            assert_eq!(m.uvs.len(), NUM_LANDMARKS);
            assert_eq!(m.triangles.len(), NUM_TRIANGLES);
            assert!(m
                .triangles
                .iter()
                .flatten()
                .all(|&i| (i as usize) < NUM_LANDMARKS));
            assert!(!m.procrustes_basis.is_empty());
        }
        Err(e) => drop(e.to_string()),
    }
}

/// `NetworkConfig::parse` (a depth network's JSON description): what is accepted validates,
/// and an error names the file.
pub fn network_config(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match visage_depth::NetworkConfig::parse(text, Path::new("net.json")) {
        Ok(c) => assert!(c.validate().is_ok()),
        Err(e) => assert!(e.to_string().contains("net.json")),
    }
}

/// `parse_tum_list` (a TUM RGB-D recording's lists): finite, sorted times, paths relative to
/// the recording (or absolute, as the list wrote them), and an error names the list.
pub fn tum_list(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match visage_depth::parse_tum_list(text, Path::new("rgb.txt"), Path::new("rec")) {
        Ok(list) => {
            assert!(list
                .iter()
                .all(|(t, p)| t.is_some_and(f64::is_finite)
                    && (p.starts_with("rec") || p.is_absolute())));
            assert!(list.windows(2).all(|w| w[0].0 <= w[1].0));
        }
        Err(e) => assert!(e.to_string().contains("rgb.txt")),
    }
}

/// `visage_batch::manifest::parse` (plain lines or, by the first byte, JSON Lines): every
/// clip's id is a relative path of plain names (no `..`, nothing hidden), ids are unique, and
/// lines are counted from 1.
pub fn batch_manifest(data: &[u8]) {
    let Some((&flags, text)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    match visage_batch::manifest::parse(text, Path::new("batch"), flags & 1 == 1) {
        Ok(clips) => {
            let mut ids = std::collections::HashSet::new();
            for clip in &clips {
                assert!(clip.line >= 1);
                assert!(
                    clip.id
                        .split('/')
                        .all(|part| !part.is_empty() && !part.starts_with('.')),
                    "id {:?}",
                    clip.id
                );
                assert!(ids.insert(clip.id.clone()), "id {:?} twice", clip.id);
            }
        }
        Err(e) => drop(e.to_string()),
    }
}

/// `visage_run_folder::scan_records`, the reader `--resume` cuts a killed run's streamed
/// `landmarks.json.tmp` and `blendshapes.json.tmp` back with: the records (each one JSON
/// value, as the caller's parser accepted it) come in order, each ending within the file
/// after the one before, and cutting the file at any record's end keeps exactly the records
/// before it.
pub fn streamed_records(data: &[u8]) {
    let parse = |bytes: &[u8]| serde_json::from_slice::<serde_json::Value>(bytes).ok();
    match visage_run_folder::scan_records(data, Path::new("landmarks.json.tmp"), parse) {
        Ok(scan) => {
            let mut last = scan.array_start;
            assert!(last <= data.len() as u64);
            for (_, end) in &scan.records {
                assert!(*end > last && *end <= data.len() as u64);
                last = *end;
            }
            let n = scan.records.len();
            for keep in [0, n / 2, n] {
                let cut = &data[..scan.end_of(keep) as usize];
                let again = visage_run_folder::scan_records(cut, Path::new("cut"), parse)
                    .expect("a file cut at a record's end still has its array");
                assert_eq!(again.records.len(), keep);
            }
        }
        Err(e) => drop(e.to_string()),
    }
}

/// `visage_video::decode_image` (PNG and JPEG, EXIF orientation applied): an RGB frame of
/// `width × height × 3` bytes, or an error naming the file.
pub fn image(data: &[u8]) {
    match visage_video::decode_image(data, Path::new("fuzz.jpg")) {
        Ok(frame) => {
            let (w, h) = frame.image.dimensions();
            assert!(w > 0 && h > 0);
            assert_eq!(frame.image.as_raw().len() as u64, 3 * w as u64 * h as u64);
        }
        Err(e) => assert!(e.to_string().contains("fuzz.jpg")),
    }
}
