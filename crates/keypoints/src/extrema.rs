//! Scale-space extrema of the differences of Gaussians: 26-neighbour extrema, sub-pixel and
//! sub-scale refinement by Newton steps on the quadratic model, contrast and edge-response
//! rejection (Lowe 2004 §4; the steps, scales and tests of OpenCV's `adjustLocalExtrema`).

use crate::scale_space::ScaleSpace;
use crate::GrayImage;

/// Pixels at each image side where no extremum is sought (OpenCV's `SIFT_IMG_BORDER`).
pub const IMAGE_BORDER: usize = 5;

/// Newton steps allowed before a candidate that keeps moving is dropped.
const MAX_INTERPOLATION_STEPS: usize = 5;

/// Intensities are 0–255; the refinement works in 0–1.
const INTENSITY_SCALE: f32 = 1.0 / 255.0;

/// Options of the detector's tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExtremaOptions {
    /// Intervals per octave, `s`.
    pub layers: usize,
    /// Lowe's contrast threshold on `|D(x̂)|` (0–1 intensities), divided by `s` as OpenCV does.
    pub contrast_threshold: f32,
    /// Lowe's `r`: principal-curvature ratio above which an edge response is dropped.
    pub edge_threshold: f32,
    /// `σ₀`, for the keypoint's size.
    pub sigma: f32,
}

/// A refined extremum, in its octave's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extremum {
    /// Octave index in the scale space (0 = the base, upsampled or not).
    pub octave: usize,
    /// Integer layer (1 … s) of the Gaussian level the orientation and descriptor read.
    pub layer: usize,
    /// Integer column and row after refinement, octave pixels.
    pub column: usize,
    /// See `column`.
    pub row: usize,
    /// Sub-pixel position, octave pixels.
    pub x: f32,
    /// See `x`.
    pub y: f32,
    /// Sub-layer offset in `[−0.5, 0.5]`.
    pub layer_offset: f32,
    /// Scale σ in octave pixels: `σ₀ 2^{(layer + offset)/s}`.
    pub scale: f32,
    /// `|D(x̂)|`, 0–1 intensities.
    pub response: f32,
}

/// All refined extrema of `space`.
pub fn find_extrema(space: &ScaleSpace, options: &ExtremaOptions, out: &mut Vec<Extremum>) {
    out.clear();
    let s = options.layers;
    // OpenCV's pre-threshold: floor(0.5 · contrast / s · 255).
    let threshold = (0.5 * options.contrast_threshold / s as f32 * 255.0).floor();
    let mut candidates = Vec::new();
    for (o, octave) in space.octaves[..space.octave_count].iter().enumerate() {
        let (w, h) = (octave.dogs[0].width(), octave.dogs[0].height());
        if w <= 2 * IMAGE_BORDER || h <= 2 * IMAGE_BORDER {
            continue;
        }
        for layer in 1..=s {
            let (prev, cur, next) = (
                &octave.dogs[layer - 1],
                &octave.dogs[layer],
                &octave.dogs[layer + 1],
            );
            for r in IMAGE_BORDER..h - IMAGE_BORDER {
                let row = cur.row(r);
                let rows = CandidateRows {
                    above: cur.row(r - 1),
                    row,
                    below: cur.row(r + 1),
                    previous: prev.row(r),
                    next: next.row(r),
                };
                mark_candidates(&rows, threshold, &mut candidates);
                for c in candidate_columns(&candidates, IMAGE_BORDER, w - IMAGE_BORDER) {
                    let v = row[c];
                    if !is_extremum(prev, cur, next, c, r, v) {
                        continue;
                    }
                    if let Some(e) = refine(&octave.dogs, o, layer, c, r, options) {
                        out.push(e);
                    }
                }
            }
        }
    }
}

/// The rows [`mark_candidates`] reads: a row of a difference image, its neighbours above and
/// below, and the same row of the levels below and above.
struct CandidateRows<'a> {
    above: &'a [f32],
    row: &'a [f32],
    below: &'a [f32],
    previous: &'a [f32],
    next: &'a [f32],
}

