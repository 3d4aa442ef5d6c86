//! The colour of a rendered ICT-FaceKit head: one texture atlas for every part the benchmark
//! draws, so the whole head renders in one pass with one [`Texture`].
//!
//! ICT-FaceKit lays its materials out as UDIM-like tiles (`u` in [0, 1) the face, [1, 2) the
//! back of the head with the mouth and eye sockets, [2, 3) gums and tongue, [3, 4) teeth,
//! then the overlays) and gives each eyeball its own [0, 1]² (the sclera mesh, whose texture
//! carries the iris at its front). The atlas puts each [`Part`] in a square tile of
//! [`ATLAS_COLUMNS`] × [`ATLAS_ROWS`]:
//!
//! | row \ column | 0 | 1 | 2 | 3 |
//! |---|---|---|---|---|
//! | 0 | face (a real skin texture) | scalp and neck (the texture's border skin tone) | gums and tongue | teeth |
//! | 1 | eyeball (sclera, iris, pupil) | mouth and eye sockets (dark) | — | — |
//!
//! Colours are linear RGB; the interior ones are darker than the materials themselves since
//! the renderer casts no shadows and the inside of a mouth is mostly in shade.

use image::RgbImage;
use visage_mesh::color::srgb_to_linear_u8;
use visage_render::{rasterize_uv_triangle, Texture};

use crate::EvalError;

/// Tiles across the atlas.
pub const ATLAS_COLUMNS: u32 = 4;
/// Tiles down the atlas.
pub const ATLAS_ROWS: u32 = 2;

/// Gums and tongue, linear RGB (a shaded pink).
const GUMS: [f32; 3] = [0.16, 0.035, 0.035];
/// Teeth, linear RGB (a shaded ivory).
const TEETH: [f32; 3] = [0.45, 0.40, 0.32];
/// The mouth and eye sockets, linear RGB (a dark red-brown).
const SOCKET: [f32; 3] = [0.035, 0.010, 0.010];
/// The white of the eye, linear RGB (never paper-white: it is wet, veined and shaded).
const SCLERA: [f32; 3] = [0.56, 0.50, 0.46];
/// The iris, linear RGB (a brown iris).
const IRIS: [f32; 3] = [0.10, 0.05, 0.024];
/// The dark ring at the iris's edge (the limbus), linear RGB.
const LIMBUS: [f32; 3] = [0.025, 0.015, 0.010];
/// The pupil, linear RGB.
const PUPIL: [f32; 3] = [0.008, 0.008, 0.008];
/// Angular width of the limbal ring, radians (about 1.5°).
const LIMBUS_WIDTH_RAD: f64 = 0.026;
/// Radial streaks of the iris (stripes around it).
const IRIS_STREAKS: f64 = 37.0;

/// What a triangle of the rendered head is made of: its tile in the atlas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Part {
    /// The face region (ICT's `M_Face`, UV tile 0).
    Face,
    /// The back of the head and the neck (`M_BackHead` outside the sockets).
    Scalp,
    /// The mouth and eye sockets (`M_BackHead`, vertices 11,248–14,061).
    Socket,
    /// Gums and tongue (`M_GumsTongue`).
    Gums,
    /// Teeth (`M_Teeth`).
    Teeth,
    /// An eyeball's outer surface (`M_ScleraLeft`/`Right`), iris painted at its front.
    Eye,
}

impl Part {
    /// The part's tile (column, row).
    fn tile(self) -> (u32, u32) {
        match self {
            Part::Face => (0, 0),
            Part::Scalp => (1, 0),
            Part::Gums => (2, 0),
            Part::Teeth => (3, 0),
            Part::Eye => (0, 1),
            Part::Socket => (1, 1),
        }
    }

    /// The atlas UV of the part's own UV `uv` (its fractional part is the place in the tile;
    /// `v` up, as OBJ and [`Texture`] have it).
    pub fn atlas_uv(self, uv: [f64; 2]) -> [f64; 2] {
        let (col, row) = self.tile();
        let frac = |x: f64| x - x.floor();
        [
            (f64::from(col) + frac(uv[0])) / f64::from(ATLAS_COLUMNS),
            1.0 - (f64::from(row) + 1.0 - frac(uv[1])) / f64::from(ATLAS_ROWS),
        ]
    }
}

