//! How far a fitted shape is from a true one, once the one thing landmarks cannot see — a
//! uniform scale of the face about the camera — is taken out.

/// RMS distance between point sets `a` and `b` (same order, same frame) after the best uniform
/// scale of `a` about its centroid and a translation, and that scale. Both sets share their
/// orientation (e.g. two faces in the model frame), so no rotation is fitted.
///
/// # Panics
/// If `a` and `b` differ in length or are empty.
#[track_caller]
pub fn rms_after_scale(a: &[[f64; 3]], b: &[[f64; 3]]) -> (f64, f64) {
    assert!(
        a.len() == b.len() && !a.is_empty(),
        "point sets of different sizes"
    );
    let centroid = |v: &[[f64; 3]]| -> [f64; 3] {
        std::array::from_fn(|c| v.iter().map(|p| p[c]).sum::<f64>() / v.len() as f64)
    };
    let (ca, cb) = (centroid(a), centroid(b));
    let dot = |p: &[f64; 3], pc: [f64; 3], q: &[f64; 3], qc: [f64; 3]| -> f64 {
        (0..3).map(|c| (p[c] - pc[c]) * (q[c] - qc[c])).sum()
    };
    let s = a.iter().zip(b).map(|(p, q)| dot(p, ca, q, cb)).sum::<f64>()
        / a.iter().map(|p| dot(p, ca, p, ca)).sum::<f64>();
    let sq: f64 = a
        .iter()
        .zip(b)
        .map(|(p, q)| {
            (0..3)
                .map(|c| (s * (p[c] - ca[c]) - (q[c] - cb[c])).powi(2))
                .sum::<f64>()
        })
        .sum();
    ((sq / a.len() as f64).sqrt(), s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scaled_and_moved_copy_has_no_error() {
        let a = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 2.0, 1.0],
            [0.5, 0.5, 3.0],
        ];
        let b: Vec<[f64; 3]> = a.iter().map(|p| p.map(|c| 1.1 * c + 0.3)).collect();
        let (rms, s) = rms_after_scale(&a, &b);
        assert!(rms < 1e-12 && (s - 1.1).abs() < 1e-12);
        // The same points in another order are another shape.
        let (rms, _) = rms_after_scale(&a, &[a[1], a[0], a[3], a[2]]);
        assert!(rms > 0.5, "{rms}");
    }
}