/// `marks[c] = 1` where `row[c]` passes the threshold and is an extremum of its six nearest
/// neighbours in space and scale (`marks[0]` and the last stay 0): a branch-free pass that
/// vectorises and leaves few samples for the full 26-neighbour test.
fn mark_candidates(rows: &CandidateRows, threshold: f32, marks: &mut Vec<u8>) {
    let n = rows.row.len();
    marks.clear();
    marks.resize(n, 0);
    if n < 3 {
        return;
    }
    let inner = 1..n - 1;
    let (left, centre, right) = (&rows.row[..n - 2], &rows.row[inner.clone()], &rows.row[2..]);
    let (above, below) = (&rows.above[inner.clone()], &rows.below[inner.clone()]);
    let (previous, next) = (&rows.previous[inner.clone()], &rows.next[inner]);
    for (k, m) in marks[1..n - 1].iter_mut().enumerate() {
        let v = centre[k];
        let around = [left[k], right[k], above[k], below[k], previous[k], next[k]];
        let maximum = around.iter().fold(v > threshold, |acc, &u| acc & (v >= u));
        let minimum = around.iter().fold(v < -threshold, |acc, &u| acc & (v <= u));
        *m = u8::from(maximum | minimum);
    }
}

/// The columns in `[from, to)` marked by [`mark_candidates`], read eight marks at a time as
/// one word (most words are zero).
fn candidate_columns(marks: &[u8], from: usize, to: usize) -> impl Iterator<Item = usize> + '_ {
    const WORD: usize = 8;
    marks[from..to]
        .chunks(WORD)
        .enumerate()
        .flat_map(move |(k, chunk)| {
            let mut word = [0u8; WORD];
            word[..chunk.len()].copy_from_slice(chunk);
            let mut bits = u64::from_le_bytes(word);
            std::iter::from_fn(move || {
                if bits == 0 {
                    return None;
                }
                let byte = bits.trailing_zeros() / 8;
                bits &= !(0xff << (8 * byte));
                Some(from + k * WORD + byte as usize)
            })
        })
}

/// Whether `v = cur(c, r)` is ≥ (a maximum) or ≤ (a minimum) all 26 neighbours.
#[inline]
fn is_extremum(
    prev: &GrayImage,
    cur: &GrayImage,
    next: &GrayImage,
    c: usize,
    r: usize,
    v: f32,
) -> bool {
    // The same level first: most candidates fail there.
    let levels = [(cur, true), (prev, false), (next, false)];
    if v > 0.0 {
        levels
            .iter()
            .all(|&(img, centre)| block_all(img, c, r, centre, |n| v >= n))
    } else {
        levels
            .iter()
            .all(|&(img, centre)| block_all(img, c, r, centre, |n| v <= n))
    }
}

/// Whether `test` holds for the 3 × 3 block of `img` around `(c, r)` (without its centre
/// when `skip_centre`).
#[inline]
fn block_all(
    img: &GrayImage,
    c: usize,
    r: usize,
    skip_centre: bool,
    test: impl Fn(f32) -> bool,
) -> bool {
    for dr in 0..3 {
        let row = &img.row(r + dr - 1)[c - 1..c + 2];
        for (dc, &n) in row.iter().enumerate() {
            if skip_centre && dr == 1 && dc == 1 {
                continue;
            }
            if !test(n) {
                return false;
            }
        }
    }
    true
}

/// Gradient and Hessian of D at an integer sample, in 0–1 intensities (central differences).
struct Quadratic {
    gradient: [f32; 3],
    hessian: [[f32; 3]; 3],
    value: f32,
}

fn quadratic(dogs: &[GrayImage], layer: usize, c: usize, r: usize) -> Quadratic {
    let (p, i, n) = (&dogs[layer - 1], &dogs[layer], &dogs[layer + 1]);
    let d1 = INTENSITY_SCALE * 0.5;
    let d2 = INTENSITY_SCALE;
    let cross = INTENSITY_SCALE * 0.25;
    let v = i.at(c, r);
    let gradient = [
        (i.at(c + 1, r) - i.at(c - 1, r)) * d1,
        (i.at(c, r + 1) - i.at(c, r - 1)) * d1,
        (n.at(c, r) - p.at(c, r)) * d1,
    ];
    let dxx = (i.at(c + 1, r) + i.at(c - 1, r) - 2.0 * v) * d2;
    let dyy = (i.at(c, r + 1) + i.at(c, r - 1) - 2.0 * v) * d2;
    let dss = (n.at(c, r) + p.at(c, r) - 2.0 * v) * d2;
    let dxy =
        (i.at(c + 1, r + 1) - i.at(c - 1, r + 1) - i.at(c + 1, r - 1) + i.at(c - 1, r - 1)) * cross;
    let dxs = (n.at(c + 1, r) - n.at(c - 1, r) - p.at(c + 1, r) + p.at(c - 1, r)) * cross;
    let dys = (n.at(c, r + 1) - n.at(c, r - 1) - p.at(c, r + 1) + p.at(c, r - 1)) * cross;
    Quadratic {
        gradient,
        hessian: [[dxx, dxy, dxs], [dxy, dyy, dys], [dxs, dys, dss]],
        value: v * INTENSITY_SCALE,
    }
}

