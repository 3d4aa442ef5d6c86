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
        write!(f, "{:#}", self.error)
    }
}

impl std::error::Error for Failure {}

/// Exit code of errors that do not say otherwise: bad input or environment.
pub const BAD_INPUT: u8 = 2;

/// Prints an error chain on stderr and turns it into the process exit code.
pub fn report(result: anyhow::Result<()>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            let code = err.downcast_ref::<Failure>().map_or(BAD_INPUT, |f| f.code);
            eprintln!("error: {err:#}");
            ExitCode::from(code)
        }
    }
}
