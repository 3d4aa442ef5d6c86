use image::RgbImage;

/// One decoded frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Position in its source, counted from 0 (frame number of a video, file number of a
    /// folder in name order, 0 for a single image).
    pub index: usize,
    /// Where it came from: the image file, or `video.mp4:INDEX`.
    pub source: String,
    /// RGB, 8 bits per channel, `width × height`, display orientation (rotation metadata
    /// applied).
    pub image: RgbImage,
}
