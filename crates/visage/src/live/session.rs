//! [`LiveSession`]: a live source through a reconstructor, frame by frame, to subscribers.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use visage_video::LiveCapture;

use super::recording::LiveRecording;
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
    /// Processed frames per second while frames came: over the time from the first processed
    /// frame's capture to the last one's (not the wait for a source to start or to go quiet).
    pub fps: f64,
}

/// A reconstructor fed by a live source.
pub struct LiveSession {
    reconstructor: Reconstructor,
    recording: Option<LiveRecording>,
    started: Instant,
    cpu_at_start: Option<f64>,
    latencies_ms: Vec<(usize, f64)>,
    /// When the first and the last processed frames were captured.
    span: Option<(Instant, Instant)>,
    /// What stopped [`LiveSession::run`], given back by [`LiveSession::finish`].
    error: Option<Error>,
}

impl LiveSession {
    /// A session processing frames with `reconstructor`, built for the source's size. Its
    /// landmark smoother's latency ([`crate::Builder::latency`]) is the session's: 0 hands each
    /// frame on as soon as it is processed; 1 holds it until the next frame is in (steadier
    /// curves, one frame later).
    pub fn new(reconstructor: Reconstructor) -> LiveSession {
        LiveSession {
            reconstructor,
            recording: None,
            started: Instant::now(),
            cpu_at_start: crate::process_stats::cpu_seconds(),
            latencies_ms: Vec::new(),
            span: None,
            error: None,
        }
    }

    /// Also writes every processed frame into the folder `dir` (claimed by the caller), as
    /// `visage run` does, `input` naming the source there ([`LiveRecording`]).
    ///
    /// # Errors
    /// The folder cannot be written.
    pub fn record_into(&mut self, dir: &std::path::Path, input: &str) -> Result<(), Error> {
        self.recording = Some(LiveRecording::start(dir, &self.reconstructor, input)?);
        Ok(())
    }

    /// Ends the session: a recording's files are finished and its `metrics.json` written (each
    /// frame with its latency; the status says how the session ended).
    ///
    /// # Errors
    /// What stopped [`LiveSession::run`] (the source broke, a frame could not be processed, a
    /// stream or the recording failed), else a recording's file that could not be written.
    pub fn finish(self) -> Result<(), Error> {
        let LiveSession {
            reconstructor,
            recording,
            started,
            cpu_at_start,
            latencies_ms,
            error,
            ..
        } = self;
        let Some(recording) = recording else {
            return error.map_or(Ok(()), Err);
        };
        let outcome = reconstructor.finish(started, cpu_at_start, error);
        let written = recording.finish(&outcome, &latencies_ms);
        match outcome.error {
            Some(e) => Err(e),
            None => written,
        }
    }

    /// Processes the newest frame of `capture` again and again, handing each to every
    /// subscriber (then to the recording), until the source ends, `stop` turns true or
    /// `max_frames` were processed. A failure — the source broke, a frame could not be
    /// processed, a stream or the recording failed — ends it too; [`LiveSession::finish`]
    /// gives it back. What was sent before stays sent.
    pub fn run(
        &mut self,
        capture: &LiveCapture,
        subscribers: &mut [Box<dyn LiveSubscriber>],
        stop: &AtomicBool,
        max_frames: Option<usize>,
    ) -> LiveSummary {
        // Only a recording needs every frame's record (its metrics.json).
        self.reconstructor.keep_records(self.recording.is_some());
        let mut with_face = 0;
        let mut latencies = std::mem::take(&mut self.latencies_ms);
        if let Err(e) = self.process(
            capture,
            subscribers,
            stop,
            max_frames,
            &mut latencies,
            &mut with_face,
        ) {
            self.error = Some(e);
        }
        let (captured, dropped) = capture.counts();
        let mut ms: Vec<f64> = latencies.iter().map(|l| l.1).collect();
        let summary = LiveSummary {
            captured,
            processed: latencies.len(),
            dropped,
            with_face,
            latency: latency_figures(&mut ms),
            fps: match self.span {
                Some((first, last)) if last > first => {
                    (latencies.len() - 1) as f64 / last.duration_since(first).as_secs_f64()
                }
                _ => 0.0,
            },
        };
        self.latencies_ms = latencies;
        summary
    }

    /// [`LiveSession::run`]'s loop.
    fn process(
        &mut self,
        capture: &LiveCapture,
        subscribers: &mut [Box<dyn LiveSubscriber>],
        stop: &AtomicBool,
        max_frames: Option<usize>,
        latencies: &mut Vec<(usize, f64)>,
        with_face: &mut usize,
    ) -> Result<(), Error> {
        let started = capture.started();
        // When each frame still in the reconstructor was captured: with the smoother's
        // look-ahead a frame comes out after the next one is in.
        let mut in_flight: VecDeque<(usize, Instant)> = VecDeque::new();
        loop {
            let more = !stop.load(Ordering::SeqCst)
                && max_frames.is_none_or(|m| latencies.len() + in_flight.len() < m);
            let captured = if more { capture.next()? } else { None };
            match &captured {
                Some(c) => {
                    in_flight.push_back((c.frame.index, c.captured_at));
                    self.reconstructor.push(&c.frame)?;
                }
                None => self.reconstructor.push_end()?,
            }
            while let Some(result) = self.reconstructor.next_result() {
                let result = result?;
                let captured_at = loop {
                    match in_flight.pop_front() {
                        Some((index, at)) if index == result.index() => break at,
                        Some(_) => continue,
                        None => break Instant::now(),
                    }
                };
                *with_face += usize::from(result.metrics.has_mesh());
                let first = self.span.map_or(captured_at, |s| s.0);
                self.span = Some((first, captured_at));
                let frame = LiveFrame {
                    result: &result,
                    captured_at,
                    time_s: captured_at.duration_since(started).as_secs_f64(),
                };
                for s in subscribers.iter_mut() {
                    s.frame(&frame).map_err(|e| Error::Input {
                        path: s.describe().into(),
                        reason: format!("cannot send: {e}"),
                    })?;
                }
                // The streams have it: the latency ends here, before the recording writes.
                latencies.push((result.index(), captured_at.elapsed().as_secs_f64() * 1e3));
                if let Some(recording) = &mut self.recording {
                    recording.write(&result)?;
                }
            }
            if captured.is_none() {
                return Ok(());
            }
        }
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
