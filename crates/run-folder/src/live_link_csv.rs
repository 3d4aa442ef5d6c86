//! The ARKit curves as a Live Link Face CSV (`blendshapes.csv`, [`LiveLinkCsvWriter`]), streamed
//! under a temporary name and renamed when finished.
//!
//! # Live Link Face CSV
//! One header line, then one row per frame:
//! `Timecode,BlendShapeCount,EyeBlinkLeft,…,TongueOut,HeadYaw,HeadPitch,HeadRoll,LeftEyeYaw,
//! LeftEyePitch,LeftEyeRoll,RightEyeYaw,RightEyePitch,RightEyeRoll` — the 52 blendshapes in
//! Apple's names, capitalised ([`LIVE_LINK_BLENDSHAPES`]), then the 9 rotations
//! ([`LIVE_LINK_ROTATIONS`], [`visage_rig::live_link_angles`] says how they are measured); `BlendShapeCount` is 61, values have 10 decimals. The column
//! order is that of real Live Link Face exports (the public repository
//! `alexdjulin/LiveLinkFace-CSV-Retarget-For-Motionbuilder`, `anim/*.csv` and
//! `csv/facial.csv`), which Blender and Dart importers copy verbatim. It is *not* Unreal's
//! `EARFaceBlendShape` order used by the UDP stream (`JimWest/PyLiveLinkFace`'s enum): the CSV
//! has `JawRight,JawLeft` and `MouthRight,MouthLeft` where the enum has left first. Each value
//! is written under its own name, so either order reads back correctly by name.
//!
//! **Timecode** `HH:MM:SS:FF.fff`: `FF` is the frame within the second and `.fff` the
//! sub-frame, in thousandths of a frame — not milliseconds. Real exports show it: rows 1/30 s
//! apart at a 60 fps timecode rate read `13:13:04:31.652`, `…:33.651`, `…:35.651`, …,
//! `…:59.648`, `13:13:05:01.648` (the frame steps by 2 and wraps after 59, the fraction drifts
//! by a thousandth; as milliseconds it would step by 33). It is Unreal's `FQualifiedFrameTime`,
//! frame number plus sub-frame. [`live_link_timecode`] writes it from a timestamp `t` and the
//! timecode rate `fps`: the frame time `t · fps` rounded to a thousandth of a frame is split
//! into whole frames and the fraction, and the whole frames are counted in SMPTE non-drop-frame
//! style with `round(fps)` frames a second (29.97 and 30000/1001 count 30 a second, 59.94
//! counts 60, 23.976 counts 24; like Unreal's `FTimecode` for a non-integer rate, `ceil`). At
//! 29.97 the timecode thus runs 0.1 % behind the clock, as NTSC non-drop timecode does. Ours
//! starts at `00:00:00:00.000` on the first frame; the app stamps the time of day. The app's
//! own timecode rate is 60 even when it captures at 30 fps, and some importers assume 60:
//! pass 60 as the rate for those.

use std::path::{Path, PathBuf};

use visage_rig::{
    BlendshapeFrame, LIVE_LINK_BLENDSHAPES, LIVE_LINK_ROTATIONS, LIVE_LINK_VALUE_COUNT,
};

use crate::file_names;
use crate::stream::{check_fps, Stream};
use crate::RunFolderError as Error;

/// The Live Link Face timecode `HH:MM:SS:FF.fff` of `timestamp_s` at the timecode rate `fps`:
/// `FF` the frame within the second, `.fff` thousandths of a frame (see the module's docs).
/// Negative times read as 0.
pub fn live_link_timecode(timestamp_s: f64, fps: f64) -> String {
    let per_second = timecode_frames_per_second(fps);
    let thousandths = (timestamp_s.max(0.0) * fps * 1000.0).round() as u64;
    let (frames, sub) = (thousandths / 1000, thousandths % 1000);
    let (seconds, frame) = (frames / per_second, frames % per_second);
    let (h, m, s) = (seconds / 3600, seconds / 60 % 60, seconds % 60);
    format!("{h:02}:{m:02}:{s:02}:{frame:02}.{sub:03}")
}

