use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::CameraError;

/// Horizontal field of view assumed when no intrinsics are given, in degrees.
pub const DEFAULT_FOV_DEG: f64 = 60.0;

/// The largest image side, in pixels, intrinsics may describe (16K).
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// The most pixels an image may have (a 16K × 9K frame; 570 MB as 8-bit RGB): checked before
/// any buffer of that size is reserved.
pub const MAX_IMAGE_PIXELS: u64 = 16_384 * 9_216;
/// The narrowest and widest field of view accepted, in degrees: the wider of the horizontal
/// and vertical fields must reach the first, and neither may exceed the second (a pinhole
/// model does not describe fisheye lenses).
pub const FOV_RANGE_DEG: (f64, f64) = (5.0, 170.0);

/// Pinhole intrinsics `K = [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]` for `width × height` images.
///
/// Focal lengths and principal point are in pixels; the centre of pixel `(i, j)` is at `(i, j)`.
/// The JSON form is `{"width": 640, "height": 480, "fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    pub width: u32,
    pub height: u32,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl Intrinsics {
    /// Validated intrinsics: sizes and focal lengths positive, every value finite.
    pub fn new(
        width: u32,
        height: u32,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
    ) -> Result<Self, CameraError> {
        let k = Intrinsics {
            width,
            height,
            fx,
            fy,
            cx,
            cy,
        };
        k.validate()?;
        Ok(k)
    }

    /// Square pixels, principal point at the image centre, and the 35 mm-equivalent focal
    /// length `f35_mm` (EXIF `FocalLengthIn35mmFilm`): the image diagonal maps to the 35 mm
    /// frame's diagonal (43.27 mm), so `f = f35 · diagonal_px / 43.27`, whatever the aspect.
    pub fn from_focal_35mm(width: u32, height: u32, f35_mm: f64) -> Result<Self, CameraError> {
        if !(f35_mm.is_finite() && f35_mm > 0.0) {
            return Err(CameraError::InvalidIntrinsics {
                field: "focal_length_35mm",
                value: f35_mm,
                reason: "must be positive",
            });
        }
        let diagonal_px = (width as f64).hypot(height as f64);
        let f = f35_mm * diagonal_px / 36.0f64.hypot(24.0);
        Self::new(
            width,
            height,
            f,
            f,
            0.5 * (width as f64 - 1.0),
            0.5 * (height as f64 - 1.0),
        )
    }

    /// Square pixels, principal point at the image centre, horizontal field of view `fov_deg`
    /// (within [`FOV_RANGE_DEG`]): `fx = fy = (width / 2) / tan(fov / 2)`.
    pub fn from_fov(width: u32, height: u32, fov_deg: f64) -> Result<Self, CameraError> {
        if !(fov_deg.is_finite() && fov_deg >= FOV_RANGE_DEG.0 && fov_deg <= FOV_RANGE_DEG.1) {
            return Err(CameraError::InvalidIntrinsics {
                field: "fov_deg",
                value: fov_deg,
                reason: "must lie between 5 and 170 degrees",
            });
        }
        let f = 0.5 * width as f64 / (0.5 * fov_deg.to_radians()).tan();
        Self::new(
            width,
            height,
            f,
            f,
            0.5 * (width as f64 - 1.0),
            0.5 * (height as f64 - 1.0),
        )
    }

    /// Reads and validates an intrinsics JSON file.
    pub fn load_json(path: &Path) -> Result<Self, CameraError> {
        let text = std::fs::read_to_string(path).map_err(|source| CameraError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse_json(&text, path)
    }

    /// [`Intrinsics::load_json`] of a file's text already in memory; `path` is the file it came
    /// from, named in errors.
    pub fn parse_json(text: &str, path: &Path) -> Result<Self, CameraError> {
        let k: Intrinsics =
            serde_json::from_str(text.trim_start_matches('\u{feff}')).map_err(|source| {
                CameraError::Json {
                    path: path.to_owned(),
                    source,
                }
            })?;
        k.validate()
            .map_err(|e| CameraError::InvalidIntrinsicsFile {
                path: path.to_owned(),
                source: Box::new(e),
            })?;
        Ok(k)
    }

    /// Writes the JSON form.
    pub fn save_json(&self, path: &Path) -> Result<(), CameraError> {
        let text = serde_json::to_string_pretty(self).map_err(|source| CameraError::Json {
            path: path.to_owned(),
            source,
        })?;
        std::fs::write(path, text).map_err(|source| CameraError::Io {
            path: path.to_owned(),
            source,
        })
    }

    /// Checks every parameter: sizes > 0 and within [`MAX_IMAGE_SIDE`] and [`MAX_IMAGE_PIXELS`],
    /// focal lengths > 0, everything finite, the principal point inside the image (pixel
    /// centres at integers: `−0.5 ≤ cx ≤ width − 0.5`), the field of view within
    /// [`FOV_RANGE_DEG`].
    pub fn validate(&self) -> Result<(), CameraError> {
        let positive = [
            ("width", self.width as f64),
            ("height", self.height as f64),
            ("fx", self.fx),
            ("fy", self.fy),
        ];
        for (field, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(CameraError::InvalidIntrinsics {
                    field,
                    value,
                    reason: "must be positive and finite",
                });
            }
        }
        for (field, value) in [("width", self.width), ("height", self.height)] {
            if value > MAX_IMAGE_SIDE {
                return Err(CameraError::InvalidIntrinsics {
                    field,
                    value: value as f64,
                    reason: "is more than the 16384 pixels visage accepts",
                });
            }
        }
        let pixels = self.width as u64 * self.height as u64;
        if pixels > MAX_IMAGE_PIXELS {
            return Err(CameraError::InvalidIntrinsics {
                field: "width × height",
                value: pixels as f64,
                reason: "is more than the 151 million pixels visage accepts",
            });
        }
        for (field, value, side) in [("cx", self.cx, self.width), ("cy", self.cy, self.height)] {
            if !value.is_finite() {
                return Err(CameraError::InvalidIntrinsics {
                    field,
                    value,
                    reason: "must be finite",
                });
            }
            if !(-0.5..=side as f64 - 0.5).contains(&value) {
                return Err(CameraError::InvalidIntrinsics {
                    field,
                    value,
                    reason: "puts the principal point outside the image",
                });
            }
        }
        let [fov_x, fov_y] = self.fov_deg();
        if fov_x.max(fov_y) < FOV_RANGE_DEG.0 {
            return Err(CameraError::InvalidIntrinsics {
                field: "fx",
                value: self.fx,
                reason: "gives a field of view narrower than 5 degrees",
            });
        }
        for (field, value, fov) in [("fx", self.fx, fov_x), ("fy", self.fy, fov_y)] {
            if fov > FOV_RANGE_DEG.1 {
                return Err(CameraError::InvalidIntrinsics {
                    field,
                    value,
                    reason: "gives a field of view wider than 170 degrees",
                });
            }
        }
        Ok(())
    }

    /// The horizontal and vertical fields of view in degrees, edge to edge of the image
    /// through the principal point.
    pub fn fov_deg(&self) -> [f64; 2] {
        let span = |c: f64, side: u32, f: f64| {
            let (left, right) = (c + 0.5, side as f64 - 0.5 - c);
            ((left / f).atan() + (right / f).atan()).to_degrees()
        };
        [
            span(self.cx, self.width, self.fx),
            span(self.cy, self.height, self.fy),
        ]
    }

    /// Errors unless these intrinsics are for `width × height` images.
    pub fn check_size(&self, width: u32, height: u32) -> Result<(), CameraError> {
        if self.width == width && self.height == height {
            Ok(())
        } else {
            Err(CameraError::SizeMismatch {
                expected_width: self.width,
                expected_height: self.height,
                width,
                height,
            })
        }
    }

    /// The unit ray `ρ(x) = K⁻¹x̃ / ‖K⁻¹x̃‖` through pixel position `(u, v)`: Eq. (2.1).
    #[inline]
    pub fn ray(&self, u: f64, v: f64) -> [f64; 3] {
        let x = (u - self.cx) / self.fx;
        let y = (v - self.cy) / self.fy;
        let inv = 1.0 / (x * x + y * y + 1.0).sqrt();
        [x * inv, y * inv, inv]
    }

    /// Back-projection `X = D(x) · ρ(x)` of a ray distance `distance` at `(u, v)`: Eq. (2.2).
    #[inline]
    pub fn backproject(&self, u: f64, v: f64, distance: f64) -> [f64; 3] {
        let r = self.ray(u, v);
        [distance * r[0], distance * r[1], distance * r[2]]
    }

    /// Pixel position of camera-space point `p` (requires `p[2] > 0`).
    #[inline]
    pub fn project(&self, p: [f64; 3]) -> [f64; 2] {
        [
            self.fx * p[0] / p[2] + self.cx,
            self.fy * p[1] / p[2] + self.cy,
        ]
    }

    /// Mean focal length in pixels, the pixel-per-radian scale used to make λ resolution-free.
    #[inline]
    pub fn focal(&self) -> f64 {
        0.5 * (self.fx + self.fy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_35mm_focal_length_maps_the_diagonal() {
        // 36 × 24 px "sensor" with f35 = 43.27 mm: f equals the diagonal in pixels.
        let k = Intrinsics::from_focal_35mm(3600, 2400, 36.0f64.hypot(24.0)).unwrap();
        assert!((k.fx - 3600.0f64.hypot(2400.0)).abs() < 1e-9 && k.fx == k.fy);
        // A 50 mm lens on a 3:2 frame: horizontal field of view 39.6°.
        let k = Intrinsics::from_focal_35mm(1500, 1000, 50.0).unwrap();
        let fov = 2.0 * (750.0 / k.fx).atan().to_degrees();
        assert!((fov - 39.6).abs() < 0.05, "{fov}");
        assert!(Intrinsics::from_focal_35mm(10, 10, 0.0).is_err());
        assert!(Intrinsics::from_focal_35mm(10, 10, f64::NAN).is_err());
    }

    #[test]
    fn ray_is_unit_and_projects_back() {
        let k = Intrinsics::new(640, 480, 525.0, 530.0, 319.5, 239.5).unwrap();
        for &(u, v) in &[(0.0, 0.0), (319.5, 239.5), (639.0, 479.0), (100.25, 400.75)] {
            let r = k.ray(u, v);
            let n = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            assert!((n - 1.0).abs() < 1e-14);
            let p = k.project(k.backproject(u, v, 1.7));
            assert!((p[0] - u).abs() < 1e-9 && (p[1] - v).abs() < 1e-9);
        }
    }

    #[test]
    fn fov_gives_centred_square_pixels() {
        let k = Intrinsics::from_fov(640, 480, 90.0).unwrap();
        assert!((k.fx - 320.0).abs() < 1e-9);
        assert_eq!(k.fx, k.fy);
        assert_eq!((k.cx, k.cy), (319.5, 239.5));
    }

    #[test]
    fn rejects_bad_values() {
        assert!(Intrinsics::new(640, 480, 0.0, 1.0, 0.0, 0.0).is_err());
        assert!(Intrinsics::new(640, 480, 1.0, f64::NAN, 0.0, 0.0).is_err());
        assert!(Intrinsics::new(0, 480, 1.0, 1.0, 0.0, 0.0).is_err());
        assert!(Intrinsics::new(640, 480, 1.0, 1.0, f64::INFINITY, 0.0).is_err());
        assert!(Intrinsics::from_fov(640, 480, 180.0).is_err());
        let k = Intrinsics::from_fov(64, 48, 60.0).unwrap();
        assert!(k.check_size(64, 48).is_ok());
        assert!(k.check_size(48, 64).is_err());
    }

    #[test]
    fn json_round_trip_and_errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cam.json");
        let k = Intrinsics::new(640, 480, 525.0, 525.0, 319.5, 239.5).unwrap();
        k.save_json(&path).unwrap();
        assert_eq!(Intrinsics::load_json(&path).unwrap(), k);
        std::fs::write(
            &path,
            r#"{"width": 640, "height": 480, "fx": -1, "fy": 1, "cx": 0, "cy": 0}"#,
        )
        .unwrap();
        let err = Intrinsics::load_json(&path).unwrap_err().to_string();
        assert!(err.contains("fx") && err.contains("cam.json"), "{err}");
        std::fs::write(&path, "{").unwrap();
        let err = Intrinsics::load_json(&path).unwrap_err().to_string();
        assert!(err.contains("cam.json"), "{err}");
    }

    #[test]
    fn limits_are_checked_before_anything_is_allocated() {
        let e = Intrinsics::new(100_000, 100_000, 5e4, 5e4, 5e4, 5e4).unwrap_err();
        assert!(e.to_string().contains("16384"), "{e}");
        let e = Intrinsics::new(16_384, 16_384, 1e4, 1e4, 8e3, 8e3).unwrap_err();
        assert!(e.to_string().contains("million pixels"), "{e}");
        assert!(Intrinsics::new(16_384, 9_216, 1e4, 1e4, 8e3, 4e3).is_ok());
    }

    #[test]
    fn the_principal_point_lies_in_the_image() {
        let e = Intrinsics::new(640, 480, 500.0, 500.0, 99_999.0, 239.5).unwrap_err();
        assert!(e.to_string().contains("cx = 99999") && e.to_string().contains("outside"));
        assert!(Intrinsics::new(640, 480, 500.0, 500.0, 319.5, -0.6).is_err());
        // The image's edges (pixel centres at integers) are still inside.
        assert!(Intrinsics::new(640, 480, 500.0, 500.0, -0.5, 479.5).is_ok());
    }

    #[test]
    fn the_field_of_view_lies_between_5_and_170_degrees() {
        for fov in [5.0, 60.0, 170.0] {
            let k = Intrinsics::from_fov(1280, 720, fov).unwrap();
            assert!((k.fov_deg()[0] - fov).abs() < 1e-9);
        }
        for fov in [4.9, 170.1, 0.0, 180.0, f64::NAN] {
            assert!(Intrinsics::from_fov(1280, 720, fov).is_err(), "{fov}");
        }
        // fx = 1e6 px on a 640-px image: 0.04°.
        let e = Intrinsics::new(640, 480, 1e6, 1e6, 319.5, 239.5).unwrap_err();
        assert!(e.to_string().contains("narrower than 5"), "{e}");
        let e = Intrinsics::new(640, 480, 20.0, 500.0, 319.5, 239.5).unwrap_err();
        assert!(e.to_string().contains("wider than 170"), "{e}");
        // A portrait frame: the vertical field is the wide one.
        assert!(Intrinsics::new(100, 4000, 1e4, 1e4, 49.5, 1999.5).is_ok());
    }
}
