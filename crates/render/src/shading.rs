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

/// `x^n` for `n ≥ 0` by binary exponentiation, inline (`f32::powi` is a call into
/// compiler-builtins on x86-64; this is its algorithm, so the values agree).
#[inline(always)]
fn powi(mut x: f32, mut n: i32) -> f32 {
    let mut r = 1.0;
    loop {
        if n & 1 != 0 {
            r *= x;
        }
        n >>= 1;
        if n == 0 {
            return r;
        }
        x *= x;
    }
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

    /// Radiance of Eq. (6.4) (see [`blinn_phong`] for the conventions).
    #[inline(always)]
    pub fn shade(&self, normal: [f32; 3], view: [f32; 3], albedo: [f32; 3]) -> [f32; 3] {
        let (m, light) = (&self.material, &self.light);
        let l = light.direction;
        let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let n_dot_l = dot(normal, l).max(0.0);
        let mut spec = 0.0;
        if n_dot_l > 0.0 {
            let h = [l[0] + view[0], l[1] + view[1], l[2] + view[2]];
            let h_len = dot(h, h).sqrt();
            if h_len > 0.0 {
                let n_dot_h = (dot(normal, h) / h_len).clamp(0.0, 1.0);
                if n_dot_h >= self.cos_cutoff {
                    spec = m.ks
                        * match self.integer_shininess {
                            Some(a) => powi(n_dot_h, a),
                            None => n_dot_h.powf(m.shininess),
                        };
                }
            }
        }
        std::array::from_fn(|c| {
            (m.ka * light.ambient[c] + m.kd * n_dot_l * light.diffuse[c]) * albedo[c]
                + spec * light.specular[c]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

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
            let fast = BlinnPhong::new(m, light).unwrap().shade(n, v, albedo);
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
    fn inline_powi_equals_the_builtin() {
        for n in [1, 2, 3, 7, 32, 100, 1024] {
            for k in 0..=100 {
                let x = k as f32 / 100.0;
                assert_eq!(powi(x, n), x.powi(n), "{x}^{n}");
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
