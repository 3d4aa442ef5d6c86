//! RGB-D recordings on disk: colour frames and depth maps with their timestamps, associated
//! frame by frame.
//!
//! Two layouts:
//! - **TUM RGB-D** (Sturm et al. 2012): `rgb.txt` and `depth.txt` list `timestamp filename`
//!   per line (`#` starts a comment; file names relative to the folder), depth as 16-bit PNG
//!   with 5000 units per metre, z-depth, already registered to the colour camera.
//! - **A pair of folders** `rgb/` and `depth/` (PNG or JPEG colour, 16-bit PNG depth; default
//!   1000 units per metre, i.e. millimetres, as RealSense and Kinect exports write them): when
//!   every file name is a number, it is the timestamp in seconds; otherwise the two folders
//!   pair up in name order and must hold as many files each.
//!
//! Association, as the TUM benchmark's `associate.py` does it: among all (colour, depth) pairs
//! closer in time than [`RgbdOptions::max_time_difference_s`], the closest pairs are taken first
//! and each frame is used at most once. Every colour frame stays in the recording; one without a
//! depth map within the limit has none (the fusion carries the surface through it).

use std::path::{Path, PathBuf};

use visage_camera::{read_depth_png, DepthKind, DepthMap};

use crate::{
    mask_depth_edges, DepthError, DepthProvider, DepthRequest, EdgeMask, ProvidedDepth,
    Registration,
};

/// TUM RGB-D's depth scale: 5000 units per metre.
pub const TUM_DEPTH_SCALE: f64 = 5000.0;
/// A folder pair's default depth scale: millimetres.
pub const FOLDER_DEPTH_SCALE: f64 = 1000.0;
/// Largest time between a colour frame and its depth map (TUM's `associate.py`: 20 ms).
pub const MAX_TIME_DIFFERENCE_S: f64 = 0.02;

/// Which layout a recording has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RgbdLayout {
    Tum,
    Folders,
}

/// How a recording is read.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbdOptions {
    /// Depth units per metre (default: the layout's).
    pub depth_scale: Option<f64>,
    pub max_time_difference_s: f64,
    /// Register the depth to the colour camera (`None`: the depth is registered already).
    pub registration: Option<Registration>,
    /// Mask flying pixels and hole rims (`None`: every sensor value is used).
    pub edges: Option<EdgeMask>,
}

impl Default for RgbdOptions {
    fn default() -> Self {
        RgbdOptions {
            depth_scale: None,
            max_time_difference_s: MAX_TIME_DIFFERENCE_S,
            registration: None,
            edges: Some(EdgeMask::default()),
        }
    }
}

/// One colour frame and the depth map associated with it.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbdFrame {
    pub color: PathBuf,
    /// Seconds (`None`: a folder pair without timestamps).
    pub time_s: Option<f64>,
    pub depth: Option<PathBuf>,
    pub depth_time_s: Option<f64>,
}

/// An RGB-D recording, its frames in colour-time order.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbdRecording {
    pub dir: PathBuf,
    pub layout: RgbdLayout,
    pub frames: Vec<RgbdFrame>,
    /// Depth units per metre.
    pub depth_scale: f64,
    pub registration: Option<Registration>,
    pub edges: Option<EdgeMask>,
    /// Depth maps no colour frame was associated with.
    pub unmatched_depth: usize,
}

