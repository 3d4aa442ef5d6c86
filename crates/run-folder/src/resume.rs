//! Continuing a run that stopped part-way (`visage run --resume`): what the folder's files
//! still hold whole, cut back to the last frame every one of them holds, so that the run goes
//! on after that frame and appends to them.
//!
//! A streaming run hands every frame's outputs to the operating system before it writes the
//! next frame's landmarks record ([`crate::OutputDir`]), so after a kill every stream holds
//! every frame before the last landmarks record whole; that last frame may be partly written
//! and is done again. A run that was interrupted (Ctrl-C, SIGTERM) closed its files, but gave
//! its last frames out without the landmark smoother's look-ahead: those (one with the default
//! latency) are done again too. The temporal state (the landmark smoother, the fusion's previous surface, the
//! identity estimate) is not saved: the resumed run warms it up on the last
//! [`WARM_UP_FRAMES`] kept frames, whose outputs are already written, before the new ones.
//!
//! Only a run with the same input, camera, parameters and `every` is continued (the frame limit
//! may be raised: a complete run that stopped at its limit goes on); a clip-mode run (one solve
//! over the whole clip) and an image-plane mesh (built from the first frame's face) cannot be.

use std::io::Read;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::atomic_write::tmp_path;
use crate::file_names::{self, OUTPUT_FILES, OUTPUT_FOLDERS};
use crate::folder::{clear_outputs, inspect};
use crate::json_records::scan_frames;
use crate::resume_point::{ResumePoint, RunDescription, RunParameters, WARM_UP_FRAMES};
use crate::RunFolderError as Error;

/// What [`prepare_resume`] found.
#[derive(Clone, Debug, PartialEq)]
pub enum ResumeState {
    /// No previous run, or none with a frame worth keeping (its files are removed): start
    /// from the first frame.
    Fresh,
    /// The previous run finished; nothing to do.
    Complete {
        /// Frames its `metrics.json` lists.
        frames: usize,
    },
    /// Continue after [`ResumePoint::after_frame`].
    Continue(ResumePoint),
}

/// The outputs a resumed run continues (the streams, cut back) or keeps. Every other file and
/// folder of [`OUTPUT_FILES`] and [`OUTPUT_FOLDERS`] (the exports, the identity) is made again
/// from the whole sequence, and is removed at the resume point so that none describes only the
/// earlier frames.
const CONTINUED: [&str; 11] = [
    file_names::POINT_CACHE,
    file_names::CACHE_MESH,
    file_names::CACHE_MATERIAL_FILE,
    file_names::LANDMARKS,
    file_names::METRICS,
    file_names::CAMERA,
    file_names::BLENDSHAPES_CSV,
    file_names::BLENDSHAPES_JSON,
    file_names::FACES,
    "meshes",
    "raw",
];

