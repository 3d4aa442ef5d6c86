//! The constraints file of a fairing (`visage fair --constraints`):
//! `{"constraints": [{"vertex": i, "position": [x, y, z], "weight": w}…]}`, positions in the
//! mesh's units (metres), weights in [0, 1]. Each listed vertex is pulled to its position with
//! its weight in [`fair`](crate::fair)'s positional term γ ∫ w |v − p|² dA.

use std::path::{Path, PathBuf};

use serde::Deserialize;

/// A constraints file's constraints, checked against the mesh they are for.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct FairingConstraints {
    /// The constraints, in the file's order (a vertex listed twice takes the last).
    pub constraints: Vec<FairingConstraint>,
}

/// One vertex pulled to a position.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
pub struct FairingConstraint {
    /// The vertex index.
    pub vertex: usize,
    /// Where it is pulled (metres).
    pub position: [f64; 3],
    /// The weight w of its positional term, in [0, 1].
    pub weight: f64,
}

/// A constraints file that cannot be used; `reason` says why.
#[derive(Debug, thiserror::Error)]
#[error("{}: {reason}", path.display())]
pub struct ConstraintsFileError {
    pub path: PathBuf,
    pub reason: String,
}

impl FairingConstraints {
    /// Reads a constraints file's text for a mesh of `vertices` vertices; `path` names it in
    /// errors.
    ///
    /// # Errors
    /// Not the file's JSON; the first constraint whose vertex is not below `vertices` or whose
    /// weight lies outside [0, 1].
    pub fn parse_json(
        text: &str,
        path: &Path,
        vertices: usize,
    ) -> Result<FairingConstraints, ConstraintsFileError> {
        let bad = |reason: String| ConstraintsFileError {
            path: path.to_owned(),
            reason,
        };
        let file: FairingConstraints = serde_json::from_str(text.trim_start_matches('\u{feff}'))
            .map_err(|e| bad(format!("not a constraints file: {e}")))?;
        for (k, c) in file.constraints.iter().enumerate() {
            if c.vertex >= vertices || !(0.0..=1.0).contains(&c.weight) {
                return Err(bad(format!(
                    "constraint {k}: vertex {} of {vertices}, weight {} (must lie in [0, 1])",
                    c.vertex, c.weight
                )));
            }
        }
        Ok(file)
    }

    /// Sets each listed vertex's target position and weight (`targets` and `weights` are #V
    /// long: the positions and weights of the unlisted vertices stay).
    ///
    /// # Panics
    /// If a constraint's vertex is not below `targets.len()` or `weights.len()` (the
    /// constraints were checked for another mesh).
    #[track_caller]
    pub fn apply(&self, targets: &mut [[f64; 3]], weights: &mut [f64]) {
        for c in &self.constraints {
            targets[c.vertex] = c.position;
            weights[c.vertex] = c.weight;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = r#"{"constraints": [
        {"vertex": 1, "position": [0.0, 0.5, 1.0], "weight": 0.25},
        {"vertex": 1, "position": [1.0, 2.0, 3.0], "weight": 1.0}
    ]}"#;

    #[test]
    fn listed_vertices_take_the_last_constraint_and_the_rest_stay() {
        let c = FairingConstraints::parse_json(FILE, Path::new("c.json"), 3).unwrap();
        let mut targets = [[0.0; 3]; 3];
        let mut weights = [0.5; 3];
        c.apply(&mut targets, &mut weights);
        assert_eq!(targets, [[0.0; 3], [1.0, 2.0, 3.0], [0.0; 3]]);
        assert_eq!(weights, [0.5, 1.0, 0.5]);
    }

    #[test]
    fn errors_name_the_file_and_the_constraint() {
        let e = FairingConstraints::parse_json(FILE, Path::new("c.json"), 1).unwrap_err();
        assert_eq!(
            e.to_string(),
            "c.json: constraint 0: vertex 1 of 1, weight 0.25 (must lie in [0, 1])"
        );
        let e = FairingConstraints::parse_json("[]", Path::new("c.json"), 1).unwrap_err();
        assert!(e
            .to_string()
            .starts_with("c.json: not a constraints file: "));
    }
}
