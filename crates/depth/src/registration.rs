//! Registering a depth camera's map to the colour camera: every depth pixel back-projected
//! with the depth camera's K (Eq. 2.1), moved by the depth → colour extrinsics, projected with
//! the colour camera's K, and splatted over the colour pixels its footprint covers, the nearest
//! surface kept (a z-buffer), so a coarser depth map leaves no cracks and occluded background
//! does not show through.

use visage_camera::{DepthKind, DepthMap, Intrinsics, RigidTransform};

use crate::DepthError;

/// The two cameras of an RGB-D sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Registration {
    pub depth: Intrinsics,
    pub color: Intrinsics,
    /// Depth camera coordinates → colour camera coordinates (metres).
    pub depth_to_color: RigidTransform,
}

impl Registration {
    /// Registers `depth` (a map of the depth camera's size) to the colour camera: a z-depth
    /// map of the colour camera's size.
    ///
    /// # Errors
    /// A map of another size than the depth camera's.
    pub fn register(&self, depth: &DepthMap) -> Result<DepthMap, DepthError> {
        self.depth.check_size(depth.width, depth.height)?;
        let (cw, ch) = (self.color.width, self.color.height);
        let mut out = DepthMap::empty(cw, ch, DepthKind::Z);
        // How many colour pixels one depth pixel spans at equal depth.
        let spread = [self.color.fx / self.depth.fx, self.color.fy / self.depth.fy];
        for v in 0..depth.height {
            for u in 0..depth.width {
                let d = depth.at(u, v);
                if !DepthMap::is_valid(d) {
                    continue;
                }
                let ray = self.depth.ray(u as f64, v as f64);
                let distance = depth.kind.to_ray_distance(d as f64, ray);
                let p = self
                    .depth_to_color
                    .apply(self.depth.backproject(u as f64, v as f64, distance));
                if p[2] <= 0.0 {
                    continue;
                }
                let [x, y] = self.color.project(p);
                // The footprint grows as the point comes nearer the colour camera.
                let near = (distance * ray[2] / p[2]).max(0.0);
                let half = spread.map(|s| 0.5 * (s * near).max(1.0));
                // The colour pixels whose centres the footprint square covers.
                let range = |c: f64, half: f64, n: u32| {
                    let lo = (c - half).ceil().max(0.0);
                    let hi = (c + half).floor().min(n as f64 - 1.0);
                    (lo as i64, hi as i64)
                };
                let (u0, u1) = range(x, half[0], cw);
                let (v0, v1) = range(y, half[1], ch);
                let z = p[2] as f32;
                for cv in v0..=v1 {
                    for cu in u0..=u1 {
                        let slot = &mut out.data[cv as usize * cw as usize + cu as usize];
                        if *slot == 0.0 || z < *slot {
                            *slot = z;
                        }
                    }
                }
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_seen_by_a_shifted_coarser_camera_lands_where_the_colour_camera_sees_it() {
        let depth_k = Intrinsics::new(80, 60, 70.0, 70.0, 39.5, 29.5).unwrap();
        let color_k = Intrinsics::new(160, 120, 140.0, 140.0, 79.5, 59.5).unwrap();
        // The depth camera 2.5 cm to the colour camera's right.
        let t = RigidTransform {
            translation: [0.025, 0.0, 0.0],
            ..RigidTransform::IDENTITY
        };
        let mut d = DepthMap::empty(80, 60, DepthKind::Z);
        d.data.iter_mut().for_each(|z| *z = 0.5);
        let reg = Registration {
            depth: depth_k,
            color: color_k,
            depth_to_color: t,
        };
        let out = reg.register(&d).unwrap();
        // Twice the resolution: no cracks inside; the plane stays at 0.5 m.
        let shift_px = 140.0 * 0.025 / 0.5; // 7 colour pixels
        let mut holes = 0;
        for v in 2..118 {
            for u in (shift_px as u32 + 2)..158 {
                let z = out.at(u, v);
                if z == 0.0 {
                    holes += 1;
                } else {
                    assert!((z - 0.5).abs() < 1e-6);
                }
            }
        }
        assert_eq!(holes, 0);
        // The colour camera's left edge sees what the depth camera does not.
        assert_eq!(out.at(2, 60), 0.0);
        assert!(reg
            .register(&DepthMap::empty(10, 10, DepthKind::Z))
            .is_err());
    }
}
