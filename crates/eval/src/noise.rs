//! Depth-noise models that mimic a monocular CNN's errors.
//!
//! Applied to a ground-truth z-depth map, in this order (every parameter is documented on
//! [`NoiseModel`]; 0 disables a component):
//! 1. **Depth edges** — pixels within `edge_width_px` of a depth discontinuity (a neighbour
//!    that is background or differs by more than `edge_threshold_mm`): half of them are dropped,
//!    the other half pushed back by U(0, `edge_error_mm`) ("flying pixels" smeared towards the
//!    background, as a CNN's blurry boundaries do).
//! 2. **Global flicker** — per frame, `z ← z · (1 + s) + o` with s ~ N(0, `flicker_scale`²) and
//!    o ~ N(0, `flicker_offset_mm`²): the scale/shift ambiguity a per-frame network resolves
//!    differently in every frame.
//! 3. **Low-frequency error** — a smooth field: N(0, `lowfreq_sigma_mm`²) values on a coarse grid
//!    of `lowfreq_cell_px` pixels, bilinearly interpolated; in time an AR(1) process with
//!    coefficient `lowfreq_temporal` (0: new every frame; → 1: nearly frozen).
//! 4. **Per-pixel Gaussian** — i.i.d. N(0, `gaussian_sigma_mm`²).
//! 5. **Holes** — each pixel dropped with probability `dropout`, plus `hole_blobs` discs of radius
//!    U(0.5, 1)·`hole_radius_px` at random covered pixels.
//! 6. **Relative output** (`relative_inverse`) — what a monocular network such as MiDaS or
//!    Depth Anything gives: not metres but an inverse depth known up to a scale and shift
//!    that change every frame, `y = s_k / z + t_k` with `log s_k ~ N(0, relative_scale_log_sigma²)`
//!    and `t_k ~ U(0, relative_shift) · s_k · mean(1/z)`. The errors of 1–4 are the
//!    network's distortion of the shape; the pipeline aligns `y` back to metres per frame.
//!
//! Errors 1–5 are applied to z (the project's default depth kind) in metres; missing = 0.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use visage_camera::{DepthKind, DepthMap};

use crate::normal::standard_normal;
use crate::EvalError;

/// Millimetres to metres.
const MM: f64 = 1e-3;

/// Parameters of the noise model. All zeros (`NoiseModel::default()`) is the identity.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct NoiseModel {
    /// σ of i.i.d. per-pixel depth noise, mm.
    pub gaussian_sigma_mm: f64,
    /// σ of the spatially correlated low-frequency error, mm.
    pub lowfreq_sigma_mm: f64,
    /// Grid spacing (≈ correlation length) of the low-frequency error, pixels.
    pub lowfreq_cell_px: f64,
    /// AR(1) coefficient of the low-frequency error from frame to frame, in [0, 1).
    pub lowfreq_temporal: f64,
    /// σ of the per-frame relative scale error (0.01 = 1 %).
    pub flicker_scale: f64,
    /// σ of the per-frame global depth offset, mm.
    pub flicker_offset_mm: f64,
    /// Probability that a pixel is missing, in [0, 1).
    pub dropout: f64,
    /// Number of disc-shaped holes per frame.
    pub hole_blobs: usize,
    /// Largest radius of a disc-shaped hole, pixels.
    pub hole_radius_px: f64,
    /// Width of the band around depth edges that gets edge errors, pixels.
    pub edge_width_px: u32,
    /// Largest push-back of an edge pixel, mm.
    pub edge_error_mm: f64,
    /// Depth jump between 4-neighbours that counts as an edge, mm.
    pub edge_threshold_mm: f64,
    /// The output is a relative inverse depth `s_k / z + t_k` (module docs), not metres.
    pub relative_inverse: bool,
    /// σ of the log of the per-frame scale `s_k`.
    pub relative_scale_log_sigma: f64,
    /// Largest per-frame shift `t_k`, as a fraction of `s_k · mean(1/z)`.
    pub relative_shift: f64,
}

/// Names accepted by [`NoiseModel::preset`].
pub const NOISE_PRESETS: [&str; 8] = [
    "none", "gaussian", "lowfreq", "flicker", "holes", "edges", "cnn-like", "relative",
];

