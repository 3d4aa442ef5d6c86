//! [`LiveSession`]: a live source through a reconstructor, frame by frame, to subscribers.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use visage_video::LiveCapture;

use crate::{Error, FrameResult, Reconstructor};

/// One processed frame, as subscribers get it.
pub struct LiveFrame<'a> {
    /// What the reconstructor made of it (landmarks, head pose, blendshapes, mesh).
    pub result: &'a FrameResult<'a>,
    /// When the frame was read from the source.
    pub captured_at: Instant,
    /// Seconds since the session started.
    pub time_s: f64,
}

/// A stream out of a live session: it gets every processed frame, in order, as soon as the
/// frame is done. What it does takes from the frame rate: send, do not wait.
pub trait LiveSubscriber {
    /// Hands `frame` on.
    ///
    /// # Errors
    /// The stream failed (the session stops and says which).
    fn frame(&mut self, frame: &LiveFrame<'_>) -> std::io::Result<()>;

    /// What the stream is, for messages (`VMC to 127.0.0.1:39539`).
    fn describe(&self) -> String;
}

/// Latency from a frame's capture to the moment every subscriber had it, milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LatencyFigures {
    pub p50_ms: f64,
    pub p95_ms: f64,
    pub max_ms: f64,
}

/// What a live session did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct LiveSummary {
    /// Frames read from the source.
    pub captured: usize,
    /// Frames processed and handed to the subscribers.
    pub processed: usize,
    /// Frames dropped because a newer one arrived while the last was processed.
    pub dropped: usize,
    /// Processed frames with a face.
    pub with_face: usize,
    pub latency: LatencyFigures,
    /// Processed frames per second of the session.
    pub fps: f64,
}

/// A reconstructor fed by a live source.
pub struct LiveSession {
    reconstructor: Reconstructor,
}

impl LiveSession {
    /// A session processing frames with `reconstructor` (built for the source's size; causal).
    pub fn new(reconstructor: Reconstructor) -> LiveSession {
        LiveSession { reconstructor }
    }

    /// Processes the newest frame of `capture` again and again, handing each to every
    /// subscriber, until the source ends, `stop` turns true or `max_frames` were processed.
    ///
    /// # Errors
    /// The source broke, a frame could not be processed, or a subscriber failed; what was
    /// sent before stays sent.
    pub fn run(
        &mut self,
        capture: &LiveCapture,
        subscribers: &mut [Box<dyn LiveSubscriber>],
        stop: &AtomicBool,
        max_frames: Option<usize>,
    ) -> Result<LiveSummary, Error> {
        let started = capture.started();
        let mut latencies = Vec::new();
        let mut with_face = 0;
        while !stop.load(Ordering::SeqCst) && max_frames.is_none_or(|m| latencies.len() < m) {
            let Some(captured) = capture.next()? else {
                break;
            };
            let result = self.reconstructor.process(&captured.frame)?;
            with_face += usize::from(result.metrics.has_mesh());
            let frame = LiveFrame {
                result: &result,
                captured_at: captured.captured_at,
                time_s: captured.captured_at.duration_since(started).as_secs_f64(),
            };
            for s in subscribers.iter_mut() {
                s.frame(&frame).map_err(|e| Error::Input {
                    path: s.describe().into(),
                    reason: format!("cannot send: {e}"),
                })?;
            }
            latencies.push(captured.captured_at.elapsed().as_secs_f64() * 1e3);
        }
        let (captured, dropped) = capture.counts();
        let elapsed = started.elapsed().as_secs_f64();
        Ok(LiveSummary {
            captured,
            processed: latencies.len(),
            dropped,
            with_face,
            latency: latency_figures(&mut latencies),
            fps: if elapsed > 0.0 {
                latencies.len() as f64 / elapsed
            } else {
                0.0
            },
        })
    }
}

/// Median, 95th percentile and largest of `ms` (nearest rank); zeros when empty.
fn latency_figures(ms: &mut [f64]) -> LatencyFigures {
    if ms.is_empty() {
        return LatencyFigures::default();
    }
    ms.sort_by(f64::total_cmp);
    let rank = |q: f64| ms[((q * ms.len() as f64).ceil() as usize).clamp(1, ms.len()) - 1];
    LatencyFigures {
        p50_ms: rank(0.5),
        p95_ms: rank(0.95),
        max_ms: ms[ms.len() - 1],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_figures_are_nearest_rank() {
        let mut ms: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        let f = latency_figures(&mut ms);
        assert_eq!((f.p50_ms, f.p95_ms, f.max_ms), (50.0, 95.0, 100.0));
        assert_eq!(latency_figures(&mut []), LatencyFigures::default());
    }
}
