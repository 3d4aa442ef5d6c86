//! The pinned MediaPipe model files: where they live, how they are fetched and verified.
//!
//! Two sources, both Apache-2.0, © Google LLC ([`ModelSource`]):
//! - the npm package `@mediapipe/face_mesh`, version [`NPM_VERSION`]: its
//!   `face_mesh_solution_packed_assets.data` concatenates the face networks and the face-geometry
//!   metadata; the byte ranges are listed in `face_mesh_solution_packed_assets_loader.js`. These
//!   files give the same outputs as those of the `mediapipe==0.10.21` wheel that produced
//!   `shared/reference/facemesh`.
//! - the PyPI wheel `mediapipe==0.10.21` ([`WHEEL_FILE`], downloaded with `pip download`, opened
//!   with Python's `zipfile`): the iris network `iris_landmark.tflite`, the full-range face
//!   detector `face_detection_full_range_sparse.tflite` and the attention face mesh
//!   `face_landmark_with_attention.tflite`, which the npm package lacks.
//!
//! Every archive and every extracted file is checked against a pinned SHA-256; nothing downloads
//! at run time.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::Command;

use sha2::{Digest, Sha256};

use crate::FaceError;

/// The npm package the models come from.
pub const NPM_PACKAGE: &str = "@mediapipe/face_mesh";
/// The pinned package version.
pub const NPM_VERSION: &str = "0.4.1657299874";
/// SHA-256 of the tarball `npm pack` downloads for [`NPM_VERSION`].
pub const NPM_TARBALL_SHA256: &str =
    "c08a7e0742a326285da666cf81d77c8b6f3a181a2ee948cadaf166008e0d3bc7";
/// Environment variable that overrides the model directory.
pub const MODELS_ENV: &str = "VISAGE_MODELS";
/// Model directory name, relative to the working directory (see [`models_dir`]).
pub const DEFAULT_MODELS_DIR: &str = "models";

/// The PyPI distribution the iris network, the full-range detector and the attention face mesh
/// come from.
pub const PYPI_PACKAGE: &str = "mediapipe";
/// The pinned wheel version.
pub const PYPI_VERSION: &str = "0.10.21";
/// The pinned wheel (one platform's build, chosen explicitly so that every machine downloads
/// the same bytes; the model files inside are the same in every build).
pub const WHEEL_FILE: &str = "mediapipe-0.10.21-cp311-cp311-manylinux_2_28_x86_64.whl";
/// SHA-256 of [`WHEEL_FILE`].
pub const WHEEL_SHA256: &str = "05dc4a9e593655a79558d05d6227d31018c2537a4bd3362b51e230cf22aecfe3";
/// The `pip download` arguments that select [`WHEEL_FILE`] whatever the local Python and
/// platform are.
const PIP_DOWNLOAD_ARGS: [&str; 16] = [
    "-m",
    "pip",
    "download",
    "mediapipe==0.10.21",
    "--no-deps",
    "--only-binary=:all:",
    "--platform",
    "manylinux_2_28_x86_64",
    "--python-version",
    "311",
    "--implementation",
    "cp",
    "--abi",
    "cp311",
    "--disable-pip-version-check",
    "--quiet",
];
/// The Python interpreter that runs `pip` and `zipfile`.
const PYTHON: &str = "python3";

const PACKED_DATA: &str = "package/face_mesh_solution_packed_assets.data";
const PACKED_LOADER: &str = "package/face_mesh_solution_packed_assets_loader.js";

