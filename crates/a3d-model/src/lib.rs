//! The shared data model: plain data for meshes, materials, material points and
//! FEM node fields. Every reader produces these types and every writer consumes
//! them. This module depends on nothing else in the crate and does no I/O.
//!
//! Conventions (see ARCHITECTURE.md): lengths in m, stresses and pressures in kPa,
//! unit weights in kN/m³. Inside the model every stress and pore pressure uses
//! Anura3D's sign: tension positive, pore-water pressure negative in compression.
//! Tensor components are ordered xx, yy, zz, xy, yz, xz. Indices are 0-based in
//! memory; ids printed for users and written to Anura3D files are 1-based.

mod fem;
pub mod loads;
pub mod material;
mod mesh;
mod points;

pub use fem::{FemNodes, Quantity, StressComponent};
pub use material::{Material, RetentionCurve};
pub use mesh::{AnuraModel, ComputationMethod, Dimension, ElementType, Mesh};
pub use points::{MaterialPoint, MpState};

/// Standard gravitational acceleration used when a CPS gives none (m/s²).
pub const DEFAULT_GRAVITY: f64 = 9.81;

/// Unit weight of water (kN/m³) for a density of 1000 kg/m³ under `g`.
pub fn gamma_water(g: f64) -> f64 {
    1000.0 * g / 1000.0
}
