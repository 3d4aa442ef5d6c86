//! The matches file `visage match` writes: `{"keypoints_a", "keypoints_b", "matches": [{"a",
//! "b", "distance", "a_xy", "b_xy"}…]}`, positions in OpenCV's pixel conventions
//! ([`Keypoint`](crate::Keypoint)).

use serde::{Deserialize, Serialize};

use crate::keypoint::Features;
use crate::matching::Match;

/// Two images' matches as the file holds them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MatchesFile {
    /// Keypoints found in the first image.
    pub keypoints_a: usize,
    /// Keypoints found in the second image.
    pub keypoints_b: usize,
    /// The matches, in the order [`match_descriptors`](crate::match_descriptors) gave them.
    pub matches: Vec<MatchRecord>,
}

/// One match with both keypoints' positions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MatchRecord {
    /// Keypoint index in the first image.
    pub a: usize,
    /// Keypoint index in the second image.
    pub b: usize,
    /// Descriptor distance (L2 over the bytes).
    pub distance: f32,
    /// Position in the first image, pixels.
    pub a_xy: [f32; 2],
    /// Position in the second image, pixels.
    pub b_xy: [f32; 2],
}

impl MatchesFile {
    /// The file of `matches` between `a` (the query side) and `b` (the train side).
    ///
    /// # Panics
    /// If a match indexes past `a`'s or `b`'s keypoints (they were not matched on these).
    #[track_caller]
    pub fn new(a: &Features, b: &Features, matches: &[Match]) -> MatchesFile {
        MatchesFile {
            keypoints_a: a.len(),
            keypoints_b: b.len(),
            matches: matches
                .iter()
                .map(|m| {
                    let (p, q) = (&a.keypoints[m.query], &b.keypoints[m.train]);
                    MatchRecord {
                        a: m.query,
                        b: m.train,
                        distance: m.distance,
                        a_xy: [p.x, p.y],
                        b_xy: [q.x, q.y],
                    }
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Keypoint;

    fn features(points: &[[f32; 2]]) -> Features {
        Features {
            keypoints: points
                .iter()
                .map(|p| Keypoint {
                    x: p[0],
                    y: p[1],
                    size: 4.0,
                    angle: 0.0,
                    response: 0.1,
                    octave: 0,
                })
                .collect(),
            descriptors: vec![[0; crate::DESCRIPTOR_LEN]; points.len()],
        }
    }

    /// The file's text is what `visage match` wrote before the schema moved here: field
    /// order and names are pinned.
    #[test]
    fn a_match_names_both_keypoints_and_their_positions() {
        let a = features(&[[1.0, 2.0], [3.5, 4.0]]);
        let b = features(&[[7.0, 8.25]]);
        let m = Match {
            query: 1,
            train: 0,
            distance: 12.5,
        };
        let file = MatchesFile::new(&a, &b, &[m]);
        assert_eq!(
            serde_json::to_string(&file).unwrap(),
            r#"{"keypoints_a":2,"keypoints_b":1,"matches":[{"a":1,"b":0,"distance":12.5,"a_xy":[3.5,4.0],"b_xy":[7.0,8.25]}]}"#
        );
    }
}
