//! PC2 point caches: the per-frame vertex positions of a mesh whose topology does not change,
//! the format Blender's Mesh Cache modifier (and 3ds Max's Point Cache) plays.
//!
//! Layout, little-endian: the 12 bytes `POINTCACHE2\0`, `i32` version (1), `i32` points per
//! frame, `f32` start frame, `f32` sample rate (frames between samples, 1 here), `i32`
//! samples; then every sample's points as `f32 x, y, z`. The sample count is written when the
//! cache is finished, so a cache is written as the frames come.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::MeshIoError;

const MAGIC: &[u8; 12] = b"POINTCACHE2\0";
/// Byte offset of the sample count in the header.
const SAMPLES_OFFSET: u64 = 12 + 4 + 4 + 4 + 4;

/// Writes a PC2 cache frame by frame.
pub struct Pc2Writer {
    path: PathBuf,
    file: BufWriter<File>,
    points: usize,
    samples: u32,
    /// One frame's bytes.
    buffer: Vec<u8>,
}

impl Pc2Writer {
    /// Creates `path` for `points` vertices per frame, the first frame numbered `start_frame`.
    ///
    /// # Errors
    /// The file cannot be created or written.
    pub fn create(path: &Path, points: usize, start_frame: f32) -> Result<Pc2Writer, MeshIoError> {
        let io = |source| MeshIoError::Io {
            path: path.to_owned(),
            source,
        };
        let count = i32::try_from(points).map_err(|_| MeshIoError::Unwritable {
            path: path.to_owned(),
            reason: format!("{points} points do not fit a PC2 header"),
        })?;
        let mut file = BufWriter::new(File::create(path).map_err(io)?);
        file.write_all(MAGIC).map_err(io)?;
        for bytes in [
            1i32.to_le_bytes(),
            count.to_le_bytes(),
            start_frame.to_le_bytes(),
            1f32.to_le_bytes(),
            0i32.to_le_bytes(),
        ] {
            file.write_all(&bytes).map_err(io)?;
        }
        Ok(Pc2Writer {
            path: path.to_owned(),
            file,
            points,
            samples: 0,
            buffer: Vec::with_capacity(12 * points),
        })
    }

    /// Appends a frame: one position per point (f64, written as f32).
    ///
    /// # Errors
    /// Another number of points than the header's, or a write failure.
    pub fn push(&mut self, positions: &[[f64; 3]]) -> Result<(), MeshIoError> {
        if positions.len() != self.points {
            return Err(MeshIoError::Unwritable {
                path: self.path.clone(),
                reason: format!(
                    "frame {} has {} points, the cache {}",
                    self.samples,
                    positions.len(),
                    self.points
                ),
            });
        }
        self.buffer.clear();
        for p in positions {
            for c in p {
                self.buffer.extend_from_slice(&(*c as f32).to_le_bytes());
            }
        }
        self.file
            .write_all(&self.buffer)
            .map_err(|source| MeshIoError::Io {
                path: self.path.clone(),
                source,
            })?;
        self.samples += 1;
        Ok(())
    }