/// Looks at the run in `dir` and, when it stopped part-way, cuts its streamed files back to
/// the last frame they all hold whole and removes what comes after it (per-frame PLYs of
/// later frames, the exports), ready for [`crate::OutputDir::resuming`]. Nothing is changed
/// before every check passed.
///
/// # Errors
/// [`Error::Resume`] when the previous run is of another input, camera, parameters or frame
/// selection, was a clip-mode or image-mesh run, or its files disagree; file errors.
pub fn prepare_resume<P: RunParameters>(
    dir: &Path,
    run: &RunDescription<'_, P>,
) -> Result<ResumeState, Error> {
    let refuse = |reason: String| Error::Resume {
        dir: dir.to_owned(),
        reason,
    };
    if !inspect(dir)?.has_run() {
        return Ok(ResumeState::Fresh);
    }
    let metrics_path = dir.join(file_names::METRICS);
    let metrics: serde_json::Value = match std::fs::read(&metrics_path) {
        Ok(bytes) => serde_json::from_slice(&bytes).map_err(|e| {
            refuse(format!(
                "{} is not readable JSON ({e}). Pass --overwrite to start again",
                file_names::METRICS
            ))
        })?,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(refuse(format!(
                "it has no {}, so which run made its files is unknown. Pass --overwrite to \
                 start again",
                file_names::METRICS
            )))
        }
        Err(source) => {
            return Err(Error::Read {
                path: metrics_path,
                source,
            })
        }
    };
    let status = metrics["status"].as_str().unwrap_or("").to_owned();
    let differences = differences(&metrics, run);
    if !differences.is_empty() {
        return Err(refuse(format!(
            "the previous run differs in {}. Run with its options, or pass --overwrite to \
             start again",
            differences.join("; ")
        )));
    }
    // A complete run that stopped at its frame limit (not at the input's end) goes on when
    // the limit is raised.
    let frames = listed_frames(&metrics);
    let limit = metrics["selection"]["max_frames"]
        .as_u64()
        .map(|m| m as usize);
    let limit_raised = limit.is_some_and(|before| {
        frames >= before && run.selection.max_frames.is_none_or(|now| now > before)
    });
    if status == "complete" && !limit_raised {
        return Ok(ResumeState::Complete { frames });
    }
    if let Some(reason) = run.parameters.cannot_resume() {
        return Err(refuse(reason.into()));
    }
    if !["running", "interrupted", "failed", "complete"].contains(&status.as_str()) {
        return Err(refuse(format!(
            "{}'s status {status:?} is none of visage's. Pass --overwrite to start again",
            file_names::METRICS
        )));
    }

    let Some(landmarks) = existing(dir, file_names::LANDMARKS) else {
        return start_again(dir);
    };
    let scan = scan_frames(&landmarks, |bytes| {
        serde_json::from_slice::<LandmarksRecord>(bytes).ok()
    })?;
    // A killed or failed run may have left its last frame partly written in the other
    // streams. A run that reached the end of its input gave its last frames out without the
    // look-ahead the landmark smoother waits for (`latency_frames`). Both are done again.
    let redo = run.parameters.latency_frames().max(1);
    let whole = scan.records.len().saturating_sub(redo);
    if whole == 0 {
        return start_again(dir);
    }
    if let Some(max) = run.selection.max_frames {
        if max < scan.records.len() {
            return Err(refuse(format!(
                "it already holds {} frames, more than --max-frames {max}. Resume with a larger \
                 --max-frames (or none), or pass --overwrite to start again",
                scan.records.len()
            )));
        }
    }
    let kept = &scan.records[..whole];
    let after_frame = kept[whole - 1].0.index;
    let kept_records = kept_records(&metrics, kept.iter().map(|(r, _)| r));
    let frame_indices: Vec<usize> = kept.iter().map(|(r, _)| r.index).collect();
    let meshed_indices: Vec<usize> = kept
        .iter()
        .filter(|(r, _)| r.meshed())
        .map(|(r, _)| r.index)
        .collect();

    // The point cache: a sample per meshed frame while it is written; a finished one holds a
    // sample per frame (the frames without a mesh hold a meshed one's surface).
    let cache = existing(dir, file_names::POINT_CACHE);
    let cache_indices = match &cache {
        Some(path) if path.extension().is_some_and(|e| e != "tmp") => frame_indices.clone(),
        _ => meshed_indices.clone(),
    };
    if !meshed_indices.is_empty() {
        let Some(cache) = &cache else {
            return Err(refuse(format!(
                "{} is missing, and {} lists {} meshed frames. Pass --overwrite to start again",
                file_names::POINT_CACHE,
                file_names::LANDMARKS,
                meshed_indices.len()
            )));
        };
        let samples = pc2_whole_samples(cache)?;
        if samples < cache_indices.len() as u64 {
            return Err(refuse(format!(
                "{} holds {samples} frames, and {} lists {} up to frame {after_frame}. Pass \
                 --overwrite to start again",
                cache.display(),
                file_names::LANDMARKS,
                cache_indices.len()
            )));
        }
        if !dir.join(file_names::CACHE_MESH).is_file() {
            return Err(refuse(format!(
                "{}, the point cache's mesh, is missing. Pass --overwrite to start again",
                file_names::CACHE_MESH
            )));
        }
    }

    // The blendshape curves: a frame per fitted frame, in both files.
    let fitted = run.parameters.fits_model();
    let mut blendshape_cut = None;
    if fitted {
        let (Some(json), Some(csv)) = (
            existing(dir, file_names::BLENDSHAPES_JSON),
            existing(dir, file_names::BLENDSHAPES_CSV),
        ) else {
            return Err(refuse(format!(
                "{} or {} is missing. Pass --overwrite to start again",
                file_names::BLENDSHAPES_JSON,
                file_names::BLENDSHAPES_CSV
            )));
        };
        let curves = scan_frames(&json, |bytes| {
            serde_json::from_slice::<BlendshapeRecord>(bytes).ok()
        })?;
        let count = curves
            .records
            .iter()
            .take_while(|(r, _)| r.index <= after_frame)
            .count();
        let rows = csv_line_ends(&csv, count + 1)?;
        if rows.len() < count + 1 {
            return Err(refuse(format!(
                "{} holds {} rows, and {} holds {count} frames up to frame {after_frame}. \
                 Pass --overwrite to start again",
                csv.display(),
                rows.len().saturating_sub(1),
                json.display()
            )));
        }
        blendshape_cut = Some((json, curves.end_of(count), csv, rows[count], count));
    }

    // Every check passed: cut the streams back and remove what comes after the resume point.
    let landmarks = into_tmp(&landmarks)?;
    truncate(&landmarks, scan.end_of(whole))?;
    let mut blendshape_frames = 0;
    if let Some((json, json_end, csv, csv_end, count)) = blendshape_cut {
        truncate(&into_tmp(&json)?, json_end)?;
        truncate(&into_tmp(&csv)?, csv_end)?;
        blendshape_frames = count;
    }
    match cache {
        Some(cache) if !meshed_indices.is_empty() => {
            into_tmp(&cache)?;
        }
        cache => {
            for path in cache.into_iter().chain(
                [file_names::CACHE_MESH, file_names::CACHE_MATERIAL_FILE].map(|f| dir.join(f)),
            ) {
                remove_file_if_present(&path)?;
            }
        }
    }
    for sub in ["meshes", "raw"] {
        remove_later_plys(&dir.join(sub), after_frame)?;
    }
    for name in OUTPUT_FILES.iter().filter(|n| !CONTINUED.contains(n)) {
        remove_file_if_present(&dir.join(name))?;
    }
    for name in OUTPUT_FOLDERS.iter().filter(|n| !CONTINUED.contains(n)) {
        let path = dir.join(name);
        if path.is_dir() {
            std::fs::remove_dir_all(&path).map_err(|source| Error::Write { path, source })?;
        }
    }
    Ok(ResumeState::Continue(ResumePoint {
        previous_status: status,
        after_frame,
        frames: whole,
        meshed: meshed_indices.len(),
        blendshape_frames,
        redone: scan.records.len() - whole,
        warm_up_frames: whole.min(WARM_UP_FRAMES),
        warm_up_after: whole
            .checked_sub(WARM_UP_FRAMES + 1)
            .map(|k| frame_indices[k]),
        frame_indices,
        cache_indices: if meshed_indices.is_empty() {
            Vec::new()
        } else {
            cache_indices
        },
        kept_records,
    }))
}

