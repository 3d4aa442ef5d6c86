//! Frame sources for visage: videos decoded by the FFmpeg command-line tools (`ffprobe` +
//! `ffmpeg -f rawvideo -pix_fmt rgb24 -` through a pipe, one frame in memory at a time), folders
//! of images and single images. All frames are RGB8 in display orientation.
//!
//! Why the command-line tools: no C libraries to build against (FFmpeg's libraries change their
//! API across versions), and a crash in a decoder cannot take the process down. The cost is one
//! copy per frame through the pipe. Needs the Debian package `ffmpeg` at run time.
//!
//! Frames carry presentation timestamps ([`Frame::timestamp_s`], seconds since the first
//! frame): a video's own, variable frame rates included (see [`ffmpeg`]); an image folder's
//! only when the caller states its frame rate ([`FrameSource::with_frame_rate`]).
//!
//! A truncated or corrupt video yields every decodable frame, then one
//! [`VideoError::Broken`] naming the frame index where decoding stopped.
//!
//! The other way, [`VideoWriter`] encodes RGB frames to H.264 through `ffmpeg` (the preview
//! video), under a temporary name until it is finished.

#![forbid(unsafe_code)]

mod encoder;
mod error;
mod exif;
pub mod ffmpeg;
mod frame;
mod frame_pool;
mod live_capture;
mod source;

pub use encoder::{AudioTrack, VideoWriter};
pub use error::VideoError;
pub use exif::{focal_length_35mm, focal_length_35mm_in};
pub use ffmpeg::{ffmpeg_available, probe, VideoInfo, VideoReader};
pub use frame::Frame;
pub use frame_pool::FramePool;
pub use live_capture::{CapturedFrame, LiveCapture, LiveOptions};
pub use source::{decode_image, is_image_path, read_image, FrameSource, IMAGE_EXTENSIONS};
