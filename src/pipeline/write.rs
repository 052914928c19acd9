//! Writing a mapped project: the ready-to-run Anura3D files (GOM copied byte
//! for byte, CPS with the MAPF switch on and K0 off, `<project>.MAPF` in
//! exact-point mode) and the diagnostics (`mps.csv`, `mps.vtu`, `fem.vtu`,
//! `report.json`) into a folder the caller prepared (the CLI's staging folder).

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::PipelineError;
use super::map::Mapped;
use crate::formats::{mapf, mps_table, vtu};

/// A folder files are written into.
struct Folder<'a>(&'a Path);

impl Folder<'_> {
    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    fn write(
        &self,
        name: &str,
        fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), PipelineError> {
        let path = self.path(name);
        let io =
            |e: std::io::Error| PipelineError::Input(format!("writing {}: {e}", path.display()));
        let file = std::fs::File::create(&path).map_err(io)?;
        let mut w = BufWriter::new(file);
        fill(&mut w).map_err(io)?;
        w.flush().map_err(io)?;
        Ok(())
    }

    fn copy(&self, from: &Path, name: &str) -> Result<(), PipelineError> {
        std::fs::copy(from, self.path(name))
            .map_err(|e| PipelineError::Input(format!("copying {}: {e}", from.display())))?;
        Ok(())
    }
}

/// Writes the ready-to-run project and the diagnostics into the folder `dir`;
/// returns the file names written.
pub fn write_project(mapped: &Mapped, dir: &Path) -> Result<Vec<String>, PipelineError> {
    let out = Folder(dir);
    let project = &mapped.project;
    let name = &project.files.name;
    let dim = project.model.mesh.dimension.n_dim();
    let mut written = Vec::new();
    // File names as Anura3D will look for them; the model's own CPS with two
    // switches changed, or a generated one (--generate-cps); a default OPD for a
    // 2025 CPS without one (#14).
    let names = project.files.output_names(project.gom.version());
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
        project.gom.version(),
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
    let mapf_name = format!("{name}.MAPF");
    out.write(&mapf_name, |w| {
        mapf::write(w, &project.points, &mapped.states, dim, mapped.mapf_h)
    })?;
    written.push(mapf_name);
    out.write("mps.csv", |w| {
        mps_table::write_states(w, &project.points, &mapped.states, &mapped.diagnostics)
    })?;
    written.push("mps.csv".into());
    let positions: Vec<[f64; 3]> = project.points.iter().map(|p| p.position).collect();
    let mut arrays = vec![
        vtu::PointArray {
            name: "pwp".into(),
            components: 1,
            values: mapped.states.iter().map(|s| s.pwp).collect(),
        },
        vtu::PointArray {
            name: "total_stress".into(),
            components: 9,
            values: mapped
                .states
                .iter()
                .flat_map(|s| vtu::tensor9(&s.total))
                .collect(),
        },
        vtu::PointArray {
            name: "effective_stress".into(),
            components: 9,
            values: mapped
                .states
                .iter()
                .flat_map(|s| vtu::tensor9(&s.effective()))
                .collect(),
        },
        vtu::PointArray {
            name: "saturation".into(),
            components: 1,
            values: mapped.states.iter().map(|s| s.saturation).collect(),
        },
        vtu::PointArray {
            name: "material".into(),
            components: 1,
            values: project.points.iter().map(|p| p.material as f64).collect(),
        },
        vtu::PointArray {
            name: "volume".into(),
            components: 1,
            values: project.points.iter().map(|p| p.volume).collect(),
        },
    ];
    arrays.push(vtu::PointArray {
        name: "neighbours".into(),
        components: 1,
        values: mapped
            .diagnostics
            .iter()
            .map(|d| d.neighbours as f64)
            .collect(),
    });
    arrays.push(vtu::PointArray {
        name: "shepard".into(),
        components: 1,
        values: mapped.diagnostics.iter().map(|d| d.shepard).collect(),
    });
    out.write("mps.vtu", |w| vtu::write_points(w, &positions, &arrays))?;
    written.push("mps.vtu".into());
    let fem_arrays: Vec<vtu::PointArray> = mapped
        .fem
        .nodes
        .fields
        .iter()
        .map(|(q, v)| vtu::PointArray {
            name: q.name(),
            components: 1,
            values: v.clone(),
        })
        .collect();
    out.write("fem.vtu", |w| {
        vtu::write_points(w, &mapped.fem.nodes.positions, &fem_arrays)
    })?;
    written.push("fem.vtu".into());
    let json = serde_json::to_string_pretty(&mapped.report)
        .map_err(|e| PipelineError::Input(format!("report.json: {e}")))?;
    out.write("report.json", |w| w.write_all(json.as_bytes()))?;
    written.push("report.json".into());
    Ok(written)
}