    /// Frames written so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Continues the unfinished cache `path` after its first `samples` frames: the file is cut
    /// there (a frame a killed writer left half-written goes) and frames are appended.
    ///
    /// # Errors
    /// `path` is not a PC2 cache or holds fewer than `samples` frames; it cannot be written.
    pub fn append(path: &Path, samples: u32) -> Result<Pc2Writer, MeshIoError> {
        let io = |source| MeshIoError::Io {
            path: path.to_owned(),
            source,
        };
        let bad = |reason: String| MeshIoError::Syntax {
            path: path.to_owned(),
            line: 0,
            reason,
        };
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(io)?;
        let mut header = [0u8; SAMPLES_OFFSET as usize + 4];
        std::io::Read::read_exact(&mut file, &mut header)
            .map_err(|_| bad("not a PC2 point cache (shorter than its header)".into()))?;
        if &header[..12] != MAGIC {
            return Err(bad("not a PC2 point cache (no POINTCACHE2 header)".into()));
        }
        let points = i32::from_le_bytes([header[16], header[17], header[18], header[19]]);
        let points =
            usize::try_from(points).map_err(|_| bad(format!("negative count: {points} points")))?;
        let end = header.len() as u64 + 12 * points as u64 * u64::from(samples);
        let length = file.metadata().map_err(io)?.len();
        if length < end {
            return Err(bad(format!(
                "holds {} whole frames of {points} points, not {samples}",
                (length - header.len() as u64) / (12 * points.max(1) as u64)
            )));
        }
        file.set_len(end).map_err(io)?;
        file.seek(SeekFrom::End(0)).map_err(io)?;
        Ok(Pc2Writer {
            path: path.to_owned(),
            file: BufWriter::new(file),
            points,
            samples,
            buffer: Vec::with_capacity(12 * points),
        })
    }

    /// Points per frame.
    pub fn points(&self) -> usize {
        self.points
    }

    /// Hands the frames written so far to the operating system (they survive the process being
    /// killed).
    ///
    /// # Errors
    /// A write failure.
    pub fn flush(&mut self) -> Result<(), MeshIoError> {
        self.file.flush().map_err(|source| MeshIoError::Io {
            path: self.path.clone(),
            source,
        })
    }

    /// Writes the sample count into the header and closes the file.
    ///
    /// # Errors
    /// A write failure.
    pub fn finish(mut self) -> Result<(), MeshIoError> {
        let io = |source| MeshIoError::Io {
            path: self.path.clone(),
            source,
        };
        self.file
            .seek(SeekFrom::Start(SAMPLES_OFFSET))
            .map_err(io)?;
        self.file
            .write_all(&(self.samples as i32).to_le_bytes())
            .map_err(io)?;
        self.file.flush().map_err(io)
    }
}

/// A PC2 cache read into memory.
#[derive(Clone, Debug, PartialEq)]
pub struct PointCache {
    /// The first sample's frame number.
    pub start_frame: f32,
    /// Frames between samples.
    pub sample_rate: f32,
    /// Points per sample.
    pub points: usize,
    /// Every sample's points, `x, y, z` each, sample after sample.
    pub positions: Vec<f32>,
}

impl PointCache {
    /// Samples in the cache.
    pub fn samples(&self) -> usize {
        if self.points == 0 {
            0
        } else {
            self.positions.len() / (3 * self.points)
        }
    }

    /// Sample `k`'s points, `x, y, z` each.
    pub fn sample(&self, k: usize) -> &[f32] {
        &self.positions[3 * self.points * k..3 * self.points * (k + 1)]
    }
}