/// The licence notice written next to the extracted files.
pub const NOTICE: &str =
    "The files in this directory are part of MediaPipe (https://github.com/google/mediapipe), \
Copyright Google LLC, licensed under the Apache License, Version 2.0 \
(https://www.apache.org/licenses/LICENSE-2.0). face_landmark.tflite, \
face_detection_short_range.tflite and geometry_pipeline_metadata_landmarks.binarypb are \
extracted from the npm package @mediapipe/face_mesh version 0.4.1657299874; \
iris_landmark.tflite, face_detection_full_range_sparse.tflite and \
face_landmark_with_attention.tflite are extracted from the PyPI wheel mediapipe==0.10.21 \
(mediapipe-0.10.21-cp311-cp311-manylinux_2_28_x86_64.whl, \
mediapipe/modules/iris_landmark/iris_landmark.tflite, \
mediapipe/modules/face_detection/face_detection_full_range_sparse.tflite and \
mediapipe/modules/face_landmark/face_landmark_with_attention.tflite). \
They are distributed on an \"AS IS\" BASIS, WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND. \
visage reads them unmodified; run `visage models fetch` to recreate them.\n";

/// Where a pinned file is fetched from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelSource {
    /// The npm package [`NPM_PACKAGE`]@[`NPM_VERSION`] (`npm pack`).
    Npm,
    /// The PyPI wheel [`WHEEL_FILE`] (`python3 -m pip download`).
    PypiWheel,
}

/// One of the six pinned files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFile {
    /// `face_landmark.tflite`: 192×192 RGB → 468 landmarks + presence (FaceMesh, no attention).
    FaceLandmark,
    /// `face_detection_short_range.tflite`: 128×128 RGB → 896 anchors (BlazeFace short range).
    FaceDetectionShortRange,
    /// `geometry_pipeline_metadata_landmarks.binarypb`: the canonical metric face mesh.
    GeometryPipelineMetadata,
    /// `iris_landmark.tflite`: 64×64 RGB eye crop → 71 eye-contour and brow points + 5 iris
    /// points (MediaPipe Iris). Optional at run time: without it faces have no eyes.
    IrisLandmark,
    /// `face_detection_full_range_sparse.tflite`: 192×192 RGB → 2304 anchors (MediaPipe's
    /// full-range face detector, small and distant faces). Optional at run time
    /// ([`crate::FaceDetector::load_full_range_if_present`]).
    FaceDetectionFullRange,
    /// `face_landmark_with_attention.tflite`: 192×192 RGB → 468 landmarks, the lips, both eyes'
    /// contours and irises refined by attention, and presence (the network behind MediaPipe's
    /// `refine_landmarks=True`). Optional at run time
    /// ([`crate::AttentionNetwork::load_if_present`]).
    FaceLandmarkWithAttention,
}

impl ModelFile {
    /// All pinned files.
    pub const ALL: [ModelFile; 6] = [
        ModelFile::FaceLandmark,
        ModelFile::FaceDetectionShortRange,
        ModelFile::GeometryPipelineMetadata,
        ModelFile::IrisLandmark,
        ModelFile::FaceDetectionFullRange,
        ModelFile::FaceLandmarkWithAttention,
    ];

    /// Where the file is fetched from.
    pub fn source(self) -> ModelSource {
        match self {
            ModelFile::IrisLandmark
            | ModelFile::FaceDetectionFullRange
            | ModelFile::FaceLandmarkWithAttention => ModelSource::PypiWheel,
            _ => ModelSource::Npm,
        }
    }

