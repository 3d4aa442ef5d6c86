//! The font the charts' text is laid out and drawn with: DejaVu Sans, built into the program
//! (the `dejavu` crate's copy; Bitstream Vera's licence, DejaVu's changes in the public
//! domain), so that a PNG has readable text on a machine with no fonts installed. plotters
//! measures the SVG's text with it too; the SVG itself names `sans-serif`, and the reader's
//! browser picks the face.

use std::sync::Once;

use plotters::style::{register_font, FontStyle};

/// The family every chart's text is set in, as plotters looks it up among the registered fonts.
pub(crate) const FAMILY: &str = "sans-serif";

/// Registers DejaVu Sans as [`FAMILY`], once a process; called before any chart is drawn.
pub(crate) fn register_built_in_font() {
    static REGISTER: Once = Once::new();
    REGISTER.call_once(|| {
        // The bytes are DejaVu Sans as released, which parses; a failure would leave the
        // charts without text, which the tests would see.
        let _ = register_font(FAMILY, FontStyle::Normal, dejavu::sans::regular());
    });
}
