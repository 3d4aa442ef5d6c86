//! `visage match`: SIFT matches between two images (nearest neighbours, Lowe's ratio test and
//! a mutual check), as JSON, optionally drawn side by side.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use image::RgbImage;
use serde::Serialize;
use visage_keypoints::{match_descriptors, Canvas, Features, MatchOptions, Sift};

use super::keypoints::{load, read_keypoints, save_png, SiftArgs, KEYPOINT_COLOUR};

/// Arguments of `visage match`.
#[derive(Args, Debug)]
pub struct MatchArgs {
    /// The first image (PNG or JPEG), or a keypoints file written by `visage keypoints`.
    pub a: PathBuf,
    /// The second image or keypoints file.
    pub b: PathBuf,
    /// Write the JSON here instead of standard output.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also draw both images side by side with a line per match.
    #[arg(long)]
    pub draw: Option<PathBuf>,
    /// Lowe's ratio: a match is kept when its distance is below this fraction of the second
    /// nearest's.
    #[arg(long, default_value_t = MatchOptions::default().ratio)]
    pub ratio: f32,
    /// Keep one-sided matches (by default a match must be the nearest both ways).
    #[arg(long)]
    pub no_mutual: bool,
    #[command(flatten)]
    pub sift: SiftArgs,
}

#[derive(Serialize)]
struct MatchRecord {
    /// Keypoint index in the first image.
    a: usize,
    /// Keypoint index in the second image.
    b: usize,
    /// Descriptor distance (L2 over the bytes).
    distance: f32,
    /// Position in the first image, pixels.
    a_xy: [f32; 2],
    /// Position in the second image, pixels.
    b_xy: [f32; 2],
}

#[derive(Serialize)]
struct MatchReport {
    keypoints_a: usize,
    keypoints_b: usize,
    matches: Vec<MatchRecord>,
}

/// Runs `visage match`.
pub fn run(args: MatchArgs) -> anyhow::Result<()> {
    if !(args.ratio > 0.0 && args.ratio <= 1.0) {
        anyhow::bail!("--ratio {} must lie in (0, 1]", args.ratio);
    }
    if args.draw.is_some() {
        if let Some(json) = [&args.a, &args.b]
            .into_iter()
            .find(|p| is_keypoints_file(p))
        {
            anyhow::bail!(
                "--draw needs two images, not keypoints files ({})",
                json.display()
            );
        }
    }
    let mut sift = args.sift.detector()?;
    let (fa, a) = features(&args.a, &mut sift)?;
    let (fb, b) = features(&args.b, &mut sift)?;
    let options = MatchOptions {
        ratio: args.ratio,
        mutual: !args.no_mutual,
    };
    let matches = match_descriptors(&fa.descriptors, &fb.descriptors, &options);
    let report = MatchReport {
        keypoints_a: fa.len(),
        keypoints_b: fb.len(),
        matches: matches
            .iter()
            .map(|m| {
                let (p, q) = (&fa.keypoints[m.query], &fb.keypoints[m.train]);
                MatchRecord {
                    a: m.query,
                    b: m.train,
                    distance: m.distance,
                    a_xy: [p.x, p.y],
                    b_xy: [q.x, q.y],
                }
            })
            .collect(),
    };
    let text = serde_json::to_string_pretty(&report)?;
    match &args.out {
        Some(path) => std::fs::write(path, text + "\n")
            .with_context(|| format!("{}: cannot write the matches", path.display()))?,
        None => println!("{text}"),
    }
    if let Some(path) = &args.draw {
        let (Some(a), Some(b)) = (a, b) else {
            anyhow::bail!("--draw needs two images, not keypoints files");
        };
        let (wa, ha) = a.dimensions();
        let (wb, hb) = b.dimensions();
        let mut canvas = RgbImage::new(wa + wb, ha.max(hb));
        image::imageops::replace(&mut canvas, &a, 0, 0);
        image::imageops::replace(&mut canvas, &b, i64::from(wa), 0);
        let (width, height) = (canvas.width() as usize, canvas.height() as usize);
        let mut draw = Canvas {
            width,
            height,
            rgb: &mut canvas,
        };
        let shift = wa as f32;
        for (k, m) in report.matches.iter().enumerate() {
            draw.line(m.a_xy, [m.b_xy[0] + shift, m.b_xy[1]], line_colour(k));
        }
        let kb: Vec<_> = fb
            .keypoints
            .iter()
            .map(|k| visage_keypoints::Keypoint {
                x: k.x + shift,
                ..*k
            })
            .collect();
        draw.keypoints(&fa.keypoints, KEYPOINT_COLOUR);
        draw.keypoints(&kb, KEYPOINT_COLOUR);
        save_png(path, &canvas)?;
    }
    Ok(())
}

/// The features of an image, or those a keypoints file holds (then without the image).
fn features(path: &Path, sift: &mut Sift) -> anyhow::Result<(Features, Option<RgbImage>)> {
    if is_keypoints_file(path) {
        return Ok((read_keypoints(path)?, None));
    }
    let image = load(path)?;
    Ok((sift.detect_and_compute(&image.gray), Some(image.rgb)))
}

/// Whether `path` names a keypoints file (`.json`) rather than an image.
fn is_keypoints_file(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

/// A colour per match, cycling through saturated hues.
fn line_colour(k: usize) -> [u8; 3] {
    const HUES: [[u8; 3]; 6] = [
        [255, 64, 64],
        [255, 200, 0],
        [64, 160, 255],
        [255, 0, 255],
        [0, 230, 230],
        [255, 128, 0],
    ];
    HUES[k % HUES.len()]
}
