//! `a3d-init inspect`: a readable (or JSON) summary of an Anura3D model, with
//! the predicted material points, or of a FEM node file.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use serde::Serialize;

use crate::formats::cps::CpsDocument;
use crate::formats::gom::{GomDocument, GomInfo};
use crate::formats::project::{self, ProjectFiles};
use crate::model::{AnuraModel, MaterialPoint};

#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    /// Anura3D model: a `.GOM`, `.GOM_stage<k>`, `-2.dat`, `.CPS_<nnn>` or a project directory.
    pub model: Option<PathBuf>,
    /// Inspect FEM node file(s) instead: how each column was understood.
    #[command(flatten)]
    pub fem: super::map::FemArgs,
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

/// A loaded Anura3D project: files, documents, typed model and predicted MPs.
pub struct LoadedProject {
    pub files: ProjectFiles,
    pub gom: GomDocument,
    pub cps: Option<CpsDocument>,
    pub model: AnuraModel,
    pub info: GomInfo,
    pub points: Vec<MaterialPoint>,
}

/// Reads a project and places its MPs; errors are positioned.
pub fn load_project(path: &std::path::Path) -> anyhow::Result<LoadedProject> {
    let files = project::discover(path)?;
    let gom = GomDocument::read(&files.gom)?;
    let cps = files.cps.as_deref().map(CpsDocument::read).transpose()?;
    let (model, mut info) = gom.model()?;
    let points = crate::place::place_material_points(&model).map_err(|errors| {
        let lines: Vec<String> = errors
            .0
            .iter()
            .take(20)
            .map(|e| {
                let line = e
                    .element()
                    .and_then(|el| info.element_lines.get(el))
                    .copied()
                    .unwrap_or(0);
                format!("{}:{}:1: {}", files.gom.display(), line, e)
            })
            .collect();
        let more = errors.0.len().saturating_sub(20);
        anyhow::anyhow!(
            "{}{}",
            lines.join("\n"),
            if more > 0 {
                format!("\n… and {more} more")
            } else {
                String::new()
            }
        )
    })?;
    if let Some(cps) = &cps {
        let method = cps.computation_method();
        if method == "FEM" || method == "UL-FEM" {
            info.warnings.push(format!(
                "the CPS computation method is {method}: Anura3D then creates 1 MP per element and ignores the GOM's MP counts; the MPs listed follow the GOM counts"
            ));
        }
    }
    Ok(LoadedProject {
        files,
        gom,
        cps,
        model,
        info,
        points,
    })
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

#[derive(Serialize)]
struct Summary<'a> {
    files: &'a ProjectFiles,
    version: &'a str,
    cps_version: Option<&'a str>,
    dimension: &'static str,
    element_type: &'static str,
    formulation: Option<&'a str>,
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
        .map(|m| MaterialSummary {
            index: m.index,
            name: m.name.clone(),
            material_type: m.material_type.clone(),
            model: m.model.clone(),
            elements: p
                .model
                .element_material
                .iter()
                .filter(|&&e| e == m.index)
                .count(),
            mps: p.points.iter().filter(|mp| mp.material == m.index).count(),
            porosity: m.porosity,
            density_solid: m.density_solid,
            k0: m.k0,
            young_modulus: m.young_modulus,
            poisson_ratio: m.poisson_ratio,
            friction_angle: m.friction_angle,
            cohesion: m.cohesion,
            dilatancy_angle: m.dilatancy_angle,
            gamma_dry: m.gamma_dry(g),
        })
        .collect();
    let mesh = &p.model.mesh;
    let summary = Summary {
        files: &p.files,
        version: p.gom.version(),
        cps_version: p.cps.as_ref().map(CpsDocument::version),
        dimension: mesh.dimension.gom_name(),
        element_type: mesh.element_type.gom_name(),
        formulation: p.info.formulation.as_deref(),
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
        let inputs = super::map::project_inputs(&p.files);
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
    writeln!(out, "dimension  {} ({})", s.dimension, s.element_type)?;
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
    let fem = super::map::load_fem(&args.fem)?;
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
    let nodes = &fem.nodes;
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
    let mut out = std::io::stdout().lock();
    if json {
        serde_json::to_writer_pretty(&mut out, &project)?;
        writeln!(out)?;
        return Ok(());
    }
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
    for a in &project.analyses {
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
        if let Some(last) = a.steps.last() {
            let step = crate::formats::gsz::StepChoice::Number(last.number);
            match crate::formats::gsz::read_step(
                path,
                Some(&a.index.to_string()),
                &step,
                &Default::default(),
            ) {
                Ok((nodes, _, _)) => writeln!(
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
                )?,
                Err(e) => writeln!(out, "  step {}: unreadable: {e}", last.folder)?,
            }
        }
    }
    Ok(())
}
