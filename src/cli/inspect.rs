//! `a3d-init inspect`: prints the library's summaries ([`pipeline::inspect`])
//! of an Anura3D model (with the predicted material points), of FEM node
//! files, or of a GeoStudio `.gsz` archive, as text or JSON.

use std::io::Write;
use std::path::PathBuf;

use a3d_init::formats::fem_vtu::{self, VtuReport};
use a3d_init::pipeline::fem::{FemReader, reader_for};
use a3d_init::pipeline::inspect::{
    self, CbGeoSummary, FemSummary, GszStep, GszSummary, ProjectSummary, VtuSummary,
};

#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    /// Anura3D model: a `.GOM`, `.GOM_stage<k>`, `-2.dat`, `.CPS_<nnn>` or a project directory.
    pub model: Option<PathBuf>,
    /// Inspect FEM node file(s) instead: how each column was understood.
    #[command(flatten)]
    pub fem: super::args::FemArgs,
    /// Write the predicted material points (id, element, material, x, y, z, volume) to this CSV.
    #[arg(long, value_name = "CSV")]
    pub mps: Option<PathBuf>,
    /// Print a machine-readable JSON summary instead of text.
    #[arg(long)]
    pub json: bool,
    /// Replace an existing --mps file.
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: InspectArgs) -> anyhow::Result<()> {
    // Nothing asked for is dropped in silence: a model and --fem files are
    // inspected one at a time, and --mps needs an Anura3D model.
    if let (false, Some(model)) = (args.fem.fem.is_empty(), &args.model) {
        anyhow::bail!(
            "give a model ({}) or --fem FILE, not both: inspect summarises one at a time",
            model.display()
        );
    }
    if let Some(path) = &args.mps {
        // An Anura3D model: neither a `.gsz` nor a VTK file (what `run`
        // below inspects as the model).
        let model = args
            .model
            .as_deref()
            .filter(|m| reader_for(m) == FemReader::Csv);
        if model.is_none() {
            anyhow::bail!(
                "--mps {}: the MP table is predicted from an Anura3D model (GOM, CPS or folder); {}",
                path.display(),
                match &args.model {
                    Some(m) => format!("{} is not one", m.display()),
                    None => "none was given".to_owned(),
                }
            );
        }
    }
    if !args.fem.fem.is_empty() {
        let summary = inspect::fem(&args.fem.options()?)?;
        let mut out = std::io::stdout().lock();
        if args.json {
            a3d_init::pipeline::write_json(&mut out, &summary.reports)?;
            return Ok(());
        }
        return Ok(print_fem(&mut out, &summary)?);
    }
    let Some(model) = &args.model else {
        anyhow::bail!("give a model (GOM, CPS or folder) or --fem FILE");
    };
    let reader = reader_for(model);
    if reader == FemReader::Gsz {
        let summary = inspect::gsz(model)?;
        let mut out = std::io::stdout().lock();
        if args.json {
            a3d_init::pipeline::write_json(&mut out, &summary.project)?;
        } else {
            print_gsz(&mut out, &summary)?;
        }
        return match summary.unreadable() {
            Some(e) => Err(e.into()),
            None => Ok(()),
        };
    }
    if reader == FemReader::Vtu {
        let summary = inspect::vtu(model)?;
        let mut out = std::io::stdout().lock();
        if args.json {
            a3d_init::pipeline::write_json(&mut out, &summary)?;
        } else {
            print_vtu(&mut out, &summary)?;
        }
        if let Some(first) = summary.missing.first() {
            anyhow::bail!(
                "{}: {} of the series' files are missing, the first {}",
                model.display(),
                summary.missing.len(),
                first.display()
            );
        }
        return Ok(());
    }
    let summary = inspect::project(model, args.mps.as_deref(), args.force)?;
    let mut out = std::io::stdout().lock();
    if args.json {
        a3d_init::pipeline::write_json(&mut out, &summary)?;
        return Ok(());
    }
    print_summary(&mut out, &summary)?;
    if let Some(path) = &args.mps {
        writeln!(out, "MP table written to {}", path.display())?;
    }
    Ok(())
}

