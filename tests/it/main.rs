//! The integration tests, one binary (as ripgrep and cargo do): every file
//! beside this one is a module of it, so the library is linked once, not once
//! per file, and the tests of all files share one pool of test threads.
//! `common/` holds the helpers they share. Run one file's tests with
//! `cargo test --test it <file>::`, e.g. `cargo test --test it fos_time::`.

mod common;

mod anura3d_documents;
mod anura3d_kernel_runs;
mod axisymmetric;
mod calibrate;
mod cbgeo;
mod cli;
mod demo;
mod diff;
mod durability;
mod equilibrium;
mod fem_vtu;
mod fidelity;
mod flume;
mod format_pages;
mod fos;
mod fos_time;
mod fuzz;
mod gsz;
mod hardening;
mod kernel;
mod library;
mod loads;
mod map;
mod mpm;
mod pipeline;
mod place;
mod real_projects;
mod slope;
mod slope_stability;
mod tidy;
mod two_phase;
mod verify;
