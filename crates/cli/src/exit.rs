//! Mapping of errors to exit codes and messages.

use std::process::ExitCode;

/// An error that carries its own exit code (see the crate docs for the table).
#[derive(Debug)]
pub struct Failure {
    pub code: u8,
    pub error: anyhow::Error,
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&visage::error_chain(self.error.as_ref()))
    }
}

impl std::error::Error for Failure {}

/// Exit code of errors that do not say otherwise: bad input or environment.
pub const BAD_INPUT: u8 = 2;

/// Exit code of an input in which no frame shows a face.
pub const NO_FACE: u8 = 3;

/// Exit code of a bug.
pub const INTERNAL: u8 = 1;

/// The exit code of `err`: its own (a [`Failure`]), else 1 for a bug, else 2.
pub fn code_of(err: &anyhow::Error) -> u8 {
    let internal = err.chain().any(|e| {
        e.downcast_ref::<visage::Error>()
            .is_some_and(|e| e.is_internal())
    });
    match err.downcast_ref::<Failure>() {
        Some(f) => f.code,
        None if internal => INTERNAL,
        None => BAD_INPUT,
    }
}

/// Prints an error chain on stderr and turns it into the process exit code.
pub fn report(result: anyhow::Result<()>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {}", visage::error_chain(err.as_ref()));
            ExitCode::from(code_of(&err))
        }
    }
}
