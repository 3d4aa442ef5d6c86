//! Ctrl-C and SIGTERM: the first asks a long command to stop after the current frame (it then
//! writes what it has and exits 130); a second one stops at once, leaving a clean terminal line.

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Exit code of a run stopped by Ctrl-C or SIGTERM (128 + SIGINT, as shells report it).
pub const INTERRUPTED: u8 = 130;

/// Installs the handler; the flag turns true on the first signal. A second signal ends the
/// process at once, saying so and what `after_second` tells of the files left.
pub fn install(after_second: &str) -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let seen = flag.clone();
    let message = format!("error: stopped at once by a second Ctrl-C: {after_second}\n");
    let installed = ctrlc::set_handler(move || {
        if seen.swap(true, Ordering::SeqCst) {
            // Clear the progress bar's line first.
            let _ = write!(std::io::stderr(), "\r\x1b[2K{message}");
            std::process::exit(i32::from(INTERRUPTED));
        }
    });
    if let Err(e) = installed {
        eprintln!(
            "warning: Ctrl-C will stop at once, without writing {}: {e}",
            visage::file_names::METRICS
        );
    }
    flag
}
