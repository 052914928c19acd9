//! Stage 3 of [`super::map`]: where the MPs are and which FEM nodes each may
//! take. The MPs' positions (placed as Anura3D places them by
//! [`Project::load`]), their closest spacing, the material separation (FEM
//! regions → GOM materials), the dry materials left out of the mapping, and
//! whether the FEM reaches the model at all.

use std::borrow::Cow;

use super::{Outside, StressSource};
use crate::diagnose::Reach;
use crate::formats::material_map::MaterialMap;
use crate::kernel::mapper;
use crate::pipeline::fem::LoadedFem;
use crate::pipeline::map::regions::groups;
use crate::pipeline::{PipelineError, Project};

/// Where the MPs are and which FEM nodes each may take.
#[derive(Clone, Debug)]
pub struct Placement {
    /// The smallest distance between two MPs (m), which gives the exact-point
    /// MAPF's h.
    pub min_mp_spacing: f64,
    /// Each FEM node's group (its GOM material index) when the FEM has regions.
    pub node_groups: Option<Vec<u32>>,
    /// Each MP's group (its material) when the nodes have groups.
    pub point_groups: Option<Vec<u32>>,
    /// How nodes were assigned to materials, as report.json says it.
    pub separation: String,
    /// Dry materials with MPs but no FEM nodes of their own (e.g. an
    /// impermeable base the seepage model left out): their MPs take pwp = 0
    /// and no kernel mapping.
    pub unmapped_materials: Vec<u32>,
    /// How the FEM reaches the MPs that are mapped (`None` when either side
    /// is empty).
    pub reach: Option<Reach>,
    pub notes: Vec<String>,
    pub warnings: Vec<String>,
}

/// Places the MPs of `project` against the nodes of `fem`: groups from the
/// FEM's region column and `material_map`, the dry materials without nodes
/// (a note each; with `outside` `error`, any other material without nodes is
/// an error unless the stress `source` is `fem`), and the reach of the FEM over
/// the mapped MPs for a kernel of radius `support` (m): poor reach is an error
/// under `outside` `error` and a warning otherwise.
pub fn place(
    project: &Project,
    fem: &LoadedFem,
    material_map: Option<&MaterialMap>,
    source: StressSource,
    outside: Outside,
    support: f64,
) -> Result<Placement, PipelineError> {
    let dim = project.model.mesh.dimension.n_dim();
    let (node_groups, separation) = groups(project, &fem.nodes, material_map)?;
    let points = &project.points;
    // A copy for the measures below, gone before the FEM values are copied
    // for the kernel (which reads the positions inside the MP table).
    let positions = project.mp_positions();
    // Measured before the FEM values are copied for the kernel, so its search
    // index is not held at the peak.
    let min_mp_spacing = mapper::min_spacing(&positions, dim);
    let point_groups: Option<Vec<u32>> = node_groups
        .as_ref()
        .map(|_| points.iter().map(|p| p.material).collect());
    let mut notes = Vec::new();
    let mut warnings = Vec::new();
    let mut unmapped_materials: Vec<u32> = Vec::new();
    if let (Some(ng), Some(pg)) = (&node_groups, &point_groups) {
        for m in &project.model.materials {
            if pg.contains(&m.index) && !ng.contains(&m.index) {
                if !m.has_water() && source != StressSource::Fem {
                    unmapped_materials.push(m.index);
                    notes.push(format!(
                        "material {} `{}` is dry and has no FEM nodes: its MPs take pwp = 0 (no mapping)",
                        m.index, m.name
                    ));
                } else if outside == Outside::Error {
                    return Err(PipelineError::Input(format!(
                        "material {} `{}` has MPs but no FEM nodes of its region; give its nodes, map a region to it in the material map, or choose the outside policy `nearest` or `skip`",
                        m.index, m.name
                    )));
                }
            }
        }
    }
    // A FEM that does not reach the model: name the file, both extents and a
    // unit or offset hint.
    let reach = {
        // The MPs the kernel maps; a copy only when some are left out.
        let reached: Cow<'_, [[f64; 3]]> = match &point_groups {
            Some(g) if !unmapped_materials.is_empty() => (0..positions.len())
                .filter(|&i| !unmapped_materials.contains(&g[i]))
                .map(|i| positions[i])
                .collect(),
            _ => Cow::Borrowed(&positions),
        };
        crate::diagnose::reach(
            &fem.nodes.positions,
            &project.model.mesh.nodes,
            &reached,
            dim,
            support,
        )
    };
    if let Some(r) = reach.as_ref().filter(|r| r.is_poor()) {
        let message = r.message(&crate::diagnose::file_list(&fem.paths));
        match outside {
            Outside::Error => return Err(PipelineError::Input(message)),
            _ => warnings.push(message),
        }
    }
    Ok(Placement {
        min_mp_spacing,
        node_groups,
        point_groups,
        separation,
        unmapped_materials,
        reach,
        notes,
        warnings,
    })
}
