//! Inputs as users' machines make them: a phone's portrait photo stored sideways with an EXIF
//! orientation tag, an image folder with macOS's `._name` files beside the images, and one
//! whose images are not all one size.

mod common;

use common::{json, s, visage};

/// The shared face photo cropped to a portrait (taller than wide), as RGB.
fn portrait() -> image::RgbImage {
    let face =
        visage_testdata::require(visage_testdata::shared_dir().join("data/images/astronaut.png"));
    let img = image::open(face).unwrap().to_rgb8();
    image::imageops::crop_imm(&img, 64, 0, 384, 512).to_image()
}

fn jpeg(img: &image::RgbImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 92)
        .encode_image(img)
        .unwrap();
    bytes
}

/// A portrait photo stored turned a quarter to the left, with orientation 6 (show it turned
/// a quarter clockwise): read upright, the face is found and the camera is the upright size.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn a_portrait_photo_is_read_upright_as_its_exif_says() {
    let models = visage_testdata::models_dir();
    let tmp = tempfile::tempdir().unwrap();
    let upright = portrait();
    let stored = image::imageops::rotate270(&upright);
    let photo = tmp.path().join("IMG_0001.jpg");
    std::fs::write(
        &photo,
        visage_testdata::with_exif_orientation(&jpeg(&stored), 6),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = visage(&[
        "run",
        s(&photo),
        "--out",
        s(&out),
        "--models",
        s(&models),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let camera = json(&out.join("camera.json"));
    assert_eq!(
        (camera["width"].as_u64(), camera["height"].as_u64()),
        (Some(384), Some(512))
    );
    assert_eq!(
        json(&out.join("metrics.json"))["frames"][0]["status"],
        "solved"
    );
}

/// `._a.png` beside `a.png` (an AppleDouble file, not an image) is not a frame.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn hidden_files_in_an_image_folder_are_not_frames() {
    let models = visage_testdata::models_dir();
    let tmp = tempfile::tempdir().unwrap();
    let folder = tmp.path().join("shots");
    std::fs::create_dir(&folder).unwrap();
    portrait().save(folder.join("a.png")).unwrap();
    std::fs::write(folder.join("._a.png"), b"\0\x05\x16\x07\0\x02\0\0Mac OS X").unwrap();
    let out = tmp.path().join("out");
    let o = visage(&[
        "run",
        s(&folder),
        "--out",
        s(&out),
        "--models",
        s(&models),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        json(&out.join("metrics.json"))["frames"]
            .as_array()
            .unwrap()
            .len(),
        1
    );
}

/// An image folder of mixed sizes: the images before the odd one are meshed and kept, and the
/// message names the odd image, its size and the first one's (no intrinsics were given, so
/// it does not speak of intrinsics).
#[test]
#[cfg_attr(
    not(all(shared_data, model_files)),
    ignore = "needs ../shared and the model files (scripts/setup.sh)"
)]
fn an_image_folder_of_mixed_sizes_keeps_the_images_before_the_odd_one() {
    let models = visage_testdata::models_dir();
    let tmp = tempfile::tempdir().unwrap();
    let folder = tmp.path().join("shots");
    std::fs::create_dir(&folder).unwrap();
    let img = portrait();
    img.save(folder.join("a.png")).unwrap();
    img.save(folder.join("b.png")).unwrap();
    image::imageops::resize(&img, 192, 256, image::imageops::FilterType::Triangle)
        .save(folder.join("c.png"))
        .unwrap();
    let out = tmp.path().join("out");
    let o = visage(&["run", s(&folder), "--out", s(&out), "--models", s(&models)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("c.png: this image is 192×256 but the first one")
            && err.contains("a.png, is 384×512")
            && !err.contains("intrinsics"),
        "{err}"
    );
    let m = json(&out.join("metrics.json"));
    assert_eq!(m["status"], "failed");
    assert_eq!(m["frames"].as_array().unwrap().len(), 2);
    assert_eq!(
        visage_mesh::io::read_pc2(&out.join("sequence.pc2"))
            .unwrap()
            .samples(),
        2
    );
}
