//! Blinn–Phong shading: Eq. (6.4) with the texture modulating ambient and diffuse (ERRATA 12).

use crate::RenderError;

/// Surface reflectances of Eq. (6.4). Energy conservation (ERRATA 12 / §6): every coefficient in
/// `[0, 1]`, `k_a + k_d ≤ 1` and `k_s ≤ 1 − k_a − k_d`; shininess `α ≥ 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Ambient reflectance `k_a`.
    pub ka: f32,
    /// Diffuse reflectance `k_d`.
    pub kd: f32,
    /// Specular reflectance `k_s`.
    pub ks: f32,
    /// Shininess exponent `α` of the Blinn lobe.
    pub shininess: f32,
}

impl Default for Material {
    /// A matte skin-like surface: `k_a = 0.25, k_d = 0.65, k_s = 0.1, α = 32`.
    fn default() -> Self {
        Material {
            ka: 0.25,
            kd: 0.65,
            ks: 0.1,
            shininess: 32.0,
        }
    }
}

/// Material that shows the albedo unshaded: `C = C_tex` under a white ambient light.
pub const UNLIT: Material = Material {
    ka: 1.0,
    kd: 0.0,
    ks: 0.0,
    shininess: 1.0,
};

/// Slack allowed on `k_a + k_d + k_s ≤ 1` for decimal inputs such as `0.7 + 0.2 + 0.1`.
const ENERGY_SLACK: f32 = 1e-6;

impl Material {
    /// Checks the ranges documented on the type.
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |field, value: f32, reason| {
            Err(RenderError::Parameter {
                field,
                value: value as f64,
                reason,
            })
        };
        for (field, v) in [("k_a", self.ka), ("k_d", self.kd), ("k_s", self.ks)] {
            if !(0.0..=1.0).contains(&v) {
                return bad(field, v, "reflectances must lie in [0, 1]");
            }
        }
        if self.ka + self.kd > 1.0 + ENERGY_SLACK {
            return bad(
                "k_a + k_d",
                self.ka + self.kd,
                "energy conservation needs k_a + k_d ≤ 1",
            );
        }
        if self.ks > 1.0 - self.ka - self.kd + ENERGY_SLACK {
            return bad(
                "k_s",
                self.ks,
                "energy conservation needs k_s ≤ 1 − k_a − k_d",
            );
        }
        if !(self.shininess >= 1.0 && self.shininess.is_finite()) {
            return bad(
                "shininess",
                self.shininess,
                "the Blinn exponent α must be finite and ≥ 1",
            );
        }
        Ok(())
    }
}

/// A directional light in camera coordinates with the incident colours of Eq. (6.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Unit vector `l` from the surface towards the light (camera coordinates: x right, y down,
    /// z forward; a light behind the camera has `l_z < 0`).
    pub direction: [f32; 3],
    /// Ambient colour `L_a` ∈ [0, 1]³.
    pub ambient: [f32; 3],
    /// Diffuse colour `L_d` ∈ [0, 1]³.
    pub diffuse: [f32; 3],
    /// Specular colour `L_s` ∈ [0, 1]³.
    pub specular: [f32; 3],
}

impl Default for Light {
    /// A white "key light" from above-left of the camera: `l ∝ (−0.3, −0.5, −1)`.
    fn default() -> Self {
        Light::white([-0.3, -0.5, -1.0])
    }
}

impl Light {
    /// A white light (all colours 1) from `towards_light` (normalised here).
    pub fn white(towards_light: [f32; 3]) -> Light {
        let [x, y, z] = towards_light;
        let n = (x * x + y * y + z * z).sqrt();
        Light {
            direction: [x / n, y / n, z / n],
            ambient: [1.0; 3],
            diffuse: [1.0; 3],
            specular: [1.0; 3],
        }
    }

    /// Checks that the direction is a finite unit vector and the colours lie in [0, 1].
    pub fn validate(&self) -> Result<(), RenderError> {
        let [x, y, z] = self.direction;
        let len = (x * x + y * y + z * z).sqrt();
        if (len - 1.0).abs() >= 1e-4 || len.is_nan() {
            return Err(RenderError::Parameter {
                field: "light direction length",
                value: len as f64,
                reason: "the light direction must be a unit vector",
            });
        }
        for (field, c) in [
            ("ambient light", self.ambient),
            ("diffuse light", self.diffuse),
            ("specular light", self.specular),
        ] {
            if let Some(&v) = c.iter().find(|v| !(0.0..=1.0).contains(*v)) {
                return Err(RenderError::Parameter {
                    field,
                    value: v as f64,
                    reason: "light colours must lie in [0, 1]",
                });
            }
        }
        Ok(())
    }
}

