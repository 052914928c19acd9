//! `a3d-init inspect`: a readable (or JSON) summary of an Anura3D model, with
//! the predicted material points, or of a FEM node file.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use serde::Serialize;

use crate::formats::cps::CpsDocument;
use crate::formats::project::ProjectFiles;

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

pub use crate::pipeline::Project as LoadedProject;

/// Reads a project and places its MPs for its computation method.
pub fn load_project(path: &std::path::Path) -> anyhow::Result<LoadedProject> {
    Ok(LoadedProject::load(path)?)
}

#[derive(Serialize)]
struct MaterialSummary {
    index: u32,
    name: String,
    material_type: String,
    model: Option<String>,
    elements: usize,
    mps: usize,
    porosity: Option<f64>,
    density_solid: Option<f64>,
    k0: Option<f64>,
    young_modulus: Option<f64>,
    poisson_ratio: Option<f64>,
    friction_angle: Option<f64>,
    cohesion: Option<f64>,
    dilatancy_angle: Option<f64>,
    gamma_dry: f64,
}

impl MaterialSummary {
    /// The summary of material `m` of `project`, its dry unit weight at gravity `g`.
    fn of(m: &crate::model::Material, project: &LoadedProject, g: f64) -> MaterialSummary {
        MaterialSummary {
            index: m.index,
            name: m.name.clone(),
            material_type: m.material_type.clone(),
            model: m.model.clone(),
            elements: project
                .model
                .element_material
                .iter()
                .filter(|&&e| e == m.index)
                .count(),
            mps: project
                .points
                .iter()
                .filter(|mp| mp.material == m.index)
                .count(),
            porosity: m.porosity,
            density_solid: m.density_solid,
            k0: m.k0,
            young_modulus: m.young_modulus,
            poisson_ratio: m.poisson_ratio,
            friction_angle: m.friction_angle,
            cohesion: m.cohesion,
            dilatancy_angle: m.dilatancy_angle,
            gamma_dry: m.gamma_dry(g),
        }
    }
}

#[derive(Serialize)]
struct Summary<'a> {
    files: &'a ProjectFiles,
    version: &'a str,
    cps_version: Option<&'a str>,
    dimension: &'static str,
    element_type: &'static str,
    formulation: Option<&'a str>,
    computation_method: &'static str,
    nodes: usize,
    elements: usize,
    active_elements: usize,
    material_points: usize,
    fixed_nodes: usize,
    bounding_box: ([f64; 3], [f64; 3]),
    materials: Vec<MaterialSummary>,
    warnings: &'a [String],
}

pub fn run(args: InspectArgs) -> anyhow::Result<()> {
    if !args.fem.fem.is_empty() {
        return inspect_fem(&args);
    }
    let Some(model) = &args.model else {
        anyhow::bail!("give a model (GOM, CPS or folder) or --fem FILE");
    };
    if model
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gsz"))
    {
        return inspect_gsz(model, args.json);
    }
    let p = load_project(model)?;
    let g = p
        .cps
        .as_ref()
        .map_or(crate::model::DEFAULT_GRAVITY, CpsDocument::gravity);
    let materials = p
        .model
        .materials
        .iter()
        .map(|m| MaterialSummary::of(m, &p, g))
        .collect();
    let mesh = &p.model.mesh;
    let summary = Summary {
        files: &p.files,
        version: &p.gom_version,
        cps_version: p.cps.as_ref().map(CpsDocument::version),
        dimension: mesh.dimension.gom_name(),
        element_type: mesh.element_type.gom_name(),
        formulation: p.info.formulation.as_deref(),
        computation_method: p.method.cps_name(),
        nodes: mesh.n_nodes(),
        elements: mesh.n_elements(),
        active_elements: p.model.element_material.iter().filter(|&&m| m > 0).count(),
        material_points: p.points.len(),
        fixed_nodes: p
            .model
            .solid_fixity
            .iter()
            .filter(|f| f.iter().any(|&b| b))
            .count(),
        bounding_box: mesh.bounding_box(),
        materials,
        warnings: &p.info.warnings,
    };
    if let Some(path) = &args.mps {
        let inputs = super::args::project_inputs(&p.files);
        crate::cli::output::write_new(path, args.force, &inputs, |w| {
            crate::formats::mps_table::write_points(w, &p.points)
        })
        .with_context(|| format!("writing {}", path.display()))?;
    }
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer_pretty(&mut out, &summary)?;
        writeln!(out)?;
        return Ok(());
    }
    print_summary(&mut out, &summary)?;
    if let Some(path) = &args.mps {
        writeln!(out, "MP table written to {}", path.display())?;
    }
    Ok(())
}

