//! FEM results as VTK XML: `.vtu` unstructured grids and `.pvd` time series,
//! as OpenGeoSys (OGS) writes them and as ParaView, FEniCS or MOOSE do. Spec:
//! `formats/fem-vtu.md`.
//!
//! Every node of every cell is a data point. The reader decodes the VTU
//! variants (ASCII, inline base64, appended base64 or raw; zlib or
//! uncompressed; UInt32 or UInt64 headers; any scalar type), finds the arrays
//! by OGS's names (`pressure`, `sigma`, `saturation`, `displacement`,
//! `MaterialIDs`) or by `--columns`, and converts once, into the model's
//! convention: Pa → kPa unless told otherwise (a VTU carries no units), OGS's
//! pressure (positive in compression) negated, OGS's effective `sigma` (tension
//! positive) made total. Quadratic cells whose `pressure` is zero on every
//! mid-edge node (Taylor–Hood: the pressure lives on the corners) take the
//! corners' linear interpolation there. `MaterialIDs` become regions `mat<k>`.
//!
//! Split by concept: `xml` (the document: layout and array tags), `decode`
//! (array values in every encoding), `cells` (VTK cell types), `mesh` (points,
//! cells, dimension, corners), `fields` (arrays → FEM fields: roles, units,
//! signs, stress), `pvd` (time series and the choice of a step). This file
//! holds the options, the report and the entry points.

use std::path::Path;

use super::error::FormatError;
use super::fem::StepChoice;
pub use crate::fem::{ArrayInfo, VtuReport};
use crate::fem::{FemReadReport, SignConvention, UnitOverride};
use a3d_model::FemNodes;

mod cells;
pub(crate) mod decode;
mod fields;
mod mesh;
mod options;
pub mod pvd;
pub(crate) mod xml;

pub use cells::CellKind;
pub use options::{
    Chi, Role, StressRule, arrays_from_pairs, parse_arrays_option, parse_stress_option,
};

/// How VTU results are read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VtuOptions {
    /// Arrays named explicitly (`--columns pwp=p,stress=sigma_total`); the
    /// rest by OGS's names.
    pub arrays: Vec<(Role, String)>,
    /// Units of the file (default: m and Pa).
    pub units: UnitOverride,
    /// Sign convention (default: OGS's, [`SignConvention::Ogs`]).
    pub sign: Option<SignConvention>,
    /// Whether the stress array is effective or total.
    pub stress: StressRule,
}

/// True for the extensions this reader takes (`.vtu`, `.pvd`).
pub fn is_vtk_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vtu") || e.eq_ignore_ascii_case("pvd"))
}

/// Reads a `.vtu`, or one step of a `.pvd` (chosen by `step`), into FEM nodes
/// in the model's convention.
pub fn read(
    path: &Path,
    options: &VtuOptions,
    step: &StepChoice,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    let is_pvd = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pvd"));
    if !is_pvd {
        return read_vtu(path, options);
    }
    let series = pvd::read(path)?;
    let chosen = series.choose(path, step)?;
    let (nodes, mut report) = read_vtu(&chosen.file, options)?;
    if let Some(vtu) = report.vtu.as_mut() {
        vtu.series = Some(chosen);
    }
    report.path = path.to_path_buf();
    Ok((nodes, report))
}

/// Reads one `.vtu`.
pub fn read_vtu(
    path: &Path,
    options: &VtuOptions,
) -> Result<(FemNodes, FemReadReport), FormatError> {
    let bytes = super::input::read_bytes(path)?;
    fields::read(path, &bytes, options)
}

/// The arrays, cells and materials of one `.vtu`, without converting its
/// fields (for `inspect`).
pub fn describe(path: &Path) -> Result<VtuReport, FormatError> {
    let bytes = super::input::read_bytes(path)?;
    fields::describe(path, &bytes)
}
