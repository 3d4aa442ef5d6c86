//! The model restricted to the tracked landmarks: for landmark j (a point of the model surface
//! and its offset, `Σ β_k X_{t_k} + o_j`), its neutral position `L̄_j` and the rows of every mode at it, so that
//! `L_j(p, e) = L̄_j + U_j p + B_j e` is a few hundred numbers per landmark instead of a whole
//! mesh.

use crate::FaceModel;

/// `L̄` (3 per landmark) and the basis `[U | B]` (3 rows per landmark, identity columns
/// first, then expressions), model frame, metres.
#[derive(Clone, Debug)]
pub struct LandmarkBasis {
    /// `3·#L`: x, y, z of landmark 0, then landmark 1, ….
    pub mean: Vec<f64>,
    /// `3·#L × (#identity + #expression)`, row-major (a landmark coordinate's row is
    /// contiguous: the fit takes dot products with it).
    pub modes: Vec<f64>,
    pub identity_count: usize,
    pub expression_count: usize,
    /// Per landmark, the expressions kept out of its rows ([`LandmarkBasis::exclude`]).
    excluded: Vec<Vec<usize>>,
}

impl LandmarkBasis {
    /// The basis of `model`'s landmarks.
    pub fn new(model: &FaceModel) -> LandmarkBasis {
        let (n_id, n_ex) = (model.identity.len(), model.expressions.len());
        let rows = 3 * model.landmarks.len();
        let mut mean = vec![0.0; rows];
        let m_total = n_id + n_ex;
        let mut modes = vec![0.0; rows * m_total];
        let all_modes = model.identity.iter().chain(&model.expressions);
        for (j, l) in model.landmarks.iter().enumerate() {
            for c in 0..3 {
                mean[3 * j + c] = model.landmark_offsets.get(j).map_or(0.0, |o| o[c] as f64);
            }
            for (&v, &b) in l.triangle.iter().zip(&l.bary) {
                for c in 0..3 {
                    mean[3 * j + c] += b * model.neutral[v as usize][c] as f64;
                }
            }
        }
        for (m, mode) in all_modes.enumerate() {
            for (j, l) in model.landmarks.iter().enumerate() {
                for (&v, &b) in l.triangle.iter().zip(&l.bary) {
                    for c in 0..3 {
                        modes[(3 * j + c) * m_total + m] += b * mode[v as usize][c] as f64;
                    }
                }
            }
        }
        LandmarkBasis {
            mean,
            modes,
            identity_count: n_id,
            expression_count: n_ex,
            excluded: vec![Vec::new(); model.landmarks.len()],
        }
    }

    pub fn landmark_count(&self) -> usize {
        self.mean.len() / 3
    }

    /// Modes (identity then expression).
    pub fn mode_count(&self) -> usize {
        self.identity_count + self.expression_count
    }

    /// Row `3j + c` of `[U | B]`: coordinate c of landmark j per unit of each mode.
    pub fn row(&self, row: usize) -> &[f64] {
        let m = self.mode_count();
        &self.modes[row * m..(row + 1) * m]
    }

    /// Makes landmark j the point `mean` moved by `rows` (x, y, z rows of `[U | B]`).
    ///
    /// # Panics
    /// If a row does not have one entry per mode.
    #[track_caller]
    pub fn set_landmark(&mut self, j: usize, mean: [f64; 3], rows: [&[f64]; 3]) {
        let m = self.mode_count();
        for (c, row) in rows.iter().enumerate() {
            assert_eq!(row.len(), m, "one entry per mode");
            self.mean[3 * j + c] = mean[c];
            self.modes[(3 * j + c) * m..(3 * j + c + 1) * m].copy_from_slice(row);
        }
        self.clear_excluded(j);
    }

    /// Keeps `expressions` (indices among the expressions) out of landmark j: its rows of them
    /// are 0 from now on, also after [`LandmarkBasis::set_landmark`]. The landmark then neither
    /// moves with them nor counts as their evidence.
    pub fn exclude(&mut self, j: usize, expressions: &[usize]) {
        self.excluded[j].extend_from_slice(expressions);
        self.clear_excluded(j);
    }

    fn clear_excluded(&mut self, j: usize) {
        let m = self.mode_count();
        for c in 0..3 {
            for &e in &self.excluded[j] {
                self.modes[(3 * j + c) * m + self.identity_count + e] = 0.0;
            }
        }
    }

    /// All landmarks at identity `p` and expression `e` into `out` (#L, model frame).
    ///
    /// # Panics
    /// If `p` and `e` do not have one weight per mode.
    #[track_caller]
    pub fn landmarks(&self, p: &[f64], e: &[f64], out: &mut [[f64; 3]]) {
        assert!(p.len() == self.identity_count && e.len() == self.expression_count);
        for (j, o) in out.iter_mut().enumerate() {
            *o = self.landmark(j, p, e);
        }
    }

    /// Landmark j at identity `p` and expression `e` (model frame).
    pub fn landmark(&self, j: usize, p: &[f64], e: &[f64]) -> [f64; 3] {
        std::array::from_fn(|c| {
            let (rp, re) = self.row(3 * j + c).split_at(self.identity_count);
            self.mean[3 * j + c] + dot(rp, p) + dot(re, e)
        })
    }

    /// The largest displacement (metres) any single expression at weight 1 gives landmark j:
    /// small for the rigid parts of the face.
    pub fn expression_motion(&self, j: usize) -> f64 {
        (0..self.expression_count)
            .map(|m| {
                (0..3)
                    .map(|c| self.row(3 * j + c)[self.identity_count + m].powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(0.0, f64::max)
    }
}

/// `Σ a_i b_i`, in four independent sums so the loop vectorises.
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    s[0] + s[1] + s[2] + s[3] + tail
}
