//! A folder of 16-bit PNG depth maps, one per frame in name order: listing and reading, and
//! the folder as a depth source (the i-th file for input frame i).

use std::path::{Path, PathBuf};

use visage_camera::{read_depth_png, DepthKind, DepthMap};

use crate::{DepthError, DepthProvider, DepthRequest, ProvidedDepth};

/// The frames of a depth sequence, in name order.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthSequence {
    pub dir: PathBuf,
    pub frames: Vec<PathBuf>,
    /// value / `scale` = metres.
    pub scale: f64,
    pub kind: DepthKind,
}

impl DepthSequence {
    /// Lists the `*.png` files of `dir` sorted by name.
    ///
    /// # Errors
    /// A scale that is not positive and finite, an unreadable folder, a folder without PNGs.
    pub fn open(dir: &Path, scale: f64, kind: DepthKind) -> Result<Self, DepthError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(DepthError::DepthScale { value: scale });
        }
        let entries = std::fs::read_dir(dir).map_err(|source| DepthError::Io {
            path: dir.to_owned(),
            source,
        })?;
        let mut frames = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|source| DepthError::Io {
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
            return Err(DepthError::NoFrames {
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
    ///
    /// # Panics
    /// `index` is not below `frames.len()`.
    ///
    /// # Errors
    /// An unreadable file, or not a 16-bit single-channel PNG.
    pub fn read(&self, index: usize) -> Result<DepthMap, DepthError> {
        Ok(read_depth_png(&self.frames[index], self.scale, self.kind)?)
    }
}

impl DepthProvider for DepthSequence {
    /// The folder.
    fn describe(&self) -> String {
        self.dir.display().to_string()
    }

    /// The file of input frame `request.index`, checked against the camera.
    fn depth_map(&mut self, request: DepthRequest<'_>) -> Result<ProvidedDepth, DepthError> {
        let index = request.index;
        if index >= self.frames.len() {
            return Err(DepthError::MissingFrame {
                dir: self.dir.clone(),
                frames: self.frames.len(),
                index,
            });
        }
        let map = self.read(index)?;
        request.k.check_size(map.width, map.height).map_err(|e| {
            DepthError::on_frame(&self.frames[index].display().to_string(), "depth frame", e)
        })?;
        Ok(ProvidedDepth::read(map))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use visage_camera::Intrinsics;

    #[test]
    fn lists_the_pngs_in_name_order_and_refuses_a_bad_scale() {
        let dir = tempfile::tempdir().unwrap();
        let map = DepthMap::empty(3, 2, DepthKind::Z);
        for name in ["b.png", "a.PNG", "c.png"] {
            visage_camera::write_depth_png(&dir.path().join(name), &map, 1000.0).unwrap();
        }
        std::fs::write(dir.path().join("notes.txt"), "not a frame").unwrap();
        let seq = DepthSequence::open(dir.path(), 1000.0, DepthKind::Z).unwrap();
        let names: Vec<_> = seq.frames.iter().map(|p| p.file_name().unwrap()).collect();
        assert_eq!(names, ["a.PNG", "b.png", "c.png"]);
        assert_eq!(seq.read(1).unwrap(), map);
        let bad = DepthSequence::open(dir.path(), -1.0, DepthKind::Z).unwrap_err();
        assert_eq!(
            bad.to_string(),
            "invalid option depth-scale = -1: must be positive and finite"
        );
        let empty = tempfile::tempdir().unwrap();
        let none = DepthSequence::open(empty.path(), 1000.0, DepthKind::Z).unwrap_err();
        assert!(
            none.to_string().ends_with(": no PNG depth frames found"),
            "{none}"
        );
    }

    #[test]
    fn as_a_provider_it_gives_frame_i_the_i_th_file_of_the_camera_s_size() {
        let dir = tempfile::tempdir().unwrap();
        let mut map = DepthMap::empty(4, 3, DepthKind::Z);
        map.data[5] = 0.5;
        for name in ["0.png", "1.png"] {
            visage_camera::write_depth_png(&dir.path().join(name), &map, 1000.0).unwrap();
        }
        let mut seq = DepthSequence::open(dir.path(), 1000.0, DepthKind::Z).unwrap();
        let request = |index, k| DepthRequest {
            index,
            source: "clip.mp4#1",
            image: None,
            k,
            face_box: [0.0; 4],
            reference: None,
            max_depth: 4.0,
        };
        let k = Intrinsics::new(4, 3, 4.0, 4.0, 1.5, 1.0).unwrap();
        assert_eq!(
            seq.depth_map(request(1, &k)).unwrap(),
            ProvidedDepth::read(map)
        );
        let missing = seq.depth_map(request(2, &k)).unwrap_err();
        assert_eq!(
            missing.to_string(),
            format!(
                "{}: holds 2 depth frames; input frame 2 has none",
                dir.path().display()
            )
        );
        let other = Intrinsics::new(8, 6, 8.0, 8.0, 3.5, 2.5).unwrap();
        let DepthError::Frame { frame, step, .. } = seq.depth_map(request(0, &other)).unwrap_err()
        else {
            panic!("a map of another size than the camera's names its file");
        };
        assert_eq!(
            (frame.as_str(), step),
            (seq.frames[0].to_str().unwrap(), "depth frame")
        );
    }
}
