//! Text ↔ model. Each file format has a spec page in `formats/<name>.md` at the
//! repository root. Readers return typed, positioned errors ([`error`]); nom
//! stays inside this module.

pub mod error;

pub use error::{FormatError, ParseError, Position};
pub mod cbgeo;
pub mod cps;
pub mod cps_template;
pub mod extent;
pub mod fem;
pub mod fem_csv;
pub mod fem_vtu;
pub mod gom;
pub mod gsz;
pub mod hhbf;
pub mod input;
pub mod keyword_doc;
pub mod lex;
pub mod mapf;
pub mod material_map;
pub mod mps_table;
pub mod ply;
pub mod project;
pub mod table_text;
pub mod vtu;
