//! Writing a mapped project: the ready-to-run Anura3D files (GOM copied byte
//! for byte, CPS with the MAPF switch on and K0 off, `<project>.MAPF` in
//! exact-point mode) and the diagnostics (`mps.csv`, `mps.vtu`, `fem.vtu`,
//! `report.json`) into a folder the caller prepared (the CLI's staging folder).

use std::path::Path;

use crate::formats::{mapf, mps_table, vtu};
use crate::pipeline::PipelineError;
use crate::pipeline::io::folder::Folder;
use crate::pipeline::map::Mapped;

/// FEMs up to this many nodes get a `fem.vtu` without `--fem-vtu`.
pub const FEM_VTU_AUTO_MAX: usize = 200_000;

/// Writes the ready-to-run project and the diagnostics into the folder `dir`;
/// returns the file names written. `fem.vtu` is written when `fem_vtu` or when
/// the FEM has at most [`FEM_VTU_AUTO_MAX`] nodes.
pub fn write_project(
    mapped: &Mapped,
    dir: &Path,
    fem_vtu: bool,
) -> Result<Vec<String>, PipelineError> {
    let out = Folder(dir);
    let mut written = match &mapped.project.cbgeo {
        Some(cb) => crate::pipeline::cbgeo::write::write_model(mapped, cb, &out)?,
        None => write_anura3d(mapped, &out)?,
    };
    write_diagnostics(mapped, &out, fem_vtu, &mut written)?;
    Ok(written)
}

/// The ready-to-run Anura3D files: GOM, CPS (with OPD and HHBF where they
/// belong) and the MAPF.
fn write_anura3d(mapped: &Mapped, out: &Folder<'_>) -> Result<Vec<String>, PipelineError> {
    let project = &mapped.project;
    let name = &project.files.name;
    let dim = project.model.mesh.dimension.n_dim();
    let mut written = Vec::new();
    // File names as Anura3D will look for them; the model's own CPS with two
    // switches changed, or a generated one (--generate-cps); a default OPD for a
    // 2025 CPS without one.
    let names = project.files.output_names(&project.gom_version);
    out.copy(&project.files.gom, &names.gom)?;
    written.push(names.gom.clone());
    let active = project
        .model
        .element_material
        .iter()
        .filter(|&&m| m > 0)
        .count();
    let text = crate::formats::cps_template::ready_to_run_cps(
        project.cps.as_ref(),
        &project.gom_version,
        dim,
        active,
    )?;
    out.write(&names.cps, |w| w.write_all(text.as_bytes()))?;
    written.push(names.cps.clone());
    if let Some(opd_name) = &names.opd {
        match &project.files.opd {
            Some(opd) => out.copy(opd, opd_name)?,
            None => out.write(opd_name, |w| {
                w.write_all(crate::formats::cps_template::generate_opd().as_bytes())
            })?,
        }
        written.push(opd_name.clone());
    }
    // A water level from a file travels with the project (Anura3D reads
    // `<project>.HHBF` beside the CPS).
    // It is read and checked first, as `verify` and Anura3D read it: a
    // ready-to-run project never carries a water level Anura3D would refuse,
    // and anything in its place that is not a regular file is an error, not
    // left out.
    let hhbf = crate::pipeline::check::runner::hhbf_path(project);
    if std::fs::symlink_metadata(&hhbf).is_ok() {
        let text = crate::formats::input::read_text(&hhbf)?;
        crate::formats::hhbf::parse(&hhbf, &text)?;
        let hhbf_name = format!("{name}.HHBF");
        out.write(&hhbf_name, |w| w.write_all(text.as_bytes()))?;
        written.push(hhbf_name);
    }
    let mapf_name = format!("{name}.MAPF");
    out.write(&mapf_name, |w| {
        mapf::write(
            w,
            &project.points,
            &mapped.states,
            dim,
            mapped.report.mapf_smoothing_length,
        )
    })?;
    written.push(mapf_name);
    Ok(written)
}

/// The diagnostics beside the model's files: `mps.csv`, `mps.vtu`,
/// `fem.vtu` (small FEMs, or when asked) and `report.json`.
fn write_diagnostics(
    mapped: &Mapped,
    out: &Folder<'_>,
    fem_vtu: bool,
    written: &mut Vec<String>,
) -> Result<(), PipelineError> {
    let project = &mapped.project;
    out.write("mps.csv", |w| {
        mps_table::write_states(w, &project.points, &mapped.states, &mapped.diagnostics)
    })?;
    written.push("mps.csv".into());
    // The VTU arrays are computed while written (no copies of the fields).
    let (points, states, diags) = (&project.points, &mapped.states, &mapped.diagnostics);
    let arrays = vec![
        vtu::ArrayFn::scalar("pwp", |i| states[i].pwp),
        vtu::ArrayFn {
            name: "total_stress".into(),
            components: 9,
            fill: Box::new(|i, out: &mut [f64]| {
                out.copy_from_slice(&vtu::tensor9(&states[i].total))
            }),
        },
        vtu::ArrayFn {
            name: "effective_stress".into(),
            components: 9,
            fill: Box::new(|i, out: &mut [f64]| {
                out.copy_from_slice(&vtu::tensor9(&states[i].effective()))
            }),
        },
        vtu::ArrayFn::scalar("saturation", |i| states[i].saturation),
        vtu::ArrayFn::scalar("material", |i| points[i].material as f64),
        vtu::ArrayFn::scalar("volume", |i| points[i].volume),
        vtu::ArrayFn::scalar("neighbours", |i| diags[i].neighbours as f64),
        vtu::ArrayFn::scalar("shepard", |i| diags[i].shepard.unwrap_or(f64::NAN)),
    ];
    out.write("mps.vtu", |w| {
        vtu::write_points_with(w, points.len(), &|i| points[i].position, &arrays)
    })?;
    written.push("mps.vtu".into());
    // The nodes are kept for fem.vtu (`MapConfig::keep_fem_fields`), and
    // only then.
    let kept = !mapped.fem.nodes.is_empty();
    if kept && (fem_vtu || mapped.fem.nodes.len() <= FEM_VTU_AUTO_MAX) {
        let nodes = &mapped.fem.nodes;
        let fem_arrays: Vec<vtu::ArrayFn<'_>> = nodes
            .fields
            .iter()
            .map(|(q, v)| vtu::ArrayFn::scalar(q.name(), move |i| v[i]))
            .collect();
        out.write("fem.vtu", |w| {
            vtu::write_points_with(w, nodes.len(), &|i| nodes.positions[i], &fem_arrays)
        })?;
        written.push("fem.vtu".into());
    }
    let json = serde_json::to_string_pretty(&mapped.report)
        .map_err(|e| PipelineError::Output(format!("report.json: {e}")))?;
    out.write("report.json", |w| w.write_all(json.as_bytes()))?;
    written.push("report.json".into());
    Ok(())
}