/// The app's own timecode rate, taken when a take spans no second boundary (nothing in it
/// tells the rate then).
const APP_TIMECODE_RATE: u32 = 60;
/// Timecode rates a take's rate is inferred from (frames counted per timecode second).
const TIMECODE_RATES: [u32; 7] = [24, 25, 30, 48, 50, 60, 120];

/// One row of a Live Link Face take that has tracking.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveLinkRow {
    /// The row's position among the file's data rows (0 = the line after the header).
    pub row: usize,
    /// Seconds since the take's first row, from the timecodes.
    pub time_s: f64,
    /// The 52 weights in ARKit's order ([`visage_rig::ARKIT_BLENDSHAPES`]), read by name.
    pub weights: [f32; visage_rig::ARKIT_BLENDSHAPE_COUNT],
}

/// A Live Link Face CSV read back ([`read_live_link_csv`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LiveLinkTake {
    /// The rows with tracking, in file order.
    pub rows: Vec<LiveLinkRow>,
    /// Rows left out because the app had lost tracking (`BlendShapeCount` 0).
    pub lost_rows: usize,
    /// The timecode rate the timecodes were read at: the smallest common rate above every
    /// frame number `FF` in the file when the take crosses a second, else the app's 60.
    pub timecode_rate: u32,
}

impl LiveLinkTake {
    /// The take's frame rate: one over the median step between rows' times; `None` with
    /// fewer than two rows or no positive step.
    pub fn frame_rate(&self) -> Option<f64> {
        let mut steps: Vec<f64> = self
            .rows
            .windows(2)
            .map(|w| w[1].time_s - w[0].time_s)
            .filter(|d| *d > 0.0)
            .collect();
        steps.sort_by(f64::total_cmp);
        steps.get(steps.len() / 2).map(|d| 1.0 / d)
    }
}

/// A timecode `HH:MM:SS:FF.fff` as (whole seconds, frame number + thousandths of a frame).
fn parse_timecode(text: &str) -> Option<(u64, f64)> {
    let mut parts = text.trim().split(':');
    let mut field = || parts.next()?.parse::<f64>().ok();
    let (h, m, s, f) = (field()?, field()?, field()?, field()?);
    let whole = [h, m, s].iter().all(|v| v.fract() == 0.0 && *v >= 0.0);
    (whole && f >= 0.0).then_some(((h * 3600.0 + m * 60.0 + s) as u64, f))
}