impl NoiseModel {
    /// The `cnn-like` preset, every component on: 1 mm per-pixel noise, 2 mm low-frequency
    /// error over 24 px cells (AR 0.8), 0.3 % scale and 1.5 mm offset flicker, 0.5 % dropout
    /// plus 2 holes of up to 6 px, a 2 px edge band pushed back by up to 20 mm.
    pub fn cnn_like() -> NoiseModel {
        NoiseModel {
            gaussian_sigma_mm: 1.0,
            lowfreq_sigma_mm: 2.0,
            lowfreq_cell_px: 24.0,
            lowfreq_temporal: 0.8,
            flicker_scale: 0.003,
            flicker_offset_mm: 1.5,
            dropout: 0.005,
            hole_blobs: 2,
            hole_radius_px: 6.0,
            edge_width_px: 2,
            edge_error_mm: 20.0,
            edge_threshold_mm: 10.0,
            relative_inverse: false,
            relative_scale_log_sigma: 0.0,
            relative_shift: 0.0,
        }
    }

    /// The `relative` preset, a monocular network's relative inverse depth: 1 mm per-pixel
    /// noise, a 3 mm low-frequency distortion over 32 px cells that changes quickly from frame
    /// to frame (AR 0.5: per-frame networks flicker), the `cnn-like` depth-edge errors, no
    /// holes (networks give every pixel), and the output as `s_k / z + t_k` with
    /// `log s_k ~ N(0, 0.3²)`, `t_k ~ U(0, 0.5) · s_k · mean(1/z)`.
    pub fn relative() -> NoiseModel {
        let cnn = NoiseModel::cnn_like();
        NoiseModel {
            gaussian_sigma_mm: 1.0,
            lowfreq_sigma_mm: 3.0,
            lowfreq_cell_px: 32.0,
            lowfreq_temporal: 0.5,
            edge_width_px: cnn.edge_width_px,
            edge_error_mm: cnn.edge_error_mm,
            edge_threshold_mm: cnn.edge_threshold_mm,
            relative_inverse: true,
            relative_scale_log_sigma: 0.3,
            relative_shift: 0.5,
            ..NoiseModel::default()
        }
    }

    /// A named preset: `none`, one component of `cnn-like` alone (`gaussian`, `lowfreq`,
    /// `flicker`, `holes`, `edges`), `cnn-like`, or `relative` ([`NoiseModel::relative`]).
    pub fn preset(name: &str) -> Result<NoiseModel, EvalError> {
        let all = NoiseModel::cnn_like();
        let none = NoiseModel::default();
        Ok(match name {
            "none" => none,
            "gaussian" => NoiseModel {
                gaussian_sigma_mm: all.gaussian_sigma_mm,
                ..none
            },
            "lowfreq" => NoiseModel {
                lowfreq_sigma_mm: all.lowfreq_sigma_mm,
                lowfreq_cell_px: all.lowfreq_cell_px,
                lowfreq_temporal: all.lowfreq_temporal,
                ..none
            },
            "flicker" => NoiseModel {
                flicker_scale: all.flicker_scale,
                flicker_offset_mm: all.flicker_offset_mm,
                ..none
            },
            "holes" => NoiseModel {
                dropout: all.dropout,
                hole_blobs: all.hole_blobs,
                hole_radius_px: all.hole_radius_px,
                ..none
            },
            "edges" => NoiseModel {
                edge_width_px: all.edge_width_px,
                edge_error_mm: all.edge_error_mm,
                edge_threshold_mm: all.edge_threshold_mm,
                ..none
            },
            "cnn-like" => all,
            "relative" => NoiseModel::relative(),
            _ => {
                return Err(EvalError::UnknownNoise {
                    name: name.into(),
                    known: NOISE_PRESETS.join(", "),
                })
            }
        })
    }

    /// Errors on negative or non-finite parameters, probabilities outside [0, 1), or a
    /// low-frequency error without a positive cell size.
    pub fn validate(&self) -> Result<(), EvalError> {
        let bad = |name: &'static str, value: f64, reason: &'static str| EvalError::InvalidConfig {
            name,
            value: value.to_string(),
            reason,
        };
        for (name, v) in [
            ("gaussian_sigma_mm", self.gaussian_sigma_mm),
            ("lowfreq_sigma_mm", self.lowfreq_sigma_mm),
            ("lowfreq_cell_px", self.lowfreq_cell_px),
            ("flicker_scale", self.flicker_scale),
            ("flicker_offset_mm", self.flicker_offset_mm),
            ("hole_radius_px", self.hole_radius_px),
            ("edge_error_mm", self.edge_error_mm),
            ("edge_threshold_mm", self.edge_threshold_mm),
            ("relative_scale_log_sigma", self.relative_scale_log_sigma),
            ("relative_shift", self.relative_shift),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(name, v, "must be finite and non-negative"));
            }
        }
        for (name, v) in [
            ("lowfreq_temporal", self.lowfreq_temporal),
            ("dropout", self.dropout),
        ] {
            if !(0.0..1.0).contains(&v) {
                return Err(bad(name, v, "must lie in [0, 1)"));
            }
        }
        if self.lowfreq_sigma_mm > 0.0 && self.lowfreq_cell_px < 1.0 {
            return Err(bad(
                "lowfreq_cell_px",
                self.lowfreq_cell_px,
                "must be at least 1 pixel",
            ));
        }
        Ok(())
    }
}

