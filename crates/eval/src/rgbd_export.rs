//! A synthetic sequence written as an RGB-D recording in the TUM RGB-D layout — colour renders
//! (8-bit sRGB PNG), 16-bit depth PNGs at 5000 units per metre, `rgb.txt` and `depth.txt` with
//! timestamps that jitter as a real recorder's do — so `visage run --rgbd` can be measured
//! against the ground truth.

use std::fmt::Write as _;
use std::path::Path;

use image::RgbImage;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use visage_camera::{write_depth_png, DepthMap};
use visage_mesh::color::linear_to_srgb_u8;

use crate::{EvalError, SyntheticSequence};

/// TUM RGB-D's depth units per metre.
const TUM_DEPTH_SCALE: f64 = 5000.0;

/// How the recording's clocks behave (defaults: 30 fps from 1305031102 s, colour times off
/// by up to ±3 ms, depth 4 ± 3 ms after its colour frame, every frame with a depth map).
#[derive(Clone, Debug, PartialEq)]
pub struct RecordingClock {
    pub start_s: f64,
    pub fps: f64,
    /// Largest deviation of a timestamp from its nominal time, seconds (uniform).
    pub jitter_s: f64,
    /// Depth frames come this long after their colour frame, seconds.
    pub depth_delay_s: f64,
    /// Frames written without a depth map (a dropped sensor frame).
    pub dropped_depth: Vec<usize>,
}

impl Default for RecordingClock {
    fn default() -> Self {
        RecordingClock {
            start_s: 1_305_031_102.0,
            fps: 30.0,
            jitter_s: 0.003,
            depth_delay_s: 0.004,
            dropped_depth: Vec::new(),
        }
    }
}

/// Writes `seq` into `dir` (created) as a TUM RGB-D recording: frame k's colour render with
/// per-vertex `albedo` (linear RGB, one per rendered vertex) and `depth[k]` (metres, z).
/// Returns the colour timestamps.
///
/// # Errors
/// A failing render, a `depth` list of another length, a file that cannot be written.
pub fn write_tum_recording(
    seq: &SyntheticSequence,
    albedo: &[[f32; 3]],
    depth: &[DepthMap],
    clock: &RecordingClock,
    dir: &Path,
    seed: u64,
) -> Result<Vec<f64>, EvalError> {
    if depth.len() != seq.frames.len() {
        return Err(EvalError::InvalidConfig {
            name: "depth",
            value: depth.len().to_string(),
            reason: "needs one depth map per frame",
        });
    }
    let io = |path: &Path| {
        let path = path.to_owned();
        move |source| EvalError::Io { path, source }
    };
    for sub in ["rgb", "depth"] {
        std::fs::create_dir_all(dir.join(sub)).map_err(io(&dir.join(sub)))?;
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let jitter = |rng: &mut ChaCha8Rng| rng.random_range(-clock.jitter_s..=clock.jitter_s);
    let (mut rgb_list, mut depth_list) = (
        String::from("# color images\n# timestamp filename\n"),
        String::from("# depth maps\n# timestamp filename\n"),
    );
    let mut times = Vec::with_capacity(seq.frames.len());
    let (w, h) = (seq.k.width, seq.k.height);
    for (k, map) in depth.iter().enumerate() {
        let t = clock.start_s + k as f64 / clock.fps + jitter(&mut rng);
        let name = format!("rgb/{t:.6}.png");
        let linear = seq.render_color_with(k, Some(albedo))?;
        let pixels: Vec<u8> = linear
            .iter()
            .flat_map(|c| c.map(linear_to_srgb_u8))
            .collect();
        let image = RgbImage::from_raw(w, h, pixels).ok_or(EvalError::InvalidConfig {
            name: "render",
            value: format!("{w}×{h}"),
            reason: "the render has another size than the camera",
        })?;
        let path = dir.join(&name);
        image.save(&path).map_err(|e| EvalError::Io {
            path: path.clone(),
            source: std::io::Error::other(e),
        })?;
        let _ = writeln!(rgb_list, "{t:.6} {name}");
        times.push(t);
        if !clock.dropped_depth.contains(&k) {
            let td = t + clock.depth_delay_s + jitter(&mut rng);
            let name = format!("depth/{td:.6}.png");
            write_depth_png(&dir.join(&name), map, TUM_DEPTH_SCALE)?;
            let _ = writeln!(depth_list, "{td:.6} {name}");
        }
    }
    for (file, text) in [("rgb.txt", rgb_list), ("depth.txt", depth_list)] {
        std::fs::write(dir.join(file), text).map_err(io(&dir.join(file)))?;
    }
    Ok(times)
}