/// Reads a Live Link Face CSV (the module's docs; as the app exports it or as
/// [`LiveLinkCsvWriter`] writes it): the 52 blendshapes by their column names, in any column
/// order, rows whose `BlendShapeCount` is 0 (lost tracking) skipped, times from the timecodes.
///
/// # Errors
/// An unreadable file, a header without `Timecode`, `BlendShapeCount` or one of the 52
/// blendshapes, a row with too few values, an unreadable number or timecode, no row with
/// tracking — each naming the file and the row.
pub fn read_live_link_csv(path: &Path) -> Result<LiveLinkTake, Error> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
        path: path.to_owned(),
        source,
    })?;
    let bad = |reason: String| Error::Input {
        path: path.to_owned(),
        reason,
    };
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| bad("empty file".into()))?
        .split(',')
        .map(str::trim)
        .collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| bad(format!("no column {name} in the header")))
    };
    let timecode = column("Timecode")?;
    let count = column("BlendShapeCount")?;
    let shapes = LIVE_LINK_BLENDSHAPES
        .iter()
        .map(|n| column(n))
        .collect::<Result<Vec<usize>, Error>>()?;
    let mut parsed = Vec::new();
    let mut lost_rows = 0;
    for (row, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let values: Vec<&str> = line.split(',').map(str::trim).collect();
        if values.len() < header.len() {
            return Err(bad(format!(
                "row {row}: {} values, the header has {}",
                values.len(),
                header.len()
            )));
        }
        let number = |i: usize| {
            values[i].parse::<f32>().map_err(|_| {
                bad(format!(
                    "row {row}, {}: not a number: {}",
                    header[i], values[i]
                ))
            })
        };
        if number(count)? == 0.0 {
            lost_rows += 1;
            continue;
        }
        let time = parse_timecode(values[timecode])
            .ok_or_else(|| bad(format!("row {row}: not a timecode: {}", values[timecode])))?;
        let mut weights = [0.0f32; visage_rig::ARKIT_BLENDSHAPE_COUNT];
        for (w, &i) in weights.iter_mut().zip(&shapes) {
            *w = number(i)?;
        }
        parsed.push((row, time, weights));
    }
    let largest_frame = parsed.iter().map(|(_, (_, f), _)| *f).fold(0.0, f64::max);
    let crosses_a_second = parsed.windows(2).any(|w| w[0].1 .0 != w[1].1 .0);
    let timecode_rate = if crosses_a_second {
        TIMECODE_RATES
            .into_iter()
            .find(|&r| largest_frame < f64::from(r))
            .ok_or_else(|| {
                bad(format!(
                    "frame number {largest_frame} beyond any timecode rate"
                ))
            })?
    } else {
        APP_TIMECODE_RATE.max(
            TIMECODE_RATES
                .into_iter()
                .find(|&r| largest_frame < f64::from(r))
                .unwrap_or(0),
        )
    };
    let seconds = |(s, f): (u64, f64)| s as f64 + f / f64::from(timecode_rate);
    let start = parsed
        .first()
        .map(|(_, t, _)| seconds(*t))
        .ok_or_else(|| bad("no row with tracking".into()))?;
    Ok(LiveLinkTake {
        rows: parsed
            .into_iter()
            .map(|(row, t, weights)| LiveLinkRow {
                row,
                time_s: seconds(t) - start,
                weights,
            })
            .collect(),
        lost_rows,
        timecode_rate,
    })
}

/// Frames counted per timecode second: `fps` when it is a whole number, else `ceil(fps)`.
fn timecode_frames_per_second(fps: f64) -> u64 {
    let whole = fps.round();
    let n = if (fps - whole).abs() < 1e-6 {
        whole
    } else {
        fps.ceil()
    };
    (n as u64).max(1)
}

/// Streams frames to a Live Link Face CSV (the module's docs): rows go to `<name>.tmp`, which
/// [`finish`](Self::finish) renames to the final name; dropped unfinished (or when finishing
/// fails), the rows so far stay under the temporary name, where `visage run --resume` finds
/// them.
pub struct LiveLinkCsvWriter {
    stream: Stream,
    fps: f64,
    rows: usize,
}

impl LiveLinkCsvWriter {
    /// Starts `dir/blendshapes.csv` with the timecode rate `fps` (see [`Self::create`]).
    pub fn in_dir(dir: &Path, fps: f64) -> Result<LiveLinkCsvWriter, Error> {
        LiveLinkCsvWriter::create(&dir.join(file_names::BLENDSHAPES_CSV), fps)
    }

    /// Starts the CSV `path` and writes its header; `fps` is the timecode rate, normally the
    /// input's frame rate (the rate the timestamps came from).
    ///
    /// # Errors
    /// `fps` not positive and finite; the temporary file cannot be written.
    pub fn create(path: &Path, fps: f64) -> Result<LiveLinkCsvWriter, Error> {
        check_fps(fps)?;
        let mut stream = Stream::create(path)?;
        let header = ["Timecode", "BlendShapeCount"]
            .iter()
            .chain(&LIVE_LINK_BLENDSHAPES)
            .chain(&LIVE_LINK_ROTATIONS)
            .copied()
            .collect::<Vec<_>>()
            .join(",");
        stream.write(format!("{header}\n").as_bytes())?;
        Ok(LiveLinkCsvWriter {
            stream,
            fps,
            rows: 0,
        })
    }

    /// Continues `dir/blendshapes.csv`'s temporary file, which holds its header and `rows`
    /// rows (a resumed run; [`crate::prepare_resume`] cut it there).
    ///
    /// # Errors
    /// `fps` not positive and finite; the temporary file cannot be opened.
    pub fn append_in_dir(dir: &Path, fps: f64, rows: usize) -> Result<LiveLinkCsvWriter, Error> {
        check_fps(fps)?;
        let stream = Stream::append(&dir.join(file_names::BLENDSHAPES_CSV))?;
        Ok(LiveLinkCsvWriter { stream, fps, rows })
    }

