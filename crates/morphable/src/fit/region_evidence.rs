//! Which landmarks count as evidence for which expressions: the lower face's landmarks — the
//! lips, the chin, the jaw line, the cheeks below the nose — do not drive the shapes of the
//! upper face (brows, eyes, nose, the cheeks' squint).
//!
//! ICT-FaceKit's upper-face shapes move the lower face too (`noseSneer` lifts the upper lip,
//! `cheekSquint` the mouth's corners), so a fit that lets every landmark vote reads speech —
//! lips and jaw moving in ways the model's mouth shapes do not quite match — as a sneer and a
//! squint: on the sample clip `lp_d18` `noseSneer` reached 0.28–0.29 (95th percentile) with
//! the lips, and `cheekSquintLeft` rested at 0.15 for most of the clip. With these landmarks
//! out of the upper shapes' evidence, the model's prediction at them leaves those shapes out
//! too (the fit stays one consistent least-squares problem), and a sneer's lifted lip is
//! explained by the mouth's own shapes (`mouthUpperUp`).

use super::LandmarkBasis;

/// Expression name prefixes of the upper face's shapes (ICT-FaceKit's names: `browDown_L`,
/// `eyeBlink_L`, `noseSneer_L`, `cheekSquint_L`, …; `cheekPuff` is the mouth's).
pub const UPPER_FACE_SHAPES: [&str; 4] = ["brow", "eye", "nose", "cheekSquint"];

/// FaceMesh's landmark at the base of the nose (the subnasale).
pub const NOSE_BASE: usize = 2;

/// A landmark belongs to the lower face when its neutral position lies more than this below
/// the nose's base (metres).
pub const LOWER_FACE_MARGIN_M: f64 = 0.002;

/// The landmarks of the lower face: neutral position (`basis`'s mean) more than
/// [`LOWER_FACE_MARGIN_M`] below [`NOSE_BASE`].
pub fn lower_face_landmarks(basis: &LandmarkBasis) -> Vec<usize> {
    let base = basis.mean[3 * NOSE_BASE + 1];
    (0..basis.landmark_count())
        .filter(|&j| basis.mean[3 * j + 1] < base - LOWER_FACE_MARGIN_M)
        .collect()
}

/// The expressions among `names` (the model's, in its order) that are the upper face's.
pub fn upper_face_expressions(names: &[String]) -> Vec<usize> {
    names
        .iter()
        .enumerate()
        .filter(|(_, name)| UPPER_FACE_SHAPES.iter().any(|p| name.starts_with(p)))
        .map(|(e, _)| e)
        .collect()
}

/// Keeps the upper face's expressions out of the lower face's landmarks in `basis`.
pub fn keep_evidence_local(basis: &mut LandmarkBasis, expression_names: &[String]) {
    let upper = upper_face_expressions(expression_names);
    for j in lower_face_landmarks(basis) {
        basis.exclude(j, &upper);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FaceModel;

    #[test]
    fn the_lips_cannot_drive_a_sneer_but_the_nose_can() {
        let model = FaceModel::embedded();
        let mut basis = LandmarkBasis::new(&model);
        let sneer = model.expression_index("noseSneer_L").unwrap();
        let jaw = model.expression_index("jawOpen").unwrap();
        let column = |b: &LandmarkBasis, j: usize, e: usize| -> f64 {
            (0..3)
                .map(|c| b.row(3 * j + c)[b.identity_count + e].abs())
                .sum()
        };
        // The upper lip's centre (0) and a nose wing (129, at the level of the nostrils).
        let (lip, wing) = (0, 129);
        assert!(
            column(&basis, lip, sneer) > 1e-4,
            "the model's sneer lifts the lip"
        );
        keep_evidence_local(&mut basis, &model.expression_names);
        assert_eq!(column(&basis, lip, sneer), 0.0);
        assert!(
            column(&basis, lip, jaw) > 1e-4,
            "the mouth's own shapes stay"
        );
        assert!(
            column(&basis, wing, sneer) > 1e-4,
            "the nose stays the sneer's evidence"
        );
        // The exclusion holds when a landmark's rows are replaced (a sliding contour point).
        let rows: Vec<Vec<f64>> = (0..3).map(|c| basis.row(3 * lip + c).to_vec()).collect();
        let mut moved = rows.clone();
        moved[1][basis.identity_count + sneer] = 0.01;
        basis.set_landmark(lip, [0.0; 3], [&moved[0], &moved[1], &moved[2]]);
        assert_eq!(column(&basis, lip, sneer), 0.0);
    }
}
