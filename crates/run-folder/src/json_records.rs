//! The complete records of a streamed JSON file that may have been cut short: the objects of
//! its top-level `"frames"` array, each with the byte offset just past it. `landmarks.json`
//! and `blendshapes.json` are written record by record, so a run that was killed leaves a
//! file that ends inside a record; what comes before it can still be used
//! ([`crate::prepare_resume`]).
//!
//! The file is read in blocks and never held whole (a long clip's landmarks take gigabytes);
//! one record at a time is kept and handed to the caller.

use std::io::Read;
use std::path::Path;

use crate::RunFolderError as Error;

/// What [`scan_frames`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct Scan<T> {
    /// The byte offset just past the array's `[`: where a file with no record is cut.
    pub array_start: u64,
    /// Every complete record (as `parse` made it) and the byte offset just past its `}`.
    pub records: Vec<(T, u64)>,
}

impl<T> Scan<T> {
    /// Where to cut the file so that it keeps its first `n` records.
    pub fn end_of(&self, n: usize) -> u64 {
        match n {
            0 => self.array_start,
            n => self.records[n - 1].1,
        }
    }
}

/// Reads `path` up to its first incomplete record. `parse` turns a record's bytes (one JSON
/// object) into what the caller keeps; a record it rejects ends the scan as a cut-off one does.
///
/// # Errors
/// The file cannot be read, or it has no `"frames"` array at its top level.
pub fn scan_frames<T>(
    path: &Path,
    parse: impl FnMut(&[u8]) -> Option<T>,
) -> Result<Scan<T>, Error> {
    let file = std::fs::File::open(path).map_err(|source| Error::Read {
        path: path.to_owned(),
        source,
    })?;
    scan_records(file, path, parse)
}

/// [`scan_frames`] of what `file` reads; `path` only names it in errors.
///
/// # Errors
/// `file` cannot be read, or it has no `"frames"` array at its top level.
pub fn scan_records<T>(
    mut file: impl Read,
    path: &Path,
    mut parse: impl FnMut(&[u8]) -> Option<T>,
) -> Result<Scan<T>, Error> {
    let read_error = |source| Error::Read {
        path: path.to_owned(),
        source,
    };
    let mut scanner = Scanner::default();
    let mut records = Vec::new();
    let mut block = vec![0u8; 1 << 16];
    let mut offset = 0u64;
    'read: loop {
        let n = file.read(&mut block).map_err(read_error)?;
        if n == 0 {
            break;
        }
        for (i, &byte) in block[..n].iter().enumerate() {
            match scanner.push(byte) {
                Event::None => {}
                Event::Record => {
                    let Some(value) = parse(&scanner.record) else {
                        break 'read;
                    };
                    records.push((value, offset + i as u64 + 1));
                    scanner.record.clear();
                }
                Event::ArrayClosed => break 'read,
            }
        }
        offset += n as u64;
    }
    let Some(array_start) = scanner.array_start else {
        return Err(Error::Input {
            path: path.to_owned(),
            reason: "has no \"frames\" array (not a file visage streamed)".into(),
        });
    };
    Ok(Scan {
        array_start,
        records,
    })
}

/// What a byte did.
enum Event {
    None,
    /// A record is complete in `Scanner::record`.
    Record,
    ArrayClosed,
}

/// A byte-at-a-time reader of JSON structure: nesting depth, strings and their escapes, the
/// last key of the top-level object.
#[derive(Default)]
struct Scanner {
    /// Bytes read so far.
    position: u64,
    /// Open `{` and `[` around the current byte.
    depth: usize,
    in_string: bool,
    escaped: bool,
    /// The top level's current string (a key), while and after it is read.
    key: Vec<u8>,
    /// Where the `"frames"` array's contents start, once it opened.
    array_start: Option<u64>,
    /// The record being read (depth ≥ 3 inside the array).
    record: Vec<u8>,
}

impl Scanner {
    fn in_array(&self) -> bool {
        self.array_start.is_some()
    }

    fn push(&mut self, byte: u8) -> Event {
        self.position += 1;
        let in_record = self.in_array() && self.depth >= 3;
        if in_record {
            self.record.push(byte);
        }
        if self.in_string {
            if self.escaped {
                self.escaped = false;
            } else if byte == b'\\' {
                self.escaped = true;
            } else if byte == b'"' {
                self.in_string = false;
            } else if self.depth == 1 {
                self.key.push(byte);
            }
            return Event::None;
        }
        match byte {
            b'"' => {
                self.in_string = true;
                if self.depth == 1 {
                    self.key.clear();
                }
            }
            b'{' | b'[' => {
                self.depth += 1;
                if self.depth == 2 && byte == b'[' && self.key == b"frames" && !self.in_array() {
                    self.array_start = Some(self.position);
                    return Event::None;
                }
                if self.depth == 3 && self.in_array() {
                    self.record.clear();
                    self.record.push(byte);
                }
            }
            b'}' | b']' => {
                self.depth = self.depth.saturating_sub(1);
                if self.in_array() && self.depth == 2 && in_record {
                    return Event::Record;
                }
                if self.in_array() && self.depth == 1 {
                    return Event::ArrayClosed;
                }
            }
            _ => {}
        }
        Event::None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn index(bytes: &[u8]) -> Option<usize> {
        let v: serde_json::Value = serde_json::from_slice(bytes).ok()?;
        v["index"].as_u64().map(|i| i as usize)
    }

    fn scan(text: &str) -> Result<Scan<usize>, Error> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.json");
        std::fs::write(&path, text).unwrap();
        scan_frames(&path, index)
    }

    #[test]
    fn complete_records_of_a_cut_file_with_their_ends() {
        let head = "{\"fps\":30.0,\"names\":[\"a\",\"frames\"],\"frames\":[";
        let text = format!(
            "{head}{{\"index\":0,\"s\":\"}}]\\\"\"}},{{\"index\":1,\"w\":[[1,2],[3]]}},{{\"index\":2,\"w\":[1,"
        );
        let s = scan(&text).unwrap();
        assert_eq!(s.array_start, head.len() as u64);
        let indices: Vec<usize> = s.records.iter().map(|r| r.0).collect();
        assert_eq!(indices, [0, 1]);
        let cut = s.end_of(2) as usize;
        assert_eq!(&text[cut - 1..cut + 1], "},");
        assert_eq!(s.end_of(0), s.array_start);
        // The text up to a record's end plus the closing brackets is the whole document
        // with that many records.
        let whole: serde_json::Value =
            serde_json::from_str(&format!("{}]}}", &text[..s.end_of(1) as usize])).unwrap();
        assert_eq!(whole["frames"].as_array().unwrap().len(), 1);
    }

    #[test]
    fn a_finished_file_gives_every_record_and_nothing_after() {
        let s = scan("{\"frames\": [{\"index\":4},{\"index\":5}]}\n").unwrap();
        assert_eq!(s.records.iter().map(|r| r.0).collect::<Vec<_>>(), [4, 5]);
    }

    #[test]
    fn a_record_the_caller_rejects_ends_the_scan() {
        let s = scan("{\"frames\": [{\"index\":4},{\"other\":5},{\"index\":6}]}").unwrap();
        assert_eq!(s.records.len(), 1);
    }

    #[test]
    fn a_file_without_the_array_is_an_error() {
        assert!(scan("{\"frames\": 3}").is_err());
        assert!(scan("{\"fra").is_err());
        let empty = scan("{\"frames\": [").unwrap();
        assert!(empty.records.is_empty());
    }
}
