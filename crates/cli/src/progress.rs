//! The progress bar every long command shows on standard error.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A frame counter (`total` frames when known), hidden when `quiet`.
pub fn progress_bar(quiet: bool, total: Option<usize>) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(total.map(|n| n as u64), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{bar:40} {pos}/{len} frames  {per_sec}  eta {eta}")
    {
        bar.set_style(style);
    }
    bar
}