/// Fragment radiance, linear RGB (Eq. (6.4) as corrected by ERRATA 12):
///
/// `C = k_a L_a ⊙ C_tex + k_d (ν·l)₊ L_d ⊙ C_tex + k_s (ν·h)₊^α L_s`, `h = (l + v)/‖l + v‖`.
///
/// `normal` (ν) and `view` (v, surface → eye) are unit vectors in the light's frame; `albedo` is
/// `C_tex` (texture, vertex colour or constant). With a valid [`Material`] and [`Light`] and
/// `albedo ∈ [0, 1]³`, every channel of `C` lies in `[0, 1]`: `C ≤ k_a + k_d + k_s ≤ 1`.
#[inline]
pub fn blinn_phong(
    material: &Material,
    light: &Light,
    normal: [f32; 3],
    view: [f32; 3],
    albedo: [f32; 3],
) -> [f32; 3] {
    let l = light.direction;
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let n_dot_l = dot(normal, l).max(0.0);
    let h = [l[0] + view[0], l[1] + view[1], l[2] + view[2]];
    let h_len = dot(h, h).sqrt();
    let spec = if material.ks > 0.0 && h_len > 0.0 && n_dot_l > 0.0 {
        let n_dot_h = (dot(normal, h) / h_len).clamp(0.0, 1.0);
        material.ks * n_dot_h.powf(material.shininess)
    } else {
        0.0
    };
    std::array::from_fn(|c| {
        (material.ka * light.ambient[c] + material.kd * n_dot_l * light.diffuse[c]) * albedo[c]
            + spec * light.specular[c]
    })
}

/// Largest radiance dropped by [`BlinnPhong`]'s specular cut-off (linear units; an 8-bit sRGB step
/// near black is 3·10⁻⁴).
pub const SPECULAR_CUTOFF: f32 = 1e-5;

/// [`blinn_phong`] prepared for one frame: identical except that the specular lobe is skipped
/// where `k_s (ν·h)^α < SPECULAR_CUTOFF`, which saves the `powf` on most pixels.
#[derive(Clone, Copy, Debug)]
pub struct BlinnPhong {
    material: Material,
    light: Light,
    /// `ν·h` below which the lobe is negligible.
    cos_cutoff: f32,
    /// `α` when it is a whole number up to [`MAX_INTEGER_SHININESS`] (`powi` is much cheaper).
    integer_shininess: Option<i32>,
}

/// Largest shininess evaluated by repeated multiplication.
const MAX_INTEGER_SHININESS: f32 = 1024.0;

impl BlinnPhong {
    /// Validates `material` and `light` and precomputes the cut-off.
    pub fn new(material: Material, light: Light) -> Result<BlinnPhong, RenderError> {
        material.validate()?;
        light.validate()?;
        let cos_cutoff = if material.ks > 0.0 {
            (SPECULAR_CUTOFF / material.ks).powf(1.0 / material.shininess)
        } else {
            f32::INFINITY
        };
        let a = material.shininess;
        let integer_shininess =
            (a.fract() == 0.0 && a <= MAX_INTEGER_SHININESS).then_some(a as i32);
        Ok(BlinnPhong {
            material,
            light,
            cos_cutoff,
            integer_shininess,
        })
    }

