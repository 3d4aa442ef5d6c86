//! One run per output folder: what a folder already holds ([`inspect`]), and clearing visage's
//! own outputs from it ([`clear_outputs`]) before a run that replaces them.
//!
//! A run's files are recognised by name (the point cache, the landmarks, the metrics, the
//! exports and their `.tmp` siblings, the `meshes/`, `raw/`, `plots/` and `frames/` folders);
//! anything else in the folder is the user's and is never removed.

use std::path::{Path, PathBuf};

use crate::file_names::{self, FACE_FOLDER_PREFIX, OUTPUT_FILES, OUTPUT_FOLDERS};
use crate::RunFolderError as Error;

/// What an output folder holds before a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FolderContents {
    /// visage's outputs found (names relative to the folder; folders end with `/`).
    pub outputs: Vec<String>,
    /// Files under a temporary name (`*.tmp`): a run that was killed, or one still running.
    pub temporaries: Vec<String>,
    /// Everything else (the user's files; never removed).
    pub other: Vec<String>,
    /// `metrics.json`'s `status` (`"complete"`, `"interrupted"`, `"failed"`, `"running"`),
    /// when the file is there and readable.
    pub status: Option<String>,
    /// The frames `metrics.json` lists, when it is there.
    pub frames: Option<usize>,
}

impl FolderContents {
    /// Whether the folder holds nothing.
    pub fn is_empty(&self) -> bool {
        self.outputs.is_empty() && self.temporaries.is_empty() && self.other.is_empty()
    }

    /// Whether a previous run left anything.
    pub fn has_run(&self) -> bool {
        !self.outputs.is_empty() || !self.temporaries.is_empty()
    }

    /// One sentence on the previous run: its status and frames, or that it was killed.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        match (self.status.as_deref(), self.frames) {
            (Some("running"), _) => parts.push(format!(
                "a run that was killed before it finished (or is still running): {} says \
                 \"running\"",
                file_names::METRICS
            )),
            (Some(status), Some(n)) => parts.push(format!(
                "a run with status \"{status}\" over {n} frame{}",
                if n == 1 { "" } else { "s" }
            )),
            (Some(status), None) => parts.push(format!("a run with status \"{status}\"")),
            (None, _) if self.has_run() => parts.push(format!(
                "a run that was killed before it finished (no {})",
                file_names::METRICS
            )),
            (None, _) => {}
        }
        if !self.outputs.is_empty() {
            parts.push(format!("outputs {}", list(&self.outputs)));
        }
        if !self.temporaries.is_empty() {
            parts.push(format!("unfinished files {}", list(&self.temporaries)));
        }
        if !self.other.is_empty() {
            parts.push(format!("other files {}", list(&self.other)));
        }
        parts.join("; ")
    }
}

/// Up to six names, then how many more.
fn list(names: &[String]) -> String {
    let shown: Vec<&str> = names.iter().take(6).map(String::as_str).collect();
    match names.len().saturating_sub(shown.len()) {
        0 => shown.join(", "),
        more => format!("{} and {more} more", shown.join(", ")),
    }
}

fn is_output_folder(name: &str) -> bool {
    OUTPUT_FOLDERS.contains(&name)
        || name
            .strip_prefix(FACE_FOLDER_PREFIX)
            .is_some_and(|id| !id.is_empty() && id.bytes().all(|b| b.is_ascii_digit()))
}

fn is_output_file(name: &str) -> bool {
    OUTPUT_FILES.contains(&name)
}

/// What `dir` holds (an absent folder holds nothing).
///
/// # Errors
/// When the folder exists but cannot be listed.
pub fn inspect(dir: &Path) -> Result<FolderContents, Error> {
    let mut contents = FolderContents::default();
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(contents),
        Err(source) => {
            return Err(Error::Write {
                path: dir.to_owned(),
                source,
            })
        }
    };
    for entry in entries {
        let entry = entry.map_err(|source| Error::Write {
            path: dir.to_owned(),
            source,
        })?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        if is_dir && is_output_folder(&name) {
            contents.outputs.push(format!("{name}/"));
        } else if !is_dir && is_output_file(&name) {
            contents.outputs.push(name);
        } else if !is_dir && name.ends_with(file_names::TMP_SUFFIX) {
            contents.temporaries.push(name);
        } else {
            contents
                .other
                .push(if is_dir { format!("{name}/") } else { name });
        }
    }
    for names in [
        &mut contents.outputs,
        &mut contents.temporaries,
        &mut contents.other,
    ] {
        names.sort();
    }
    if let Ok(text) = std::fs::read_to_string(dir.join(file_names::METRICS)) {
        if let Ok(value) = serde_json::from_str::<serde_json::Value>(&text) {
            contents.status = value["status"].as_str().map(str::to_owned);
            contents.frames = value["frames"].as_array().map(Vec::len);
        }
    }
    Ok(contents)
}

