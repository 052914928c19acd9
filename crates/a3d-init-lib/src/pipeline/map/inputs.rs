//! Stage 1 of [`super::map`]: the FEM nodes checked against the model (same
//! dimension, enough nodes, a field to map) and the stress source decided.
//! The FEM files themselves are read before this, by [`crate::pipeline::fem::load`].

use super::StressSource;
use crate::pipeline::fem::LoadedFem;
use crate::pipeline::{PipelineError, Project};

macro_rules! input_err {
    ($($t:tt)*) => { PipelineError::Input(format!($($t)*)) };
}

/// The warnings of reading the model and the FEM files, each FEM warning
/// prefixed with its file: where the report's warnings start.
pub fn read_warnings(project: &Project, fem: &LoadedFem) -> Vec<String> {
    let mut warnings: Vec<String> = project.info.warnings.clone();
    for r in &fem.reports {
        warnings.extend(
            r.warnings
                .iter()
                .map(|w| format!("{}: {w}", r.path.display())),
        );
    }
    warnings
}

/// Checks that `fem` can be mapped onto `project`: nodes of the model's
/// dimension, at least 3 of them, and a pore-water pressure or total-stress
/// column.
pub fn check_fem(project: &Project, fem: &LoadedFem) -> Result<(), PipelineError> {
    let dim = project.model.mesh.dimension.n_dim();
    if fem.nodes.dim != dim {
        return Err(input_err!(
            "{}: the FEM nodes are {}D but the Anura3D model is {} ({}D)",
            fem.paths[0].display(),
            fem.nodes.dim,
            project.model.mesh.dimension.gom_name(),
            dim
        ));
    }
    if fem.nodes.len() < 3 {
        return Err(input_err!(
            "{}: at least 3 FEM nodes are needed, found {}",
            fem.paths[0].display(),
            fem.nodes.len()
        ));
    }
    if fem.nodes.field(crate::model::Quantity::Pwp).is_none() && !fem.nodes.has_total_stress() {
        return Err(input_err!(
            "{}: no pore-water pressure or total stress columns found",
            fem.paths[0].display()
        ));
    }
    Ok(())
}

/// The stress source a mapping uses, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedSource {
    pub source: StressSource,
    /// Why: `requested`, or what `auto` saw.
    pub because: String,
}

/// The stress source `requested` comes to for these nodes on `project`:
/// `auto` is `fem` when they have total stresses; with pore pressures only it
/// is `equilibrium` when the ground surface is not flat
/// ([`crate::state::ground`]) and the model can be solved, else `geostatic`
/// (the column formula is in equilibrium on flat ground). `fem` needs
/// total-stress columns, every other source a pore-water pressure column.
pub fn stress_source(
    requested: StressSource,
    project: &Project,
    fem: &LoadedFem,
) -> Result<ResolvedSource, PipelineError> {
    let resolved = match requested {
        StressSource::Auto if fem.nodes.has_total_stress() => ResolvedSource {
            source: StressSource::Fem,
            because: "auto: the FEM files have total stresses".into(),
        },
        StressSource::Auto => auto_without_stress(project),
        StressSource::Fem if !fem.nodes.has_total_stress() => {
            return Err(input_err!(
                "stress source `fem`: the FEM files have no total stress columns (sxx, syy, sxy{})",
                if fem.nodes.dim == 3 {
                    ", szz, syz, sxz"
                } else {
                    ""
                }
            ));
        }
        s => ResolvedSource {
            source: s,
            because: "requested".into(),
        },
    };
    if resolved.source != StressSource::Fem
        && fem.nodes.field(crate::model::Quantity::Pwp).is_none()
    {
        return Err(input_err!(
            "{}: the stress source `{}` needs a pore-water pressure column",
            fem.paths[0].display(),
            resolved.source
        ));
    }
    Ok(resolved)
}

/// `auto` for a FEM with pore pressures only: `geostatic` on flat ground,
/// `equilibrium` elsewhere unless the model cannot be solved.
fn auto_without_stress(project: &Project) -> ResolvedSource {
    let model = &project.model;
    let ground =
        crate::state::ground::ground_surface(&model.mesh, |e| model.element_material[e] > 0);
    let seen = format!(
        "auto: the FEM gives pore pressure only and {}",
        ground.describe()
    );
    if ground.flat {
        return ResolvedSource {
            source: StressSource::Geostatic,
            because: format!("{seen}, where the geostatic column formula is in equilibrium"),
        };
    }
    match super::equilibrium::unsupported(project) {
        None => ResolvedSource {
            source: StressSource::Equilibrium,
            because: seen,
        },
        Some(why) => ResolvedSource {
            source: StressSource::Geostatic,
            because: format!(
                "{seen}, but {why}: geostatic, which is not in equilibrium on this ground"
            ),
        },
    }
}
