//! a3d-init: carry a FEM seepage/stress state onto the material points of an
//! Anura3D model.
//!
//! This crate holds the use cases ([`pipeline`]: map, verify and run,
//! stability, diff, inspect, demo); the layers beneath it are crates of their
//! own, re-exported here under the names the pipeline uses, in the order data
//! flows:
//!
//! 1. [`formats`] (`a3d-formats`) reads FEM node results and the Anura3D model
//!    (GOM, CPS) into the plain data of [`model`] (`a3d-model`); the GOM and
//!    CPS documents are lossless.
//! 2. [`place`] (in `a3d-element`) predicts every material point exactly as
//!    Anura3D creates it, on the shape functions of [`element`].
//! 3. [`kernel`] (`a3d-kernel`) maps the nodal fields onto the material points
//!    with the Shepard-normalised kernel interpolation of the seed paper;
//!    [`calibrate`] chooses the smoothing length by leave-one-out annealing.
//! 4. [`formats`] writes the MAPF, the CPS switch, tables, VTU and reports.
//! 5. [`mpm`] (`a3d-mpm`) runs an explicit MPM check of the mapped state under
//!    gravity and solves for equilibrium; [`slope`] (`a3d-slope`) is limit
//!    equilibrium; [`state`] (`a3d-state`) the closed-form initial states.
//!
//! Nothing here prints or exits: the `a3d-init` binary (the workspace root) is
//! the command line. See ARCHITECTURE.md.

pub mod diagnose;
pub mod pipeline;

pub use a3d_element as element;
pub use a3d_element::place;
pub use a3d_formats as formats;
pub use a3d_kernel as kernel;
pub use a3d_kernel::calibrate;
pub use a3d_model as model;
pub use a3d_mpm as mpm;
pub use a3d_progress as progress;
pub use a3d_slope as slope;
pub use a3d_state as state;