/// Reads a PC2 cache.
///
/// # Errors
/// A file that is not a PC2 cache or whose size does not match its header.
pub fn read_pc2(path: &Path) -> Result<PointCache, MeshIoError> {
    let bytes = std::fs::read(path).map_err(|source| MeshIoError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse_pc2(&bytes, path)
}

/// [`read_pc2`] of a file's bytes already in memory; `path` is the file they came from, named in
/// errors.
///
/// # Errors
/// As [`read_pc2`], except that nothing is read from disk.
pub fn parse_pc2(bytes: &[u8], path: &Path) -> Result<PointCache, MeshIoError> {
    let bad = |reason: String| MeshIoError::Syntax {
        path: path.to_owned(),
        line: 0,
        reason,
    };
    if bytes.len() < SAMPLES_OFFSET as usize + 4 || &bytes[..12] != MAGIC {
        return Err(bad("not a PC2 point cache (no POINTCACHE2 header)".into()));
    }
    let word = |at: usize| -> [u8; 4] { bytes[at..at + 4].try_into().unwrap_or([0; 4]) };
    let points = i32::from_le_bytes(word(16));
    let start_frame = f32::from_le_bytes(word(20));
    let sample_rate = f32::from_le_bytes(word(24));
    let samples = i32::from_le_bytes(word(28));
    let (Ok(points), Ok(samples)) = (usize::try_from(points), usize::try_from(samples)) else {
        return Err(bad(format!(
            "negative counts: {points} points, {samples} samples"
        )));
    };
    let body = &bytes[SAMPLES_OFFSET as usize + 4..];
    // Both counts come from the file: up to 2^31 each, 12 bytes per point overflow a u64.
    let expected = (points as u64)
        .checked_mul(samples as u64)
        .and_then(|n| n.checked_mul(12));
    if expected != Some(body.len() as u64) {
        return Err(bad(format!(
            "{} bytes of points for {samples} samples of {points} points (truncated or not finished)",
            body.len()
        )));
    }
    let positions = body
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Ok(PointCache {
        start_frame,
        sample_rate,
        points,
        positions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cache_reads_back_with_its_count_and_start() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("a.pc2");
        let mut w = Pc2Writer::create(&path, 2, 5.0).unwrap();
        w.push(&[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]).unwrap();
        w.push(&[[0.5, 0.25, -1.0], [0.0, 0.0, 0.0]]).unwrap();
        assert!(w.push(&[[0.0; 3]]).is_err(), "a frame of another size");
        assert_eq!(w.samples(), 2);
        w.finish().unwrap();
        let cache = read_pc2(&path).unwrap();
        assert_eq!((cache.start_frame, cache.sample_rate), (5.0, 1.0));
        assert_eq!((cache.points, cache.samples()), (2, 2));
        assert_eq!(&cache.sample(1)[..3], &[0.5, 0.25, -1.0]);
        // 32-byte header + 2 frames × 2 points × 12 bytes.
        assert_eq!(std::fs::metadata(&path).unwrap().len(), 32 + 48);
        std::fs::write(&path, b"not a cache").unwrap();
        let e = read_pc2(&path).unwrap_err().to_string();
        assert!(e.contains("a.pc2") && e.contains("POINTCACHE2"), "{e}");
    }

    #[test]
    fn an_unfinished_cache_continues_after_its_whole_frames() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("a.pc2");
        let mut w = Pc2Writer::create(&path, 2, 0.0).unwrap();
        for k in 0..3 {
            w.push(&[[k as f64; 3], [0.0; 3]]).unwrap();
        }
        w.flush().unwrap();
        drop(w);
        // A killed writer: no sample count in the header, half a frame at the end.
        let mut bytes = std::fs::read(&path).unwrap();
        bytes.truncate(bytes.len() - 6);
        std::fs::write(&path, &bytes).unwrap();
        assert!(
            Pc2Writer::append(&path, 3).is_err(),
            "the third frame is cut"
        );
        let mut w = Pc2Writer::append(&path, 1).unwrap();
        assert_eq!((w.samples(), w.points()), (1, 2));
        w.push(&[[7.0; 3], [0.0; 3]]).unwrap();
        w.finish().unwrap();
        let cache = read_pc2(&path).unwrap();
        assert_eq!(cache.samples(), 2);
        assert_eq!((cache.sample(0)[0], cache.sample(1)[0]), (0.0, 7.0));
    }

    #[test]
    fn counts_whose_size_overflows_are_a_size_mismatch() {
        // 2 130 706 432 points × 1 056 964 650 samples × 12 bytes overflows a u64 (this header
        // used to panic on the multiplication, and could wrap to a plausible size).
        let mut bytes = MAGIC.to_vec();
        for word in [
            0x000b_ff01u32,
            0x7f00_0000,
            0x0000_fdc0,
            0x8000_0000,
            0x3f00_002a,
        ] {
            bytes.extend_from_slice(&word.to_le_bytes());
        }
        let e = parse_pc2(&bytes, Path::new("huge.pc2"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("huge.pc2") && e.contains("0 bytes of points for 1056964650 samples"),
            "{e}"
        );
    }
}