fn print_summary(out: &mut impl Write, s: &ProjectSummary) -> std::io::Result<()> {
    writeln!(out, "project    {}", s.files.name)?;
    for note in &s.files.notes {
        writeln!(out, "  {note}")?;
    }
    if let Some(cb) = &s.cbgeo {
        print_cbgeo(out, cb)?;
    } else {
        print_anura3d_files(out, s)?;
    }
    print_model(out, s)
}

/// The CB-Geo lines of `inspect`: branch, cells, analysis, generators, sets, files.
fn print_cbgeo(out: &mut impl Write, cb: &CbGeoSummary) -> std::io::Result<()> {
    writeln!(out, "CB-Geo     {}", cb.branch.name())?;
    writeln!(
        out,
        "analysis   {} ({} cells), gravity ({}, {}, {}) m/s²",
        if cb.analysis.is_empty() {
            "-"
        } else {
            &cb.analysis
        },
        cb.cell_type,
        cb.gravity[0],
        cb.gravity[1],
        cb.gravity[2]
    )?;
    for g in &cb.generators {
        writeln!(out, "generator  {g}")?;
    }
    if cb.two_phase_particles > 0 {
        writeln!(out, "two-phase  {} particles", cb.two_phase_particles)?;
    }
    if !cb.cell_sets.is_empty() {
        let sets: Vec<String> = cb
            .cell_sets
            .iter()
            .map(|(id, n)| format!("{id} ({n} cells)"))
            .collect();
        writeln!(out, "cell sets  {}", sets.join(", "))?;
    }
    writeln!(out, "stresses   {:?}", cb.stresses_key)?;
    writeln!(out, "files      {}", cb.files.join(", "))
}

/// The Anura3D lines of `inspect`: versions and the names `map` writes.
fn print_anura3d_files(out: &mut impl Write, s: &ProjectSummary) -> std::io::Result<()> {
    writeln!(
        out,
        "version    GOM {}{}",
        s.version,
        s.cps_version
            .as_deref()
            .map(|v| format!(", CPS {v}"))
            .unwrap_or_default()
    )?;
    // The names the ready-to-run project uses, and why.
    let names = &s.output_names;
    writeln!(
        out,
        "names      map writes {}, {}{} ({})",
        names.gom,
        names.cps,
        names
            .opd
            .as_deref()
            .map(|o| format!(", {o}"))
            .unwrap_or_default(),
        names.reason
    )
}

/// The model's lines of `inspect`, for either target.
fn print_model(out: &mut impl Write, s: &ProjectSummary) -> std::io::Result<()> {
    writeln!(out, "dimension  {} ({})", s.dimension, s.element_type)?;
    writeln!(
        out,
        "method     {}{}",
        s.computation_method,
        match s.computation_method {
            "FEM" | "UL-FEM" =>
                ": one MP per active element at the mean of its corners, whatever the GOM's counts",
            "MPM-MIXED" =>
                ": fully filled elements are integrated at one point (their MPs share MP 1's state after the first step)",
            _ => "",
        }
    )?;
    if let Some(f) = &s.formulation {
        writeln!(out, "formulation {f}")?;
    }
    writeln!(
        out,
        "mesh       {} nodes, {} elements ({} active), {} fixed nodes",
        s.nodes, s.elements, s.active_elements, s.fixed_nodes
    )?;
    writeln!(out, "MPs        {}", s.material_points)?;
    let (lo, hi) = s.bounding_box;
    writeln!(
        out,
        "bbox       x {:.4} .. {:.4}, y {:.4} .. {:.4}, z {:.4} .. {:.4} m",
        lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]
    )?;
    writeln!(out, "materials")?;
    for summary in &s.materials {
        let m = &summary.material;
        writeln!(
            out,
            "  {} {:<14} {} / {}: {} elements, {} MPs",
            m.index,
            m.name,
            m.material_type,
            m.model.as_deref().unwrap_or("-"),
            summary.elements,
            summary.mps
        )?;
        let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v}"));
        writeln!(
            out,
            "      n = {}, ρs = {} kg/m³, γdry = {:.3} kN/m³, K0 = {}, E = {} kPa, ν = {}, φ' = {}°, c' = {} kPa, ψ = {}°",
            fmt(m.porosity),
            fmt(m.density_solid),
            summary.gamma_dry,
            fmt(m.k0),
            fmt(m.young_modulus),
            fmt(m.poisson_ratio),
            fmt(m.friction_angle),
            fmt(m.cohesion),
            fmt(m.dilatancy_angle)
        )?;
    }
    if s.warnings.is_empty() {
        writeln!(out, "warnings   none")?;
    } else {
        writeln!(out, "warnings")?;
        for w in &s.warnings {
            writeln!(out, "  - {}", super::spelled(w))?;
        }
    }
    Ok(())
}