impl RgbdRecording {
    /// Reads the recording's lists (not its images).
    ///
    /// # Errors
    /// A folder that is neither layout, unreadable or malformed lists (the line is named), no
    /// colour frames, folders that cannot be paired, a scale that is not positive.
    pub fn open(dir: &Path, options: &RgbdOptions) -> Result<RgbdRecording, DepthError> {
        let bad = |path: &Path, reason: String| DepthError::Recording {
            path: path.to_owned(),
            reason,
        };
        if !dir.is_dir() {
            return Err(bad(dir, "not a folder".into()));
        }
        let (layout, color, depth) = if dir.join("rgb.txt").is_file() {
            let color = read_list(&dir.join("rgb.txt"), dir)?;
            let depth_list = dir.join("depth.txt");
            if !depth_list.is_file() {
                return Err(bad(
                    dir,
                    "has rgb.txt but no depth.txt (TUM RGB-D layout)".into(),
                ));
            }
            (RgbdLayout::Tum, color, read_list(&depth_list, dir)?)
        } else if dir.join("rgb").is_dir() && dir.join("depth").is_dir() {
            let color = list_folder(&dir.join("rgb"), &["png", "jpg", "jpeg"])?;
            let depth = list_folder(&dir.join("depth"), &["png"])?;
            (RgbdLayout::Folders, color, depth)
        } else {
            return Err(bad(
                dir,
                "not an RGB-D recording: expected rgb.txt and depth.txt (TUM RGB-D) or the \
                 folders rgb/ and depth/"
                    .into(),
            ));
        };
        if color.is_empty() {
            return Err(bad(dir, "no colour frames".into()));
        }
        let depth_scale = options.depth_scale.unwrap_or(match layout {
            RgbdLayout::Tum => TUM_DEPTH_SCALE,
            RgbdLayout::Folders => FOLDER_DEPTH_SCALE,
        });
        if !(depth_scale.is_finite() && depth_scale > 0.0) {
            return Err(DepthError::InvalidOption {
                name: "--depth-scale",
                value: depth_scale.to_string(),
                reason: "must be a positive number of units per metre",
            });
        }
        let timed = color.iter().chain(&depth).all(|(t, _)| t.is_some());
        let (frames, unmatched_depth) = if timed {
            associate(&color, &depth, options.max_time_difference_s)
        } else if color.len() == depth.len() {
            let frames = color
                .into_iter()
                .zip(depth)
                .map(|((_, c), (_, d))| RgbdFrame {
                    color: c,
                    time_s: None,
                    depth: Some(d),
                    depth_time_s: None,
                })
                .collect();
            (frames, 0)
        } else {
            return Err(bad(
                dir,
                format!(
                    "rgb/ holds {} frames and depth/ {}: without timestamps in the file names \
                     (seconds, e.g. 1305031102.175304.png) they pair only in name order, one \
                     for one",
                    color.len(),
                    depth.len()
                ),
            ));
        };
        Ok(RgbdRecording {
            dir: dir.to_owned(),
            layout,
            frames,
            depth_scale,
            registration: options.registration,
            edges: options.edges,
            unmatched_depth,
        })
    }

    /// Colour frames with a depth map.
    pub fn associated(&self) -> usize {
        self.frames.iter().filter(|f| f.depth.is_some()).count()
    }

    /// The frame rate from the colour timestamps (the median interval), if they exist.
    pub fn frame_rate(&self) -> Option<f64> {
        let times: Vec<f64> = self.frames.iter().filter_map(|f| f.time_s).collect();
        let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        if steps.is_empty() {
            return None;
        }
        steps.sort_by(f64::total_cmp);
        let median = steps[steps.len() / 2];
        (median > 0.0).then(|| 1.0 / median)
    }

    /// Frame `index`'s depth map in metres (z), edges masked and registered to the colour
    /// camera as set up; `None` when no depth map was associated with it.
    ///
    /// # Errors
    /// An index past the recording, an unreadable or malformed depth image, a map of another
    /// size than the depth camera's.
    pub fn depth(&self, index: usize) -> Result<Option<DepthMap>, DepthError> {
        let frame = self
            .frames
            .get(index)
            .ok_or_else(|| DepthError::Recording {
                path: self.dir.clone(),
                reason: format!(
                    "frame {index} asked for; the recording has {}",
                    self.frames.len()
                ),
            })?;
        let Some(path) = &frame.depth else {
            return Ok(None);
        };
        let mut map = read_depth_png(path, self.depth_scale, DepthKind::Z)?;
        if let Some(edges) = &self.edges {
            mask_depth_edges(&mut map, edges);
        }
        if let Some(registration) = &self.registration {
            map = registration
                .register(&map)
                .map_err(|e| DepthError::Recording {
                    path: path.clone(),
                    reason: e.to_string(),
                })?;
        }
        Ok(Some(map))
    }
}