/// `H x = b` by Cramer's rule; `None` when `H` is singular.
fn solve3(h: &[[f32; 3]; 3], b: [f32; 3]) -> Option<[f32; 3]> {
    let det3 = |m: &[[f32; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let det = det3(h);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut m = *h;
        for (row, &bv) in m.iter_mut().zip(&b) {
            row[k] = bv;
        }
        *xk = det3(&m) / det;
    }
    Some(x)
}

/// Newton steps from the sample `(c, r, layer)` to the extremum of the quadratic model, then
/// the contrast and edge tests; `None` when the candidate is rejected.
fn refine(
    dogs: &[GrayImage],
    octave: usize,
    mut layer: usize,
    mut c: usize,
    mut r: usize,
    options: &ExtremaOptions,
) -> Option<Extremum> {
    let s = options.layers;
    let (w, h) = (dogs[0].width(), dogs[0].height());
    let mut step = 0;
    let (q, offset) = loop {
        let q = quadratic(dogs, layer, c, r);
        let x = solve3(&q.hessian, q.gradient)?;
        let offset = x.map(|v| -v);
        if offset.iter().all(|v| v.abs() < 0.5) {
            break (q, offset);
        }
        if offset.iter().any(|v| v.abs() > (i32::MAX / 3) as f32) {
            return None;
        }
        let moved = |v: usize, d: f32| v as isize + d.round() as isize;
        let (nc, nr, nl) = (
            moved(c, offset[0]),
            moved(r, offset[1]),
            moved(layer, offset[2]),
        );
        let border = IMAGE_BORDER as isize;
        if nl < 1
            || nl > s as isize
            || nc < border
            || nc >= w as isize - border
            || nr < border
            || nr >= h as isize - border
        {
            return None;
        }
        (c, r, layer) = (nc as usize, nr as usize, nl as usize);
        step += 1;
        if step >= MAX_INTERPOLATION_STEPS {
            return None;
        }
    };
    let t: f32 = q.gradient.iter().zip(&offset).map(|(g, x)| g * x).sum();
    let contrast = q.value + 0.5 * t;
    if contrast.abs() * (s as f32) < options.contrast_threshold {
        return None;
    }
    let [[dxx, dxy, _], [_, dyy, _], _] = q.hessian;
    let trace = dxx + dyy;
    let det = dxx * dyy - dxy * dxy;
    let e = options.edge_threshold;
    if det <= 0.0 || trace * trace * e >= (e + 1.0) * (e + 1.0) * det {
        return None;
    }
    Some(Extremum {
        octave,
        layer,
        column: c,
        row: r,
        x: c as f32 + offset[0],
        y: r as f32 + offset[1],
        layer_offset: offset[2],
        scale: options.sigma * 2f32.powf((layer as f32 + offset[2]) / s as f32),
        response: contrast.abs(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidate_columns_lists_the_marked_ones_in_range() {
        let mut marks = vec![0u8; 37];
        for c in [0, 3, 8, 9, 15, 16, 30, 36] {
            marks[c] = 1;
        }
        let got: Vec<usize> = candidate_columns(&marks, 2, 36).collect();
        assert_eq!(got, vec![3, 8, 9, 15, 16, 30]);
    }

    #[test]
    fn solve3_inverts_a_symmetric_system() {
        let h = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let x = [0.3, -0.7, 1.1];
        let b: [f32; 3] = std::array::from_fn(|i| (0..3).map(|j| h[i][j] * x[j]).sum());
        let got = solve3(&h, b).unwrap();
        for k in 0..3 {
            assert!((got[k] - x[k]).abs() < 1e-5);
        }
        assert!(solve3(&[[0.0; 3]; 3], b).is_none());
    }
}