fn print_fem(out: &mut impl Write, s: &FemSummary) -> std::io::Result<()> {
    for r in &s.reports {
        writeln!(out, "file       {}", r.path.display())?;
        match &r.vtu {
            Some(vtu) => print_vtu_report(out, vtu)?,
            None => writeln!(
                out,
                "dialect    delimiter `{}`, decimal {}, BOM {}, header on line {}",
                r.delimiter,
                if r.decimal_comma { "comma" } else { "point" },
                if r.bom { "yes" } else { "no" },
                r.header_line
            )?,
        }
        writeln!(out, "nodes      {} ({}D)", r.nodes, r.dim)?;
        writeln!(out, "sign       {:?}", r.sign)?;
        writeln!(out, "columns")?;
        for c in &r.columns {
            writeln!(
                out,
                "  {:<32} → {:<8} unit {:<6} ×{}{}",
                format!("`{}`", c.header),
                c.understood_as,
                c.unit.as_deref().unwrap_or("-"),
                c.factor,
                if c.sign_flipped { ", sign flipped" } else { "" }
            )?;
        }
        for w in &r.warnings {
            writeln!(out, "  warning: {}", super::spelled(w))?;
        }
    }
    for n in &s.notes {
        writeln!(out, "note       {n}")?;
    }
    // The coordinate range of the table.
    if let Some(extent) = &s.extent {
        writeln!(out, "extent     {extent}")?;
    }
    for f in &s.fields {
        writeln!(
            out,
            "field      {:<6} {:.4} .. {:.4} kPa (Anura3D signs)",
            f.name, f.min, f.max
        )?;
    }
    writeln!(
        out,
        "spacing    median nearest-node distance l = {:.6} m",
        s.spacing
    )
}

