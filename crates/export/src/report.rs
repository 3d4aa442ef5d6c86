//! `report.html`: one self-contained page that opens offline by double-click — the run's summary
//! numbers, the take's moments (blinks, cuts, the strongest expressions) beside their source
//! frames, the per-frame charts and a three.js viewer playing the
//! animated glb. Browsers refuse `fetch` and module imports from `file://` pages, so the
//! viewer's code (one classic script bundled from `web/viewer` at build time) and the glb
//! (base64) are inside the page.

use std::fmt::Write as _;

use serde_json::Value;

use crate::capture::Capture;
use crate::moments::{moments, MomentKind};
use crate::plots::{shapes_by_motion, Plot};
use crate::ExportSummary;
use visage_run_folder::{file_names, FILE_GUIDE, PER_FRAME_MESHES};

/// The viewer bundle (`web/viewer/dist/viewer.js`), when it was built before visage.
#[cfg(viewer_bundle)]
pub const VIEWER_JS: Option<&str> = Some(include_str!("../../../web/viewer/dist/viewer.js"));
/// The viewer bundle (`web/viewer/dist/viewer.js`), when it was built before visage.
#[cfg(not(viewer_bundle))]
pub const VIEWER_JS: Option<&str> = None;

/// A render shown in the report.
pub struct Render {
    pub caption: String,
    pub png: Vec<u8>,
}

/// The page. `viewer`: the bundle and the glb, or `None` for a page without the 3-D viewer.
pub fn report_html(
    capture: &Capture,
    summary: &ExportSummary,
    plots: &[Plot],
    renders: &[Render],
    viewer: Option<(&str, &[u8])>,
) -> String {
    let m = &capture.metrics;
    let s = &m["summary"];
    let input = capture.input.file_name().map_or_else(
        || capture.input.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    );
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>visage — {}</title><style>{STYLE}</style></head><body>\n\
         <h1>visage report: {}</h1>\n<p class=\"sub\">{} · {} frames · status {}</p>\n",
        escape(&input),
        escape(&input),
        escape(&capture.input.display().to_string()),
        s["frames"],
        escape(m["status"].as_str().unwrap_or("?")),
    );
    // The viewer and the summary side by side on a wide screen: what a first look needs.
    h.push_str("<div class=\"top\">\n");
    match viewer {
        Some((_, glb)) => {
            let _ = writeln!(
                h,
                "<section><h2>Animation</h2><p class=\"sub\">{}: the fused surface \
                 as morph targets and head motion, with the fused texture. Drag to orbit, \
                 scroll to zoom.</p><div id=\"visage-viewer\"></div>\
                 <script id=\"visage-glb\" type=\"application/octet-stream\">{}</script>\
                 </section>",
                file_names::GLB,
                base64(glb)
            );
        }
        None => h.push_str(
            "<section><h2>Animation</h2><p>This visage was built without the 3-D viewer \
             (web/viewer/build.sh before building visage adds it).</p></section>\n",
        ),
    }
    h.push_str("<section><h2>Summary</h2><table>\n");
    for (label, value) in take_rows(capture)
        .into_iter()
        .chain(summary_rows(m, summary))
    {
        let _ = writeln!(
            h,
            "<tr><th>{}</th><td>{}</td></tr>",
            escape(&label),
            escape(&value)
        );
    }
    h.push_str("</table></section></div>\n");
    h.push_str("<section><h2>Warnings</h2><ul>\n");
    for w in warnings(m) {
        let _ = writeln!(h, "<li>{}</li>", escape(&w));
    }
    h.push_str("</ul></section>\n");
    if !renders.is_empty() {
        h.push_str("<section><h2>Moments: blinks, cuts and the strongest expressions</h2><p class=\"sub\">Each beside its source frame.</p><div class=\"grid\">\n");
        for r in renders {
            let _ = writeln!(
                h,
                "<figure><img alt=\"{0}\" src=\"data:image/png;base64,{1}\"><figcaption>{0}\
                 </figcaption></figure>",
                escape(&r.caption),
                base64(&r.png)
            );
        }
        h.push_str("</div></section>\n");
    }
    if !plots.is_empty() {
        h.push_str(
            "<section><h2>Curves: the face, the head, then the run</h2><div class=\"grid\">\n",
        );
        for p in plots {
            let _ = writeln!(h, "<figure class=\"chart\">{}</figure>", p.svg);
        }
        h.push_str("</div></section>\n");
    }
    h.push_str(
        "<section><h2>Files and where they go</h2><table>\n\
         <tr><th>file</th><th>holds</th><th>goes to</th></tr>\n",
    );
    for row in FILE_GUIDE.iter().chain([&PER_FRAME_MESHES]) {
        let path = capture.dir.join(row.file);
        let size = match std::fs::metadata(&path) {
            Ok(m) if m.is_file() => format!(" ({:.2} MB)", m.len() as f64 / 1e6),
            Ok(_) => String::new(),
            Err(_) => continue,
        };
        let _ = writeln!(
            h,
            "<tr><td><a href=\"{0}\">{0}</a>{1}</td><td>{2}</td><td>{3}</td></tr>",
            escape(row.file),
            size,
            escape(row.holds),
            escape(row.goes_to)
        );
    }
    h.push_str("</table></section>\n");
    if let Some((js, _)) = viewer {
        // The bundle is inlined as a classic script; it must not close the tag early.
        let _ = writeln!(
            h,
            "<script>{}</script>",
            js.replace("</script", "<\\/script")
        );
    }
    h.push_str("</body></html>\n");
    h
}