    /// Radiance of Eq. (6.4) (see [`blinn_phong`] for the conventions) of the first `m` lanes
    /// of `s` (`m ≤ LANES`), written over their albedo.
    ///
    /// Lane-parallel and branch-free: the specular cut-off becomes a mask and an integer
    /// exponent is applied by squaring over the whole block, so the loops compile to SIMD code.
    /// Per lane, the same operations in the same order as a scalar evaluation.
    ///
    /// # Panics
    /// If `m > LANES`.
    #[inline(always)]
    pub(crate) fn shade_lanes(&self, s: &mut SurfaceLanes, m: usize) {
        let (mt, light) = (&self.material, &self.light);
        let l = light.direction;
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (n_dot_l, n_dot_h) = (&mut s.n_dot_l, &mut s.n_dot_h);
        for k in 0..m {
            let n = [s.normal[0][k], s.normal[1][k], s.normal[2][k]];
            let v = [s.view[0][k], s.view[1][k], s.view[2][k]];
            let ndl = dot(n, l).max(0.0);
            let h = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
            let h_len = dot(h, h).sqrt();
            // NaN where `h_len = 0`, which fails the comparison below.
            let ndh = (dot(n, h) / h_len).clamp(0.0, 1.0);
            let lit = (ndl > 0.0) & (h_len > 0.0) & (ndh >= self.cos_cutoff);
            n_dot_l[k] = ndl;
            // `ν·h` where the lobe counts, else 0 (`0^α = 0` for `α ≥ 1`).
            n_dot_h[k] = if lit { ndh } else { 0.0 };
        }
        // `(ν·h)^α` in place.
        match self.integer_shininess {
            Some(a) => powi_lanes(n_dot_h, m, a),
            None => n_dot_h[..m]
                .iter_mut()
                .for_each(|x| *x = x.powf(mt.shininess)),
        }
        for c in 0..3 {
            let (la, ld, ls) = (light.ambient[c], light.diffuse[c], light.specular[c]);
            for (k, out) in s.albedo[c][..m].iter_mut().enumerate() {
                *out = (mt.ka * la + mt.kd * n_dot_l[k] * ld) * *out + mt.ks * n_dot_h[k] * ls;
            }
        }
    }
}

/// Pixels shaded together by [`BlinnPhong::shade_lanes`].
pub(crate) const LANES: usize = 64;

/// Surface samples in structure-of-arrays form (`[axis or channel][lane]`): unit normals `ν`,
/// unit view vectors `v` (surface → eye) and albedos `C_tex`, as [`blinn_phong`] takes them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SurfaceLanes {
    pub normal: [[f32; LANES]; 3],
    pub view: [[f32; LANES]; 3],
    /// Albedo in, radiance out ([`BlinnPhong::shade_lanes`]).
    pub albedo: [[f32; LANES]; 3],
    /// Scratch of [`BlinnPhong::shade_lanes`].
    n_dot_l: [f32; LANES],
    n_dot_h: [f32; LANES],
}

impl Default for SurfaceLanes {
    fn default() -> Self {
        SurfaceLanes {
            normal: [[0.0; LANES]; 3],
            view: [[0.0; LANES]; 3],
            albedo: [[0.0; LANES]; 3],
            n_dot_l: [0.0; LANES],
            n_dot_h: [0.0; LANES],
        }
    }
}

