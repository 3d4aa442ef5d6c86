//! `visage live`: a camera, a stream, standard input or a file played at its pace, processed
//! frame by frame as it arrives and streamed out while it happens. A command of its own rather
//! than `visage run --live`: it is causal only, drops frames rather than queue them when it
//! falls behind, runs until the source ends or Ctrl-C, and its outputs are streams: the VMC
//! protocol (VTuber apps), Live Link Face's packets (Unreal) and a web page.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use indicatif::ProgressBar;
use visage::live::{
    LiveFrame, LiveLinkFaceSender, LivePage, LiveSession, LiveSubscriber, VmcSender,
};
use visage::{check_fov, Camera, Reconstructor};
use visage_video::{LiveCapture, LiveOptions};

use crate::interrupt;

/// Seconds without a frame after which a network stream is over, unless `--idle-end` says.
const DEFAULT_NETWORK_IDLE_END_S: f64 = 5.0;

/// `visage live`'s flags.
#[derive(Args, Debug)]
pub struct LiveArgs {
    /// What to read: a camera (`/dev/video0`, through FFmpeg's V4L2 input), a network stream
    /// FFmpeg opens (`udp://…`, `rtsp://…`, `http://…`, `srt://…`), `-` for standard input (any
    /// container FFmpeg recognises), or a video file (with --realtime, at its own pace).
    pub source: String,
    /// Read a file at its own frame rate, as a camera delivers frames. Without it a file is
    /// read as fast as FFmpeg decodes it, and the frames that arrive while one is processed
    /// are dropped (to process every frame of a file, use `visage run`).
    #[arg(long)]
    pub realtime: bool,
    /// Send the ARKit weights by the VMC protocol (OSC over UDP) to HOST:PORT (VSeeFace,
    /// Warudo, VNyan and VMagicMirror listen on 39539 by default).
    #[arg(long, value_name = "HOST:PORT")]
    pub vmc: Option<String>,
    /// With --vmc: also send the head's and the eyes' rotations as the `Head`, `LeftEye` and
    /// `RightEye` bones (local rotations in Unity's frame, the subject's own sides; the
    /// position is 0, so the receiver must take only the rotation).
    #[arg(long, requires = "vmc")]
    pub vmc_bones: bool,
    /// Send Live Link Face's UDP packets (what Unreal's Live Link receives from the iPhone app)
    /// to HOST:PORT (Unreal listens on 11111).
    #[arg(long, value_name = "HOST:PORT")]
    pub live_link: Option<String>,
    /// The Live Link subject name.
    #[arg(long, default_value = "visage", requires = "live_link")]
    pub subject: String,
    /// The Live Link device id (the app sends a 36-character UUID).
    #[arg(long, default_value = visage::live::DEFAULT_DEVICE_ID, requires = "live_link")]
    pub device_id: String,
    /// Serve a web page showing the face mesh, head motion, a few curves, the frame rate and
    /// the latency as they happen, on ADDRESS (`HOST:PORT`, or a port alone for 127.0.0.1;
    /// nothing is served without it). It serves only its own page, answers only to that
    /// address, and refuses WebSocket requests from pages of other origins; binding to an
    /// address other machines reach shows them the face.
    #[arg(long, value_name = "ADDRESS")]
    pub listen: Option<String>,
    /// End the session when the source has sent no frame for this many seconds after its
    /// first: a network stream has no end of its own, its sender just stops (default: 5 for a
    /// network stream, never for a camera, a file or standard input; 0: never).
    #[arg(long, value_name = "SECONDS")]
    pub idle_end: Option<f64>,
    /// Frames of look-ahead of the landmark smoother: 0 sends each frame as soon as it is
    /// processed; 1 holds it until the next one is in (steadier curves, a frame's time later).
    #[arg(long, default_value_t = 0, value_name = "FRAMES")]
    pub latency: usize,
    /// Horizontal field of view of the camera, degrees (default: as `visage run`).
    #[arg(long)]
    pub fov_deg: Option<f64>,
    /// Also record the session into this folder, as `visage run` writes one (point cache,
    /// landmarks, blendshape curves, metrics with each frame's latency), for `visage export`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// With --out: replace a previous run's files in the folder (other files stay).
    #[arg(long, requires = "out")]
    pub overwrite: bool,
    /// Stop after this many processed frames.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Model directory; default: $VISAGE_MODELS, else ./models or a models/ folder beside the
    /// executable (see `visage models fetch`).
    #[arg(long)]
    pub models: Option<PathBuf>,
    /// No closing line.
    #[arg(long)]
    pub quiet: bool,
}