/// What [`claim`] removed from a folder that held a previous run.
#[derive(Clone, Debug, PartialEq)]
pub struct Cleared {
    /// The entries removed.
    pub removed: Vec<PathBuf>,
    /// What the folder held ([`FolderContents::describe`]).
    pub held: String,
}

/// Makes `dir` ready for a run, one run per folder: a missing or empty folder is taken as it
/// is, and so is one that holds a run when `resume` (it is continued); any other folder that
/// holds anything is refused, unless `overwrite`, which removes a previous run's files (the
/// user's stay) and says what it removed.
///
/// # Errors
/// [`Error::NotEmpty`] naming what the folder holds; a file that cannot be read or removed.
pub fn claim(dir: &Path, overwrite: bool, resume: bool) -> Result<Option<Cleared>, Error> {
    let contents = inspect(dir)?;
    if contents.is_empty() || (resume && contents.has_run()) {
        return Ok(None);
    }
    if !overwrite {
        return Err(Error::NotEmpty {
            dir: dir.to_owned(),
            holds: contents.describe(),
        });
    }
    if !contents.has_run() {
        return Ok(None);
    }
    Ok(Some(Cleared {
        removed: clear_outputs(dir)?,
        held: contents.describe(),
    }))
}

/// Removes visage's outputs and temporary files from `dir` (as [`inspect`] finds them) and
/// returns what it removed; the user's files stay.
///
/// # Errors
/// When something cannot be removed (what was removed before stays removed).
pub fn clear_outputs(dir: &Path) -> Result<Vec<PathBuf>, Error> {
    let contents = inspect(dir)?;
    let mut removed = Vec::new();
    for name in contents.outputs.iter().chain(&contents.temporaries) {
        let path = dir.join(name.trim_end_matches('/'));
        let result = if name.ends_with('/') {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
        result.map_err(|source| Error::Write {
            path: path.clone(),
            source,
        })?;
        removed.push(path);
    }
    Ok(removed)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(dir: &Path, name: &str) {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, b"x").unwrap();
    }

    #[test]
    fn an_absent_or_empty_folder_holds_nothing() {
        let dir = tempfile::tempdir().unwrap();
        assert!(inspect(&dir.path().join("absent")).unwrap().is_empty());
        assert!(inspect(dir.path()).unwrap().is_empty());
    }

    #[test]
    fn a_killed_run_is_told_apart_from_the_users_files() {
        let dir = tempfile::tempdir().unwrap();
        for name in [
            "camera.json",
            "landmarks.json.tmp",
            "sequence.pc2.tmp",
            "meshes/000001.ply",
            "face-2/metrics.json",
            "notes.txt",
            "face-x/keep.txt",
        ] {
            touch(dir.path(), name);
        }
        let c = inspect(dir.path()).unwrap();
        assert_eq!(c.outputs, ["camera.json", "face-2/", "meshes/"]);
        assert_eq!(c.temporaries, ["landmarks.json.tmp", "sequence.pc2.tmp"]);
        assert_eq!(c.other, ["face-x/", "notes.txt"]);
        assert!(c.has_run());
        assert!(c.describe().contains("killed"), "{}", c.describe());

        let removed = clear_outputs(dir.path()).unwrap();
        assert_eq!(removed.len(), 5);
        let after = inspect(dir.path()).unwrap();
        assert!(!after.has_run());
        assert_eq!(after.other, ["face-x/", "notes.txt"]);
    }

    #[test]
    fn the_status_and_frames_come_from_metrics_json() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("metrics.json"),
            r#"{"status": "interrupted", "frames": [{}, {}, {}]}"#,
        )
        .unwrap();
        let c = inspect(dir.path()).unwrap();
        assert_eq!(c.status.as_deref(), Some("interrupted"));
        assert_eq!(c.frames, Some(3));
        assert!(c.describe().contains("\"interrupted\" over 3 frames"));
    }
}
