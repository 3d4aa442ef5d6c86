//! The quality figures of a run, measured frame by frame: jitter with the rigid head motion
//! removed ([`crate::rigid_jitter`]) on every vertex and on the 468 landmark points, and the
//! landmark reprojection error, each for the fused and the raw surface; and in the image, the
//! second-difference jitter of the fused landmarks against the tracked ones (what the temporal
//! model is judged by).

use visage_camera::Intrinsics;
use visage_run_folder::{FusedAndRaw, QualitySummary};

use crate::rigid_jitter::JitterMeter;

/// Accumulates the quality figures frame by frame (memory: one frame of each surface).
#[derive(Default)]
pub struct QualityMeter {
    vertex_fused: JitterMeter,
    vertex_raw: JitterMeter,
    landmark_fused: JitterMeter,
    landmark_raw: JitterMeter,
    reprojection: (f64, f64, usize),
    image_fused: SecondDifference,
    image_tracked: SecondDifference,
}

/// Accumulates squared second differences of a point track over consecutive frames.
#[derive(Default)]
struct SecondDifference {
    /// The two frames before the current one (oldest first).
    previous: Vec<Vec<[f64; 2]>>,
    sum: f64,
    count: usize,
}

impl SecondDifference {
    fn push(&mut self, points: Vec<[f64; 2]>) {
        if let [a, b] = self.previous.as_slice() {
            for ((p, q), r) in a.iter().zip(b).zip(&points) {
                let d = [r[0] - 2.0 * q[0] + p[0], r[1] - 2.0 * q[1] + p[1]];
                if d.iter().all(|v| v.is_finite()) {
                    self.sum += d[0] * d[0] + d[1] * d[1];
                    self.count += 1;
                }
            }
            self.previous.remove(0);
        }
        self.previous.push(points);
    }

    fn gap(&mut self) {
        self.previous.clear();
    }

    fn rms(&self) -> Option<f64> {
        (self.count > 0).then(|| (self.sum / self.count as f64).sqrt())
    }
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
        self.image_fused.push(
            fused_landmarks
                .iter()
                .map(|&p| {
                    if p[2] > 0.0 {
                        k.project(p)
                    } else {
                        [f64::NAN; 2]
                    }
                })
                .collect(),
        );
        self.image_tracked.push(landmarks_px.to_vec());
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
        self.image_fused.gap();
        self.image_tracked.gap();
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
        let image = FusedAndRaw {
            fused: self.image_fused.rms(),
            raw: self.image_tracked.rms(),
        };
        QualitySummary {
            vertex_jitter_mm: vertex,
            landmark_jitter_mm: landmark,
            reprojection_px: FusedAndRaw {
                fused: (n > 0).then(|| sf / n as f64),
                raw: (n > 0).then(|| sr / n as f64),
            },
            image_jitter_px: image,
            image_jitter_reduction: ratio(image),
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
    fn image_jitter_is_the_rms_second_difference_within_runs() {
        let mut d = SecondDifference::default();
        for x in [0.0, 1.0, 0.0, 1.0] {
            d.push(vec![[x, 0.0]]);
        }
        // Second differences −2 and +2.
        assert_eq!(d.rms(), Some(2.0));
        d.gap();
        d.push(vec![[50.0, 0.0]]);
        d.push(vec![[0.0, 0.0]]);
        assert_eq!(d.rms(), Some(2.0), "no difference spans a gap");
    }

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
