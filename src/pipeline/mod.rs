//! The pipeline as library calls: load an Anura3D project ([`Project::load`]),
//! and rebuild the state Anura3D will hold from the files it reads
//! ([`anura3d`]). The CLI turns arguments into these calls and prints; tests and
//! benchmarks call them directly.
//!
//! This module reads files (through [`crate::formats`]) but never prints.

pub mod anura3d;
pub mod calibrate;
mod direct;
pub mod fem;
pub mod map;
pub mod project;
mod regions;
pub mod report;
pub mod verify;
pub mod write;

pub use project::Project;

/// Why a pipeline step could not run. Reader errors keep their `path:line:col`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PipelineError {
    #[error(transparent)]
    Format(#[from] crate::formats::error::FormatError),
    /// Positioned lines, one per problem (already formatted `path:line:col: …`).
    #[error("{0}")]
    Positioned(String),
    #[error("{0}")]
    Input(String),
}