    /// The file's path inside [`WHEEL_FILE`], for the files from the wheel.
    pub fn wheel_member(self) -> Option<&'static str> {
        match self {
            ModelFile::IrisLandmark => Some("mediapipe/modules/iris_landmark/iris_landmark.tflite"),
            ModelFile::FaceDetectionFullRange => {
                Some("mediapipe/modules/face_detection/face_detection_full_range_sparse.tflite")
            }
            ModelFile::FaceLandmarkWithAttention => {
                Some("mediapipe/modules/face_landmark/face_landmark_with_attention.tflite")
            }
            _ => None,
        }
    }

    /// File name on disk (as in the MediaPipe source tree).
    pub fn file_name(self) -> &'static str {
        match self {
            ModelFile::FaceLandmark => "face_landmark.tflite",
            ModelFile::FaceDetectionShortRange => "face_detection_short_range.tflite",
            ModelFile::GeometryPipelineMetadata => "geometry_pipeline_metadata_landmarks.binarypb",
            ModelFile::IrisLandmark => "iris_landmark.tflite",
            ModelFile::FaceDetectionFullRange => "face_detection_full_range_sparse.tflite",
            ModelFile::FaceLandmarkWithAttention => "face_landmark_with_attention.tflite",
        }
    }

    /// Pinned SHA-256 (lower-case hex).
    pub fn sha256(self) -> &'static str {
        match self {
            ModelFile::FaceLandmark => {
                "c603fa6149219a3e9487dc9abd7a0c24474c77263273d24868378cdf40aa26d1"
            }
            ModelFile::FaceDetectionShortRange => {
                "3bc182eb9f33925d9e58b5c8d59308a760f4adea8f282370e428c51212c26633"
            }
            ModelFile::GeometryPipelineMetadata => {
                "bdbcda96dfcb7da883da124aaa2c55dee49770d934f0fcc71747f8c21bdc75b4"
            }
            ModelFile::IrisLandmark => {
                "d1744d2a09c25f501d39eba4faff47e53ecca8852c5ce19bce8eeac39357521f"
            }
            ModelFile::FaceDetectionFullRange => {
                "2c3728e6da56f21e21a320433396fb06d40d9088f2247c05e5635a688d45dfe1"
            }
            ModelFile::FaceLandmarkWithAttention => {
                "e06a804e0144f9929eda782122916b35d60c697c3c9344013ca2bbe76a6ce2b4"
            }
        }
    }

    /// Reads the file from `dir` and verifies its SHA-256; the error names the file and says
    /// how to fetch it.
    pub fn read(self, dir: &Path) -> Result<Vec<u8>, FaceError> {
        let path = dir.join(self.file_name());
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(FaceError::ModelMissing { path })
            }
            Err(source) => return Err(FaceError::Io { path, source }),
        };
        let found = sha256_hex(&bytes);
        if found != self.sha256() {
            return Err(FaceError::ModelChecksum {
                path,
                expected: self.sha256(),
                found,
            });
        }
        Ok(bytes)
    }
}

/// The model directory: `$VISAGE_MODELS` if set; else `./models` if it exists; else the first
/// `models/` folder found beside the running executable or one of its ancestors (so
/// `target/release/visage` finds the checkout's `models/` from any working directory); else
/// `./models` (where `visage models fetch` writes by default).
pub fn models_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os(MODELS_ENV) {
        return PathBuf::from(dir);
    }
    let local = PathBuf::from(DEFAULT_MODELS_DIR);
    if local.is_dir() {
        return local;
    }
    std::env::current_exe()
        .ok()
        .and_then(|exe| {
            exe.ancestors()
                .skip(1)
                .map(|a| a.join(DEFAULT_MODELS_DIR))
                .find(|d| d.is_dir())
        })
        .unwrap_or(local)
}

/// Lower-case hex SHA-256 of `bytes`.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Whether every pinned file is present in `dir` with the right checksum.
pub fn models_present(dir: &Path) -> bool {
    ModelFile::ALL.iter().all(|f| f.read(dir).is_ok())
}

/// Whether every pinned file from `source` is present in `dir` with the right checksum.
pub fn source_present(dir: &Path, source: ModelSource) -> bool {
    ModelFile::ALL
        .iter()
        .filter(|f| f.source() == source)
        .all(|f| f.read(dir).is_ok())
}

/// Runs `npm pack @mediapipe/face_mesh@VERSION` in a temporary folder inside `dir` and extracts
/// the pinned files into `dir` (see [`extract_from_tarball`]). Needs `npm` on the `PATH` and
/// access to the npm registry. Returns the paths written.
pub fn fetch_with_npm(dir: &Path) -> Result<Vec<PathBuf>, FaceError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| FaceError::Io { path, source }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let work = dir.join(".npm-pack.tmp");
    std::fs::create_dir_all(&work).map_err(io(&work))?;
    let spec = format!("{NPM_PACKAGE}@{NPM_VERSION}");
    let result = Command::new("npm")
        .args(["pack", &spec, "--silent"])
        .current_dir(&work)
        .output()
        .map_err(|e| FaceError::Fetch {
            reason: format!(
                "cannot run `npm pack {spec}` ({e}); install Node.js/npm or pass a tarball"
            ),
        })
        .and_then(|out| {
            if !out.status.success() {
                return Err(FaceError::Fetch {
                    reason: format!(
                        "`npm pack {spec}` failed: {}",
                        String::from_utf8_lossy(&out.stderr).trim()
                    ),
                });
            }
            let tarball = work.join(format!("mediapipe-face_mesh-{NPM_VERSION}.tgz"));
            extract_from_tarball(&tarball, dir)
        });
    let _ = std::fs::remove_dir_all(&work);
    result
}

