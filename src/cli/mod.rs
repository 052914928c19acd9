//! Command-line interface: arguments → validated configuration → pipeline.
#![allow(clippy::print_stdout, clippy::print_stderr)]
//! The only module that prints or chooses an exit code.

use std::process::ExitCode;

/// Entry point of the binary. Exit codes: 0 success, 1 a negative verdict
/// (`diff` found differences, `verify` found no equilibrium), 2 bad input or error.
pub fn main() -> ExitCode {
    ExitCode::SUCCESS
}
