//! Helpers shared by the integration tests: fixture paths and the real binary.
//! Each test file includes this module with `mod common;`; not every file uses
//! every helper.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// `fixtures/<rel>` of this repository.
pub fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(rel)
}

/// The `a3d-init` binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_a3d-init"))
}

/// Runs the binary: (exit code, stdout, stderr).
pub fn run_split(args: &[&str]) -> (i32, String, String) {
    let out = bin().args(args).output().expect("the binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs the binary: (exit code, stdout followed by stderr).
pub fn run(args: &[&str]) -> (i32, String) {
    let (code, stdout, stderr) = run_split(args);
    (code, stdout + &stderr)
}
