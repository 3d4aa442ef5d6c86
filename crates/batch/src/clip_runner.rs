//! How one clip is run: the caller's, behind [`ClipRunner`]. The `visage` binary parses the
//! clip's options as `visage run`'s flags and runs its pipeline; tests can run anything.
//!
//! The batch sets a clip's output folder itself (a temporary one under `OUT/.partial/`, then
//! `OUT/ID/`), so options may not name [`RESERVED_FLAGS`]; every clip's options are checked
//! before any work starts, so that a typo fails the invocation rather than each clip.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use crate::error::{BoxError, Error};
use crate::manifest::Clip;

/// Flags the batch sets itself; a clip's options may not name them (alone or as `FLAG=…`).
pub const RESERVED_FLAGS: [&str; 3] = ["--out", "--overwrite", "--resume"];

/// Runs one clip as `visage run INPUT --out OUT --quiet OPTIONS` would. Called from
/// several threads at once (`--jobs`).
pub trait ClipRunner: Sync {
    /// Checks that `options` (the clip's, then the batch's; no reserved flag among them)
    /// can run `clip`, before any clip runs; the error says what is wrong.
    fn check(&self, clip: &Clip, options: &[String]) -> Result<(), BoxError>;

    /// Runs `clip` with `options` into `out`, an empty folder. When `stop` turns true the run
    /// should end after the frame in hand ([`ClipError::Interrupted`]); whatever it returns
    /// then, nothing is placed.
    fn run(
        &self,
        clip: &Clip,
        out: &Path,
        options: &[String],
        stop: &Arc<AtomicBool>,
    ) -> Result<(), ClipError>;
}

/// Why a clip's run did not finish.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ClipError {
    /// Stopped by the stop flag (Ctrl-C, SIGTERM).
    Interrupted,
    /// Failed: what its `error.json` records.
    Failed {
        /// The exit code `visage run` gives for this error: 2 bad input, 3 no face,
        /// 1 internal.
        exit_code: u8,
        /// The error with its causes, `: `-separated (`visage::error_chain`).
        error: String,
    },
}

/// Checks every clip's options — its own, then `common` — before any work starts: no
/// [`RESERVED_FLAGS`], and `runner` accepts them. The error names the manifest line.
pub fn check_options(
    clips: &[Clip],
    common: &[String],
    runner: &impl ClipRunner,
) -> Result<(), Error> {
    for clip in clips {
        let options = clip.options_with(common);
        let checked = match reserved_flag(&options) {
            Some(flag) => Err(Error::ReservedFlag {
                flag: flag.to_owned(),
            }
            .into()),
            None => runner.check(clip, &options),
        };
        checked.map_err(|source| Error::BadOptions {
            line: clip.line,
            id: clip.id.clone(),
            source,
        })?;
    }
    Ok(())
}

/// The first option that names a reserved flag.
fn reserved_flag(options: &[String]) -> Option<&str> {
    options
        .iter()
        .find(|o| {
            RESERVED_FLAGS
                .iter()
                .any(|r| o.split('=').next() == Some(*r))
        })
        .map(String::as_str)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Accepts anything but `--typo`.
    struct NoTypos;

    impl ClipRunner for NoTypos {
        fn check(&self, _: &Clip, options: &[String]) -> Result<(), BoxError> {
            if options.iter().any(|o| o == "--typo") {
                return Err("unexpected argument '--typo'".into());
            }
            Ok(())
        }

        fn run(
            &self,
            _: &Clip,
            _: &Path,
            _: &[String],
            _: &Arc<AtomicBool>,
        ) -> Result<(), ClipError> {
            Ok(())
        }
    }

    #[test]
    fn reserved_flags_and_typos_name_the_line() {
        let clip = |line, options: &[&str]| Clip {
            line,
            id: format!("c{line}"),
            input: "c.mp4".into(),
            options: options.iter().map(|o| o.to_string()).collect(),
        };
        let err = |clips: &[Clip], common: &[String]| {
            visage::error_chain(&check_options(clips, common, &NoTypos).unwrap_err())
        };
        let ok = [clip(1, &["--fov-deg", "50"])];
        assert!(check_options(&ok, &[], &NoTypos).is_ok());
        assert_eq!(
            err(&[clip(1, &[]), clip(2, &["--out=x"])], &[]),
            "manifest line 2 (c2): bad options: --out=x is set by `visage batch` itself (each \
             clip goes to OUT/ID)"
        );
        assert_eq!(
            err(&ok, &["--typo".to_owned()]),
            "manifest line 1 (c1): bad options: unexpected argument '--typo'"
        );
    }
}
