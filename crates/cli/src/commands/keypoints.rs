//! `visage keypoints`: SIFT keypoints and descriptors of an image (paper §3), as JSON in
//! OpenCV's conventions, optionally drawn.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use visage_keypoints::{
    Canvas, Features, GrayImage, KeypointsFile, Sift, SiftOptions, KEYPOINT_COLOUR,
};
use visage_video::read_image;

/// Arguments of `visage keypoints`.
#[derive(Args, Debug)]
pub struct KeypointsArgs {
    /// The image (PNG or JPEG).
    pub image: PathBuf,
    /// The JSON: {"width", "height", "keypoints": [{"x", "y", "size", "angle", "response",
    /// "octave"}…], "descriptors": [[128 bytes]…]}, OpenCV's conventions (pixel centres at
    /// integers, size = diameter in pixels, angle in degrees in [0, 360)).
    #[arg(long)]
    pub out: PathBuf,
    /// Also draw the keypoints (circle of their size, radius along their angle) on the image.
    #[arg(long)]
    pub draw: Option<PathBuf>,
    /// Time the detection: run it this many times on the same buffers (as on a video's
    /// frames) and print the median and the first call's milliseconds.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeat: u32,
    #[command(flatten)]
    pub sift: SiftArgs,
}

/// The detector's options shared by `keypoints` and `match`.
#[derive(Args, Debug, Clone)]
pub struct SiftArgs {
    /// Do not double the image first: about four times less work, no keypoints smaller than
    /// ~2.5 px.
    #[arg(long)]
    pub no_upsample: bool,
    /// Keep only the strongest N keypoints.
    #[arg(long)]
    pub max_keypoints: Option<usize>,
    /// Contrast threshold (intensities 0–1, divided by the 3 layers per octave).
    #[arg(long, default_value_t = SiftOptions::default().contrast_threshold)]
    pub contrast_threshold: f32,
}

impl SiftArgs {
    /// The detector these flags describe.
    pub fn detector(&self) -> anyhow::Result<Sift> {
        if !(self.contrast_threshold.is_finite() && self.contrast_threshold >= 0.0) {
            anyhow::bail!(
                "--contrast-threshold {} must be a non-negative number",
                self.contrast_threshold
            );
        }
        Ok(Sift::new(SiftOptions {
            upsample: !self.no_upsample,
            max_keypoints: self.max_keypoints,
            contrast_threshold: self.contrast_threshold,
            ..SiftOptions::default()
        }))
    }
}

/// An image read for SIFT: its RGB pixels and grey levels.
pub struct LoadedImage {
    /// RGB, for drawing.
    pub rgb: image::RgbImage,
    /// Grey levels 0–255.
    pub gray: GrayImage,
}

/// Reads `path` as an image.
pub fn load(path: &Path) -> anyhow::Result<LoadedImage> {
    let rgb = read_image(path)?.image;
    let (w, h) = (rgb.width() as usize, rgb.height() as usize);
    let gray = GrayImage::from_rgb8(w, h, rgb.as_raw())
        .with_context(|| format!("{}: the decoded image has the wrong size", path.display()))?;
    Ok(LoadedImage { rgb, gray })
}

/// Runs `visage keypoints`; prints a one-line JSON summary (count; median and first call's
/// milliseconds).
pub fn run(args: KeypointsArgs) -> anyhow::Result<()> {
    let image = load(&args.image)?;
    let mut sift = args.sift.detector()?;
    let mut times = Vec::with_capacity(args.repeat as usize);
    let mut features = Features::default();
    for _ in 0..args.repeat {
        let start = Instant::now();
        features = sift.detect_and_compute(&image.gray);
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let first_ms = times[0];
    times.sort_by(f64::total_cmp);
    let ms = times[times.len() / 2];
    write_keypoints(&args.out, &image.rgb, &features)?;
    if let Some(path) = &args.draw {
        let mut rgb = image.rgb.clone();
        let (width, height) = (rgb.width() as usize, rgb.height() as usize);
        Canvas::new(width, height, &mut rgb).keypoints(&features.keypoints, KEYPOINT_COLOUR);
        save_png(path, &rgb)?;
    }
    println!(
        "{}",
        serde_json::json!({"keypoints": features.len(), "ms": ms, "first_ms": first_ms})
    );
    Ok(())
}

fn write_keypoints(path: &Path, rgb: &image::RgbImage, features: &Features) -> anyhow::Result<()> {
    let file = KeypointsFile::new(rgb.width(), rgb.height(), features);
    visage::write_atomically(path, |tmp| {
        std::fs::File::create(tmp)
            .and_then(|f| {
                serde_json::to_writer(std::io::BufWriter::new(f), &file)
                    .map_err(std::io::Error::other)
            })
            .map_err(|source| visage::run_folder::RunFolderError::Write {
                path: tmp.to_owned(),
                source,
            })
    })
    .with_context(|| format!("{}: cannot write the keypoints", path.display()))
}

/// Writes an RGB image as PNG, atomically.
pub fn save_png(path: &Path, rgb: &image::RgbImage) -> anyhow::Result<()> {
    visage::write_atomically(path, |tmp| {
        rgb.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| visage::run_folder::RunFolderError::Write {
                path: tmp.to_owned(),
                source: std::io::Error::other(e),
            })
    })
    .with_context(|| format!("{}: cannot write the drawing", path.display()))
}
