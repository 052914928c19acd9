//! What every use case writes through: atomic, durable output folders and
//! files and the guard that keeps inputs from being overwritten ([`output`]),
//! direct I/O for the large tables (`direct`), the folder writers fill
//! ([`folder`]), and SVG charts ([`plot`]).

pub(crate) mod direct;
pub mod folder;
pub mod output;
pub mod plot;