/// Runs `visage live`.
pub fn run(args: LiveArgs) -> anyhow::Result<()> {
    if let Some(fov) = args.fov_deg {
        check_fov(fov)?;
    }
    let mut subscribers: Vec<Box<dyn LiveSubscriber>> = Vec::new();
    if let Some(target) = &args.vmc {
        let sender = VmcSender::new(target)
            .with_context(|| format!("--vmc {target}"))?
            .with_bones(args.vmc_bones);
        subscribers.push(Box::new(sender));
    }
    if let Some(target) = &args.live_link {
        let sender = LiveLinkFaceSender::new(target, &args.subject, &args.device_id)
            .with_context(|| format!("--live-link {target}"))?;
        subscribers.push(Box::new(sender));
    }
    if let Some(address) = &args.listen {
        let page = LivePage::bind(address).with_context(|| format!("--listen {address}"))?;
        if !args.quiet {
            eprintln!("the live page: {}", page.url());
        }
        subscribers.push(Box::new(page));
    }
    let idle_end = match args.idle_end {
        Some(s) if !(s.is_finite() && s >= 0.0) => {
            anyhow::bail!("--idle-end {s}: a number of seconds, 0 or more")
        }
        Some(s) => (s > 0.0).then(|| std::time::Duration::from_secs_f64(s)),
        None => args
            .source
            .contains("://")
            .then(|| std::time::Duration::from_secs_f64(DEFAULT_NETWORK_IDLE_END_S)),
    };
    let options = LiveOptions {
        realtime: args.realtime,
        idle_end,
    };
    let capture = LiveCapture::open(&args.source, &options)?;
    let (width, height) = capture.size();
    let mut builder = Reconstructor::builder()
        .latency(args.latency)
        .camera(match args.fov_deg {
            Some(fov) => Camera::FovDeg(fov),
            None => Camera::Auto,
        });
    if let Some(dir) = &args.models {
        builder = builder.models_dir(dir);
    }
    let mut session = LiveSession::new(builder.build(width, height)?);
    // Held until the recording is finished.
    let _lock = match &args.out {
        Some(dir) => {
            let lock = crate::commands::run::claim_output_folder(dir, args.overwrite, false)?;
            session.record_into(dir, &args.source)?;
            Some(lock)
        }
        None => None,
    };
    let stop = interrupt::install("the streams stopped where they were");
    let streams = subscribers.len();
    let bar = crate::progress::progress_bar(args.quiet, None);
    subscribers.push(Box::new(Status { bar: bar.clone() }));
    let summary = session.run(&capture, &mut subscribers, &stop, args.max_frames);
    bar.finish_and_clear();
    subscribers.truncate(streams);
    if capture.went_quiet() && !args.quiet {
        eprintln!(
            "{}: no frame for {:.0} s: the stream is over",
            args.source,
            idle_end.map_or(0.0, |d| d.as_secs_f64())
        );
    }
    if !args.quiet {
        let to: Vec<String> = subscribers.iter().map(|s| s.describe()).collect();
        eprintln!(
            "{}: {} frames in, {} processed ({} with a face), {} dropped; {:.1} fps; latency \
             p50 {:.1} ms, p95 {:.1} ms{}",
            args.source,
            summary.captured,
            summary.processed,
            summary.with_face,
            summary.dropped,
            summary.fps,
            summary.latency.p50_ms,
            summary.latency.p95_ms,
            match (to.is_empty(), &args.out) {
                (true, None) =>
                    "; nothing streamed or recorded (--vmc, --live-link, --listen, --out)"
                        .to_owned(),
                (true, Some(dir)) => format!("; recorded into {}", dir.display()),
                (false, None) => format!("; sent {}", to.join(", ")),
                (false, Some(dir)) => {
                    format!("; sent {}; recorded into {}", to.join(", "), dir.display())
                }
            }
        );
    }
    Ok(session.finish()?)
}

/// The terminal's status line while it runs: frames, frame rate, this frame's latency so far
/// (its packets have left: it is the last subscriber) and whether it had a face.
struct Status {
    bar: ProgressBar,
}

impl LiveSubscriber for Status {
    fn frame(&mut self, frame: &LiveFrame<'_>) -> std::io::Result<()> {
        self.bar.inc(1);
        self.bar.set_message(format!(
            "latency {:.0} ms{}",
            frame.captured_at.elapsed().as_secs_f64() * 1e3,
            if frame.result.blendshapes.is_some() {
                ""
            } else {
                ", no face"
            }
        ));
        Ok(())
    }

    fn describe(&self) -> String {
        "the terminal".into()
    }
}