/// Applies a [`NoiseModel`] frame after frame; holds the random stream and the low-frequency
/// field's state, so a sequence is reproducible from its seed.
#[derive(Clone, Debug)]
pub struct NoiseGenerator {
    model: NoiseModel,
    rng: ChaCha8Rng,
    /// Low-frequency grid values (units of σ), `grid_w × grid_h`, empty before the first frame.
    field: Vec<f64>,
    grid_w: usize,
    grid_h: usize,
}

impl NoiseGenerator {
    /// A generator for `model` seeded with `seed`.
    pub fn new(model: NoiseModel, seed: u64) -> Result<NoiseGenerator, EvalError> {
        model.validate()?;
        Ok(NoiseGenerator {
            model,
            rng: ChaCha8Rng::seed_from_u64(seed),
            field: Vec::new(),
            grid_w: 0,
            grid_h: 0,
        })
    }

    /// The noisy version of the next frame's ground-truth `depth` (z-depth, metres, 0 =
    /// background); the output has the same size and kind `Z` (with `relative_inverse`, its
    /// values are the relative inverse depth, not metres).
    pub fn apply(&mut self, depth: &DepthMap) -> DepthMap {
        let m = self.model;
        let (w, h) = (depth.width as usize, depth.height as usize);
        let valid = |z: f32| DepthMap::is_valid(z);
        let mut out = DepthMap::empty(depth.width, depth.height, DepthKind::Z);
        for (o, &z) in out.data.iter_mut().zip(&depth.data) {
            *o = if valid(z) { z } else { 0.0 };
        }

        // 1. Depth edges.
        if m.edge_width_px > 0 {
            let threshold = (m.edge_threshold_mm * MM) as f32;
            let mut edge: Vec<bool> = (0..w * h)
                .map(|i| {
                    let (u, v) = (i % w, i / w);
                    let z = depth.data[i];
                    valid(z)
                        && [(0i64, 1i64), (0, -1), (1, 0), (-1, 0)]
                            .iter()
                            .any(|&(du, dv)| {
                                let (nu, nv) = (u as i64 + du, v as i64 + dv);
                                if nu < 0 || nv < 0 || nu >= w as i64 || nv >= h as i64 {
                                    return false;
                                }
                                let zn = depth.data[nv as usize * w + nu as usize];
                                !valid(zn) || (zn - z).abs() > threshold
                            })
                })
                .collect();
            // Grow the band to edge_width_px (8-connected, within the valid depth).
            for _ in 1..m.edge_width_px {
                let prev = edge.clone();
                for i in 0..w * h {
                    if prev[i] || !valid(depth.data[i]) {
                        continue;
                    }
                    let (u, v) = ((i % w) as i64, (i / w) as i64);
                    edge[i] = (-1..=1).any(|dv| {
                        (-1..=1).any(|du| {
                            let (nu, nv) = (u + du, v + dv);
                            nu >= 0
                                && nv >= 0
                                && nu < w as i64
                                && nv < h as i64
                                && prev[nv as usize * w + nu as usize]
                        })
                    });
                }
            }
            for (o, &e) in out.data.iter_mut().zip(&edge) {
                if e {
                    if self.rng.random::<bool>() {
                        *o = 0.0;
                    } else {
                        *o += (self.rng.random::<f64>() * m.edge_error_mm * MM) as f32;
                    }
                }
            }
        }

        // 2. Flicker.
        let scale = 1.0 + m.flicker_scale * standard_normal(&mut self.rng);
        let offset = m.flicker_offset_mm * MM * standard_normal(&mut self.rng);

        // 3. Low-frequency field (AR(1) on a coarse grid).
        if m.lowfreq_sigma_mm > 0.0 {
            let (gw, gh) = (
                (w as f64 / m.lowfreq_cell_px).ceil() as usize + 2,
                (h as f64 / m.lowfreq_cell_px).ceil() as usize + 2,
            );
            if self.field.len() != gw * gh {
                self.grid_w = gw;
                self.grid_h = gh;
                self.field = (0..gw * gh)
                    .map(|_| standard_normal(&mut self.rng))
                    .collect();
            } else {
                let a = m.lowfreq_temporal;
                let b = (1.0 - a * a).sqrt();
                for g in &mut self.field {
                    *g = a * *g + b * standard_normal(&mut self.rng);
                }
            }
        }

        for (i, o) in out.data.iter_mut().enumerate() {
            if *o == 0.0 {
                continue;
            }
            let mut z = *o as f64 * scale + offset;
            if m.lowfreq_sigma_mm > 0.0 {
                z += m.lowfreq_sigma_mm * MM * self.lowfreq_at((i % w) as f64, (i / w) as f64);
            }
            if m.gaussian_sigma_mm > 0.0 {
                z += m.gaussian_sigma_mm * MM * standard_normal(&mut self.rng);
            }
            *o = z.max(0.0) as f32;
        }

        // 5. Holes.
        if m.dropout > 0.0 {
            for o in out.data.iter_mut() {
                if self.rng.random::<f64>() < m.dropout {
                    *o = 0.0;
                }
            }
        }
        if m.hole_blobs > 0 && m.hole_radius_px > 0.0 {
            let covered: Vec<usize> = (0..w * h).filter(|&i| out.data[i] > 0.0).collect();
            for _ in 0..m.hole_blobs {
                if covered.is_empty() {
                    break;
                }
                let c = covered[self.rng.random_range(0..covered.len())];
                let (cu, cv) = ((c % w) as f64, (c / w) as f64);
                let r = m.hole_radius_px * self.rng.random_range(0.5..=1.0);
                let (v0, v1) = (
                    (cv - r).floor().max(0.0) as usize,
                    ((cv + r).ceil() as usize).min(h - 1),
                );
                let (u0, u1) = (
                    (cu - r).floor().max(0.0) as usize,
                    ((cu + r).ceil() as usize).min(w - 1),
                );
                for v in v0..=v1 {
                    for u in u0..=u1 {
                        if (u as f64 - cu).powi(2) + (v as f64 - cv).powi(2) <= r * r {
                            out.data[v * w + u] = 0.0;
                        }
                    }
                }
            }
        }

        // 6. Relative inverse depth.
        if m.relative_inverse {
            let scale = (m.relative_scale_log_sigma * standard_normal(&mut self.rng)).exp();
            let (sum, n) = out
                .data
                .iter()
                .filter(|&&z| z > 0.0)
                .fold((0.0, 0usize), |(s, n), &z| (s + 1.0 / z as f64, n + 1));
            let shift = self.rng.random::<f64>() * m.relative_shift * scale * sum / n.max(1) as f64;
            for o in out.data.iter_mut().filter(|z| **z > 0.0) {
                *o = (scale / *o as f64 + shift) as f32;
            }
        }
        out
    }

