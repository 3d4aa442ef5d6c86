//! The progress bar every long command shows on standard error.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};

/// Frames per second with one decimal, as the bar shows it.
fn fps_text(per_sec: f64) -> String {
    format!("{per_sec:.1} fps")
}

fn fps(state: &ProgressState, w: &mut dyn std::fmt::Write) {
    let _ = w.write_str(&fps_text(state.per_sec()));
}

/// A frame counter (`total` frames when known) with the frame rate and the time left, hidden
/// when `quiet`.
pub fn progress_bar(quiet: bool, total: Option<usize>) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(total.map(|n| n as u64), ProgressDrawTarget::stderr());
    let template = match total {
        Some(_) => "{bar:40} {pos}/{len} frames  {fps}  eta {eta}",
        None => "{spinner} {pos} frames  {fps}  {msg}",
    };
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style.with_key("fps", fps));
    }
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rate_has_one_decimal() {
        assert_eq!(fps_text(12.3456), "12.3 fps");
        assert_eq!(fps_text(0.0), "0.0 fps");
    }
}
