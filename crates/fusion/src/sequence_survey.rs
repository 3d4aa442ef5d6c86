//! The per-pixel survey of a depth sequence that fixes its meshing domain (the paper's design,
//! §4): the pixels valid in most frames, and their mean depth.

use std::path::{Path, PathBuf};

use visage_camera::DepthMap;
use visage_mesh::Mask;

use crate::FusionError;

/// Fraction of frames in which a pixel must have valid depth to be part of the meshing domain.
pub const DOMAIN_MAJORITY: f64 = 0.5;

/// What the whole sequence says about each pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceSurvey {
    pub width: u32,
    pub height: u32,
    /// Pixels valid in at least [`DOMAIN_MAJORITY`] of the frames: the meshing domain.
    pub domain: Mask,
    /// Per-pixel mean of the valid values (0 where never valid): the reference surface for
    /// refinement, depth-aware flips and the flatness ratio.
    pub mean_depth: DepthMap,
    /// Frames with no valid pixel at all.
    pub empty_frames: Vec<usize>,
}

impl SequenceSurvey {
    /// Reads every frame of the sequence in `dir` once (`read(i)` for frame `i` of `frames`,
    /// whose paths name it in errors; values beyond `max_depth` metres count as no depth):
    /// checks that all are of one size, and builds the domain mask and mean depth (of the
    /// first frame's kind). Nothing is written, so a bad frame anywhere stops the run before
    /// any output exists.
    ///
    /// `frames` is not empty: frame 0 is read first, whatever its count.
    ///
    /// # Errors
    /// What `read` returns, frames of different sizes, a sequence without any valid depth.
    pub fn new<E: From<FusionError>>(
        dir: &Path,
        frames: &[PathBuf],
        max_depth: f64,
        mut read: impl FnMut(usize) -> Result<DepthMap, E>,
    ) -> Result<Self, E> {
        let first = read(0)?;
        let (width, height) = (first.width, first.height);
        let pixels = first.data.len();
        let mut count = vec![0u32; pixels];
        let mut sum = vec![0.0f64; pixels];
        let mut empty_frames = Vec::new();
        for (index, path) in frames.iter().enumerate() {
            let frame = if index == 0 {
                first.clone()
            } else {
                read(index)?
            };
            if (frame.width, frame.height) != (width, height) {
                return Err(FusionError::FrameSize {
                    path: path.clone(),
                    width: frame.width,
                    height: frame.height,
                    expected_width: width,
                    expected_height: height,
                }
                .into());
            }
            let mut any = false;
            for (p, &d) in frame.data.iter().enumerate() {
                if DepthMap::is_valid(d) && (d as f64) <= max_depth {
                    count[p] += 1;
                    sum[p] += d as f64;
                    any = true;
                }
            }
            if !any {
                empty_frames.push(index);
            }
        }
        if empty_frames.len() == frames.len() {
            return Err(FusionError::NoValidDepth {
                dir: dir.to_owned(),
            }
            .into());
        }
        let needed = (DOMAIN_MAJORITY * (frames.len() - empty_frames.len()) as f64).max(1.0);
        let domain = Mask {
            width,
            height,
            data: count.iter().map(|&c| c as f64 >= needed).collect(),
        };
        let mut mean_depth = DepthMap::empty(width, height, first.kind);
        for ((m, &s), &c) in mean_depth.data.iter_mut().zip(&sum).zip(&count) {
            if c > 0 {
                *m = (s / c as f64) as f32;
            }
        }
        Ok(SequenceSurvey {
            width,
            height,
            domain,
            mean_depth,
            empty_frames,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use visage_camera::DepthKind;

    #[test]
    fn the_domain_is_the_majority_of_the_frames_with_depth() {
        // Pixel 0 valid in 3 of 3 frames, pixel 1 in 1 of 3, pixel 2 always beyond max_depth;
        // the fourth frame is empty and does not count.
        let maps: Vec<DepthMap> = [[1.0, 0.0, 9.0], [3.0, 2.0, 9.0], [2.0, 0.0, 9.0], [0.0; 3]]
            .iter()
            .map(|d| DepthMap {
                width: 3,
                height: 1,
                kind: DepthKind::Z,
                data: d.to_vec(),
            })
            .collect();
        let paths: Vec<PathBuf> = (0..4).map(|i| PathBuf::from(format!("{i}.png"))).collect();
        let survey = SequenceSurvey::new(Path::new("seq"), &paths, 5.0, |i| {
            Ok::<_, FusionError>(maps[i].clone())
        })
        .unwrap();
        assert_eq!(survey.domain.data, [true, false, false]);
        assert_eq!(survey.mean_depth.data, [2.0, 2.0, 0.0]);
        assert_eq!(survey.empty_frames, [3]);
    }
}