/// Where the iris sits in the eyeball's UVs: the UV of the eyeball's front (the gaze axis) and
/// how far from it, in UV units, a point at angle θ from the axis lies (`ρ = uv_per_rad · θ`,
/// fitted on the mesh), with the iris's and pupil's angular radii.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeLayout {
    pub front_uv: [f64; 2],
    pub uv_per_rad: f64,
    /// Angle from the axis to the iris's edge, radians.
    pub iris_rad: f64,
    /// Angle from the axis to the pupil's edge, radians.
    pub pupil_rad: f64,
}

/// The atlas: the real face texture `face` (square, sRGB, ICT's face UVs) in the face tile,
/// the other tiles drawn (the module's table), each tile `face`'s size.
///
/// # Errors
/// A face texture that is not square or is empty.
pub fn head_texture(face: &RgbImage, eye: &EyeLayout) -> Result<Texture, EvalError> {
    let t = face.width();
    if t == 0 || face.height() != t {
        return Err(EvalError::InvalidConfig {
            name: "face texture",
            value: format!("{}×{}", face.width(), face.height()),
            reason: "must be square and not empty",
        });
    }
    let linear: [f32; 256] = std::array::from_fn(|c| srgb_to_linear_u8(c as u8));
    let skin = border_skin(face, &linear);
    let (w, h) = (t * ATLAS_COLUMNS, t * ATLAS_ROWS);
    let mut texels = vec![[0.0f32; 4]; w as usize * h as usize];
    let mut fill = |part: Part, color: &dyn Fn(u32, u32) -> [f32; 3]| {
        let (col, row) = part.tile();
        for j in 0..t {
            for i in 0..t {
                let c = color(i, j);
                let at = (row * t + j) as usize * w as usize + (col * t + i) as usize;
                texels[at] = [c[0], c[1], c[2], 1.0];
            }
        }
    };
    fill(Part::Face, &|i, j| {
        face.get_pixel(i, j).0.map(|c| linear[c as usize])
    });
    fill(Part::Scalp, &|i, j| {
        // A faint mottling so the skin is not a flat colour.
        let n = 1.0 + 0.04 * hash_noise(i / 4, j / 4);
        skin.map(|c| (c * n).clamp(0.0, 1.0))
    });
    fill(Part::Gums, &|_, _| GUMS);
    fill(Part::Teeth, &|_, _| TEETH);
    fill(Part::Socket, &|_, _| SOCKET);
    fill(Part::Eye, &|i, j| {
        let uv = [
            (f64::from(i) + 0.5) / f64::from(t),
            1.0 - (f64::from(j) + 0.5) / f64::from(t),
        ];
        eye_color(eye, uv)
    });
    Ok(Texture::new(w, h, texels)?)
}

/// How far a blink moves a point of the lids (metres) where the face texture starts to be
/// painted over with lid skin, and where it is lid skin only.
pub const LID_SKIN_M: (f64, f64) = (0.002, 0.005);

/// How far a blink moves the lid's margin (metres): from the first value the lid skin darkens
/// into the lash line, fully at the second (ICT-FaceKit's upper lid margin moves 9.5 mm).
pub const LASH_LINE_M: (f64, f64) = (0.0075, 0.009);

/// The lash line's colour as a fraction of the lid skin's.
const LASH_LINE_SHADE: f64 = 0.25;

