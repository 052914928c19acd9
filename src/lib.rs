//! a3d-init: carry a FEM seepage/stress state onto the material points of an
//! Anura3D model.
//!
//! The pipeline, in the order data flows:
//!
//! 1. [`formats`] reads FEM node results and the Anura3D model (GOM, CPS)
//!    into the plain data of [`model`]; the GOM and CPS documents are lossless.
//! 2. `place` predicts every material point exactly as Anura3D creates it.
//! 3. `kernel` maps the nodal fields onto the material points with the
//!    Shepard-normalised kernel interpolation of the seed paper.
//! 4. `calibrate` chooses the smoothing length by leave-one-out annealing.
//! 5. [`formats`] writes the MAPF, the CPS switch, tables, VTU and reports.
//! 6. `mpm` runs an explicit MPM check of the mapped state under gravity.
//!
//! `cli` (feature `cli`, on by default) is the only module that prints or
//! exits; the library builds without it. See ARCHITECTURE.md.

pub mod calibrate;
#[cfg(feature = "cli")]
pub mod cli;
pub mod diagnose;
pub mod element;
pub mod formats;
pub mod kernel;
pub mod model;
pub mod mpm;
pub mod pipeline;
pub mod place;
pub mod progress;
pub mod slope;
pub mod state;
#[cfg(any(test, feature = "testkit"))]
pub mod testkit;