impl DepthProvider for RgbdRecording {
    /// The recording's folder.
    fn describe(&self) -> String {
        self.dir.display().to_string()
    }

    /// The map associated with colour frame `request.index`, checked against the camera; an
    /// empty map when none was associated with it.
    fn depth_map(&mut self, request: DepthRequest<'_>) -> Result<ProvidedDepth, DepthError> {
        let k = request.k;
        let map = match self
            .depth(request.index)
            .map_err(|e| DepthError::on_frame(request.source, "depth", e))?
        {
            Some(map) => {
                k.check_size(map.width, map.height).map_err(|e| {
                    DepthError::on_frame(request.source, "depth map of the recording", e)
                })?;
                map
            }
            None => DepthMap::empty(k.width, k.height, DepthKind::Z),
        };
        Ok(ProvidedDepth::read(map))
    }
}

/// A TUM list file (see [`parse_tum_list`]).
fn read_list(path: &Path, dir: &Path) -> Result<Vec<(Option<f64>, PathBuf)>, DepthError> {
    let text = std::fs::read_to_string(path).map_err(|source| DepthError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_tum_list(&text, path, dir)
}

/// A TUM list's text (`path`: the file it came from, named in errors): `timestamp filename`
/// per line (more columns are ignored), `#` comments, file names relative to `dir`; sorted by
/// time.
///
/// # Errors
/// A line without two columns, or a first column that is not a finite number of seconds.
pub fn parse_tum_list(
    text: &str,
    path: &Path,
    dir: &Path,
) -> Result<Vec<(Option<f64>, PathBuf)>, DepthError> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut parts = line.split_whitespace();
        let (Some(t), Some(file)) = (parts.next(), parts.next()) else {
            return Err(DepthError::Recording {
                path: path.to_owned(),
                reason: format!("line {}: expected \"timestamp filename\"", n + 1),
            });
        };
        let t: f64 = t
            .parse()
            .ok()
            .filter(|t: &f64| t.is_finite())
            .ok_or_else(|| DepthError::Recording {
                path: path.to_owned(),
                reason: format!("line {}: {t:?} is not a timestamp in seconds", n + 1),
            })?;
        out.push((Some(t), dir.join(file)));
    }
    out.sort_by(|a, b| a.0.unwrap_or(0.0).total_cmp(&b.0.unwrap_or(0.0)));
    Ok(out)
}

/// A folder's files with these extensions in name order, each with its name as a timestamp
/// when it is a number.
fn list_folder(dir: &Path, extensions: &[&str]) -> Result<Vec<(Option<f64>, PathBuf)>, DepthError> {
    let entries = std::fs::read_dir(dir).map_err(|source| DepthError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let mut paths: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| extensions.iter().any(|x| x.eq_ignore_ascii_case(e)))
        })
        .collect();
    paths.sort();
    let mut out: Vec<(Option<f64>, PathBuf)> = paths
        .into_iter()
        .map(|p| {
            let t = p
                .file_stem()
                .and_then(|s| s.to_str())
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|t| t.is_finite());
            (t, p)
        })
        .collect();
    if out.iter().all(|(t, _)| t.is_some()) {
        out.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(std::cmp::Ordering::Equal));
    }
    Ok(out)
}