/// Paints lid skin over the parts of the eyelids that a blink brings over the eye, in the
/// face texture `face` (square, ICT's face UVs): a clip with open eyes sees those parts folded
/// away, so the texture fused from it holds the eye's own colours there (sclera, iris,
/// lashes), and a closed lid would show them. `lids` are the face triangles' UVs with how far
/// a blink moves each corner; a texel is blended toward the lid's skin by
/// `smoothstep(LID_SKIN_M.0, LID_SKIN_M.1, d)` of its interpolated motion `d`, and the margin
/// ([`LASH_LINE_M`]) darkens into a lash line, which a closed eye shows. The lid's skin
/// is the texture's mean colour (linear light) over the texels a blink moves less than
/// [`LID_SKIN_M`]`.0` (the lid's seen skin beside them).
pub fn paint_lids(face: &mut RgbImage, lids: &[([[f64; 2]; 3], [f64; 3])]) {
    let t = face.width() as usize;
    if t == 0 || face.height() as usize != t || lids.is_empty() {
        return;
    }
    let mut moved = vec![f64::NAN; t * t];
    for (uv, d) in lids {
        rasterize_uv_triangle(*uv, t, |x, y, b| {
            moved[y * t + x] = b[0] * d[0] + b[1] * d[1] + b[2] * d[2];
        });
    }
    let linear: [f32; 256] = std::array::from_fn(|c| srgb_to_linear_u8(c as u8));
    let (mut sum, mut n) = ([0.0f64; 3], 0.0);
    for (p, &d) in face.pixels().zip(&moved) {
        if d < LID_SKIN_M.0 {
            for c in 0..3 {
                sum[c] += f64::from(linear[p.0[c] as usize]);
            }
            n += 1.0;
        }
    }
    if n == 0.0 {
        return;
    }
    let skin = sum.map(|s| s / n);
    let smoothstep = |(a, b): (f64, f64), d: f64| {
        let x = ((d - a) / (b - a)).clamp(0.0, 1.0);
        x * x * (3.0 - 2.0 * x)
    };
    for (p, &d) in face.pixels_mut().zip(&moved) {
        if d.is_nan() || d <= LID_SKIN_M.0 {
            continue;
        }
        let w = smoothstep(LID_SKIN_M, d);
        let shade = 1.0 - (1.0 - LASH_LINE_SHADE) * smoothstep(LASH_LINE_M, d);
        for c in 0..3 {
            let v = (1.0 - w) * f64::from(linear[p.0[c] as usize]) + w * shade * skin[c];
            p.0[c] = visage_mesh::color::linear_to_srgb_u8(v as f32);
        }
    }
}

/// The eyeball's colour at its UV `uv`: pupil, iris with radial streaks, the limbal ring,
/// then the sclera, a little redder toward the back.
fn eye_color(eye: &EyeLayout, uv: [f64; 2]) -> [f32; 3] {
    let d = [uv[0] - eye.front_uv[0], uv[1] - eye.front_uv[1]];
    let theta = (d[0] * d[0] + d[1] * d[1]).sqrt() / eye.uv_per_rad;
    if theta < eye.pupil_rad {
        return PUPIL;
    }
    if theta < eye.iris_rad - LIMBUS_WIDTH_RAD {
        let phi = d[1].atan2(d[0]);
        let r = (theta - eye.pupil_rad) / (eye.iris_rad - eye.pupil_rad);
        // Streaks, and a lighter ring around the pupil (the collarette).
        let streak = 1.0 + 0.25 * (IRIS_STREAKS * phi).sin() * (0.5 + 0.5 * (97.0 * phi).cos());
        let collarette = 1.0 + 0.5 * (-((r - 0.3) / 0.12).powi(2)).exp();
        return IRIS.map(|c| (c as f64 * streak * collarette) as f32);
    }
    if theta < eye.iris_rad {
        return LIMBUS;
    }
    let redden = ((theta - eye.iris_rad) / 1.2).clamp(0.0, 1.0) as f32;
    [
        SCLERA[0] * (1.0 - 0.1 * redden),
        SCLERA[1] * (1.0 - 0.3 * redden),
        SCLERA[2] * (1.0 - 0.35 * redden),
    ]
}