fn print_gsz(out: &mut impl Write, s: &GszSummary) -> std::io::Result<()> {
    let project = &s.project;
    let (length, pressure) = if project.unit_system.eq_ignore_ascii_case("Imperial") {
        ("ft", "psf")
    } else {
        ("m", "kPa")
    };
    writeln!(
        out,
        "project    {} ({})",
        s.path.display(),
        project.xml_name
    )?;
    writeln!(
        out,
        "units      {} base units: length {length}, pressure {pressure}, time s",
        project.unit_system
    )?;
    for (a, step) in project.analyses.iter().zip(&s.last_steps) {
        writeln!(
            out,
            "analysis   {} `{}`: {} {}, folder `{}`, mesh {}",
            a.index,
            a.name,
            a.kind,
            a.method,
            a.folder,
            if a.has_mesh { "yes" } else { "no" }
        )?;
        let times: Vec<String> = a
            .steps
            .iter()
            .map(|s| {
                format!(
                    "{}{}",
                    s.folder,
                    s.time.map(|t| format!(" (t = {t} s)")).unwrap_or_default()
                )
            })
            .collect();
        writeln!(
            out,
            "  saved steps ({}): {}",
            a.steps.len(),
            times.join(", ")
        )?;
        let Some(last) = a.steps.last() else {
            continue;
        };
        match step {
            GszStep::None => {}
            GszStep::NoMesh => writeln!(
                out,
                "  no Mesh.ply in `{}`: its results cannot be placed",
                a.folder
            )?,
            GszStep::Read { nodes, note } => {
                writeln!(
                    out,
                    "  step {}: {} nodes ({}D), fields: {}",
                    last.folder,
                    nodes.len(),
                    nodes.dim,
                    nodes
                        .fields
                        .iter()
                        .map(|(q, _)| q.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                )?;
                if let Some(extent) = a3d_init::diagnose::Extent::of(&nodes.positions, nodes.dim) {
                    writeln!(out, "  extent {extent}")?;
                }
                if let Some((_, subset)) = note.split_once("; the table lists") {
                    writeln!(out, "  note: the table lists{subset}")?;
                }
            }
            GszStep::Unreadable(e) => writeln!(out, "  step {}: unreadable: {e}", last.folder)?,
        }
    }
    Ok(())
}

fn print_vtu(out: &mut impl Write, s: &VtuSummary) -> std::io::Result<()> {
    if let (Some(first), Some(last)) = (s.outputs.first(), s.outputs.last()) {
        writeln!(
            out,
            "series     {}: {} outputs, t = {} .. {}",
            s.path.display(),
            s.outputs.len(),
            fem_vtu::pvd::time_text(first.time),
            fem_vtu::pvd::time_text(last.time)
        )?;
        for (k, o) in s.outputs.iter().enumerate() {
            writeln!(
                out,
                "  step {k:>3}  t = {:<26} {}{}",
                fem_vtu::pvd::time_text(o.time),
                o.file.display(),
                if s.missing.contains(&o.file) {
                    "  (missing)"
                } else {
                    ""
                }
            )?;
        }
        writeln!(
            out,
            "last       {} (described below)",
            s.last.file.display()
        )?;
    } else {
        writeln!(out, "file       {}", s.path.display())?;
    }
    print_vtu_report(out, &s.last)?;
    writeln!(
        out,
        "signs      OGS by default (--fem-sign): pressure positive in compression (negated), stress tension positive (kept)"
    )?;
    writeln!(
        out,
        "stress     `sigma` with a pressure array is effective (OGS's HydroMechanics, RichardsMechanics): made total with α = 1 and χ = S (1 without saturation); --fem-sigma"
    )
}

fn print_vtu_report(out: &mut impl Write, r: &VtuReport) -> std::io::Result<()> {
    if let Some(c) = &r.series {
        writeln!(
            out,
            "step       {} of {} (0-based), t = {}: {}",
            c.step,
            c.steps,
            fem_vtu::pvd::time_text(c.time),
            c.file.display()
        )?;
    }
    writeln!(out, "encoding   {}", r.encoding)?;
    let cells: Vec<String> = r.cells.iter().map(|(k, n)| format!("{n} {k}")).collect();
    writeln!(out, "cells      {}", cells.join(", "))?;
    if !r.materials.is_empty() {
        let m: Vec<String> = r
            .materials
            .iter()
            .map(|(id, n)| format!("{id}: {n} cells (region `mat{id}`)"))
            .collect();
        writeln!(out, "materials  MaterialIDs {}", m.join(", "))?;
    }
    writeln!(out, "arrays")?;
    for a in &r.arrays {
        writeln!(
            out,
            "  {:<24} {:<5} {} × {:<8} → {}",
            a.name, a.location, a.components, a.scalar, a.used_as
        )?;
    }
    writeln!(out, "units      {}", r.units)?;
    if let Some(rule) = &r.stress_rule {
        writeln!(out, "stress     {rule}")?;
    }
    for n in &r.notes {
        writeln!(out, "note       {n}")?;
    }
    Ok(())
}