    /// The final path.
    pub fn path(&self) -> &Path {
        self.stream.path()
    }

    /// Rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Hands the rows so far to the operating system.
    ///
    /// # Errors
    /// The temporary file cannot be written.
    pub fn flush(&mut self) -> Result<(), Error> {
        self.stream.flush()
    }

    /// Appends `frame`'s row.
    ///
    /// # Errors
    /// A negative or non-finite timestamp or a non-finite value; the file cannot be written.
    pub fn write(&mut self, frame: &BlendshapeFrame) -> Result<(), Error> {
        self.stream.check(frame)?;
        let mut row = live_link_timecode(frame.timestamp_s, self.fps);
        row.push_str(&format!(",{LIVE_LINK_VALUE_COUNT}"));
        for v in frame.live_link_values() {
            // `+ 0.0` writes −0 as 0.
            row.push_str(&format!(",{:.10}", v + 0.0));
        }
        row.push('\n');
        self.stream.write(row.as_bytes())?;
        self.rows += 1;
        Ok(())
    }

    /// Completes the file and moves it to its final name, which it returns.
    pub fn finish(self) -> Result<PathBuf, Error> {
        self.stream.finish(b"")
    }

    /// Completes the file under its temporary name ([`crate::stream::Completed`]), to be renamed
    /// or taken back together with the run's other files.
    pub(crate) fn complete(self) -> Result<crate::stream::Completed, Error> {
        self.stream.complete(b"")
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::{tmp_path, BlendshapesJsonWriter};

    /// The Live Link Face CSV header, copied from a real export.
    const LIVE_LINK_HEADER: &str = "Timecode,BlendShapeCount,EyeBlinkLeft,EyeLookDownLeft,\
        EyeLookInLeft,EyeLookOutLeft,EyeLookUpLeft,EyeSquintLeft,EyeWideLeft,EyeBlinkRight,\
        EyeLookDownRight,EyeLookInRight,EyeLookOutRight,EyeLookUpRight,EyeSquintRight,\
        EyeWideRight,JawForward,JawRight,JawLeft,JawOpen,MouthClose,MouthFunnel,MouthPucker,\
        MouthRight,MouthLeft,MouthSmileLeft,MouthSmileRight,MouthFrownLeft,MouthFrownRight,\
        MouthDimpleLeft,MouthDimpleRight,MouthStretchLeft,MouthStretchRight,MouthRollLower,\
        MouthRollUpper,MouthShrugLower,MouthShrugUpper,MouthPressLeft,MouthPressRight,\
        MouthLowerDownLeft,MouthLowerDownRight,MouthUpperUpLeft,MouthUpperUpRight,BrowDownLeft,\
        BrowDownRight,BrowInnerUp,BrowOuterUpLeft,BrowOuterUpRight,CheekPuff,CheekSquintLeft,\
        CheekSquintRight,NoseSneerLeft,NoseSneerRight,TongueOut,HeadYaw,HeadPitch,HeadRoll,\
        LeftEyeYaw,LeftEyePitch,LeftEyeRoll,RightEyeYaw,RightEyePitch,RightEyeRoll";

    pub(crate) fn sample_frame(index: usize, timestamp_s: f64) -> BlendshapeFrame {
        let mut f = BlendshapeFrame::new(index, timestamp_s);
        for (i, w) in f.weights.iter_mut().enumerate() {
            *w = (i as f32 * 0.37 + index as f32 * 0.11).fract();
        }
        f.head = [0.1, -0.2, 0.05];
        f.left_eye = [-0.25, 0.125, 0.0];
        f.right_eye = [-0.2, 0.125, -0.01];
        f
    }

    #[test]
    fn takes_read_back_by_name_skipping_lost_rows_with_times_from_timecodes() {
        let dir = tempfile::tempdir().unwrap();
        // 1.5 s at 30 Hz on a 60-frame timecode (as the app writes): frames step by 2.
        let mut w = LiveLinkCsvWriter::in_dir(dir.path(), 60.0).unwrap();
        for i in 0..45 {
            w.write(&sample_frame(i, i as f64 / 30.0)).unwrap();
        }
        let csv = w.finish().unwrap();
        // A row the app lost tracking in, as real exports have them.
        let mut text = std::fs::read_to_string(&csv).unwrap();
        let zeros = vec!["0"; LIVE_LINK_VALUE_COUNT].join(",");
        text.push_str(&format!("00:00:01:32.000,0,{zeros}\n"));
        std::fs::write(&csv, &text).unwrap();
        let take = read_live_link_csv(&csv).unwrap();
        assert_eq!(take.rows.len(), 45);
        assert_eq!(take.lost_rows, 1);
        assert_eq!(take.timecode_rate, 60);
        assert!((take.frame_rate().unwrap() - 30.0).abs() < 1e-6);
        for (i, row) in take.rows.iter().enumerate() {
            assert_eq!(row.row, i);
            assert!(
                (row.time_s - i as f64 / 30.0).abs() < 1e-6,
                "row {i}: {}",
                row.time_s
            );
            let expected = sample_frame(i, 0.0).weights;
            for (a, b) in row.weights.iter().zip(expected) {
                assert!((a - b).abs() < 1e-6, "row {i}: {a} vs {b}");
            }
        }
        // Columns are read by name: swap two and the weights follow.
        let joined: Vec<String> = text
            .lines()
            .map(|l| {
                let mut v: Vec<&str> = l.split(',').collect();
                v.swap(2, 3);
                v.join(",")
            })
            .collect();
        let swapped = dir.path().join("swapped.csv");
        std::fs::write(&swapped, joined.join("\n")).unwrap();
        assert_eq!(read_live_link_csv(&swapped).unwrap(), take);
        // A missing blendshape column is named.
        let cut = dir.path().join("cut.csv");
        std::fs::write(&cut, text.replacen("JawOpen", "Jaw", 1)).unwrap();
        let e = read_live_link_csv(&cut).unwrap_err().to_string();
        assert!(e.contains("no column JawOpen"), "{e}");
    }

    #[test]
    fn a_take_within_one_second_reads_at_the_apps_timecode_rate() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = LiveLinkCsvWriter::in_dir(dir.path(), 60.0).unwrap();
        for i in 0..4 {
            w.write(&sample_frame(i, i as f64 / 60.0)).unwrap();
        }
        let take = read_live_link_csv(&w.finish().unwrap()).unwrap();
        assert_eq!(take.timecode_rate, 60);
        assert!((take.frame_rate().unwrap() - 60.0).abs() < 1e-6);
    }

