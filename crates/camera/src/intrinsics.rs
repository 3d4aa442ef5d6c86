use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::CameraError;

/// Horizontal field of view assumed when no intrinsics are given, in degrees.
pub const DEFAULT_FOV_DEG: f64 = 60.0;

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

    /// Square pixels, principal point at the image centre, horizontal field of view `fov_deg`:
    /// `fx = fy = (width / 2) / tan(fov / 2)`.
    pub fn from_fov(width: u32, height: u32, fov_deg: f64) -> Result<Self, CameraError> {
        if !(fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(CameraError::InvalidIntrinsics {
                field: "fov_deg",
                value: fov_deg,
                reason: "must lie strictly between 0 and 180 degrees",
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
        let k: Intrinsics = serde_json::from_str(&text).map_err(|source| CameraError::Json {
            path: path.to_owned(),
            source,
        })?;
        k.validate()?;
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

    /// Checks every parameter: sizes > 0, focal lengths > 0, everything finite.
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
        for (field, value) in [("cx", self.cx), ("cy", self.cy)] {
            if !value.is_finite() {
                return Err(CameraError::InvalidIntrinsics {
                    field,
                    value,
                    reason: "must be finite",
                });
            }
        }
        Ok(())
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
        assert!(err.contains("fx"), "{err}");
        std::fs::write(&path, "{").unwrap();
        let err = Intrinsics::load_json(&path).unwrap_err().to_string();
        assert!(err.contains("cam.json"), "{err}");
    }
}
