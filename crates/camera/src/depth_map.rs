use crate::{DepthKind, Intrinsics};

/// A depth image in metres, row-major, `width × height`.
///
/// A pixel holds valid depth when its value is finite and positive; `0` or NaN mean "no data".
#[derive(Clone, Debug, PartialEq)]
pub struct DepthMap {
    pub width: u32,
    pub height: u32,
    /// What the values measure.
    pub kind: DepthKind,
    /// `width · height` values in metres, row-major (`data[v · width + u]`).
    pub data: Vec<f32>,
}

impl DepthMap {
    /// An all-invalid (zero) depth map.
    pub fn empty(width: u32, height: u32, kind: DepthKind) -> Self {
        DepthMap {
            width,
            height,
            kind,
            data: vec![0.0; width as usize * height as usize],
        }
    }

    /// Whether a stored value counts as valid depth.
    #[inline]
    pub fn is_valid(value: f32) -> bool {
        value.is_finite() && value > 0.0
    }

    /// The value at integer pixel `(u, v)`.
    ///
    /// # Panics
    /// If `(u, v)` is outside the image.
    #[inline]
    #[track_caller]
    pub fn at(&self, u: u32, v: u32) -> f32 {
        assert!(
            u < self.width && v < self.height,
            "pixel ({u}, {v}) outside {}×{}",
            self.width,
            self.height
        );
        self.data[v as usize * self.width as usize + u as usize]
    }

    /// Number of pixels with valid depth.
    pub fn valid_count(&self) -> usize {
        self.data.iter().filter(|&&d| Self::is_valid(d)).count()
    }

    /// Bilinear sample of the ray distance `D` at a sub-pixel position, using only valid
    /// neighbours (weights renormalised). `None` when no neighbour is valid or `(u, v)` is outside.
    ///
    /// Depth is interpolated as stored (z or ray) and then converted, so a plane stays a plane.
    pub fn sample_ray_distance(&self, k: &Intrinsics, u: f64, v: f64) -> Option<f64> {
        let (w, h) = (self.width as f64, self.height as f64);
        if !(u >= 0.0 && v >= 0.0 && u <= w - 1.0 && v <= h - 1.0) {
            return None;
        }
        let u0 = (u.floor() as u32).min(self.width.saturating_sub(2));
        let v0 = (v.floor() as u32).min(self.height.saturating_sub(2));
        let (fu, fv) = (u - u0 as f64, v - v0 as f64);
        let mut sum = 0.0;
        let mut weight = 0.0;
        for (du, dv, wgt) in [
            (0, 0, (1.0 - fu) * (1.0 - fv)),
            (1, 0, fu * (1.0 - fv)),
            (0, 1, (1.0 - fu) * fv),
            (1, 1, fu * fv),
        ] {
            let (uu, vv) = (
                (u0 + du).min(self.width - 1),
                (v0 + dv).min(self.height - 1),
            );
            let d = self.at(uu, vv);
            if wgt > 0.0 && Self::is_valid(d) {
                sum += wgt * d as f64;
                weight += wgt;
            }
        }
        if weight <= 1e-9 {
            return None;
        }
        Some(self.kind.to_ray_distance(sum / weight, k.ray(u, v)))
    }

    /// Flatness ratio `(max − min) / mean` of the valid depth values (ERRATA 9), or `None` if
    /// there are none.
    pub fn flatness_ratio(&self) -> Option<f64> {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let mut sum = 0.0;
        let mut n = 0usize;
        for &d in self.data.iter().filter(|&&d| Self::is_valid(d)) {
            let d = d as f64;
            lo = lo.min(d);
            hi = hi.max(d);
            sum += d;
            n += 1;
        }
        (n > 0).then(|| (hi - lo) / (sum / n as f64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_sample_skips_holes_and_converts_z() {
        let k = Intrinsics::from_fov(4, 4, 60.0).unwrap();
        let mut d = DepthMap::empty(4, 4, DepthKind::Z);
        d.data.iter_mut().for_each(|x| *x = 2.0);
        d.data[5] = 0.0; // hole at (1, 1)
        let dist = d.sample_ray_distance(&k, 1.5, 1.5).unwrap();
        let r = k.ray(1.5, 1.5);
        assert!((dist * r[2] - 2.0).abs() < 1e-12);
        assert!(d.sample_ray_distance(&k, -0.1, 0.0).is_none());
        assert_eq!(d.valid_count(), 15);
        assert!(d.flatness_ratio().unwrap().abs() < 1e-12);
    }
}