fn print_summary(out: &mut impl Write, s: &Summary<'_>) -> std::io::Result<()> {
    writeln!(out, "project    {}", s.files.name)?;
    for note in &s.files.notes {
        writeln!(out, "  {note}")?;
    }
    writeln!(
        out,
        "version    GOM {}{}",
        s.version,
        s.cps_version
            .map(|v| format!(", CPS {v}"))
            .unwrap_or_default()
    )?;
    // #14: the names the ready-to-run project uses, and why.
    let names = s.files.output_names(s.version);
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
    )?;
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
    if let Some(f) = s.formulation {
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
    for m in &s.materials {
        writeln!(
            out,
            "  {} {:<14} {} / {}: {} elements, {} MPs",
            m.index,
            m.name,
            m.material_type,
            m.model.as_deref().unwrap_or("-"),
            m.elements,
            m.mps
        )?;
        let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v}"));
        writeln!(
            out,
            "      n = {}, ρs = {} kg/m³, γdry = {:.3} kN/m³, K0 = {}, E = {} kPa, ν = {}, φ' = {}°, c' = {} kPa, ψ = {}°",
            fmt(m.porosity),
            fmt(m.density_solid),
            m.gamma_dry,
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
        for w in s.warnings {
            writeln!(out, "  - {w}")?;
        }
    }
    Ok(())
}

fn inspect_fem(args: &InspectArgs) -> anyhow::Result<()> {
    let fem = args.fem.load()?;
    let mut out = std::io::stdout().lock();
    if args.json {
        serde_json::to_writer_pretty(&mut out, &fem.reports)?;
        writeln!(out)?;
        return Ok(());
    }
    for r in &fem.reports {
        writeln!(out, "file       {}", r.path.display())?;
        writeln!(
            out,
            "dialect    delimiter `{}`, decimal {}, BOM {}, header on line {}",
            r.delimiter,
            if r.decimal_comma { "comma" } else { "point" },
            if r.bom { "yes" } else { "no" },
            r.header_line
        )?;
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
            writeln!(out, "  warning: {w}")?;
        }
    }
    for n in &fem.notes {
        writeln!(out, "note       {n}")?;
    }
    let nodes = &fem.nodes;
    // #14: the coordinate range of the table.
    if let Some(extent) = crate::diagnose::Extent::of(&nodes.positions, nodes.dim) {
        writeln!(out, "extent     {extent}")?;
    }
    for (q, v) in &nodes.fields {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(*x), b.max(*x))
            });
        writeln!(
            out,
            "field      {:<6} {lo:.4} .. {hi:.4} kPa (Anura3D signs)",
            q.name()
        )?;
    }
    writeln!(
        out,
        "spacing    median nearest-node distance l = {:.6} m",
        crate::kernel::mapper::median_spacing(&nodes.positions, nodes.dim)
    )?;
    Ok(())
}

fn inspect_gsz(path: &std::path::Path, json: bool) -> anyhow::Result<()> {
    let project = crate::formats::gsz::read_project(path)?;
    // The last saved step of every analysis with a mesh is read, so that an
    // archive whose results cannot be read is an error (exit 2, #14).
    let steps: Vec<_> = project
        .analyses
        .iter()
        .map(|a| {
            let last = a.steps.last().filter(|_| a.has_mesh)?;
            Some(crate::formats::gsz::read_step(
                path,
                Some(&a.index.to_string()),
                &crate::formats::gsz::StepChoice::Number(last.number),
                &Default::default(),
            ))
        })
        .collect();
    let mut out = std::io::stdout().lock();
    if json {
        serde_json::to_writer_pretty(&mut out, &project)?;
        writeln!(out)?;
    } else {
        print_gsz(&mut out, path, &project, &steps)?;
    }
    match steps.into_iter().flatten().find_map(Result::err) {
        Some(e) => Err(anyhow::Error::new(e).context(format!(
            "{}: the archive lists results that cannot be read",
            path.display()
        ))),
        None => Ok(()),
    }
}

type StepRead = Result<
    (
        crate::model::FemNodes,
        crate::formats::fem_csv::FemReadReport,
        String,
    ),
    crate::formats::FormatError,
>;

fn print_gsz(
    out: &mut impl Write,
    path: &std::path::Path,
    project: &crate::formats::gsz::GszProject,
    steps: &[Option<StepRead>],
) -> anyhow::Result<()> {
    let (length, pressure) = if project.unit_system.eq_ignore_ascii_case("Imperial") {
        ("ft", "psf")
    } else {
        ("m", "kPa")
    };
    writeln!(out, "project    {} ({})", path.display(), project.xml_name)?;
    writeln!(
        out,
        "units      {} base units: length {length}, pressure {pressure}, time s",
        project.unit_system
    )?;
    for (a, step) in project.analyses.iter().zip(steps) {
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
            None => writeln!(
                out,
                "  no Mesh.ply in `{}`: its results cannot be placed",
                a.folder
            )?,
            Some(Ok((nodes, _, note))) => {
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
                if let Some(extent) = crate::diagnose::Extent::of(&nodes.positions, nodes.dim) {
                    writeln!(out, "  extent {extent}")?;
                }
                if let Some((_, subset)) = note.split_once("; the table lists") {
                    writeln!(out, "  note: the table lists{subset}")?;
                }
            }
            Some(Err(e)) => writeln!(out, "  step {}: unreadable: {e}", last.folder)?,
        }
    }
    Ok(())
}
