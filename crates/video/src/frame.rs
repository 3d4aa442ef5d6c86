use image::RgbImage;

/// One decoded frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Position in its source, counted from 0 (frame number of a video, file number of a
    /// folder in name order, 0 for a single image).
    pub index: usize,
    /// Where it came from: the image file, or `video.mp4:INDEX`.
    pub source: String,
    /// Presentation time in seconds since the source's first frame (so the first frame is at
    /// 0). A video's frames take the stream's own timestamps (variable frame rates included),
    /// or `index / fps` when the container has none; an image folder's frames are at
    /// `index / fps` only when the caller gave a frame rate
    /// ([`FrameSource::with_frame_rate`](crate::FrameSource::with_frame_rate)), else `None`.
    pub timestamp_s: Option<f64>,
    /// RGB, 8 bits per channel, `width × height`, display orientation (rotation metadata
    /// applied).
    pub image: RgbImage,
}