/// The face texture's most frequent colour (by 4-bit bins per channel; the mean of the bin),
/// linear RGB: the flat colour the texture fusion gives what the clip never saw, which is also
/// what borders the scalp (the face region's edge, the neck), so the two meet without a seam.
fn border_skin(face: &RgbImage, linear: &[f32; 256]) -> [f32; 3] {
    let bin =
        |p: &[u8; 3]| (p[0] as usize >> 4) << 8 | (p[1] as usize >> 4) << 4 | p[2] as usize >> 4;
    let mut counts = vec![0usize; 1 << 12];
    for p in face.pixels() {
        counts[bin(&p.0)] += 1;
    }
    let Some(mode) = (0..counts.len()).max_by_key(|&b| counts[b]) else {
        return crate::SKIN_ALBEDO;
    };
    if counts[mode] == 0 {
        return crate::SKIN_ALBEDO;
    }
    let mut sum = [0.0f64; 3];
    for p in face.pixels().filter(|p| bin(&p.0) == mode) {
        for c in 0..3 {
            sum[c] += f64::from(linear[p.0[c] as usize]);
        }
    }
    sum.map(|s| (s / counts[mode] as f64) as f32)
}

/// A deterministic value in [−1, 1] per integer cell.
fn hash_noise(i: u32, j: u32) -> f32 {
    let h = crate::mix_seed(u64::from(i) << 32 | u64::from(j));
    (h >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_land_in_their_own_tiles() {
        let face = Part::Face.atlas_uv([0.25, 0.75]);
        assert_eq!(face, [0.0625, 0.875]);
        // ICT's UDIM tiles: the teeth's u in [3, 4) keeps only its fraction.
        let teeth = Part::Teeth.atlas_uv([3.5, 0.5]);
        assert_eq!(teeth, [0.875, 0.75]);
        let eye = Part::Eye.atlas_uv([0.5, 0.5]);
        assert_eq!(eye, [0.125, 0.25]);
    }

    #[test]
    fn the_atlas_keeps_the_face_and_paints_an_eye() {
        let mut face = RgbImage::new(64, 64);
        for (i, j, p) in face.enumerate_pixels_mut() {
            *p = image::Rgb([(i * 4) as u8, (j * 4) as u8, 128]);
        }
        let eye = EyeLayout {
            front_uv: [0.5, 0.5],
            uv_per_rad: 0.25,
            iris_rad: 0.36,
            pupil_rad: 0.12,
        };
        let atlas = head_texture(&face, &eye).unwrap();
        assert_eq!((atlas.width(), atlas.height()), (256, 128));
        let lin = |c: u8| srgb_to_linear_u8(c);
        let got = atlas.texel(10, 20, visage_render::Wrap::Clamp);
        for (g, e) in got.iter().zip([lin(40), lin(80), lin(128)]) {
            assert!((g - e).abs() < 1e-4);
        }
        // The eye tile: pupil at the front, sclera far from it.
        let centre = atlas.texel(32, 64 + 32, visage_render::Wrap::Clamp);
        assert!(centre[0] < 0.02, "{centre:?}");
        let corner = atlas.texel(1, 64 + 1, visage_render::Wrap::Clamp);
        assert!(corner[0] > 0.3, "{corner:?}");
        assert!(head_texture(&RgbImage::new(4, 8), &eye).is_err());
    }

    #[test]
    fn lids_are_painted_with_the_skin_beside_them() {
        // A grey texture with a blue "eye" band across the middle; one quad over the whole UV
        // square, whose upper half a blink moves 8 mm and lower half not at all.
        let mut face = RgbImage::from_pixel(32, 32, image::Rgb([150, 120, 100]));
        for x in 0..32 {
            for y in 1..5 {
                face.put_pixel(x, y, image::Rgb([40, 60, 160]));
            }
        }
        let (lo, mid, hi) = (0.0, 0.5, 1.0);
        let lids = [
            ([[lo, mid], [hi, mid], [hi, hi]], [0.0, 0.0, 0.008]),
            ([[lo, mid], [hi, hi], [lo, hi]], [0.0, 0.008, 0.008]),
            ([[lo, lo], [hi, lo], [hi, mid]], [0.0, 0.0, 0.0]),
        ];
        paint_lids(&mut face, &lids);
        // The band near the top (moved over 5 mm) is skin now; the skin below is untouched.
        let p = face.get_pixel(16, 3).0;
        assert!(
            (i32::from(p[0]) - 150).abs() <= 2 && (i32::from(p[2]) - 100).abs() <= 2,
            "{p:?}"
        );
        assert_eq!(face.get_pixel(16, 28).0, [150, 120, 100]);
    }
}
