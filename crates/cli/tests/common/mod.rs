//! Helpers shared by the CLI tests: run the real `visage` binary.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// Runs `visage ARGS…` and returns its output.
pub fn visage(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_visage"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `visage ARGS…` and fails the test (with its stderr) unless it succeeds.
pub fn run_ok(args: &[&str]) {
    let o = visage(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}
