//! Command-line interface: arguments → validated configuration → pipeline.
//! This is the only module that prints or chooses an exit code. Errors travel as
//! `anyhow::Error` and print as one chain (`error: {:#}`); see [`main`].
//!
//! Output goes through `say!` and `say_err!`, never `println!`: a closed
//! stdout or stderr (a reader that went away, `| head -1`) ends that stream's
//! output quietly, and the command goes on to its own exit code, as ripgrep
//! and cargo do. Nothing here can panic on a broken pipe, the panic hook
//! included.

/// `println!` that never panics: once stdout is closed, output stops quietly.
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::cli::write_line(false, format_args!($($arg)*))
    };
}

/// `eprintln!` that never panics: once stderr is closed, output stops quietly.
macro_rules! say_err {
    ($($arg:tt)*) => {
        $crate::cli::write_line(true, format_args!($($arg)*))
    };
}

pub mod args;
pub mod calibrate;
mod demo;
mod diff;
mod fos;
mod fos_time;
mod inspect;
pub mod map;
mod print;
mod progress;
mod verify;

use std::io::Write;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

use a3d_init::pipeline::setting::{Setting, spell_settings};
use clap::{Parser, Subcommand};

/// a3d-init: carry a FEM seepage/stress state onto Anura3D material points.
#[derive(Debug, Parser)]
#[command(name = "a3d-init", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Summarise an Anura3D model (GOM/CPS) or a FEM node file.
    Inspect(inspect::InspectArgs),
    /// Map FEM node results onto the MPs of an Anura3D model and write a ready-to-run project.
    Map(map::MapArgs),
    /// Calibrate the smoothing length h by leave-one-out cross-validation (paper Eq. 4).
    Calibrate(calibrate::CalibrateArgs),
    /// Compare two Anura3D projects or files (GOM, CPS, MAPF, mps.csv) within tolerances.
    Diff(diff::DiffArgs),
    /// Run the paper's slope application end to end on the shipped fixture.
    Demo(demo::DemoArgs),
    /// Check with the built-in explicit MPM solver that a mapped state is in equilibrium under gravity.
    Verify(verify::VerifyArgs),
    /// Factor of safety of a mapped state: limit equilibrium (methods of slices) or strength reduction on the built-in MPM solver.
    Fos(fos::FosArgs),
    /// Factor of safety over a time series of FEM fields (limit equilibrium), and the first time it falls to 1.
    FosTime(fos_time::FosTimeArgs),
    /// Keep the explicit MPM solver going for a given time, with snapshots (run-out demonstration).
    Run(verify::RunArgs),
}

/// Set once a write to stdout (or stderr) failed: later lines are dropped.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);
static STDERR_CLOSED: AtomicBool = AtomicBool::new(false);

/// Writes one line to stdout (`to_stderr`: stderr). A failed write (a closed
/// pipe) marks the stream closed; nothing is ever retried or reported.
pub fn write_line(to_stderr: bool, args: std::fmt::Arguments<'_>) {
    let closed = if to_stderr {
        &STDERR_CLOSED
    } else {
        &STDOUT_CLOSED
    };
    if closed.load(Ordering::Relaxed) {
        return;
    }
    let written = if to_stderr {
        writeln!(std::io::stderr().lock(), "{args}")
    } else {
        writeln!(std::io::stdout().lock(), "{args}")
    };
    if written.is_err() {
        closed.store(true, Ordering::Relaxed);
    }
}

/// True when `e` comes from writing to a closed pipe.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    let pipe = Some(std::io::ErrorKind::BrokenPipe);
    e.chain()
        .any(|c| c.downcast_ref::<std::io::Error>().map(std::io::Error::kind) == pipe)
}

