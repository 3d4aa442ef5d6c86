//! A folder of 16-bit PNG depth frames: listing, validation and the per-pixel survey that fixes
//! the sequence's meshing domain.

use std::path::{Path, PathBuf};

use visage_camera::{read_depth_png, DepthKind, DepthMap};
use visage_mesh::Mask;

use crate::FusionError;

/// Fraction of frames in which a pixel must have valid depth to be part of the meshing domain.
pub const DOMAIN_MAJORITY: f64 = 0.5;

/// The frames of a depth sequence, in name order.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthSequence {
    pub dir: PathBuf,
    pub frames: Vec<PathBuf>,
    /// value / `scale` = metres.
    pub scale: f64,
    pub kind: DepthKind,
}

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

impl DepthSequence {
    /// Lists the `*.png` files of `dir` sorted by name.
    pub fn open(dir: &Path, scale: f64, kind: DepthKind) -> Result<Self, FusionError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(FusionError::InvalidOption {
                name: "depth-scale",
                value: scale.to_string(),
                reason: "must be positive and finite",
            });
        }
        let entries = std::fs::read_dir(dir).map_err(|source| FusionError::Io {
            path: dir.to_owned(),
            source,
        })?;
        let mut frames = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|source| FusionError::Io {
                path: dir.to_owned(),
                source,
            })?;
            let path = entry.path();
            let is_png = path
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| e.eq_ignore_ascii_case("png"));
            if is_png && path.is_file() {
                frames.push(path);
            }
        }
        frames.sort();
        if frames.is_empty() {
            return Err(FusionError::NoFrames {
                dir: dir.to_owned(),
            });
        }
        Ok(DepthSequence {
            dir: dir.to_owned(),
            frames,
            scale,
            kind,
        })
    }

    /// Reads frame `index`.
    pub fn read(&self, index: usize) -> Result<DepthMap, FusionError> {
        Ok(read_depth_png(&self.frames[index], self.scale, self.kind)?)
    }

    /// Reads every frame once: checks that all are readable 16-bit PNGs of one size, and
    /// builds the domain mask and mean depth. Nothing is written, so a bad frame anywhere stops
    /// the run before any output exists.
    pub fn survey(&self, max_depth: f64) -> Result<SequenceSurvey, FusionError> {
        let first = self.read(0)?;
        let (width, height) = (first.width, first.height);
        let pixels = first.data.len();
        let mut count = vec![0u32; pixels];
        let mut sum = vec![0.0f64; pixels];
        let mut empty_frames = Vec::new();
        for index in 0..self.frames.len() {
            let frame = if index == 0 {
                first.clone()
            } else {
                self.read(index)?
            };
            if (frame.width, frame.height) != (width, height) {
                return Err(FusionError::FrameSize {
                    path: self.frames[index].clone(),
                    width: frame.width,
                    height: frame.height,
                    expected_width: width,
                    expected_height: height,
                });
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
        if empty_frames.len() == self.frames.len() {
            return Err(FusionError::NoValidDepth {
                dir: self.dir.clone(),
            });
        }
        let needed = (DOMAIN_MAJORITY * (self.frames.len() - empty_frames.len()) as f64).max(1.0);
        let domain = Mask {
            width,
            height,
            data: count.iter().map(|&c| c as f64 >= needed).collect(),
        };
        let mut mean_depth = DepthMap::empty(width, height, self.kind);
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
