//! `visage match`: SIFT matches between two images (nearest neighbours, Lowe's ratio test and
//! a mutual check), as JSON, optionally drawn side by side.

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use image::RgbImage;
use visage_keypoints::{
    match_descriptors, Canvas, Features, KeypointsFile, MatchOptions, MatchesFile, Sift,
};

use super::keypoints::{load, save_png, SiftArgs};

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
    let report = MatchesFile::new(&fa, &fb, &matches);
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
        let mut draw = Canvas::new(width, height, &mut canvas);
        draw.matches(&fa.keypoints, &fb.keypoints, &report.matches, wa as f32);
        save_png(path, &canvas)?;
    }
    Ok(())
}

/// The features of an image, or those a keypoints file holds (then without the image).
fn features(path: &Path, sift: &mut Sift) -> anyhow::Result<(Features, Option<RgbImage>)> {
    if is_keypoints_file(path) {
        return Ok((KeypointsFile::load_json(path)?, None));
    }
    let image = load(path)?;
    Ok((sift.detect_and_compute(&image.gray), Some(image.rgb)))
}

/// Whether `path` names a keypoints file (`.json`) rather than an image.
fn is_keypoints_file(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
}
