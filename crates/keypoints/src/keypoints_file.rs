//! The keypoints file `visage keypoints` writes and `visage match` reads:
//! `{"width", "height", "keypoints": [{"x", "y", "size", "angle", "response", "octave"}…],
//! "descriptors": [[128 bytes]…]}`, in OpenCV's conventions ([`Keypoint`]).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::keypoint::{Descriptor, Features, Keypoint, DESCRIPTOR_LEN};

/// An image's keypoints and descriptors as the file holds them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KeypointsFile {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// The keypoints.
    pub keypoints: Vec<Keypoint>,
    /// One descriptor (128 bytes) per keypoint.
    pub descriptors: Vec<Vec<u8>>,
}

/// A keypoints file that cannot be used, or read (then `source` says why).
#[derive(Debug, thiserror::Error)]
#[error("{}: {reason}", path.display())]
pub struct KeypointsFileError {
    pub path: PathBuf,
    pub reason: String,
    #[source]
    pub source: Option<std::io::Error>,
}

impl KeypointsFile {
    /// The file of `features` found in a `width × height` image.
    pub fn new(width: u32, height: u32, features: &Features) -> KeypointsFile {
        KeypointsFile {
            width,
            height,
            keypoints: features.keypoints.clone(),
            descriptors: features.descriptors.iter().map(|d| d.to_vec()).collect(),
        }
    }

    /// Reads a keypoints file.
    ///
    /// # Errors
    /// The file cannot be read (`reason` "cannot read the keypoints", the I/O error as
    /// `source`); otherwise as [`KeypointsFile::parse_json`].
    pub fn load_json(path: &Path) -> Result<Features, KeypointsFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| KeypointsFileError {
            path: path.to_owned(),
            reason: "cannot read the keypoints".into(),
            source: Some(source),
        })?;
        KeypointsFile::parse_json(&text, path)
    }

    /// Reads a keypoints file's text; `path` names it in errors.
    ///
    /// # Errors
    /// Not the file's JSON; another number of descriptors than keypoints; a descriptor of
    /// another length than 128.
    pub fn parse_json(text: &str, path: &Path) -> Result<Features, KeypointsFileError> {
        let bad = |reason: String| KeypointsFileError {
            path: path.to_owned(),
            reason,
            source: None,
        };
        let file: KeypointsFile = serde_json::from_str(text.trim_start_matches('\u{feff}'))
            .map_err(|e| bad(format!("not a keypoints file: {e}")))?;
        if file.descriptors.len() != file.keypoints.len() {
            return Err(bad(format!(
                "{} keypoints but {} descriptors",
                file.keypoints.len(),
                file.descriptors.len()
            )));
        }
        let descriptors = file
            .descriptors
            .iter()
            .enumerate()
            .map(|(k, d)| {
                Descriptor::try_from(d.as_slice()).map_err(|_| {
                    bad(format!(
                        "descriptor {k} has {} values, not {DESCRIPTOR_LEN}",
                        d.len()
                    ))
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Features {
            keypoints: file.keypoints,
            descriptors,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn features() -> Features {
        Features {
            keypoints: vec![Keypoint {
                x: 1.5,
                y: 2.0,
                size: 3.2,
                angle: 90.0,
                response: 0.02,
                octave: 0x00ff_0001,
            }],
            descriptors: vec![[7u8; DESCRIPTOR_LEN]],
        }
    }

    #[test]
    fn a_written_file_reads_back() {
        let text = serde_json::to_string(&KeypointsFile::new(10, 20, &features())).unwrap();
        let read = KeypointsFile::parse_json(&text, Path::new("k.json")).unwrap();
        assert_eq!(read, features());
    }

    #[test]
    fn bad_files_are_named_with_the_problem() {
        let mut file = KeypointsFile::new(10, 20, &features());
        file.descriptors[0].pop();
        let text = serde_json::to_string(&file).unwrap();
        let e = KeypointsFile::parse_json(&text, Path::new("k.json"))
            .unwrap_err()
            .to_string();
        assert_eq!(e, "k.json: descriptor 0 has 127 values, not 128");
        file.descriptors.clear();
        let text = serde_json::to_string(&file).unwrap();
        let e = KeypointsFile::parse_json(&text, Path::new("k.json"))
            .unwrap_err()
            .to_string();
        assert_eq!(e, "k.json: 1 keypoints but 0 descriptors");
        let e = KeypointsFile::parse_json("{", Path::new("k.json"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("k.json: not a keypoints file: "), "{e}");
    }
}