/// What a user should know before using the take: stretches of frames without a face or
/// without data (their meshes carry the last solved surface), and shot cuts; one line saying
/// so when there is none.
fn warnings(m: &Value) -> Vec<String> {
    let frames = m["frames"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or_default();
    let mut out = Vec::new();
    for (status, what) in [
        ("no_face", "no face was found"),
        ("no_data", "no depth data"),
        ("carried", "the mesh carries the last solved surface"),
    ] {
        let indices: Vec<u64> = frames
            .iter()
            .filter(|f| f["status"] == status)
            .filter_map(|f| f["index"].as_u64())
            .collect();
        if !indices.is_empty() {
            out.push(format!(
                "{} frame{}: {what} ({})",
                indices.len(),
                if indices.len() == 1 { "" } else { "s" },
                ranges(&indices)
            ));
        }
    }
    let cuts: Vec<u64> = m["summary"]["cuts"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_u64)
        .collect();
    if !cuts.is_empty() {
        out.push(format!(
            "shot cut{} at frame{} {}: the tracker started again (the curves jump there)",
            if cuts.len() == 1 { "" } else { "s" },
            if cuts.len() == 1 { "" } else { "s" },
            ranges(&cuts)
        ));
    }
    if out.is_empty() {
        out.push("None: every frame has a face and its own surface, and there is no cut.".into());
    }
    out
}

/// Sorted indices as runs: "3, 10–14, 20".
fn ranges(indices: &[u64]) -> String {
    let mut runs: Vec<(u64, u64)> = Vec::new();
    for &i in indices {
        match runs.last_mut() {
            Some((_, end)) if *end + 1 == i => *end = i,
            _ => runs.push((i, i)),
        }
    }
    let runs: Vec<String> = runs
        .iter()
        .map(|&(a, b)| {
            if a == b {
                format!("{a}")
            } else {
                format!("{a}–{b}")
            }
        })
        .collect();
    runs.join(", ")
}

/// What the take holds, for its user: its blinks, how far the head turns, the shapes that
/// move most.
fn take_rows(capture: &Capture) -> Vec<(String, String)> {
    let Some(b) = &capture.blendshapes else {
        return Vec::new();
    };
    let blinks: Vec<String> = moments(capture)
        .iter()
        .filter(|m| m.kind == MomentKind::Blink)
        .map(|m| format!("{:.2} s", capture.frames[m.frame].time_s))
        .collect();
    let mut rows = vec![(
        "blinks (both eyes closed)".to_string(),
        match blinks.len() {
            0 => "none".to_string(),
            n => format!("{n}, at {}", blinks.join(", ")),
        },
    )];
    let range = |axis: usize| {
        let values = b.head.iter().flatten().map(|h| h[axis].to_degrees());
        let (lo, hi) = values.fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
        // Whole degrees as integers: no "-0°".
        (lo <= hi).then(|| format!("{}° to {}°", lo.round() as i32, hi.round() as i32))
    };
    if let (Some(yaw), Some(pitch), Some(roll)) = (range(0), range(1), range(2)) {
        rows.push((
            "head turn (yaw, pitch, roll)".into(),
            format!("{yaw}, {pitch}, {roll}"),
        ));
    }
    let active: Vec<String> = shapes_by_motion(capture)
        .into_iter()
        .take(5)
        .map(|(_, s)| s.name)
        .collect();
    if !active.is_empty() {
        rows.push(("shapes that move most".into(), active.join(", ")));
    }
    rows
}

/// The summary table: what a user checks first.
fn summary_rows(m: &Value, e: &ExportSummary) -> Vec<(String, String)> {
    let s = &m["summary"];
    let q = &s["quality"];
    let num = |v: &Value, digits: usize| {
        v.as_f64()
            .map_or_else(|| "—".to_string(), |x| format!("{x:.digits$}"))
    };
    let mut rows = vec![
        (
            "frames (meshed / without a face)".into(),
            format!(
                "{} ({} / {})",
                s["frames"],
                s["solved"].as_u64().unwrap_or(0) + s["carried"].as_u64().unwrap_or(0),
                s["no_face"]
            ),
        ),
        (
            "speed".into(),
            format!(
                "{} fps, CPU use {} cores, peak memory {} MiB",
                num(&s["fps"], 1),
                num(&s["cpu_use"], 2),
                num(&s["peak_rss_mib"], 0)
            ),
        ),
        (
            "camera".into(),
            format!(
                "{}×{}, fx {} px",
                m["intrinsics"]["width"],
                m["intrinsics"]["height"],
                num(&m["intrinsics"]["fx"], 1)
            ),
        ),
        (
            "landmark image jitter, fused / tracked".into(),
            format!(
                "{} / {} px ({}× steadier)",
                num(&q["image_jitter_px"]["fused"], 3),
                num(&q["image_jitter_px"]["raw"], 3),
                num(&q["image_jitter_reduction"], 2)
            ),
        ),
        (
            "vertex jitter, fused / raw (head motion removed)".into(),
            format!(
                "{} / {} mm",
                num(&q["vertex_jitter_mm"]["fused"], 3),
                num(&q["vertex_jitter_mm"]["raw"], 3)
            ),
        ),
        (
            "reprojection of the fused landmarks".into(),
            format!("{} px", num(&q["reprojection_px"]["fused"], 2)),
        ),
        (
            "mean curvature improvement, roughness raw → fused".into(),
            format!(
                "{}, {} → {}",
                num(&s["mean_curvature_improvement"], 2),
                num(&s["mean_roughness_raw"], 4),
                num(&s["mean_roughness"], 4)
            ),
        ),
    ];
    if let Some(rms) = e.glb_rms_error_m {
        rows.push((
            file_names::GLB.into(),
            format!(
                "{} morph targets ({} ARKit), {:.3} mm RMS from the point cache",
                e.named_targets + e.residual_targets,
                e.named_targets,
                rms * 1e3
            ),
        ));
    }
    if let Some(c) = e.texture_coverage {
        rows.push((
            "texture".into(),
            format!(
                "{} frames, {:.0} % of the face seen",
                e.texture_frames,
                c * 100.0
            ),
        ));
    }
    rows
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * i)) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

