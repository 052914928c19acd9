//! The use cases as library calls, each in a folder of its own: [`map`]
//! (FEM fields onto the MPs, written as an Anura3D project), [`check`]
//! (`verify` and `run` on the built-in runner, from the state Anura3D will
//! hold), [`stability`] (factors of safety, FS(t), the failure step),
//! [`diff`], [`inspect`], [`calibrate`] and [`demo`]; what they share: the
//! project ([`Project::load`]) and FEM ([`fem`]) loaders, the output guard
//! and plots ([`io`]), and the settings messages name ([`setting`]). The CLI
//! turns arguments into these calls and prints; tests and benchmarks call
//! them directly.
//!
//! This module reads files (through [`crate::formats`]) but never prints.

pub mod calibrate;
pub mod cbgeo;
pub mod check;
pub mod demo;
pub mod diff;
pub mod fem;
pub mod inspect;
pub mod io;
pub mod map;
pub mod project;
pub mod setting;
pub mod stability;

pub use project::Project;

/// Why a pipeline step could not run. Reader errors keep their `path:line:col`;
/// [`PipelineError::kind`] says which kind of problem it is, for a caller to
/// match on. Messages name concepts (the smoothing length, the output folder),
/// not command-line flags.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    /// A reader's error, positioned in its file.
    #[error(transparent)]
    Format(#[from] crate::formats::error::FormatError),
    /// Positioned lines, one per problem (already formatted `path:line:col: …`).
    #[error("{0}")]
    Positioned(String),
    /// An input file whose content cannot be used (not positioned).
    #[error("{0}")]
    Input(String),
    /// An option's value that cannot be used (a smoothing length of zero, an
    /// unknown kernel, a time that is not a number).
    #[error("{0}")]
    Option(String),
    /// A model the step cannot work on (an element type, material model or
    /// setting it does not support).
    #[error("{0}")]
    Model(String),
    /// A numerical failure (no convergence, a singular system, a state that
    /// cannot be computed).
    #[error("{0}")]
    Numerical(String),
    /// An output that cannot or may not be written (is an input, a write or
    /// a sync failed).
    #[error("{0}")]
    Output(String),
    /// An output that exists, and replacing it was not asked for
    /// ([`setting::Setting::Replace`]).
    #[error("{} exists, and replacing an output was not asked for", .0.display())]
    Exists(std::path::PathBuf),
}

/// The kinds of [`PipelineError`] (more may come: match with a wildcard arm).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[non_exhaustive]
pub enum ErrorKind {
    /// An input file: missing, unreadable or malformed.
    InputFile,
    /// An option's value.
    OptionValue,
    /// The model: something the step does not support.
    Model,
    /// A numerical failure.
    Numerical,
    /// An output that cannot or may not be written.
    Output,
}

impl PipelineError {
    /// Which kind of problem this is.
    pub fn kind(&self) -> ErrorKind {
        match self {
            PipelineError::Format(_) | PipelineError::Positioned(_) | PipelineError::Input(_) => {
                ErrorKind::InputFile
            }
            PipelineError::Option(_) => ErrorKind::OptionValue,
            PipelineError::Model(_) => ErrorKind::Model,
            PipelineError::Numerical(_) => ErrorKind::Numerical,
            PipelineError::Output(_) | PipelineError::Exists(_) => ErrorKind::Output,
        }
    }
}

/// Writes `value` to `out` as indented JSON (a report the command line
/// prints); a failed write, a closed pipe included, is the `io::Error` it was.
pub fn write_json<W: std::io::Write, T: serde::Serialize + ?Sized>(
    out: &mut W,
    value: &T,
) -> std::io::Result<()> {
    serde_json::to_writer_pretty(&mut *out, value).map_err(std::io::Error::from)?;
    writeln!(out)
}

/// `value` as indented JSON text.
pub fn json_text<T: serde::Serialize + ?Sized>(value: &T) -> std::io::Result<String> {
    serde_json::to_string_pretty(value).map_err(std::io::Error::from)
}