/// `x^n` (`n ≥ 0`) of the first `m` lanes, in place, by binary exponentiation: one pass over
/// the block per exponent bit. `f32::powi` is a call into compiler-builtins on x86-64; this is
/// its algorithm, so the values agree.
#[inline(always)]
fn powi_lanes(x: &mut [f32; LANES], m: usize, mut n: i32) {
    let mut r = [1.0f32; LANES];
    loop {
        if n & 1 != 0 {
            for (r, x) in r[..m].iter_mut().zip(&x[..m]) {
                *r *= x;
            }
        }
        n >>= 1;
        if n == 0 {
            break;
        }
        for x in &mut x[..m] {
            *x *= *x;
        }
    }
    x[..m].copy_from_slice(&r[..m]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// [`BlinnPhong::shade_lanes`] of one sample, placed in a middle lane.
    fn shade_one(s: &BlinnPhong, n: [f32; 3], v: [f32; 3], albedo: [f32; 3]) -> [f32; 3] {
        let mut lanes = SurfaceLanes::default();
        let k = LANES / 2 + 3;
        for c in 0..3 {
            (lanes.normal[c][k], lanes.view[c][k], lanes.albedo[c][k]) = (n[c], v[c], albedo[c]);
        }
        s.shade_lanes(&mut lanes, LANES);
        lanes.albedo.map(|c| c[k])
    }

    fn unit(rng: &mut impl Rng) -> [f32; 3] {
        loop {
            let v: [f32; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if n > 0.1 && n <= 1.0 {
                return v.map(|x| x / n);
            }
        }
    }

    #[test]
    fn radiance_is_bounded_by_one_for_energy_conserving_parameters() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let mut max_seen = 0.0f32;
        for _ in 0..20_000 {
            let ka: f32 = rng.random_range(0.0..1.0);
            let kd: f32 = rng.random_range(0.0..=1.0 - ka);
            let ks: f32 = rng.random_range(0.0..=1.0 - ka - kd);
            let m = Material {
                ka,
                kd,
                ks,
                shininess: rng.random_range(1.0..200.0),
            };
            m.validate().unwrap();
            let mut light = Light::white(unit(&mut rng));
            light.ambient = std::array::from_fn(|_| rng.random_range(0.0..=1.0));
            light.diffuse = std::array::from_fn(|_| rng.random_range(0.0..=1.0));
            light.specular = std::array::from_fn(|_| rng.random_range(0.0..=1.0));
            let albedo = std::array::from_fn(|_| rng.random_range(0.0..=1.0));
            let (n, v) = (unit(&mut rng), unit(&mut rng));
            let c = blinn_phong(&m, &light, n, v, albedo);
            let fast = shade_one(&BlinnPhong::new(m, light).unwrap(), n, v, albedo);
            for k in 0..3 {
                assert!(
                    (fast[k] - c[k]).abs() <= SPECULAR_CUTOFF * 1.01,
                    "{fast:?} vs {c:?}"
                );
            }
            for v in c {
                assert!((0.0..=1.0 + 1e-5).contains(&v), "{v} from {m:?} {light:?}");
                max_seen = max_seen.max(v);
            }
        }
        // The bound is tight: all-white light along the normal with k_a + k_d + k_s = 1 gives 1.
        let m = Material {
            ka: 0.2,
            kd: 0.5,
            ks: 0.3,
            shininess: 8.0,
        };
        let c = blinn_phong(
            &m,
            &Light::white([0.0, 0.0, -1.0]),
            [0.0, 0.0, -1.0],
            [0.0, 0.0, -1.0],
            [1.0; 3],
        );
        assert!(c.iter().all(|&v| (v - 1.0).abs() < 1e-6), "{c:?}");
        assert!(max_seen > 0.5);
    }

    #[test]
    fn lane_powi_equals_the_builtin() {
        let x: [f32; LANES] = std::array::from_fn(|k| k as f32 / (LANES - 1) as f32);
        for n in [1, 2, 3, 7, 32, 100, 1024] {
            let mut r = x;
            powi_lanes(&mut r, LANES, n);
            for k in 0..LANES {
                assert_eq!(r[k], x[k].powi(n), "{}^{n}", x[k]);
            }
        }
    }

    #[test]
    fn texture_modulates_ambient_and_diffuse_but_not_specular() {
        let m = Material::default();
        let light = Light::white([0.0, 0.0, -1.0]);
        let n = [0.0, 0.0, -1.0];
        let c = blinn_phong(&m, &light, n, n, [0.0, 0.5, 1.0]);
        assert!(
            (c[0] - m.ks).abs() < 1e-6,
            "black albedo leaves only the highlight"
        );
        assert!((c[2] - (m.ka + m.kd + m.ks)).abs() < 1e-6);
        assert!((c[1] - (0.5 * (m.ka + m.kd) + m.ks)).abs() < 1e-6);
    }

    #[test]
    fn invalid_parameters_are_rejected_with_their_value() {
        let m = Material {
            ka: 0.6,
            kd: 0.6,
            ks: 0.0,
            shininess: 2.0,
        };
        let err = m.validate().unwrap_err().to_string();
        assert!(err.contains("1.2"), "{err}");
        assert!(Material {
            ks: 0.2,
            ..Material::default()
        }
        .validate()
        .is_err());
        assert!(Material {
            shininess: 0.5,
            ..Material::default()
        }
        .validate()
        .is_err());
        assert!(Light {
            direction: [0.0, 0.0, 2.0],
            ..Light::default()
        }
        .validate()
        .is_err());
        assert!(Light {
            ambient: [1.5, 0.0, 0.0],
            ..Light::default()
        }
        .validate()
        .is_err());
        Material::default().validate().unwrap();
        UNLIT.validate().unwrap();
    }
}