/// Extracts the pinned files from an `npm pack` tarball of [`NPM_PACKAGE`]@[`NPM_VERSION`]:
/// checks the tarball's SHA-256, slices `face_mesh_solution_packed_assets.data` by the offsets of
/// the loader script, verifies every file's SHA-256, writes them (atomically) with a `NOTICE`.
pub fn extract_from_tarball(tarball: &Path, dir: &Path) -> Result<Vec<PathBuf>, FaceError> {
    let fetch = |reason: String| FaceError::Fetch {
        reason: format!("{}: {reason}", tarball.display()),
    };
    let bytes = std::fs::read(tarball).map_err(|source| FaceError::Io {
        path: tarball.to_owned(),
        source,
    })?;
    let found = sha256_hex(&bytes);
    if found != NPM_TARBALL_SHA256 {
        return Err(fetch(format!(
            "sha256 {found}, expected {NPM_TARBALL_SHA256} ({NPM_PACKAGE}@{NPM_VERSION})"
        )));
    }
    let mut data = None;
    let mut loader = None;
    let mut archive = tar::Archive::new(flate2::read::GzDecoder::new(bytes.as_slice()));
    let entries = archive.entries().map_err(|e| fetch(e.to_string()))?;
    for entry in entries {
        let mut entry = entry.map_err(|e| fetch(e.to_string()))?;
        let path = entry
            .path()
            .map_err(|e| fetch(e.to_string()))?
            .to_string_lossy()
            .into_owned();
        let slot = match path.as_str() {
            PACKED_DATA => &mut data,
            PACKED_LOADER => &mut loader,
            _ => continue,
        };
        let mut buf = Vec::new();
        entry
            .read_to_end(&mut buf)
            .map_err(|e| fetch(e.to_string()))?;
        *slot = Some(buf);
    }
    let data = data.ok_or_else(|| fetch(format!("no {PACKED_DATA}")))?;
    let loader =
        String::from_utf8_lossy(&loader.ok_or_else(|| fetch(format!("no {PACKED_LOADER}")))?)
            .into_owned();
    std::fs::create_dir_all(dir).map_err(|source| FaceError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let mut written = Vec::new();
    for file in ModelFile::ALL
        .into_iter()
        .filter(|f| f.source() == ModelSource::Npm)
    {
        let (start, end) = packed_range(&loader, file.file_name()).ok_or_else(|| {
            fetch(format!(
                "no byte range for {} in the loader",
                file.file_name()
            ))
        })?;
        let slice = data.get(start..end).ok_or_else(|| {
            fetch(format!(
                "range {start}..{end} of {} outside the {}-byte data file",
                file.file_name(),
                data.len()
            ))
        })?;
        let sha = sha256_hex(slice);
        if sha != file.sha256() {
            return Err(fetch(format!(
                "{} has sha256 {sha}, expected {}",
                file.file_name(),
                file.sha256()
            )));
        }
        let path = dir.join(file.file_name());
        write_atomic(&path, slice)?;
        written.push(path);
    }
    let notice = dir.join("NOTICE");
    write_atomic(&notice, NOTICE.as_bytes())?;
    written.push(notice);
    Ok(written)
}

/// Downloads [`WHEEL_FILE`] with `python3 -m pip download` (pinned version, platform and Python
/// tag, no dependencies) into a temporary folder inside `dir` and extracts the iris network, the
/// full-range detector and the attention face mesh from it (see [`extract_from_wheel`]). Needs
/// Python 3 with pip and access to PyPI. Returns the paths written.
pub fn fetch_with_pip(dir: &Path) -> Result<Vec<PathBuf>, FaceError> {
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| FaceError::Io { path, source }
    };
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let work = dir.join(".pip-download.tmp");
    std::fs::create_dir_all(&work).map_err(io(&work))?;
    let spec = format!("{PYPI_PACKAGE}=={PYPI_VERSION}");
    let result = Command::new(PYTHON)
        .args(PIP_DOWNLOAD_ARGS)
        .arg("--dest")
        .arg(&work)
        .output()
        .map_err(|e| FaceError::Fetch {
            reason: format!(
                "cannot run `{PYTHON} -m pip download {spec}` ({e}); install Python 3 with pip \
                 (Debian: python3-pip) or pass the wheel {WHEEL_FILE} with --from-wheel"
            ),
        })
        .and_then(|out| {
            if !out.status.success() {
                return Err(FaceError::Fetch {
                    reason: format!(
                        "`{PYTHON} -m pip download {spec}` failed: {}",
                        String::from_utf8_lossy(&out.stderr).trim()
                    ),
                });
            }
            extract_from_wheel(&work.join(WHEEL_FILE), dir)
        });
    let _ = std::fs::remove_dir_all(&work);
    result
}

