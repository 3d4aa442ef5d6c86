//! The batch manifest: the clips to process, one per line, as plain paths or JSON Lines.
//!
//! Plain lines: `PATH` or `PATH<TAB>INTRINSICS.json`; blank lines and lines starting with `#`
//! are skipped. JSON Lines (a `.jsonl` file, or one whose first entry starts with `{`): one
//! object per line, `{"input": PATH, "intrinsics": FILE, "id": NAME, "options": [FLAG…]}`, all
//! but `input` optional; `options` are `visage run` flags for that clip. Relative paths are
//! relative to the manifest's folder.

use std::path::{Component, Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, IdError, ManifestError};

/// One clip of the manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// The 1-based manifest line, for messages.
    pub line: usize,
    /// The clip's name: its output folder under the batch's folder and the key its shard is
    /// drawn from (the path as written, without its extension, unless the line names an id).
    pub id: String,
    /// The input, resolved against the manifest's folder.
    pub input: PathBuf,
    /// `visage run` flags of this clip (its intrinsics among them).
    pub options: Vec<String>,
}

impl Clip {
    /// The clip's own options, then the batch's `common` ones: what it is run with.
    pub fn options_with(&self, common: &[String]) -> Vec<String> {
        self.options.iter().chain(common).cloned().collect()
    }
}

/// A JSON Lines entry.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    input: String,
    #[serde(default)]
    intrinsics: Option<String>,
    #[serde(default)]
    id: Option<String>,
    #[serde(default)]
    options: Vec<String>,
}

/// Reads and checks the manifest at `path`: every line parsed, ids unique and usable as
/// folder names. Missing inputs are not an error here (those clips fail on their own).
pub fn read(path: &Path) -> Result<Vec<Clip>, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::ReadManifest {
        path: path.to_owned(),
        source,
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    parse(&text, base, path.extension().is_some_and(|e| e == "jsonl")).map_err(|source| {
        Error::Manifest {
            path: path.to_owned(),
            source,
        }
    })
}

/// [`read`] of manifest text whose relative paths are relative to `base`.
pub fn parse(text: &str, base: &Path, json_lines: bool) -> Result<Vec<Clip>, ManifestError> {
    // A byte-order mark (Windows editors write one) is not part of the first line.
    let entries = text
        .trim_start_matches('\u{feff}')
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let mut json = json_lines;
    let mut clips: Vec<Clip> = Vec::new();
    for (line, l) in entries {
        if clips.is_empty() && l.starts_with('{') {
            json = true;
        }
        let entry = if json {
            serde_json::from_str::<Entry>(l)
                .map_err(|source| ManifestError::NotJson { line, source })?
        } else {
            let mut fields = l.split('\t').map(str::trim);
            let input = fields.next().unwrap_or_default().to_owned();
            let intrinsics = fields.next().filter(|f| !f.is_empty()).map(str::to_owned);
            if let Some(extra) = fields.next() {
                return Err(ManifestError::ExtraField {
                    line,
                    extra: extra.to_owned(),
                });
            }
            Entry {
                input,
                intrinsics,
                id: None,
                options: Vec::new(),
            }
        };
        if entry.input.is_empty() {
            return Err(ManifestError::NoInput { line });
        }
        let id = match entry.id {
            Some(id) => id,
            None => default_id(&entry.input),
        };
        if let Err(source) = check_id(&id) {
            return Err(ManifestError::BadId { line, id, source });
        }
        if let Some(other) = clips.iter().find(|c| c.id == id) {
            return Err(ManifestError::DuplicateId {
                first: other.line,
                line,
                id,
            });
        }
        let mut options = entry.options;
        if let Some(k) = entry.intrinsics {
            options.extend([
                "--intrinsics".to_owned(),
                base.join(k).display().to_string(),
            ]);
        }
        clips.push(Clip {
            line,
            id,
            input: base.join(&entry.input),
            options,
        });
    }
    if clips.is_empty() {
        return Err(ManifestError::NoClips);
    }
    Ok(clips)
}

/// The path as written, without its extension and any leading `/` or `./`.
fn default_id(input: &str) -> String {
    let p = Path::new(input);
    let p = p.with_extension("");
    let parts: Vec<String> = p
        .components()
        .filter_map(|c| match c {
            Component::Normal(s) => Some(s.to_string_lossy().into_owned()),
            Component::ParentDir => Some("..".to_owned()),
            _ => None,
        })
        .collect();
    parts.join("/")
}

/// An id is a relative path of plain names: no `..`, no hidden names (the batch's own files
/// start with a dot).
fn check_id(id: &str) -> Result<(), IdError> {
    if id.is_empty() {
        return Err(IdError::Empty);
    }
    for part in id.split('/') {
        if part.is_empty() || part == "." || part == ".." || part.starts_with('.') {
            return Err(IdError::NotPlain {
                part: part.to_owned(),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_lines_with_intrinsics_comments_and_blank_lines() {
        let clips = parse(
            "# clips\n\nday1/a.mp4\nday1/b.mov\tk.json\n/data/c.mp4\n",
            Path::new("/m"),
            false,
        )
        .unwrap();
        assert_eq!(clips.len(), 3);
        assert_eq!(clips[0].id, "day1/a");
        assert_eq!(clips[0].line, 3);
        assert_eq!(clips[0].input, Path::new("/m/day1/a.mp4"));
        assert_eq!(clips[1].options, ["--intrinsics", "/m/k.json"]);
        assert_eq!(clips[2].id, "data/c");
        assert_eq!(clips[2].input, Path::new("/data/c.mp4"));
    }

    #[test]
    fn json_lines_with_ids_and_options() {
        let text = r#"{"input": "a.mp4", "options": ["--fov-deg", "50"]}
{"input": "a.mov", "id": "a-mov", "intrinsics": "k.json"}"#;
        let clips = parse(text, Path::new("m"), false).unwrap();
        assert_eq!(clips[0].id, "a");
        assert_eq!(clips[0].options, ["--fov-deg", "50"]);
        assert_eq!(clips[1].id, "a-mov");
        assert_eq!(clips[1].options, ["--intrinsics", "m/k.json"]);
    }

    #[test]
    fn bad_manifests_name_the_line() {
        let err = |t: &str| visage::error_chain(&parse(t, Path::new("."), false).unwrap_err());
        assert!(err("a.mp4\na.mov\n").contains("lines 1 and 2 both name the clip \"a\""));
        assert!(err("../x.mp4\n").contains("line 1"));
        assert!(err("{\"input\": \"a\"}\n{\"inptu\": \"b\"}\n").contains("line 2"));
        assert!(err("# nothing\n").contains("no clips"));
        assert!(err("a.mp4\tk.json\textra\n").contains("line 1"));
    }
}