/// The kept frames' `metrics.json` records: the previous run's own where it has them (its
/// `frames` list, which after a resume lists every frame too), else rebuilt from the frame's
/// landmarks record.
fn kept_records<'a>(
    metrics: &serde_json::Value,
    kept: impl Iterator<Item = &'a LandmarksRecord>,
) -> Vec<serde_json::Value> {
    let listed: std::collections::HashMap<u64, &serde_json::Value> = metrics["frames"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|f| Some((f["index"].as_u64()?, f)))
        .collect();
    kept.map(|r| match listed.get(&(r.index as u64)) {
        Some(&f) => f.clone(),
        None => {
            let pose = r.faces.first().and_then(|f| f.pose.clone());
            serde_json::json!({
                "index": r.index,
                "source": r.source,
                "status": if r.meshed() { "solved" } else { "no_face" },
                "pose": pose,
                "restored": true,
            })
        }
    })
    .collect()
}

/// The frames a run's `metrics.json` accounts for. A resumed run lists every frame; one
/// written before that was so listed only its new frames, after `resumed.after_frame`, and
/// counted the kept ones in `resumed.frames`.
fn listed_frames(metrics: &serde_json::Value) -> usize {
    let listed = metrics["frames"].as_array().map_or(&[][..], Vec::as_slice);
    let first = listed.first().and_then(|f| f["index"].as_u64());
    let after = metrics["resumed"]["after_frame"].as_u64();
    match (first, after) {
        (Some(first), Some(after)) if first > after => {
            listed.len() + metrics["resumed"]["frames"].as_u64().unwrap_or(0) as usize
        }
        (None, Some(_)) => metrics["resumed"]["frames"].as_u64().unwrap_or(0) as usize,
        _ => listed.len(),
    }
}

