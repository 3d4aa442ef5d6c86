//! Frame buffers used again: a decoded frame's pixels are read into a buffer that an earlier
//! frame no longer needs, when the pipeline hands one back. A fresh allocation of a 4K frame
//! (25 MB) is new memory, and the kernel faults in and zeroes every one of its pages as the
//! pipe is read into it — about a thousand to two thousand page faults a frame on the 4K
//! clip; a buffer used again has its pages already.

use std::sync::{Arc, Mutex};

use crate::Frame;

/// Buffers kept at most: about the frames a pipeline holds in flight.
const MAX_POOLED: usize = 8;

/// A shared stack of frame buffers; clones share it.
#[derive(Clone, Debug, Default)]
pub struct FramePool {
    buffers: Arc<Mutex<Vec<Vec<u8>>>>,
}

impl FramePool {
    /// An empty buffer with room for `len` bytes: one handed back, or a new allocation.
    pub fn buffer(&self, len: usize) -> Vec<u8> {
        let reused = self.buffers.lock().ok().and_then(|mut b| b.pop());
        match reused {
            Some(mut buffer) if buffer.capacity() >= len => {
                buffer.clear();
                buffer
            }
            _ => Vec::with_capacity(len),
        }
    }

    /// Takes `frame`'s pixels back for a later frame (dropped when the pool is full).
    pub fn recycle(&self, frame: Frame) {
        if let Ok(mut buffers) = self.buffers.lock() {
            if buffers.len() < MAX_POOLED {
                buffers.push(frame.image.into_raw());
            }
        }
    }

    /// Buffers waiting to be used again.
    #[cfg(test)]
    fn len(&self) -> usize {
        self.buffers.lock().map_or(0, |b| b.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::RgbImage;

    fn frame(w: u32, h: u32) -> Frame {
        Frame {
            index: 0,
            source: String::new(),
            timestamp_s: None,
            image: RgbImage::new(w, h),
        }
    }

    #[test]
    fn a_recycled_buffer_is_handed_out_again_empty() {
        let pool = FramePool::default();
        let f = frame(4, 2);
        let pointer = f.image.as_raw().as_ptr();
        pool.clone().recycle(f);
        assert_eq!(pool.len(), 1);
        let b = pool.buffer(24);
        assert_eq!((b.len(), b.as_ptr()), (0, pointer));
        assert_eq!(pool.len(), 0);
        // Too small for the frame asked for: a new allocation instead.
        pool.recycle(frame(2, 2));
        assert!(pool.buffer(24).capacity() >= 24);
        assert_eq!(pool.len(), 0);
    }

    #[test]
    fn the_pool_keeps_a_bounded_number_of_buffers() {
        let pool = FramePool::default();
        for _ in 0..MAX_POOLED + 3 {
            pool.recycle(frame(2, 2));
        }
        assert_eq!(pool.len(), MAX_POOLED);
    }
}
