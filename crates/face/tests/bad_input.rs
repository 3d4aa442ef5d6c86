//! Bad and awkward inputs: no face, several faces, tiny faces, faces at the border, corrupt
//! model files.

mod common;

use image::{imageops, RgbImage};
use visage_face::{FaceError, FaceMesh, LandmarkNetwork, ModelFile};

#[track_caller]
fn astronaut() -> RgbImage {
    let p = visage_testdata::require(common::data_dir().join("images/astronaut.png"));
    image::open(p).unwrap().to_rgb8()
}

#[test]
#[cfg_attr(not(model_files), ignore = "needs the model files (scripts/setup.sh)")]
fn an_image_without_a_face_gives_no_face() {
    let models = common::models_dir();
    let mut mesh = FaceMesh::load(&models).unwrap();
    let grey = RgbImage::from_pixel(320, 240, image::Rgb([128, 128, 128]));
    assert!(mesh.process(&grey).unwrap().is_empty());
    let noise = RgbImage::from_fn(200, 300, |x, y| {
        let v = ((x * 7919 + y * 104_729) % 251) as u8;
        image::Rgb([v, v.wrapping_mul(3), v.wrapping_mul(7)])
    });
    assert!(mesh.process(&noise).unwrap().is_empty());
    // Degenerate sizes do not panic.
    assert!(mesh.process(&RgbImage::new(1, 1)).unwrap().is_empty());
    assert!(mesh.process(&RgbImage::new(0, 0)).is_err());
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn several_faces_are_all_reported_highest_score_first() {
    let (models, img) = (common::models_dir(), astronaut());
    let mut mesh = FaceMesh::load(&models).unwrap();
    let single = mesh.process(&img).unwrap();
    assert_eq!(single.len(), 1);
    // Two portraits cropped around the face (2× the box), side by side in a square canvas,
    // the right one smaller.
    let b = single[0].bbox;
    let side = (2.0 * b[2]) as u32;
    let x0 = (b[0] + 0.5 * b[2]) as u32 - side / 2;
    let y0 = ((b[1] + 0.5 * b[3]) as u32).saturating_sub(side / 2);
    let face = imageops::crop_imm(&img, x0, y0, side, side).to_image();
    let small = imageops::resize(
        &face,
        side * 4 / 5,
        side * 4 / 5,
        imageops::FilterType::Triangle,
    );
    let mut canvas = RgbImage::from_pixel(2 * side + 20, 2 * side + 20, image::Rgb([40, 40, 40]));
    imageops::replace(&mut canvas, &face, 0, (side / 2) as i64);
    imageops::replace(&mut canvas, &small, (side + 20) as i64, (side / 2) as i64);
    let faces = mesh.process(&canvas).unwrap();
    assert_eq!(faces.len(), 2, "two faces expected");
    assert!(faces[0].score >= faces[1].score);
    let cx: Vec<f32> = faces.iter().map(|f| f.bbox[0] + 0.5 * f.bbox[2]).collect();
    assert!(
        cx.iter().any(|&x| x < side as f32) && cx.iter().any(|&x| x > side as f32),
        "{cx:?}"
    );
    for f in &faces {
        assert!(f.landmarks.presence > 0.5);
    }
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn a_tiny_face_is_found_or_cleanly_missed_and_a_border_face_is_tracked() {
    let (models, img) = (common::models_dir(), astronaut());
    let mut mesh = FaceMesh::load(&models).unwrap();
    // Tiny: the whole 512² portrait shrunk into 96² (face ≈ 18 px) on a larger canvas.
    let small = imageops::resize(&img, 96, 96, imageops::FilterType::Triangle);
    let mut canvas = RgbImage::from_pixel(256, 256, image::Rgb([90, 90, 90]));
    imageops::replace(&mut canvas, &small, 80, 80);
    let faces = mesh.process(&canvas).unwrap();
    for f in &faces {
        assert!(f
            .landmarks
            .points
            .iter()
            .all(|p| p.iter().all(|v| v.is_finite())));
    }
    println!("tiny face: {} found", faces.len());
    // At the border: crop so that the face box is cut by the left edge.
    let full = mesh.process(&img).unwrap();
    let b = full[0].bbox;
    let x0 = (b[0] + 0.35 * b[2]) as u32;
    let cut = imageops::crop_imm(&img, x0, 0, img.width() - x0, img.height()).to_image();
    let faces = mesh.process(&cut).unwrap();
    assert_eq!(faces.len(), 1, "face cut by the border must still be found");
    let lm = &faces[0].landmarks.points;
    assert!(
        lm.iter().any(|p| p[0] < 0.0),
        "some landmarks lie beyond the left edge"
    );
    assert!(lm.iter().all(|p| p.iter().all(|v| v.is_finite())));
}

#[test]
#[cfg_attr(not(model_files), ignore = "needs the model files (scripts/setup.sh)")]
fn corrupt_or_truncated_model_files_are_named() {
    let models = common::models_dir();
    let dir = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(models.join("face_landmark.tflite")).unwrap();
    std::fs::write(
        dir.path().join("face_landmark.tflite"),
        &bytes[..bytes.len() / 2],
    )
    .unwrap();
    let err = LandmarkNetwork::load(dir.path()).unwrap_err();
    assert!(matches!(err, FaceError::ModelChecksum { .. }));
    assert!(err.to_string().contains("face_landmark.tflite"));
    // Bypassing the checksum, the parser itself rejects truncations without panicking.
    for cut in [0, 7, 100, 4096, bytes.len() / 3, bytes.len() - 1] {
        assert!(
            LandmarkNetwork::from_bytes(&bytes[..cut]).is_err(),
            "cut at {cut}"
        );
    }
    let mut flipped = bytes.clone();
    for i in (64..flipped.len()).step_by(997) {
        flipped[i] ^= 0x5a;
    }
    let _ = LandmarkNetwork::from_bytes(&flipped); // must not panic
    assert!(matches!(
        ModelFile::FaceDetectionShortRange.read(dir.path()),
        Err(FaceError::ModelMissing { .. })
    ));
}
