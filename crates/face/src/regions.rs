//! Regions of MediaPipe's 468 face landmarks, for figures that show where on the face an
//! error or a lag lives (the mouth moves fastest). The index sets are MediaPipe's drawing
//! connections: lips (outer and inner contours), the eyes' contours and the face oval.

/// A part of the face, as a set of landmark indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceRegion {
    /// Both lip contours, outer and inner.
    Lips,
    /// The inner lip contour (the mouth's opening), a subset of [`FaceRegion::Lips`].
    InnerLips,
    /// Both eyes' contours (the lids).
    Eyes,
    /// The face oval (jaw line, temples, forehead).
    Contour,
    /// Every landmark in none of lips, eyes and contour (nose, cheeks, brows).
    Rest,
}

const INNER_LIPS: [usize; 20] = [
    78, 95, 88, 178, 87, 14, 317, 402, 318, 324, 308, 191, 80, 81, 82, 13, 312, 311, 310, 415,
];
const OUTER_LIPS: [usize; 20] = [
    61, 146, 91, 181, 84, 17, 314, 405, 321, 375, 291, 185, 40, 39, 37, 0, 267, 269, 270, 409,
];
const EYES: [usize; 32] = [
    263, 249, 390, 373, 374, 380, 381, 382, 362, 466, 388, 387, 386, 385, 384, 398, // left
    33, 7, 163, 144, 145, 153, 154, 155, 133, 246, 161, 160, 159, 158, 157, 173, // right
];
const CONTOUR: [usize; 36] = [
    10, 338, 297, 332, 284, 251, 389, 356, 454, 323, 361, 288, 397, 365, 379, 378, 400, 377, 152,
    148, 176, 149, 150, 136, 172, 58, 132, 93, 234, 127, 162, 21, 54, 103, 67, 109,
];

impl FaceRegion {
    /// Every region, in report order.
    pub const ALL: [FaceRegion; 5] = [
        FaceRegion::Lips,
        FaceRegion::InnerLips,
        FaceRegion::Eyes,
        FaceRegion::Contour,
        FaceRegion::Rest,
    ];

    /// The region's name in reports (`snake_case`).
    pub fn name(self) -> &'static str {
        match self {
            FaceRegion::Lips => "lips",
            FaceRegion::InnerLips => "inner_lips",
            FaceRegion::Eyes => "eyes",
            FaceRegion::Contour => "contour",
            FaceRegion::Rest => "rest",
        }
    }

    /// The region's landmark indices (ascending).
    pub fn landmarks(self) -> Vec<usize> {
        let mut v: Vec<usize> = match self {
            FaceRegion::Lips => INNER_LIPS.iter().chain(&OUTER_LIPS).copied().collect(),
            FaceRegion::InnerLips => INNER_LIPS.to_vec(),
            FaceRegion::Eyes => EYES.to_vec(),
            FaceRegion::Contour => CONTOUR.to_vec(),
            FaceRegion::Rest => (0..crate::NUM_LANDMARKS)
                .filter(|i| {
                    !INNER_LIPS.contains(i)
                        && !OUTER_LIPS.contains(i)
                        && !EYES.contains(i)
                        && !CONTOUR.contains(i)
                })
                .collect(),
        };
        v.sort_unstable();
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_partition_the_landmarks() {
        let mut seen = vec![0; crate::NUM_LANDMARKS];
        for r in FaceRegion::ALL {
            if r == FaceRegion::InnerLips {
                continue;
            }
            for i in r.landmarks() {
                seen[i] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n == 1));
        let lips = FaceRegion::Lips.landmarks();
        assert!(FaceRegion::InnerLips
            .landmarks()
            .iter()
            .all(|i| lips.contains(i)));
        assert_eq!(lips.len(), 40);
    }
}
