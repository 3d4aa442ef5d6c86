//! Masking a sensor's unreliable depth: the flying pixels at depth discontinuities (a
//! time-of-flight or structured-light pixel that straddles the face's silhouette reads a depth
//! between face and background) and the ragged rims of its holes.

use visage_camera::DepthMap;

/// What counts as a depth edge (defaults: 10 mm or 2 % of the depth, one pixel around).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct EdgeMask {
    /// A neighbour differing by more than this is across an edge, metres …
    pub jump_m: f64,
    /// … or by more than this fraction of the pixel's depth, whichever is larger (a sensor's
    /// noise grows with the distance).
    pub relative: f64,
    /// Pixels within this many pixels (Chebyshev) of an edge pixel are masked too.
    pub radius_px: u32,
}

impl Default for EdgeMask {
    /// At 0.6 m a 10 mm jump between neighbours is a slope of ~84° for a 525 px focal length:
    /// steeper than the face anywhere but at its silhouette.
    fn default() -> Self {
        EdgeMask {
            jump_m: 0.01,
            relative: 0.02,
            radius_px: 1,
        }
    }
}

/// Sets to 0 (no data) every valid pixel of `depth` that has an 8-neighbour across an edge —
/// a depth jump beyond the mask's threshold, or a hole — and the pixels within
/// `radius_px` of one. Returns how many pixels were masked.
pub fn mask_depth_edges(depth: &mut DepthMap, mask: &EdgeMask) -> usize {
    let (w, h) = (depth.width as usize, depth.height as usize);
    let valid = |z: f32| DepthMap::is_valid(z);
    let data = &depth.data;
    let mut edge = vec![false; w * h];
    for v in 0..h {
        for u in 0..w {
            let z = data[v * w + u];
            if !valid(z) {
                continue;
            }
            let threshold = mask.jump_m.max(mask.relative * z as f64);
            'neighbours: for dv in -1i64..=1 {
                for du in -1i64..=1 {
                    let (nu, nv) = (u as i64 + du, v as i64 + dv);
                    if (du, dv) == (0, 0) || nu < 0 || nv < 0 || nu >= w as i64 || nv >= h as i64 {
                        continue;
                    }
                    let n = data[nv as usize * w + nu as usize];
                    if !valid(n) || (n as f64 - z as f64).abs() > threshold {
                        edge[v * w + u] = true;
                        break 'neighbours;
                    }
                }
            }
        }
    }
    let r = mask.radius_px as i64;
    let mut masked = 0;
    let mut out = depth.data.clone();
    for v in 0..h as i64 {
        for u in 0..w as i64 {
            let i = v as usize * w + u as usize;
            if !valid(out[i]) {
                continue;
            }
            let near = (-r..=r).any(|dv| {
                (-r..=r).any(|du| {
                    let (nu, nv) = (u + du, v + dv);
                    nu >= 0
                        && nv >= 0
                        && nu < w as i64
                        && nv < h as i64
                        && edge[nv as usize * w + nu as usize]
                })
            });
            if near {
                out[i] = 0.0;
                masked += 1;
            }
        }
    }
    depth.data = out;
    masked
}

#[cfg(test)]
mod tests {
    use super::*;
    use visage_camera::DepthKind;

    #[test]
    fn a_step_and_a_hole_lose_their_rims_and_a_slope_stays() {
        // 20×10: a face-like slope at 0.6 m (2 mm per pixel) in the left half, a wall at 1.5 m
        // in the right half, a hole at (5, 5).
        let mut d = DepthMap::empty(20, 10, DepthKind::Z);
        for v in 0..10 {
            for u in 0..20 {
                d.data[v * 20 + u] = if u < 10 { 0.6 + 0.002 * u as f32 } else { 1.5 };
            }
        }
        d.data[5 * 20 + 5] = 0.0;
        let masked = mask_depth_edges(&mut d, &EdgeMask::default());
        // Columns 9 and 10 straddle the step; radius 1 takes 8 and 11 too.
        for v in 0..10 {
            for u in 8..12 {
                assert_eq!(d.at(u, v), 0.0, "({u}, {v})");
            }
            assert!(d.at(2, v) > 0.0 && d.at(15, v) > 0.0);
        }
        // The hole's neighbours and theirs (radius 1): a 5×5 block minus the hole itself.
        assert_eq!(d.at(3, 3), 0.0);
        assert!(d.at(2, 5) > 0.0);
        assert_eq!(masked, 4 * 10 + 24);
    }
}