const STYLE: &str = "body{font:15px/1.45 system-ui,sans-serif;margin:2em auto;max-width:1200px;\
padding:0 1em;color:#222}.top{display:flex;flex-wrap:wrap;gap:2em;align-items:flex-start}\
.top>section{flex:1 1 480px;min-width:0}h1{font-size:1.5em;margin-bottom:.2em}.sub{color:#666;margin-top:0}\
table{border-collapse:collapse}th,td{padding:.25em .8em;border-bottom:1px solid #ddd;\
text-align:left;vertical-align:top}th{font-weight:500;color:#444}\
.grid{display:flex;flex-wrap:wrap;gap:1em}figure{margin:0}figure img{max-width:420px;\
border:1px solid #ccc}figure.chart{flex:1 1 540px;min-width:0}figure svg{display:block;\
width:100%;height:auto}figcaption{color:#666;\
font-size:.9em}#visage-viewer{max-width:640px}";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warnings_name_the_stretches_without_a_face_and_the_cuts() {
        let frames: Vec<Value> = (0..12)
            .map(|i| {
                let status = if (3..=5).contains(&i) || i == 9 {
                    "no_face"
                } else {
                    "solved"
                };
                serde_json::json!({"index": i, "status": status})
            })
            .collect();
        let m = serde_json::json!({"frames": frames, "summary": {"cuts": [7]}});
        assert_eq!(
            warnings(&m),
            [
                "4 frames: no face was found (3–5, 9)",
                "shot cut at frame 7: the tracker started again (the curves jump there)"
            ]
        );
        let clean = serde_json::json!({"frames": [{"index": 0, "status": "solved"}]});
        assert!(warnings(&clean)[0].starts_with("None"));
    }

    #[test]
    fn base64_matches_the_standard_vectors() {
        for (input, expected) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(input.as_bytes()), expected);
        }
    }
}