/// TUM's association: the closest pairs first, each frame once, within `max_difference`.
/// Returns every colour frame (with its depth or none) and the count of unused depth maps.
fn associate(
    color: &[(Option<f64>, PathBuf)],
    depth: &[(Option<f64>, PathBuf)],
    max_difference: f64,
) -> (Vec<RgbdFrame>, usize) {
    let depth_times: Vec<f64> = depth.iter().map(|(t, _)| t.unwrap_or(f64::NAN)).collect();
    let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
    for (i, (t, _)) in color.iter().enumerate() {
        let t = t.unwrap_or(f64::NAN);
        // The depth list is sorted: only its window [t − max, t + max] can match.
        let start = depth_times.partition_point(|&d| d < t - max_difference);
        for (j, &d) in depth_times.iter().enumerate().skip(start) {
            if d > t + max_difference {
                break;
            }
            let dt = (d - t).abs();
            if dt < max_difference {
                candidates.push((dt, i, j));
            }
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut depth_of = vec![None; color.len()];
    let mut used = vec![false; depth.len()];
    for (_, i, j) in candidates {
        if depth_of[i].is_none() && !used[j] {
            depth_of[i] = Some(j);
            used[j] = true;
        }
    }
    let frames = color
        .iter()
        .zip(depth_of)
        .map(|((t, c), j)| RgbdFrame {
            color: c.clone(),
            time_s: *t,
            depth: j.map(|j| depth[j].1.clone()),
            depth_time_s: j.and_then(|j| depth[j].0),
        })
        .collect();
    (frames, used.iter().filter(|u| !**u).count())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timed(times: &[f64], prefix: &str) -> Vec<(Option<f64>, PathBuf)> {
        times
            .iter()
            .map(|&t| (Some(t), PathBuf::from(format!("{prefix}/{t}.png"))))
            .collect()
    }

    #[test]
    fn closest_pairs_first_each_frame_once() {
        let color = timed(&[0.0, 0.033, 0.066, 0.1], "rgb");
        // Depth 0.05 is 17 ms from colour 0.033 and 16 ms from 0.066: 0.066 takes it, and
        // 0.033 gets nothing within 20 ms; 0.2 matches no colour frame.
        let depth = timed(&[0.004, 0.05, 0.101, 0.2], "depth");
        let (frames, unmatched) = associate(&color, &depth, MAX_TIME_DIFFERENCE_S);
        let got: Vec<Option<f64>> = frames.iter().map(|f| f.depth_time_s).collect();
        assert_eq!(got, [Some(0.004), None, Some(0.05), Some(0.101)]);
        assert_eq!(unmatched, 1);
    }

    #[test]
    fn tum_lists_and_folder_pairs_are_read_and_their_mistakes_named() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(
            d.join("rgb.txt"),
            "# color images\n1.0 rgb/1.0.png\n1.033 rgb/1.033.png\n",
        )
        .unwrap();
        std::fs::write(d.join("depth.txt"), "# depth\n1.002 depth/1.002.png\n").unwrap();
        let rec = RgbdRecording::open(d, &RgbdOptions::default()).unwrap();
        assert_eq!(rec.layout, RgbdLayout::Tum);
        assert_eq!(rec.depth_scale, TUM_DEPTH_SCALE);
        assert_eq!(rec.associated(), 1);
        assert!((rec.frame_rate().unwrap() - 1.0 / 0.033).abs() < 1e-6);
        assert_eq!(rec.frames[0].depth, Some(d.join("depth/1.002.png")));
        std::fs::write(d.join("depth.txt"), "1.002\n").unwrap();
        let e = RgbdRecording::open(d, &RgbdOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("depth.txt") && e.contains("line 1"), "{e}");

        let pair = tempfile::tempdir().unwrap();
        let p = pair.path();
        std::fs::create_dir_all(p.join("rgb")).unwrap();
        std::fs::create_dir_all(p.join("depth")).unwrap();
        for name in ["a.png", "b.png"] {
            std::fs::write(p.join("rgb").join(name), b"").unwrap();
        }
        std::fs::write(p.join("depth/a.png"), b"").unwrap();
        let e = RgbdRecording::open(p, &RgbdOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("2 frames") && e.contains("depth/ 1"), "{e}");
        std::fs::write(p.join("depth/b.png"), b"").unwrap();
        let rec = RgbdRecording::open(p, &RgbdOptions::default()).unwrap();
        assert_eq!((rec.layout, rec.associated()), (RgbdLayout::Folders, 2));
        assert_eq!(rec.depth_scale, FOLDER_DEPTH_SCALE);
        let e = RgbdRecording::open(&p.join("rgb"), &RgbdOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("not an RGB-D recording"), "{e}");
    }
}
