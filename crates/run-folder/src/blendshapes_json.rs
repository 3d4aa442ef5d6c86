//! The ARKit curves as compact JSON (`blendshapes.json`, [`BlendshapesJsonWriter`]), streamed
//! under a temporary name and renamed when finished.
//!
//! # blendshapes.json
//! `{"fps":30.0,"names":["eyeBlinkLeft",…],"frames":[{"index":0,"timestamp_s":0.0,
//! "weights":[…52],"head":[yaw,pitch,roll],"left_eye":[…],"right_eye":[…]},…]}` on one line:
//! [`visage_rig::BlendshapeTrack`] reads it back. `names` are Apple's camelCase names in the CSV's order,
//! `weights` follow `names`, angles as in the CSV (radians, the signs above), `fps` is `null`
//! when unknown.

use std::path::{Path, PathBuf};

use visage_rig::{BlendshapeFrame, ARKIT_BLENDSHAPES};

use crate::file_names;
use crate::stream::{check_fps, Stream};
use crate::RunFolderError as Error;

/// Streams frames to `blendshapes.json` (the module's docs), compact, under `<name>.tmp` until
/// [`finish`](Self::finish); dropped unfinished, the frames so far stay under the temporary
/// name.
pub struct BlendshapesJsonWriter {
    stream: Stream,
    frames: usize,
}

impl BlendshapesJsonWriter {
    /// Starts `dir/blendshapes.json` (see [`Self::create`]).
    pub fn in_dir(dir: &Path, fps: Option<f64>) -> Result<BlendshapesJsonWriter, Error> {
        BlendshapesJsonWriter::create(&dir.join(file_names::BLENDSHAPES_JSON), fps)
    }

    /// Starts the JSON file `path` for an input at `fps` frames per second (`None`: unknown).
    ///
    /// # Errors
    /// `fps` given but not positive and finite; the temporary file cannot be written.
    pub fn create(path: &Path, fps: Option<f64>) -> Result<BlendshapesJsonWriter, Error> {
        if let Some(fps) = fps {
            check_fps(fps)?;
        }
        let mut stream = Stream::create(path)?;
        let head = serde_json::to_string(&fps)
            .and_then(|fps| Ok((fps, serde_json::to_string(&ARKIT_BLENDSHAPES[..])?)))
            .map(|(fps, names)| format!("{{\"fps\":{fps},\"names\":{names},\"frames\":["))
            .map_err(|e| stream.io_error(e.into()))?;
        stream.write(head.as_bytes())?;
        Ok(BlendshapesJsonWriter { stream, frames: 0 })
    }

    /// Continues `dir/blendshapes.json`'s temporary file, which holds its head and `frames`
    /// frames (a resumed run; [`crate::prepare_resume`] cut it there).
    ///
    /// # Errors
    /// The temporary file cannot be opened.
    pub fn append_in_dir(dir: &Path, frames: usize) -> Result<BlendshapesJsonWriter, Error> {
        let stream = Stream::append(&dir.join(file_names::BLENDSHAPES_JSON))?;
        Ok(BlendshapesJsonWriter { stream, frames })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        self.stream.path()
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Hands the frames so far to the operating system.
    ///
    /// # Errors
    /// The temporary file cannot be written.
    pub fn flush(&mut self) -> Result<(), Error> {
        self.stream.flush()
    }

    /// Appends `frame`.
    ///
    /// # Errors
    /// A negative or non-finite timestamp or a non-finite value; the file cannot be written.
    pub fn write(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        self.stream.check(frame)?;
        let mut text = if self.frames == 0 {
            String::new()
        } else {
            ",".to_owned()
        };
        text.push_str(&serde_json::to_string(frame).map_err(|e| self.stream.io_error(e.into()))?);
        self.stream.write(text.as_bytes())?;
        self.frames += 1;
        Ok(())
    }

    /// Closes the JSON document and moves the file to its final name, which it returns.
    pub fn finish(self) -> Result<PathBuf, Error> {
        self.stream.finish(b"]}\n")
    }

    /// Completes the file under its temporary name ([`crate::stream::Completed`]), to be renamed
    /// or taken back together with the run's other files.
    pub(crate) fn complete(self) -> Result<crate::stream::Completed, Error> {
        self.stream.complete(b"]}\n")
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::live_link_csv::tests::sample_frame;
    use visage_rig::BlendshapeTrack;

    #[test]
    fn json_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let frames: Vec<_> = (0..4)
            .map(|i| sample_frame(i * 2, i as f64 * 2.0 / 29.97))
            .collect();
        let mut w = BlendshapesJsonWriter::in_dir(dir.path(), Some(29.97)).unwrap();
        for f in &frames {
            w.write(f).unwrap();
        }
        assert_eq!(w.frames(), 4);
        let path = w.finish().unwrap();
        assert_eq!(path, dir.path().join(file_names::BLENDSHAPES_JSON));
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 1, "compact");
        let track: BlendshapeTrack = serde_json::from_str(&text).unwrap();
        assert_eq!(track.fps, Some(29.97));
        assert_eq!(track.names, ARKIT_BLENDSHAPES);
        assert_eq!(track.frames, frames);
        // What the writer streams is what serde writes for the whole track.
        assert_eq!(text.trim_end(), serde_json::to_string(&track).unwrap());
        // No frames, no frame rate.
        let empty = BlendshapesJsonWriter::create(&dir.path().join("empty.json"), None).unwrap();
        let text = std::fs::read_to_string(empty.finish().unwrap()).unwrap();
        let track: BlendshapeTrack = serde_json::from_str(&text).unwrap();
        assert_eq!((track.fps, track.frames.len()), (None, 0));
        // The weights must be 52.
        let short = text.replace("\"frames\":[]", "\"frames\":[{\"index\":0,\"timestamp_s\":0.0,\"weights\":[0.5],\"head\":[0,0,0],\"left_eye\":[0,0,0],\"right_eye\":[0,0,0]}]");
        assert!(serde_json::from_str::<BlendshapeTrack>(&short).is_err());
    }
}