/// An error that carries its own exit code (1 = a negative verdict).
#[derive(Debug)]
pub struct Verdict {
    pub message: String,
    pub code: u8,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Verdict {}

impl Verdict {
    /// `Ok` when `holds`, else a negative verdict (exit 1) saying `message`.
    pub fn check(holds: bool, message: &str) -> anyhow::Result<()> {
        if holds {
            return Ok(());
        }
        Err(Verdict {
            message: message.into(),
            code: 1,
        }
        .into())
    }
}

/// Entry point of the binary. Exit codes: 0 success, 1 a negative verdict
/// (`diff` found differences, `verify` found no equilibrium, `map --stress
/// equilibrium` found no state at rest; under `--stress auto` that is a
/// finding, exit 0 with a warning), 2 bad input or any other error.
/// Never panics on bad input.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            if !e.use_stderr() {
                // --help and --version.
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            // clap repeats a bad value whole: cut a long one.
            let text = e.render().to_string();
            let text = a3d_init::formats::error::clip_long_words(&text, MAX_PRINTED_WORD);
            let _ = write!(std::io::stderr(), "{text}");
            return ExitCode::from(2);
        }
    };
    // Last line of defence: a panic is a bug, but it still ends as exit 2 with one
    // line on stderr, after unwinding has removed any staging folder.
    std::panic::set_hook(Box::new(|info| {
        let location = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        let message = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        // Never panics, even on a closed stderr.
        let _ = writeln!(
            std::io::stderr(),
            "error: internal error{location}: {message} (please report this bug)"
        );
    }));
    // Ctrl-C, SIGTERM or SIGHUP: delete what the run had not finished
    // writing, then end with 130, as a shell reports an interrupted command.
    // Without a handler (another one was set first) the signal's default
    // stands.
    let _ = ctrlc::set_handler(|| {
        let removed = a3d_init::pipeline::io::output::discard_unfinished();
        let names: Vec<String> = removed.iter().map(|p| p.display().to_string()).collect();
        let _ = writeln!(
            std::io::stderr(),
            "interrupted: {}",
            if names.is_empty() {
                "no output was being written".to_owned()
            } else {
                format!("removed the unfinished output {}", names.join(", "))
            }
        );
        std::process::exit(130);
    });
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(cli)));
    let Ok(result) = result else {
        return ExitCode::from(2);
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => match e.downcast_ref::<Verdict>() {
            Some(v) => {
                say_err!("{}", v.message);
                ExitCode::from(v.code)
            }
            // A table written straight to a closed stdout: the reader has
            // what it wanted.
            None if is_broken_pipe(&e) => ExitCode::SUCCESS,
            None => {
                say_err!("error: {}", message(&e));
                ExitCode::from(2)
            }
        },
    }
}

/// Longest word an error line repeats whole (paths included); every reader
/// already cuts the tokens it quotes to
/// [`a3d_init::formats::error::MAX_ECHOED_WORD`] characters.
const MAX_PRINTED_WORD: usize = 512;

/// The error's chain as one line, with the command-line flag where the
/// library names a concept, and no word longer than [`MAX_PRINTED_WORD`].
fn message(e: &anyhow::Error) -> String {
    let text = match e.downcast_ref::<a3d_init::pipeline::PipelineError>() {
        Some(a3d_init::pipeline::PipelineError::Exists(path)) => {
            format!("{} exists; pass --force to replace it", path.display())
        }
        _ => spelled(&chain_text(e)),
    };
    a3d_init::formats::error::clip_long_words(&text, MAX_PRINTED_WORD).into_owned()
}

/// The chain as `a: b: c`, as `{:#}` writes it, leaving out a cause that the
/// text before it already ends with (an error that prints its own source,
/// `{path}: {source}`, would otherwise say it twice).
fn chain_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let part = cause.to_string();
        if text.is_empty() {
            text = part;
        } else if !text.ends_with(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
    }
    text
}

/// The command-line flag of each setting the library names.
fn flag(setting: Setting) -> &'static str {
    match setting {
        Setting::Columns => "--columns",
        Setting::FemUnits => "--fem-units",
        Setting::FemSign => "--fem-sign",
        Setting::FemMesh => "--fem-mesh",
        Setting::Analysis => "--analysis",
        Setting::GeneratedCps => "--generate-cps",
        Setting::Replace => "--force",
        Setting::SmoothingLength => "--h",
        Setting::Outside => "--outside",
        Setting::StressSource => "--stress",
        Setting::MixedState => "--mixed-state",
    }
}

/// A library message with the flags of the settings it names.
pub fn spelled(message: &str) -> String {
    spell_settings(message, flag)
}

/// Runs one parsed command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Inspect(args) => inspect::run(args),
        Command::Map(args) => map::run(args),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Diff(args) => diff::run(args),
        Command::Verify(args) => verify::run_verify(args),
        Command::Demo(args) => demo::run(args),
        Command::Run(args) => verify::run_run(args),
        Command::Fos(args) => fos::run(args),
        Command::FosTime(args) => fos_time::run(args),
    }
}