/// A previous run with no frame worth keeping: its files go and the run starts afresh.
fn start_again(dir: &Path) -> Result<ResumeState, Error> {
    clear_outputs(dir)?;
    Ok(ResumeState::Fresh)
}

/// A landmarks record as far as resuming needs it.
#[derive(Deserialize)]
struct LandmarksRecord {
    index: usize,
    #[serde(default)]
    source: String,
    faces: Vec<FaceEntry>,
}

#[derive(Deserialize)]
struct FaceEntry {
    /// Present when the frame was meshed.
    fused_landmarks: Option<serde::de::IgnoredAny>,
    /// The metric face fit's pose, as `metrics.json` records it.
    pose: Option<serde_json::Value>,
}

impl LandmarksRecord {
    fn meshed(&self) -> bool {
        self.faces
            .first()
            .is_some_and(|f| f.fused_landmarks.is_some())
    }
}

#[derive(Deserialize)]
struct BlendshapeRecord {
    index: usize,
}

/// Whether the input differs, in words: by content where both runs recorded it (the same
/// bytes under another path, or typed relative instead of absolute, are the same input; a
/// different file at the same path is not), else by the path, resolved where it can be.
fn input_difference(before: &serde_json::Value, now: &serde_json::Value) -> Option<String> {
    let (b, n) = (&before["input_file"], &now["input_file"]);
    if let (Some(x), Some(y)) = (b["sha256"].as_str(), n["sha256"].as_str()) {
        return (x != y || b["bytes"] != n["bytes"]).then(|| {
            format!(
                "input: another file's content ({} bytes, sha256 {}… then; {} bytes, sha256 {}… \
                 now)",
                b["bytes"],
                &x[..x.len().min(12)],
                n["bytes"],
                &y[..y.len().min(12)]
            )
        });
    }
    let resolved = |v: &serde_json::Value| {
        let typed = v["input"].as_str().unwrap_or_default();
        std::fs::canonicalize(typed).unwrap_or_else(|_| PathBuf::from(typed))
    };
    (resolved(before) != resolved(now))
        .then(|| format!("input ({} then, {} now)", before["input"], now["input"]))
}

/// What differs between the run recorded in `metrics` and `run`, in words (empty: the same).
/// Both sides go through the same JSON text, so numbers compare exactly.
fn differences<P: RunParameters>(
    metrics: &serde_json::Value,
    run: &RunDescription<'_, P>,
) -> Vec<String> {
    let now = serde_json::to_string(run)
        .ok()
        .and_then(|text| serde_json::from_str::<serde_json::Value>(&text).ok())
        .unwrap_or_default();
    let mut found = Vec::new();
    // `max_frames` may change: a run can be extended.
    let every = |v: &serde_json::Value| serde_json::json!({ "every": v["selection"]["every"] });
    let (every_before, every_now) = (every(metrics), every(&now));
    for key in ["input", "intrinsics", "selection", "parameters"] {
        let (before, after) = match key {
            "selection" => (&every_before, &every_now),
            _ => (&metrics[key], &now[key]),
        };
        if key == "input" {
            if let Some(d) = input_difference(metrics, &now) {
                found.push(d);
            }
            continue;
        }
        if before == after {
            continue;
        }
        match (before.as_object(), after.as_object()) {
            (Some(b), Some(a)) if key == "parameters" => {
                let mut names: Vec<&String> = b.keys().chain(a.keys()).collect();
                names.sort();
                names.dedup();
                for name in names {
                    let (x, y) = (&b.get(name), &a.get(name));
                    if x != y {
                        found.push(format!("{name} ({} then, {} now)", shown(*x), shown(*y)));
                    }
                }
            }
            _ => found.push(format!(
                "{key} ({} then, {} now)",
                shown(Some(before)),
                shown(Some(after))
            )),
        }
    }
    found
}

