//! One run per output folder: taking the folder for a run ([`claim`]: its lock, then what it
//! holds), what a folder already holds ([`inspect`]), and clearing visage's own outputs from
//! it ([`clear_outputs`]) before a run that replaces them.
//!
//! A folder is a previous run's when visage wrote to it: it has the lock file
//! ([`crate::FolderLock`]), a `metrics.json` that a run wrote, or a `faces.json` of a run over
//! every face. In such a folder the run's files are recognised by name (the point cache, the
//! landmarks, the metrics, the exports and their `.tmp` siblings, the `meshes/`, `raw/`,
//! `plots/` and `frames/` folders); anything else is the user's and is never removed. Files
//! that only share those names in a folder no run wrote to are the user's too.

use std::path::{Path, PathBuf};

use crate::file_names::{self, FACE_FOLDER_PREFIX, LOCK, OUTPUT_FILES, OUTPUT_FOLDERS};
use crate::{FolderLock, RunFolderError as Error};

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
    /// Whether the folder has visage's lock file.
    pub lock_file: bool,
    /// Whether it has a `metrics.json` with a run's status and parameters, or a `faces.json`
    /// of a run over every face.
    pub run_records: bool,
}

impl FolderContents {
    /// Whether the folder holds nothing (its lock file aside).
    pub fn is_empty(&self) -> bool {
        self.outputs.is_empty() && self.temporaries.is_empty() && self.other.is_empty()
    }

    /// Whether visage wrote to the folder: its lock file or a run's records are there.
    pub fn written_by_visage(&self) -> bool {
        self.lock_file || self.run_records
    }

    /// Whether a previous run left anything: visage wrote to the folder and files of a run's
    /// names are there.
    pub fn has_run(&self) -> bool {
        self.written_by_visage() && (!self.outputs.is_empty() || !self.temporaries.is_empty())
    }

    /// Everything in the folder, for a message (its lock file aside).
    fn everything(&self) -> String {
        let mut all: Vec<String> = [&self.outputs, &self.temporaries, &self.other]
            .into_iter()
            .flatten()
            .cloned()
            .collect();
        all.sort();
        list(&all)
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
        if name == LOCK {
            contents.lock_file = true;
        } else if is_dir && is_output_folder(&name) {
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
            contents.run_records |= contents
                .status
                .as_deref()
                .is_some_and(|s| ["complete", "interrupted", "failed", "running"].contains(&s))
                && value.get("parameters").is_some();
        }
    }
    if let Ok(text) = std::fs::read_to_string(dir.join(file_names::FACES)) {
        contents.run_records |= serde_json::from_str::<serde_json::Value>(&text)
            .is_ok_and(|v| v.get("faces").is_some());
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

impl Cleared {
    /// What `--overwrite` removed from `dir`, in words.
    pub fn describe(&self, dir: &Path) -> String {
        format!(
            "--overwrite: removed {} entries of the previous run from {} (it held {})",
            self.removed.len(),
            dir.display(),
            self.held
        )
    }
}

/// An output folder taken for a run: its lock (held until dropped) and what `--overwrite`
/// removed.
#[derive(Debug)]
pub struct Claimed {
    pub lock: FolderLock,
    pub cleared: Option<Cleared>,
}

/// Takes `dir` for a run, one run per folder: first its lock ([`FolderLock`]: a folder another
/// process writes into is refused, naming it), then what it holds: a missing or empty folder
/// is taken as it is, and so is one that holds a run when `resume` (it is continued); any
/// other folder that holds anything is refused, unless `overwrite` and it is a previous run's
/// ([`FolderContents::written_by_visage`]), whose files are then removed (the user's stay).
///
/// # Errors
/// [`Error::Locked`] naming the process that holds the folder; [`Error::NotEmpty`] naming what
/// the folder holds; [`Error::NotARun`] for `overwrite` of a folder no run wrote to, listing
/// what it holds (nothing is removed); a file that cannot be read or removed.
pub fn claim(dir: &Path, overwrite: bool, resume: bool) -> Result<Claimed, Error> {
    // Whether visage wrote here before: taking the lock makes the lock file.
    let had_lock_file = dir.join(LOCK).exists();
    let lock = FolderLock::acquire(dir)?;
    let mut contents = inspect(dir)?;
    contents.lock_file = had_lock_file;
    if contents.is_empty() || (resume && contents.has_run()) {
        return Ok(Claimed {
            lock,
            cleared: None,
        });
    }
    let refusal = if !overwrite {
        Some(Error::NotEmpty {
            dir: dir.to_owned(),
            holds: contents.describe(),
        })
    } else if !contents.written_by_visage() {
        Some(Error::NotARun {
            dir: dir.to_owned(),
            holds: contents.everything(),
        })
    } else {
        None
    };
    if let Some(e) = refusal {
        if !had_lock_file {
            lock.discard();
        }
        return Err(e);
    }
    let held = contents.describe();
    let removed = clear_outputs(dir)?;
    Ok(Claimed {
        lock,
        cleared: Some(Cleared { removed, held }),
    })
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
            ".visage.lock",
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
        assert!(c.lock_file && c.has_run());
        assert!(c.describe().contains("killed"), "{}", c.describe());

        let removed = clear_outputs(dir.path()).unwrap();
        assert_eq!(removed.len(), 5);
        let after = inspect(dir.path()).unwrap();
        assert!(!after.has_run() && after.lock_file);
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
        assert!(!c.run_records, "no parameters: not a run's");
        assert_eq!(c.status.as_deref(), Some("interrupted"));
        assert_eq!(c.frames, Some(3));
        assert!(c.describe().contains("\"interrupted\" over 3 frames"));
    }

    #[test]
    fn only_a_folder_visage_wrote_to_is_a_run() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["mesh.obj", "camera.json", "meshes/scan.ply"] {
            touch(dir.path(), name);
        }
        let c = inspect(dir.path()).unwrap();
        assert_eq!(c.outputs, ["camera.json", "mesh.obj", "meshes/"]);
        assert!(!c.written_by_visage() && !c.has_run());
        let err = claim(dir.path(), true, false).unwrap_err().to_string();
        assert!(err.contains("does not hold one"), "{err}");
        assert!(
            !dir.path().join(LOCK).exists(),
            "a refused folder is left unmarked"
        );
        std::fs::write(
            dir.path().join("metrics.json"),
            r#"{"status": "complete", "parameters": {}, "frames": []}"#,
        )
        .unwrap();
        let c = inspect(dir.path()).unwrap();
        assert!(c.run_records && c.has_run());
        let claimed = claim(dir.path(), true, false).unwrap();
        assert_eq!(claimed.cleared.unwrap().removed.len(), 4);
        assert!(claimed.lock.path().exists());
    }
}
