//! The quality figures of a run, measured frame by frame: jitter with the rigid head motion
//! removed ([`crate::rigid_jitter`]) on every vertex and on the 468 landmark points, and the
//! landmark reprojection error, each for the fused and the raw surface.

use serde::Serialize;
use visage_camera::Intrinsics;

use crate::rigid_jitter::JitterMeter;

/// A figure for the fused surface and the raw one.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FusedAndRaw {
    pub fused: Option<f64>,
    pub raw: Option<f64>,
}

/// The quality figures of a run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct QualitySummary {
    /// Mean over consecutive meshed frames of the RMS vertex motion after the best rigid
    /// alignment (mm), over all mesh vertices. Image mesh: vertices are fixed pixels, not
    /// fixed points of the face, so compare the designs on `landmark_jitter_mm`.
    pub vertex_jitter_mm: FusedAndRaw,
    /// The same on the surface at the 468 landmarks (image mesh: interpolated at the landmark
    /// pixels; landmarks outside the mesh are left out of the pair). None without landmarks
    /// (a depth folder).
    pub landmark_jitter_mm: FusedAndRaw,
    /// Mean over meshed frames of the mean landmark reprojection error (px).
    pub reprojection_px: FusedAndRaw,
    /// Consecutive frame pairs measured.
    pub pairs: usize,
    /// `raw / fused` vertex and landmark jitter.
    pub vertex_jitter_reduction: Option<f64>,
    pub landmark_jitter_reduction: Option<f64>,
}

/// Accumulates the quality figures frame by frame (memory: one frame of each surface).
#[derive(Default)]
pub struct QualityMeter {
    vertex_fused: JitterMeter,
    vertex_raw: JitterMeter,
    landmark_fused: JitterMeter,
    landmark_raw: JitterMeter,
    reprojection: (f64, f64, usize),
}

impl QualityMeter {
    /// A meshed frame: its fused and raw surfaces, the same at the landmarks, and the tracked
    /// landmark pixels. Returns the frame's mean reprojection errors (fused, raw).
    pub fn push(
        &mut self,
        k: &Intrinsics,
        fused: &[[f64; 3]],
        raw: &[[f64; 3]],
        fused_landmarks: &[[f64; 3]],
        raw_landmarks: &[[f64; 3]],
        landmarks_px: &[[f64; 2]],
    ) -> (Option<f64>, Option<f64>) {
        self.vertex_fused.push(fused);
        self.vertex_raw.push(raw);
        self.landmark_fused.push(fused_landmarks);
        self.landmark_raw.push(raw_landmarks);
        let f = reprojection_px(k, fused_landmarks, landmarks_px);
        let r = reprojection_px(k, raw_landmarks, landmarks_px);
        if let (Some(f), Some(r)) = (f, r) {
            self.reprojection.0 += f;
            self.reprojection.1 += r;
            self.reprojection.2 += 1;
        }
        (f, r)
    }

    /// A frame without a mesh: no pair spans it.
    pub fn gap(&mut self) {
        for m in [
            &mut self.vertex_fused,
            &mut self.vertex_raw,
            &mut self.landmark_fused,
            &mut self.landmark_raw,
        ] {
            m.gap();
        }
    }

    pub fn summary(&self) -> QualitySummary {
        let mm = |m: &JitterMeter| m.mean().map(|v| v * 1e3);
        let pair = |f: &JitterMeter, r: &JitterMeter| FusedAndRaw {
            fused: mm(f),
            raw: mm(r),
        };
        let ratio = |p: FusedAndRaw| match (p.fused, p.raw) {
            (Some(f), Some(r)) if f > 0.0 => Some(r / f),
            _ => None,
        };
        let vertex = pair(&self.vertex_fused, &self.vertex_raw);
        let landmark = pair(&self.landmark_fused, &self.landmark_raw);
        let (sf, sr, n) = self.reprojection;
        QualitySummary {
            vertex_jitter_mm: vertex,
            landmark_jitter_mm: landmark,
            reprojection_px: FusedAndRaw {
                fused: (n > 0).then(|| sf / n as f64),
                raw: (n > 0).then(|| sr / n as f64),
            },
            pairs: self.vertex_fused.pairs(),
            vertex_jitter_reduction: ratio(vertex),
            landmark_jitter_reduction: ratio(landmark),
        }
    }
}

/// Mean pixel distance between the projections of `points` (NaN = missing) and `pixels`.
fn reprojection_px(k: &Intrinsics, points: &[[f64; 3]], pixels: &[[f64; 2]]) -> Option<f64> {
    let (sum, count) = points
        .iter()
        .zip(pixels)
        .filter(|(p, _)| p.iter().all(|c| c.is_finite()) && p[2] > 0.0)
        .fold((0.0, 0usize), |(s, n), (p, q)| {
            let u = k.project(*p);
            (s + (u[0] - q[0]).hypot(u[1] - q[1]), n + 1)
        });
    (count > 0).then(|| sum / count as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reprojection_of_points_on_their_rays_is_zero() {
        let k = Intrinsics::from_fov(64, 48, 60.0).unwrap();
        let pixels = [[10.0, 20.0], [30.5, 7.25]];
        let points = pixels.map(|[u, v]| k.backproject(u, v, 0.7));
        assert!(reprojection_px(&k, &points, &pixels).unwrap() < 1e-9);
        let moved = [[11.0, 20.0], [30.5, 9.25]];
        let e = reprojection_px(&k, &points, &moved).unwrap();
        assert!((e - 1.5).abs() < 1e-9);
        assert_eq!(reprojection_px(&k, &[[f64::NAN; 3]], &[[0.0; 2]]), None);
    }
}