fn shown(value: Option<&serde_json::Value>) -> String {
    match value {
        None | Some(serde_json::Value::Null) => "none".into(),
        Some(v) => v.to_string(),
    }
}

/// `dir/name`, else its temporary sibling, whichever exists.
fn existing(dir: &Path, name: &str) -> Option<PathBuf> {
    let path = dir.join(name);
    [path.clone(), tmp_path(&path)]
        .into_iter()
        .find(|p| p.is_file())
}

/// Renames a finished file to its temporary name (a resumed run appends to it and renames it
/// back when it finishes); a temporary file stays.
fn into_tmp(path: &Path) -> Result<PathBuf, Error> {
    if path.extension().is_some_and(|e| e == "tmp") {
        return Ok(path.to_owned());
    }
    let tmp = tmp_path(path);
    std::fs::rename(path, &tmp).map_err(|source| Error::Write {
        path: tmp.clone(),
        source,
    })?;
    Ok(tmp)
}

fn truncate(path: &Path, length: u64) -> Result<(), Error> {
    let write_error = |source| Error::Write {
        path: path.to_owned(),
        source,
    };
    std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .and_then(|f| f.set_len(length))
        .map_err(write_error)
}

fn remove_file_if_present(path: &Path) -> Result<(), Error> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(Error::Write {
            path: path.to_owned(),
            source: e,
        }),
        _ => Ok(()),
    }
}

/// Whole samples in a point cache (its header's count is only written when it is finished).
fn pc2_whole_samples(path: &Path) -> Result<u64, Error> {
    let read_error = |source| Error::Read {
        path: path.to_owned(),
        source,
    };
    let mut header = [0u8; 32];
    let mut file = std::fs::File::open(path).map_err(read_error)?;
    file.read_exact(&mut header).map_err(read_error)?;
    let points = u64::from(u32::from_le_bytes([
        header[16], header[17], header[18], header[19],
    ]));
    let length = file.metadata().map_err(read_error)?.len();
    Ok((length - 32) / (12 * points.max(1)))
}

