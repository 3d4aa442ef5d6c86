//! The camera's focal length from an image's EXIF metadata, for intrinsics when the user gives
//! none (`--intrinsics`, else `--fov-deg`, else EXIF).
//!
//! Only the 35 mm-equivalent focal length (tag `FocalLengthIn35mmFilm`, 0xA405, in the Exif
//! sub-IFD) is used: the plain `FocalLength` (0x920A) needs the sensor size, which EXIF rarely
//! records reliably. The TIFF structure is read by hand (a few dozen lines, bounds-checked)
//! rather than through an EXIF crate; the bytes come from `image`'s decoders (JPEG, PNG, WebP).

use std::path::Path;

/// Tag of the pointer from IFD0 to the Exif sub-IFD.
const EXIF_IFD_POINTER: u16 = 0x8769;
/// Tag of the 35 mm-equivalent focal length (SHORT, millimetres).
const FOCAL_LENGTH_35MM: u16 = 0xA405;

/// The 35 mm-equivalent focal length (mm) recorded in the image file's EXIF, if any.
pub fn focal_length_35mm(path: &Path) -> Option<f64> {
    use image::ImageDecoder;
    let reader = image::ImageReader::open(path)
        .ok()?
        .with_guessed_format()
        .ok()?;
    let mut decoder = reader.into_decoder().ok()?;
    let exif = decoder.exif_metadata().ok()??;
    focal_length_35mm_in(&exif)
}

/// [`focal_length_35mm`] of raw EXIF bytes (a TIFF structure, optionally after the JPEG APP1
/// `Exif\0\0` marker).
pub fn focal_length_35mm_in(exif: &[u8]) -> Option<f64> {
    let tiff = exif.strip_prefix(b"Exif\0\0").unwrap_or(exif);
    let little = match tiff.get(0..2)? {
        b"II" => true,
        b"MM" => false,
        _ => return None,
    };
    let u16_at = |at: usize| -> Option<u16> {
        let b: [u8; 2] = tiff.get(at..at + 2)?.try_into().ok()?;
        Some(if little {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    };
    let u32_at = |at: usize| -> Option<u32> {
        let b: [u8; 4] = tiff.get(at..at + 4)?.try_into().ok()?;
        Some(if little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    };
    // An IFD: entry count, then 12-byte entries (tag, type, count, value or offset).
    let find = |ifd: usize, tag: u16| -> Option<usize> {
        let entries = u16_at(ifd)? as usize;
        (0..entries)
            .map(|e| ifd + 2 + 12 * e)
            .find(|&entry| u16_at(entry) == Some(tag))
    };
    let ifd0 = u32_at(4)? as usize;
    let exif_ifd = u32_at(find(ifd0, EXIF_IFD_POINTER)? + 8)? as usize;
    let entry = find(exif_ifd, FOCAL_LENGTH_35MM)?;
    // SHORT (type 3), count 1: the value sits in the first two bytes of the value field.
    if u16_at(entry + 2)? != 3 {
        return None;
    }
    let mm = u16_at(entry + 8)? as f64;
    (mm > 0.0).then_some(mm)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A TIFF structure with IFD0 → Exif IFD → FocalLengthIn35mmFilm = `mm`.
    fn exif_bytes(mm: u16, little: bool) -> Vec<u8> {
        let w16 = |v: u16| {
            if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
        };
        let w32 = |v: u32| {
            if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
        };
        let mut b = Vec::new();
        b.extend_from_slice(if little { b"II" } else { b"MM" });
        b.extend_from_slice(&w16(42));
        b.extend_from_slice(&w32(8));
        // IFD0 at 8: one entry (Exif pointer, LONG, 1, offset 26), next IFD 0.
        b.extend_from_slice(&w16(1));
        b.extend_from_slice(&w16(EXIF_IFD_POINTER));
        b.extend_from_slice(&w16(4));
        b.extend_from_slice(&w32(1));
        b.extend_from_slice(&w32(26));
        b.extend_from_slice(&w32(0));
        // Exif IFD at 26: one entry (FocalLengthIn35mmFilm, SHORT, 1, value).
        b.extend_from_slice(&w16(1));
        b.extend_from_slice(&w16(FOCAL_LENGTH_35MM));
        b.extend_from_slice(&w16(3));
        b.extend_from_slice(&w32(1));
        b.extend_from_slice(&w16(mm));
        b.extend_from_slice(&[0, 0]);
        b.extend_from_slice(&w32(0));
        b
    }

    #[test]
    fn reads_the_35mm_focal_length_in_either_byte_order() {
        for little in [true, false] {
            assert_eq!(focal_length_35mm_in(&exif_bytes(28, little)), Some(28.0));
            let mut app1 = b"Exif\0\0".to_vec();
            app1.extend(exif_bytes(50, little));
            assert_eq!(focal_length_35mm_in(&app1), Some(50.0));
        }
        assert_eq!(focal_length_35mm_in(&exif_bytes(0, true)), None);
        let truncated = exif_bytes(28, true);
        // Cut anywhere before the end of the value: nothing (never a panic).
        for len in 0..truncated.len() - 6 {
            assert_eq!(focal_length_35mm_in(&truncated[..len]), None, "{len}");
        }
    }

    #[test]
    fn reads_it_from_a_jpeg_file() {
        let dir = tempfile::tempdir().unwrap();
        let img = image::RgbImage::from_pixel(32, 24, image::Rgb([90, 120, 150]));
        let mut jpeg = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut jpeg),
            image::ImageFormat::Jpeg,
        )
        .unwrap();
        // APP1 "Exif" segment right after SOI.
        let mut payload = b"Exif\0\0".to_vec();
        payload.extend(exif_bytes(35, false));
        let mut file = jpeg[..2].to_vec();
        file.extend_from_slice(&[0xFF, 0xE1]);
        file.extend_from_slice(&((payload.len() + 2) as u16).to_be_bytes());
        file.extend(payload);
        file.extend_from_slice(&jpeg[2..]);
        let with = dir.path().join("with.jpg");
        let without = dir.path().join("without.jpg");
        std::fs::write(&with, file).unwrap();
        std::fs::write(&without, jpeg).unwrap();
        assert_eq!(focal_length_35mm(&with), Some(35.0));
        assert_eq!(focal_length_35mm(&without), None);
    }
}
