//! `a3d-bench`: speed figures of a3d-init's hot paths on generated data. A
//! binary of its own, built on the test kit's generators, so that neither the
//! workloads nor their generators ship in `a3d-init`:
//!
//! ```text
//! cargo run --release -p a3d-bench -- map|gom|loo|e2e|csv|equilibrium|fos|runner
//! ```

/// `println!` that never panics: a closed stdout ends the output quietly.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::write_line(format_args!($($arg)*))
    };
}

mod bench;
mod bench_fos;
mod bench_runner;

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;

/// a3d-bench: speed figures of a3d-init's hot paths on generated data.
#[derive(Debug, Parser)]
#[command(name = "a3d-bench", version, about, long_about = None)]
struct Cli {
    #[command(flatten)]
    args: bench::BenchArgs,
}

fn write_line(args: std::fmt::Arguments) {
    let mut out = std::io::stdout().lock();
    let _ = out.write_fmt(args).and_then(|()| out.write_all(b"\n"));
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match bench::run(cli.args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let _ = writeln!(std::io::stderr(), "error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