/// The byte offsets just past each of the first `limit` line ends of `path`.
fn csv_line_ends(path: &Path, limit: usize) -> Result<Vec<u64>, Error> {
    let read_error = |source| Error::Read {
        path: path.to_owned(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(read_error)?;
    let mut ends = Vec::new();
    let mut block = vec![0u8; 1 << 16];
    let mut offset = 0u64;
    while ends.len() < limit {
        let n = file.read(&mut block).map_err(read_error)?;
        if n == 0 {
            break;
        }
        ends.extend(
            block[..n]
                .iter()
                .enumerate()
                .filter(|(_, &b)| b == b'\n')
                .map(|(i, _)| offset + i as u64 + 1)
                .take(limit - ends.len()),
        );
        offset += n as u64;
    }
    Ok(ends)
}

/// Removes `dir/NNNNNN.ply` of frames after `after_frame`.
fn remove_later_plys(dir: &Path, after_frame: usize) -> Result<(), Error> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let index = name
            .to_str()
            .and_then(|n| n.strip_suffix(".ply"))
            .and_then(|n| n.parse::<usize>().ok());
        if index.is_some_and(|i| i > after_frame) {
            remove_file_if_present(&entry.path())?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resume_point::FrameSelection;
    use visage_camera::Intrinsics;

    /// Parameters as the pipeline's would be recorded: a clip-mode or image-mesh run cannot
    /// be continued.
    #[derive(Clone, Debug, serde::Serialize)]
    struct Parameters {
        mode: &'static str,
        mesh: &'static str,
        landmark_smoothing: Option<f64>,
    }

    impl RunParameters for Parameters {
        fn cannot_resume(&self) -> Option<&'static str> {
            match (self.mode, self.mesh) {
                ("clip", _) => Some("a clip-mode run cannot go on part-way"),
                (_, "image") => Some("an image-plane mesh would be built again"),
                _ => None,
            }
        }

        fn latency_frames(&self) -> usize {
            1
        }

        fn fits_model(&self) -> bool {
            true
        }
    }

    fn parameters(mode: &'static str, mesh: &'static str) -> Parameters {
        Parameters {
            mode,
            mesh,
            landmark_smoothing: Some(1.0),
        }
    }

    fn k() -> Intrinsics {
        Intrinsics::from_fov(64, 48, 60.0).unwrap()
    }

    /// A killed run's folder: `metrics.json` "running" for `run`, records of frames 0, 2, 4
    /// and half of frame 6 (frames 2 and 4 meshed, all fitted), the point cache and the curves
    /// with the frames before 6, PLYs of frames 2 and 4, an export.
    fn killed_run(dir: &Path, run: &RunDescription<'_, Parameters>) {
        let mut metrics = serde_json::to_value(run).unwrap();
        metrics["status"] = "running".into();
        std::fs::write(dir.join("metrics.json"), metrics.to_string()).unwrap();
        let record = |i: usize, meshed: bool| {
            let fused = if meshed {
                ",\"fused_landmarks\":[[1,2]]"
            } else {
                ""
            };
            format!("{{\"index\":{i},\"faces\":[{{\"landmarks\":[[0,0,0]]{fused}}}]}}")
        };
        let landmarks = format!(
            "{{\"frames\": [{},{},{},{{\"index\":6,\"fa",
            record(0, false),
            record(2, true),
            record(4, true)
        );
        std::fs::write(dir.join("landmarks.json.tmp"), landmarks).unwrap();
        let mut cache = Vec::new();
        cache.extend_from_slice(b"POINTCACHE2\0");
        for v in [1i32, 2] {
            cache.extend_from_slice(&v.to_le_bytes());
        }
        cache.extend_from_slice(&0f32.to_le_bytes());
        cache.extend_from_slice(&1f32.to_le_bytes());
        cache.extend_from_slice(&0i32.to_le_bytes());
        cache.extend(std::iter::repeat_n(0u8, 2 * 24 + 7));
        std::fs::write(dir.join("sequence.pc2.tmp"), cache).unwrap();
        std::fs::write(dir.join("mesh.obj"), "v 0 0 0\n").unwrap();
        let curve = |i: usize| format!("{{\"index\":{i},\"timestamp_s\":0}}");
        std::fs::write(
            dir.join("blendshapes.json.tmp"),
            format!(
                "{{\"fps\":30,\"names\":[\"a\"],\"frames\":[{},{},{}",
                curve(0),
                curve(2),
                curve(4)
            ),
        )
        .unwrap();
        std::fs::write(
            dir.join("blendshapes.csv.tmp"),
            "Timecode,x\n00:00:00:00.000,0\n00:00:00:02.000,0\n00:00:00:04.000,0\n00:00:0",
        )
        .unwrap();
        std::fs::create_dir_all(dir.join("meshes")).unwrap();
        for i in [2, 4] {
            std::fs::write(dir.join(format!("meshes/{i:06}.ply")), "ply").unwrap();
        }
        std::fs::write(dir.join("sequence.glb"), "glb").unwrap();
    }

    fn description<'a>(
        parameters: &'a Parameters,
        intrinsics: &'a Intrinsics,
    ) -> RunDescription<'a, Parameters> {
        RunDescription {
            input: "clip.mp4",
            input_file: None,
            intrinsics,
            parameters,
            selection: FrameSelection {
                every: 2,
                max_frames: None,
            },
        }
    }

    #[test]
    fn a_killed_run_is_cut_back_to_the_frame_before_its_last_record() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let (p, k) = (parameters("streaming", "face"), k());
        let run = description(&p, &k);
        killed_run(dir, &run);
        let ResumeState::Continue(point) = prepare_resume(dir, &run).unwrap() else {
            panic!("not continued");
        };
        // Frame 6's record is cut off; frame 4's is whole, but may be partly written in the
        // other streams: done again.
        assert_eq!(point.after_frame, 2);
        assert_eq!((point.frames, point.meshed, point.redone), (2, 1, 1));
        assert_eq!(point.frame_indices, [0, 2]);
        assert_eq!(point.cache_indices, [2]);
        assert_eq!(point.blendshape_frames, 2);
        let text = |name: &str| std::fs::read_to_string(dir.join(name)).unwrap();
        let landmarks: serde_json::Value =
            serde_json::from_str(&(text("landmarks.json.tmp") + "]}")).unwrap();
        assert_eq!(landmarks["frames"].as_array().unwrap().len(), 2);
        let curves: serde_json::Value =
            serde_json::from_str(&(text("blendshapes.json.tmp") + "]}")).unwrap();
        assert_eq!(curves["frames"][1]["index"], 2);
        assert_eq!(text("blendshapes.csv.tmp").lines().count(), 3);
        assert!(text("blendshapes.csv.tmp").ends_with('\n'));
        assert!(dir.join("meshes/000002.ply").exists());
        assert!(!dir.join("meshes/000004.ply").exists());
        assert!(!dir.join("sequence.glb").exists());
        assert!(dir.join("sequence.pc2.tmp").exists() && dir.join("mesh.obj").exists());
    }

    #[test]
    fn another_run_is_refused_naming_what_differs() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let (p, k) = (parameters("streaming", "face"), k());
        killed_run(dir, &description(&p, &k));
        let mut other = p.clone();
        other.landmark_smoothing = Some(3.0);
        let e = prepare_resume(dir, &description(&other, &k))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cannot resume") && e.contains("landmark_smoothing (1.0 then, 3.0 now)"),
            "{e}"
        );
        let mut every = description(&p, &k);
        every.selection.every = 1;
        let e = prepare_resume(dir, &every).unwrap_err().to_string();
        assert!(e.contains("selection") && e.contains("--overwrite"), "{e}");
        // Nothing was touched.
        assert!(dir.join("meshes/000004.ply").exists());
        // The frame limit may change.
        let mut longer = description(&p, &k);
        longer.selection.max_frames = Some(50);
        assert!(matches!(
            prepare_resume(dir, &longer).unwrap(),
            ResumeState::Continue(_)
        ));
    }

    #[test]
    fn clip_mode_and_the_image_mesh_are_refused() {
        let k = k();
        for (mode, mesh, word) in [
            ("clip", "face", "clip-mode"),
            ("streaming", "image", "image-plane"),
        ] {
            let tmp = tempfile::tempdir().unwrap();
            let p = parameters(mode, mesh);
            killed_run(tmp.path(), &description(&p, &k));
            let e = prepare_resume(tmp.path(), &description(&p, &k))
                .unwrap_err()
                .to_string();
            assert!(e.contains(word), "{e}");
        }
    }

    #[test]
    fn a_complete_run_stays_unless_its_frame_limit_is_raised() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let (p, k) = (parameters("streaming", "face"), k());
        let mut run = description(&p, &k);
        run.selection.max_frames = Some(3);
        killed_run(dir, &run);
        let mut metrics = serde_json::to_value(run).unwrap();
        metrics["status"] = "complete".into();
        metrics["frames"] = serde_json::json!([{}, {}, {}]);
        std::fs::write(dir.join("metrics.json"), metrics.to_string()).unwrap();
        assert_eq!(
            prepare_resume(dir, &run).unwrap(),
            ResumeState::Complete { frames: 3 }
        );
        run.selection.max_frames = Some(10);
        let ResumeState::Continue(point) = prepare_resume(dir, &run).unwrap() else {
            panic!("not continued");
        };
        // A complete run's records are all whole, but its last frame had no look-ahead.
        assert_eq!(point.after_frame, 2);
        assert_eq!(point.redone, 1);
    }

    #[test]
    fn an_empty_folder_or_a_run_without_frames_starts_afresh() {
        let tmp = tempfile::tempdir().unwrap();
        let (p, k) = (parameters("streaming", "face"), k());
        let run = description(&p, &k);
        assert_eq!(
            prepare_resume(tmp.path(), &run).unwrap(),
            ResumeState::Fresh
        );
        let mut metrics = serde_json::to_value(run).unwrap();
        metrics["status"] = "running".into();
        std::fs::write(tmp.path().join("metrics.json"), metrics.to_string()).unwrap();
        std::fs::write(tmp.path().join("landmarks.json.tmp"), "{\"frames\": [").unwrap();
        assert_eq!(
            prepare_resume(tmp.path(), &run).unwrap(),
            ResumeState::Fresh
        );
        assert!(!tmp.path().join("metrics.json").exists());
    }
}