    /// Bilinear interpolation of the low-frequency grid at pixel (u, v), units of σ. Grid node
    /// (i, j) sits at pixel ((i − 1)·cell, (j − 1)·cell), so the image lies inside the grid.
    fn lowfreq_at(&self, u: f64, v: f64) -> f64 {
        let cell = self.model.lowfreq_cell_px;
        let (gx, gy) = (u / cell + 1.0, v / cell + 1.0);
        let (i, j) = (
            (gx.floor() as usize).min(self.grid_w - 2),
            (gy.floor() as usize).min(self.grid_h - 2),
        );
        let (fx, fy) = (gx - i as f64, gy - j as f64);
        let g = |a: usize, b: usize| self.field[b * self.grid_w + a];
        (1.0 - fy) * ((1.0 - fx) * g(i, j) + fx * g(i + 1, j))
            + fy * ((1.0 - fx) * g(i, j + 1) + fx * g(i + 1, j + 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 64×48 plane at 0.5 m with a 20 mm step in the right half and background in the last
    /// column.
    fn scene() -> DepthMap {
        let mut d = DepthMap::empty(64, 48, DepthKind::Z);
        for v in 0..48 {
            for u in 0..63 {
                d.data[v * 64 + u] = if u < 32 { 0.5 } else { 0.52 };
            }
        }
        d
    }

    fn stats(a: &DepthMap, b: &DepthMap) -> (f64, f64, usize) {
        let diffs: Vec<f64> = a
            .data
            .iter()
            .zip(&b.data)
            .filter(|(x, y)| **x > 0.0 && **y > 0.0)
            .map(|(x, y)| (*x - *y) as f64)
            .collect();
        let n = diffs.len() as f64;
        let mean = diffs.iter().sum::<f64>() / n;
        let sd = (diffs.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
        (mean, sd, a.data.iter().filter(|&&x| x > 0.0).count())
    }

    #[test]
    fn none_is_the_identity_and_unknown_presets_are_named() {
        let gt = scene();
        let mut g = NoiseGenerator::new(NoiseModel::preset("none").unwrap(), 1).unwrap();
        assert_eq!(g.apply(&gt), gt);
        let e = NoiseModel::preset("cnn").unwrap_err().to_string();
        assert!(e.contains("\"cnn\"") && e.contains("cnn-like"), "{e}");
        let bad = NoiseModel {
            dropout: 1.0,
            ..Default::default()
        };
        assert!(NoiseGenerator::new(bad, 1).is_err());
    }

    #[test]
    fn components_have_their_documented_size() {
        let gt = scene();
        let covered = gt.valid_count();
        // Gaussian: sd ≈ σ, mean ≈ 0, nothing dropped.
        let mut g = NoiseGenerator::new(NoiseModel::preset("gaussian").unwrap(), 2).unwrap();
        let (mean, sd, n) = stats(&g.apply(&gt), &gt);
        assert_eq!(n, covered);
        assert!(mean.abs() < 1e-4 && (sd - 1e-3).abs() < 1e-4, "{mean} {sd}");
        // Flicker: one offset for the whole frame (tiny spread), varying between frames.
        let mut g = NoiseGenerator::new(NoiseModel::preset("flicker").unwrap(), 3).unwrap();
        let (m1, sd1, _) = stats(&g.apply(&gt), &gt);
        let (m2, _, _) = stats(&g.apply(&gt), &gt);
        assert!(sd1 < 0.2e-3 && (m1 - m2).abs() > 1e-6, "{m1} {m2} {sd1}");
        // Low frequency: neighbouring pixels nearly agree; consecutive frames correlate.
        let mut g = NoiseGenerator::new(NoiseModel::preset("lowfreq").unwrap(), 4).unwrap();
        let a = g.apply(&gt);
        let (_, sd, _) = stats(&a, &gt);
        assert!(sd > 0.3e-3 && sd < 4e-3, "{sd}");
        let step = (a.data[10 * 64 + 11] - a.data[10 * 64 + 10]).abs() as f64;
        assert!(step < 0.3e-3, "{step}");
        // Holes: some pixels go, most stay.
        let mut g = NoiseGenerator::new(NoiseModel::preset("holes").unwrap(), 5).unwrap();
        let n = g.apply(&gt).valid_count();
        assert!(n < covered && n > covered * 8 / 10, "{n} of {covered}");
        // Edges: only pixels near the step or the background column change.
        let mut g = NoiseGenerator::new(NoiseModel::preset("edges").unwrap(), 6).unwrap();
        let e = g.apply(&gt);
        for v in 0..48 {
            for u in 0..63 {
                let near_edge = (29..=34).contains(&u) || u >= 61;
                let i = v * 64 + u;
                if !near_edge {
                    assert_eq!(e.data[i], gt.data[i], "({u}, {v})");
                } else if e.data[i] > 0.0 {
                    assert!(e.data[i] >= gt.data[i] && e.data[i] <= gt.data[i] + 0.0201);
                }
            }
        }
        assert!(e.valid_count() < covered);
    }

    #[test]
    fn the_relative_preset_is_an_affine_inverse_depth_per_frame() {
        let gt = scene();
        let exact = NoiseModel {
            relative_inverse: true,
            relative_scale_log_sigma: 0.3,
            relative_shift: 0.5,
            ..NoiseModel::default()
        };
        let mut g = NoiseGenerator::new(exact, 7).unwrap();
        for _ in 0..3 {
            let y = g.apply(&gt);
            // y = s / z + t: two pixels at different depths give s and t; every pixel agrees.
            let (y0, y1) = (y.data[0] as f64, y.data[40] as f64);
            let s = (y0 - y1) / (1.0 / 0.5 - 1.0 / 0.52);
            let t = y0 - s / 0.5;
            assert!(s > 0.0 && t >= 0.0, "{s} {t}");
            for (o, z) in y.data.iter().zip(&gt.data).filter(|(_, z)| **z > 0.0) {
                assert!((*o as f64 - (s / *z as f64 + t)).abs() < 1e-4);
            }
        }
        assert!(NoiseModel::preset("relative").unwrap().relative_inverse);
    }

    #[test]
    fn same_seed_same_noise() {
        let gt = scene();
        let model = NoiseModel::cnn_like();
        let run = |seed| {
            let mut g = NoiseGenerator::new(model, seed).unwrap();
            (0..3).map(|_| g.apply(&gt)).collect::<Vec<_>>()
        };
        assert_eq!(run(9), run(9));
        assert_ne!(run(9), run(10));
    }
}
