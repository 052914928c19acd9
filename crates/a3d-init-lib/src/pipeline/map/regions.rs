//! Material separation: which GOM material each FEM node belongs to, from the
//! FEM's region column, a material map (`region=material`) and name or index
//! matching. MPs then take only nodes of their own material, so nothing is
//! smoothed across a material boundary.

use crate::formats::material_map::MaterialMap;
use crate::model::FemNodes;
use crate::model::material::lookup;
use crate::pipeline::{PipelineError, Project};

macro_rules! input_err {
    ($($t:tt)*) => { PipelineError::Input(format!($($t)*)) };
}

/// Assigns FEM nodes and MPs to groups (GOM material indices) when the FEM has a
/// region column; returns (node groups, description).
pub(super) fn groups(
    project: &Project,
    fem: &FemNodes,
    material_map: Option<&MaterialMap>,
) -> Result<(Option<Vec<u32>>, String), PipelineError> {
    let materials = &project.model.materials;
    let explicit = match material_map {
        Some(map) => map
            .resolve(materials, fem.region.as_deref())
            .map_err(|e| input_err!("material map: {e}"))?,
        None => Vec::new(),
    };
    let Some(regions) = &fem.region else {
        return Ok((None, "none: the FEM file has no region column, so nodes of every material were used for every MP".into()));
    };
    let resolve = |region: &str| -> Option<u32> {
        explicit
            .iter()
            .find(|(r, _)| r == region)
            .map(|(_, i)| *i)
            .or_else(|| lookup::by_name(materials, region))
            .or_else(|| lookup::by_number(materials, region))
    };
    let mut out = Vec::with_capacity(regions.len());
    let mut unknown: Vec<&str> = Vec::new();
    for r in regions {
        match resolve(r) {
            Some(i) => out.push(i),
            None => {
                if !unknown.contains(&r.as_str()) {
                    unknown.push(r);
                }
                out.push(0);
            }
        }
    }
    if !unknown.is_empty() {
        return Err(input_err!(
            "FEM regions {} match no GOM material (materials: {}); map them to materials in a material map (region=material)",
            unknown
                .iter()
                .map(|s| format!("`{s}`"))
                .collect::<Vec<_>>()
                .join(", "),
            lookup::list(materials)
        ));
    }
    Ok((Some(out), "by region: each MP takes only FEM nodes of its own material (no smoothing across material boundaries)".into()))
}
