//! Weighted non-maximum suppression as MediaPipe's `NonMaxSuppressionCalculator` with
//! `algorithm: WEIGHTED` (the BlazeFace post-processing).

use crate::Detection;

/// IoU above which a detection is merged into a higher-scoring one (MediaPipe's
/// `min_suppression_threshold` for face detection).
pub const NMS_IOU_THRESHOLD: f32 = 0.3;

/// Weighted NMS: repeatedly takes the highest-scoring remaining detection, gathers every
/// remaining detection whose IoU with it exceeds `iou_threshold`, and replaces the group by the
/// score-weighted mean of their boxes and keypoints (keeping the top score). Output is sorted by
/// score, highest first.
pub fn weighted_nms(mut candidates: Vec<Detection>, iou_threshold: f32) -> Vec<Detection> {
    candidates.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut out = Vec::new();
    while let Some(top) = candidates.first().copied() {
        let (group, rest): (Vec<Detection>, Vec<Detection>) = candidates
            .into_iter()
            .partition(|d| top.iou(d) > iou_threshold || *d == top);
        candidates = rest;
        let total: f32 = group.iter().map(|d| d.score).sum();
        if total <= 0.0 {
            out.push(top);
            continue;
        }
        let mut merged = Detection {
            score: top.score,
            center: [0.0; 2],
            size: [0.0; 2],
            keypoints: [[0.0; 2]; 6],
        };
        // MediaPipe averages the box corners; averaging centre and size is the same affine mean.
        for d in &group {
            let w = d.score / total;
            for k in 0..2 {
                merged.center[k] += w * d.center[k];
                merged.size[k] += w * d.size[k];
            }
            for (m, p) in merged.keypoints.iter_mut().zip(&d.keypoints) {
                m[0] += w * p[0];
                m[1] += w * p[1];
            }
        }
        out.push(merged);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn det(score: f32, cx: f32, cy: f32, s: f32) -> Detection {
        Detection {
            score,
            center: [cx, cy],
            size: [s, s],
            keypoints: [[cx, cy]; 6],
        }
    }

    #[test]
    fn merges_overlaps_and_keeps_separate_faces() {
        let dets = vec![
            det(0.6, 0.52, 0.5, 0.2),
            det(0.9, 0.5, 0.5, 0.2),
            det(0.8, 0.1, 0.1, 0.1),
        ];
        let out = weighted_nms(dets, NMS_IOU_THRESHOLD);
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].score, 0.9);
        let expected = (0.9 * 0.5 + 0.6 * 0.52) / 1.5;
        assert!((out[0].center[0] - expected).abs() < 1e-6);
        assert_eq!(out[1].center, [0.1, 0.1]);
        assert!(weighted_nms(Vec::new(), 0.3).is_empty());
    }
}
