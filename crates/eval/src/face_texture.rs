//! The real skin texture of the rendered heads: a face fused from a real clip by visage's own
//! pipeline, in ICT-FaceKit's face UVs, built into the crate (`data/face_texture.jpg`; its
//! README says where it comes from, its licence, and the command that makes it again).

use image::RgbImage;

use crate::EvalError;

/// The JPEG, square, sRGB, ICT-FaceKit's face UV layout (`u` right, `v` up, row 0 at `v = 1`).
const FACE_TEXTURE_JPEG: &[u8] = include_bytes!("../data/face_texture.jpg");

/// The built-in face texture.
///
/// # Errors
/// Never for the file shipped; a damaged build would report the decoder's error.
pub fn face_texture() -> Result<RgbImage, EvalError> {
    image::load_from_memory(FACE_TEXTURE_JPEG)
        .map(|i| i.to_rgb8())
        .map_err(|e| EvalError::InvalidConfig {
            name: "built-in face texture",
            value: "data/face_texture.jpg".into(),
            reason: if matches!(e, image::ImageError::Decoding(_)) {
                "the JPEG is damaged"
            } else {
                "cannot be decoded"
            },
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_texture_is_a_square_skin_coloured_face() {
        let t = face_texture().unwrap();
        assert_eq!(t.width(), t.height());
        assert!(t.width() >= 256);
        // The middle of the face UVs (nose and cheeks) is skin: red above green above blue.
        let p = t.get_pixel(t.width() / 2, t.height() / 2).0;
        assert!(p[0] > p[1] && p[1] > p[2], "{p:?}");
    }
}