/// Extracts the wheel's pinned files (`iris_landmark.tflite`,
/// `face_detection_full_range_sparse.tflite`, `face_landmark_with_attention.tflite`) from
/// [`WHEEL_FILE`]: checks the wheel's SHA-256,
/// reads each member ([`ModelFile::wheel_member`]) with Python's `zipfile` (a wheel is a zip
/// archive), verifies every file's SHA-256 before writing any, then writes them (atomically)
/// with the `NOTICE`.
pub fn extract_from_wheel(wheel: &Path, dir: &Path) -> Result<Vec<PathBuf>, FaceError> {
    let fetch = |reason: String| FaceError::Fetch {
        reason: format!("{}: {reason}", wheel.display()),
    };
    let bytes = std::fs::read(wheel).map_err(|source| FaceError::Io {
        path: wheel.to_owned(),
        source,
    })?;
    let found = sha256_hex(&bytes);
    if found != WHEEL_SHA256 {
        return Err(fetch(format!(
            "sha256 {found}, expected {WHEEL_SHA256} ({WHEEL_FILE})"
        )));
    }
    drop(bytes);
    let mut extracted = Vec::new();
    for file in ModelFile::ALL {
        let Some(member) = file.wheel_member() else {
            continue;
        };
        let out = Command::new(PYTHON)
            .args([
                "-c",
                "import sys, zipfile; sys.stdout.buffer.write(zipfile.ZipFile(sys.argv[1]).read(sys.argv[2]))",
            ])
            .arg(wheel)
            .arg(member)
            .output()
            .map_err(|e| fetch(format!("cannot run {PYTHON} to open the wheel ({e})")))?;
        if !out.status.success() {
            return Err(fetch(format!(
                "cannot extract {member}: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            )));
        }
        let sha = sha256_hex(&out.stdout);
        if sha != file.sha256() {
            return Err(fetch(format!(
                "{member} has sha256 {sha}, expected {}",
                file.sha256()
            )));
        }
        extracted.push((file, out.stdout));
    }
    std::fs::create_dir_all(dir).map_err(|source| FaceError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let mut written = Vec::new();
    for (file, bytes) in extracted {
        let path = dir.join(file.file_name());
        write_atomic(&path, &bytes)?;
        written.push(path);
    }
    let notice = dir.join("NOTICE");
    write_atomic(&notice, NOTICE.as_bytes())?;
    written.push(notice);
    Ok(written)
}

fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FaceError> {
    let tmp = path.with_extension("partial");
    std::fs::write(&tmp, bytes)
        .and_then(|()| std::fs::rename(&tmp, path))
        .map_err(|source| FaceError::Io {
            path: path.to_owned(),
            source,
        })
}

/// Byte range of `name` in the packed data, from the loader's
/// `{"filename": ".../name", "start": S, "end": E}` metadata.
fn packed_range(loader: &str, name: &str) -> Option<(usize, usize)> {
    let key = format!("/{name}\"");
    let at = loader.find(&key)? + key.len();
    let rest = &loader[at..];
    let number = |field: &str| -> Option<usize> {
        let p = rest.find(field)? + field.len();
        let digits: String = rest[p..]
            .trim_start_matches([':', ' '])
            .chars()
            .take_while(|c| c.is_ascii_digit())
            .collect();
        digits.parse().ok()
    };
    let (start, end) = (number("\"start\"")?, number("\"end\"")?);
    (start < end).then_some((start, end))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loader_offsets_are_parsed() {
        let js = r#"{"files": [{"filename": "/a/face_landmark_with_attention.tflite", "start": 0, "end": 10}, {"filename": "/a/face_landmark.tflite", "start": 10, "end": 25}]}"#;
        assert_eq!(packed_range(js, "face_landmark.tflite"), Some((10, 25)));
        assert_eq!(packed_range(js, "face_detection_short_range.tflite"), None);
    }

    #[test]
    fn missing_and_corrupt_files_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let err = ModelFile::FaceLandmark.read(dir.path()).unwrap_err();
        assert!(matches!(err, FaceError::ModelMissing { .. }));
        assert!(
            err.to_string().contains("face_landmark.tflite")
                && err.to_string().contains("visage models fetch")
        );
        std::fs::write(dir.path().join("face_landmark.tflite"), b"truncated").unwrap();
        let err = ModelFile::FaceLandmark.read(dir.path()).unwrap_err();
        assert!(matches!(err, FaceError::ModelChecksum { .. }), "{err}");
        assert!(err.to_string().contains("face_landmark.tflite"));
    }

    #[test]
    fn wrong_tarball_is_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let fake = dir.path().join("fake.tgz");
        std::fs::write(&fake, b"not a tarball").unwrap();
        let err = extract_from_tarball(&fake, dir.path())
            .unwrap_err()
            .to_string();
        assert!(err.contains("fake.tgz") && err.contains("sha256"), "{err}");
    }

    #[test]
    fn wrong_wheel_is_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let fake = dir.path().join(WHEEL_FILE);
        std::fs::write(&fake, b"not a wheel").unwrap();
        let err = extract_from_wheel(&fake, dir.path())
            .unwrap_err()
            .to_string();
        assert!(err.contains(WHEEL_FILE) && err.contains("sha256"), "{err}");
        for file in ModelFile::ALL.iter().filter(|f| f.wheel_member().is_some()) {
            assert!(!dir.path().join(file.file_name()).exists(), "{file:?}");
        }
    }

    #[test]
    fn every_file_has_a_source_and_a_distinct_name() {
        let npm = ModelFile::ALL
            .iter()
            .filter(|f| f.source() == ModelSource::Npm)
            .count();
        assert_eq!(npm, 3, "the npm package's three files keep their source");
        assert_eq!(ModelFile::IrisLandmark.source(), ModelSource::PypiWheel);
        assert_eq!(
            ModelFile::FaceDetectionFullRange.source(),
            ModelSource::PypiWheel
        );
        assert_eq!(
            ModelFile::FaceLandmarkWithAttention.source(),
            ModelSource::PypiWheel
        );
        for (i, a) in ModelFile::ALL.iter().enumerate() {
            // Exactly the wheel's files have a member path, ending in their file name.
            match a.wheel_member() {
                Some(m) => {
                    assert_eq!(a.source(), ModelSource::PypiWheel);
                    assert!(m.ends_with(&format!("/{}", a.file_name())), "{m}");
                }
                None => assert_eq!(a.source(), ModelSource::Npm),
            }
            for b in &ModelFile::ALL[i + 1..] {
                assert_ne!(a.file_name(), b.file_name());
            }
            assert_eq!(a.sha256().len(), 64);
        }
    }
}