    #[test]
    fn csv_header_is_live_link_faces() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = LiveLinkCsvWriter::in_dir(dir.path(), 30.0).unwrap();
        let csv = dir.path().join(file_names::BLENDSHAPES_CSV);
        assert!(!csv.exists(), "nothing under the final name before finish");
        w.write(&sample_frame(0, 0.0)).unwrap();
        w.write(&sample_frame(1, 1.0 / 30.0)).unwrap();
        assert_eq!(w.finish().unwrap(), csv);
        assert!(!tmp_path(&csv).exists());
        let text = std::fs::read_to_string(&csv).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let expected: String = LIVE_LINK_HEADER.split_whitespace().collect();
        assert_eq!(lines[0], expected);
        assert_eq!(lines[0].split(',').count(), 2 + LIVE_LINK_VALUE_COUNT);
        assert_eq!(lines.len(), 3);
        let row: Vec<&str> = lines[2].split(',').collect();
        assert_eq!(row.len(), 2 + LIVE_LINK_VALUE_COUNT);
        assert_eq!(&row[..2], ["00:00:00:01.000", "61"]);
        let frame = sample_frame(1, 1.0 / 30.0);
        let values: Vec<f32> = row[2..].iter().map(|v| v.parse().unwrap()).collect();
        for (got, want) in values.iter().zip(frame.live_link_values()) {
            assert!((got - want).abs() <= 1e-9, "{got} vs {want}");
        }
        // By name: the weights follow the header.
        let jaw_left = lines[0].split(',').position(|c| c == "JawLeft").unwrap();
        assert_eq!(
            row[jaw_left].parse::<f32>().unwrap(),
            frame.weight("jawLeft").unwrap()
        );
        assert_eq!(row[2 + 52], "0.1000000015"); // HeadYaw, f32 0.1 to 10 decimals
    }

    #[test]
    fn unfinished_writers_leave_their_frames_under_the_temporary_name() {
        let dir = tempfile::tempdir().unwrap();
        let mut csv = LiveLinkCsvWriter::in_dir(dir.path(), 30.0).unwrap();
        let mut json = BlendshapesJsonWriter::in_dir(dir.path(), Some(30.0)).unwrap();
        csv.write(&sample_frame(0, 0.0)).unwrap();
        json.write(&sample_frame(0, 0.0)).unwrap();
        let mut bad = sample_frame(1, 0.1);
        bad.head[1] = f32::NAN;
        let err = csv.write(&bad).unwrap_err();
        assert!(matches!(err, Error::Write { .. }), "{err}");
        assert!(json.write(&bad).is_err());
        assert!(csv.write(&sample_frame(2, f64::NAN)).is_err());
        drop((csv, json));
        // Nothing under a final name; the frames written so far under the temporary ones,
        // where a resumed run continues them.
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["blendshapes.csv.tmp", "blendshapes.json.tmp"]);
        let csv_rows = std::fs::read_to_string(dir.path().join("blendshapes.csv.tmp")).unwrap();
        assert_eq!(csv_rows.lines().count(), 2, "the header and frame 0");
        assert!(LiveLinkCsvWriter::in_dir(dir.path(), 0.0).is_err());
        assert!(BlendshapesJsonWriter::in_dir(dir.path(), Some(f64::NAN)).is_err());
        let missing = dir.path().join("no/such/dir");
        assert!(matches!(
            LiveLinkCsvWriter::in_dir(&missing, 30.0),
            Err(Error::Write { .. })
        ));
    }

    #[test]
    fn timecodes_count_frames_and_thousandths_of_a_frame() {
        // 30 fps.
        assert_eq!(live_link_timecode(0.0, 30.0), "00:00:00:00.000");
        assert_eq!(live_link_timecode(29.0 / 30.0, 30.0), "00:00:00:29.000");
        assert_eq!(live_link_timecode(31.0 / 30.0, 30.0), "00:00:01:01.000");
        assert_eq!(live_link_timecode(0.05, 30.0), "00:00:00:01.500");
        assert_eq!(live_link_timecode(3661.5, 30.0), "01:01:01:15.000");
        assert_eq!(live_link_timecode(-1.0, 30.0), "00:00:00:00.000");
        // 29.97 (NTSC): 30 frames a timecode second, non-drop-frame.
        let ntsc = 30000.0 / 1001.0;
        for (n, tc) in [
            (29, "00:00:00:29.000"),
            (30, "00:00:01:00.000"),
            (1799, "00:00:59:29.000"),
            (1800, "00:01:00:00.000"),
            (107_892, "00:59:56:12.000"),
        ] {
            assert_eq!(live_link_timecode(n as f64 / ntsc, ntsc), tc, "frame {n}");
            assert_eq!(live_link_timecode(n as f64 / 29.97, 29.97), tc, "frame {n}");
        }
        assert_eq!(
            live_link_timecode(10.25 / ntsc, ntsc),
            "00:00:00:10.250",
            "a quarter frame"
        );
        // 60 fps, as Live Link Face stamps its takes.
        assert_eq!(live_link_timecode(0.5, 60.0), "00:00:00:30.000");
        assert_eq!(
            live_link_timecode(1.0 + 59.0 / 60.0, 60.0),
            "00:00:01:59.000"
        );
        assert_eq!(live_link_timecode(2.0, 60.0), "00:00:02:00.000");
        assert_eq!(
            live_link_timecode((31.652 + 60.0 * 4.0) / 60.0, 60.0),
            "00:00:04:31.652"
        );
    }
}
