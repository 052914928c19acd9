//! Slope stability of a model's state: a model's section, unit weights and
//! pore field for limit equilibrium ([`slope`]), the factor of safety by
//! either method and their comparison ([`fos`]), FS(t) over a FEM series
//! ([`fos_time`]), and the first saved step with FS ≤ 1 that `map` can map
//! ([`failure`]).

pub mod failure;
pub mod fos;
pub mod fos_time;
pub mod slope;
