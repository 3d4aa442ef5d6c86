//! A seeded procedural skin albedo, baked per vertex, for colour renders with image detail
//! (the benchmark's [`SyntheticSequence::render_color`] is a constant albedo, which leaves
//! SIFT only the silhouette and the shading). The ICT mesh is used without UVs, so the texture
//! is a function of the vertex's head coordinates ([`SyntheticSequence::head_coordinates`]
//! of the first frame) evaluated once per vertex: it stays on the skin as the head turns.
//!
//! Content, multiplying 0.8 × [`SKIN_ALBEDO`]: blotches (3-D value noise, 15 mm cells, ±25 %),
//! mottling (6 mm, ±20 %), fine mottling (2 mm, ±12 %), pores (0.8 mm, about the mesh's vertex
//! spacing, ±6 %) and freckles (brown spots of 1.5–4 mm radius, 35–70 % darker, about one per
//! 30 vertices). At the benchmark's scale (f = 350 px, 0.4–0.8 m) a millimetre is about half
//! a pixel, so the spots and the coarser layers are what SIFT can see.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::synthesis::SKIN_ALBEDO;
use crate::SyntheticSequence;

/// Lattice period of the value noise, cells.
const PERIOD: usize = 256;

/// 3-D value noise on a unit lattice: a seeded permutation and per-cell values in [−1, 1],
/// quintic interpolation.
struct ValueNoise {
    perm: [u8; PERIOD],
    values: [f32; PERIOD],
}

impl ValueNoise {
    fn new(rng: &mut ChaCha8Rng) -> ValueNoise {
        let mut perm: [u8; PERIOD] = std::array::from_fn(|i| i as u8);
        for i in (1..PERIOD).rev() {
            perm.swap(i, rng.random_range(0..=i));
        }
        let values = std::array::from_fn(|_| rng.random_range(-1.0f32..=1.0));
        ValueNoise { perm, values }
    }

    fn lattice(&self, i: i64, j: i64, k: i64) -> f32 {
        let p = |x: usize| self.perm[x % PERIOD] as usize;
        let m = |x: i64| x.rem_euclid(PERIOD as i64) as usize;
        self.values[p(p(p(m(i)) + m(j)) + m(k))]
    }

    /// The noise at `x` (lattice units), in [−1, 1].
    fn at(&self, x: [f64; 3]) -> f32 {
        let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let cell = x.map(f64::floor);
        let f: [f64; 3] = std::array::from_fn(|a| x[a] - cell[a]);
        let w = f.map(fade);
        let c = cell.map(|v| v as i64);
        let mut sum = 0.0;
        for corner in 0..8 {
            let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
            let weight: f64 = (0..3)
                .map(|a| if o[a] == 1 { w[a] } else { 1.0 - w[a] })
                .product();
            sum += weight
                * f64::from(self.lattice(
                    c[0] + o[0] as i64,
                    c[1] + o[1] as i64,
                    c[2] + o[2] as i64,
                ));
        }
        sum as f32
    }
}

/// The noise layers: cell size (metres) and relative amplitude.
const LAYERS: [(f64, f32); 4] = [(0.015, 0.25), (0.006, 0.20), (0.002, 0.12), (0.0008, 0.06)];

/// Vertices per freckle, on average.
const VERTICES_PER_FRECKLE: usize = 30;

/// The texture's mean relative to [`SKIN_ALBEDO`]: a little darker, so that the lit side
/// does not clip.
const BASE: f32 = 0.8;

/// Linear RGB albedo per vertex of `points` (head coordinates, metres), deterministic in
/// `seed`.
pub fn skin_albedo(points: &[[f64; 3]], seed: u64) -> Vec<[f32; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let layers: Vec<(ValueNoise, f64, f32)> = LAYERS
        .iter()
        .map(|&(cell, amp)| (ValueNoise::new(&mut rng), cell, amp))
        .collect();
    let mut shade: Vec<f32> = points
        .iter()
        .map(|p| {
            1.0 + layers
                .iter()
                .map(|(noise, cell, amp)| amp * noise.at(p.map(|x| x / cell)))
                .sum::<f32>()
        })
        .collect();
    // Freckles: darkening per vertex, 0 = none.
    let mut freckle = vec![0.0f32; points.len()];
    if !points.is_empty() {
        for _ in 0..points.len() / VERTICES_PER_FRECKLE {
            let centre = points[rng.random_range(0..points.len())];
            let radius = rng.random_range(0.0015..=0.004);
            let strength: f32 = rng.random_range(0.35..=0.7);
            let reach2 = (3.0 * radius) * (3.0 * radius);
            for (v, p) in points.iter().enumerate() {
                let d2: f64 = (0..3).map(|a| (p[a] - centre[a]).powi(2)).sum();
                if d2 < reach2 {
                    let g = strength * (-d2 / (2.0 * radius * radius)).exp() as f32;
                    freckle[v] = freckle[v].max(g);
                }
            }
        }
    }
    // Freckles are brown: they darken blue and green more than red.
    const FRECKLE_TINT: [f32; 3] = [0.8, 1.0, 1.2];
    shade
        .iter_mut()
        .zip(&freckle)
        .map(|(s, &f)| {
            std::array::from_fn(|c| {
                (BASE * SKIN_ALBEDO[c] * *s * (1.0 - (f * FRECKLE_TINT[c]).min(0.9)))
                    .clamp(0.02, 1.0)
            })
        })
        .collect()
}

/// [`skin_albedo`] of `seq`'s surface, its head coordinates taken from the first frame.
pub fn sequence_skin_albedo(seq: &SyntheticSequence, seed: u64) -> Vec<[f32; 3]> {
    skin_albedo(&seq.head_coordinates(0), seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_albedo_is_seeded_bounded_and_has_contrast() {
        let points: Vec<[f64; 3]> = (0..4000)
            .map(|i| {
                let (x, y) = ((i % 80) as f64, (i / 80) as f64);
                [x * 0.001, y * 0.001, 0.0]
            })
            .collect();
        let a = skin_albedo(&points, 7);
        assert_eq!(a, skin_albedo(&points, 7));
        assert_ne!(a, skin_albedo(&points, 8));
        assert!(a.iter().flatten().all(|&c| (0.02..=1.0).contains(&c)));
        let red: Vec<f32> = a.iter().map(|c| c[0]).collect();
        let (lo, hi) = red
            .iter()
            .fold((f32::MAX, f32::MIN), |(l, h), &r| (l.min(r), h.max(r)));
        assert!(hi - lo > 0.3, "red albedo spans {lo}..{hi}");
    }
}
