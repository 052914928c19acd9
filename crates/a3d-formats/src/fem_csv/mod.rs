//! FEM node tables: GeoStudio-style CSV exports in their many dialects, and the
//! `node.csv` that GeoStudio keeps inside a `.gsz` (with coordinates from the
//! sibling `Mesh.ply`). Spec: `formats/geostudio-csv.md`.
//!
//! The reader sniffs the dialect (BOM, delimiter `,` `;` tab or blanks, decimal
//! comma, preamble lines), matches headers loosely through a synonym table,
//! converts units given in the header to m and kPa, and converts signs to
//! Anura3D's (tension positive, pwp negative in compression) when the source is
//! GeoStudio. Every conversion is recorded in [`FemReadReport`]. Errors name the
//! file, line and column.
//!
//! The reader is split by concept: `headers` (column roles, the synonym
//! table, units), `options` (reader options, `--columns`, `--fem-units`),
//! `dialect` (delimiter sniffing, field splitting), `table` (the whole-table
//! pass: header, column report, assembly, checks), `rows` (the data rows in
//! parallel chunks, and the field-by-field path with positioned errors) and
//! `fast` (the allocation-free path for common rows), `source` (the input
//! read in blocks of whole lines). This file holds the
//! report types and the entry points.

use std::path::Path;

use super::error::FormatError;
use crate::fem::FemReadReport;
use a3d_model::FemNodes;
use table::Sizes;

mod dialect;
mod fast;
mod headers;
mod options;
mod rows;
mod schema;
mod source;
mod table;
#[cfg(test)]
mod tests;

pub use headers::{Field, normalise, synonym, unit_factor};
pub use options::{
    CsvOptions, columns_from_pairs, parse_columns_option, parse_units_option, units_from,
};

/// Reads a node table, block by block (the file's text is never held
/// whole). `path` names the file in errors.
pub fn read_csv(
    path: &Path,
    options: &CsvOptions,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    let limit = super::input::MAX_INPUT_BYTES;
    let (mut file, len) = super::input::open_limited(path, limit)?;
    table::parse_csv_stream(path, &mut file, (len, limit), options, Sizes::DEFAULT)
}

/// Parses node-table bytes (see [`read_csv`]).
pub fn parse_csv(
    path: &Path,
    bytes: &[u8],
    options: &CsvOptions,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    let mut reader = bytes;
    let len = bytes.len() as u64;
    table::parse_csv_stream(path, &mut reader, (len, u64::MAX), options, Sizes::DEFAULT)
}

/// Gives a GeoStudio `node.csv` its coordinates from the mesh PLY: node id k is
/// PLY node k − 1. 2D when every z is 0.
pub fn attach_mesh(
    nodes: &mut FemNodes,
    csv_path: &Path,
    mesh: &[[f64; 3]],
) -> Result<(), FormatError> {
    for (i, id) in nodes.ids.iter().enumerate() {
        let k = *id;
        if k < 1 || k as usize > mesh.len() {
            return Err(FormatError::file(
                csv_path,
                format!(
                    "node {k} (row {}) has no coordinates: the mesh has {} nodes",
                    i + 1,
                    mesh.len()
                ),
            ));
        }
        nodes.positions[i] = mesh[k as usize - 1];
    }
    if let Some((a, b)) = super::extent::first_coincident(&nodes.positions) {
        return Err(FormatError::file(
            csv_path,
            format!(
                "duplicate node: node {} (row {}) is at the same mesh point as node {} (row {})",
                nodes.ids[b],
                b + 1,
                nodes.ids[a],
                a + 1
            ),
        ));
    }
    nodes.dim = if nodes.positions.iter().all(|p| p[2] == 0.0) {
        2
    } else {
        3
    };
    Ok(())
}
