//! `a3d-init map`: FEM node results → kernel-mapped initial state on the MPs of an
//! Anura3D model → a ready-to-run Anura3D project (GOM copied, CPS switched to
//! MAPF initialisation with K0 off, `<project>.MAPF` in exact-point mode) plus
//! `mps.csv`, `mps.vtu`, `fem.vtu` and `report.json`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, bail};
use serde::Serialize;

use super::inspect::{LoadedProject, load_project};
use super::output::OutputDir;
use crate::formats::cps::CpsDocument;
use crate::formats::fem_csv::{self, CsvOptions, FemReadReport, SignConvention};
use crate::formats::mps_table::{self, MpDiagnostics};
use crate::formats::{mapf, vtu};
use crate::kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy, PointStatus};
use crate::kernel::{Kernel, KernelKind};
use crate::model::{FemNodes, MpState, Quantity, StressComponent};
use crate::state::{self, geostatic};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
pub enum SignArg {
    Geostudio,
    TensionPositive,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
pub enum OutsideArg {
    Error,
    Nearest,
    Skip,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
pub enum StressArg {
    /// `fem` when the FEM file has total stresses, otherwise `geostatic`.
    Auto,
    /// Map the FEM total stresses.
    Fem,
    /// Overburden of the GOM materials along the vertical, σh = K0·σ'v + S·p.
    Geostatic,
    /// Zero total stress (warned).
    Zero,
}

/// Options shared by every command that reads FEM node files.
#[derive(Debug, Clone, clap::Args)]
pub struct FemArgs {
    /// FEM node file(s): CSV node tables, or a GeoStudio node.csv with --fem-mesh. Several files are joined by node id or coordinates.
    #[arg(long = "fem", value_name = "FILE")]
    pub fem: Vec<PathBuf>,
    /// Explicit column mapping, e.g. `x=X (m),y=Y (m),pwp=PWP`.
    #[arg(long, value_name = "FIELD=HEADER,…")]
    pub columns: Option<String>,
    /// Unit overrides, e.g. `length=ft,pressure=psf`.
    #[arg(long, value_name = "length=…,pressure=…")]
    pub fem_units: Option<String>,
    /// Sign convention of the FEM file.
    #[arg(long, value_enum, default_value_t = SignArg::Geostudio)]
    pub fem_sign: SignArg,
    /// GeoStudio mesh (`Mesh.ply`) giving the coordinates of a `node.csv` without X, Y columns.
    #[arg(long, value_name = "PLY")]
    pub fem_mesh: Option<PathBuf>,
    /// Analysis of a `.gsz` project: its name or 1-based index (needed when there are several).
    #[arg(long, value_name = "NAME|INDEX")]
    pub analysis: Option<String>,
    /// Saved step of a `.gsz` analysis: a step number, `last`, or `time=<seconds>`.
    #[arg(long, default_value = "last", value_name = "k|last|time=T")]
    pub step: String,
}

#[derive(Debug, clap::Args)]
pub struct MapArgs {
    #[command(flatten)]
    pub fem: FemArgs,
    /// Anura3D model: `.GOM`, `.GOM_stage<k>`, `-2.dat`, `.CPS_<nnn>` or a project folder.
    #[arg(long, value_name = "MODEL")]
    pub mpm: PathBuf,
    /// Kernel: cubic (paper Eq. 2), gaussian (Eq. 3, truncated at 3h) or wendland (C2).
    #[arg(long, default_value = "cubic")]
    pub kernel: String,
    /// Smoothing length: metres, or `auto` (leave-one-out calibration, paper Eq. 4); default: the paper's spacing rule (h = 1.0·l cubic/Wendland, 0.8·l Gaussian, l = median nearest-node spacing).
    #[arg(long, value_name = "METRES|auto")]
    pub h: Option<String>,
    /// Seed of the calibration's annealer (with --h auto).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// What to do with MPs that no FEM node reaches.
    #[arg(long, value_enum, default_value_t = OutsideArg::Error)]
    pub outside: OutsideArg,
    /// Null-point threshold on the Shepard ratio Σw·l^dim (≈ 1 inside, 0.5 on an edge).
    #[arg(long, default_value_t = 0.02)]
    pub min_shepard: f64,
    /// Where total stresses come from.
    #[arg(long, value_enum, default_value_t = StressArg::Auto)]
    pub stress: StressArg,
    /// FEM region → GOM material, e.g. `sand=1,clay=Base` (default: by name or index).
    #[arg(long, value_name = "REGION=MATERIAL,…")]
    pub material_map: Option<String>,
    /// Output folder (default `<project>.a3d-init/` next to the model).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace an existing output folder.
    #[arg(long)]
    pub force: bool,
    /// Also write `fem.vtu` (the FEM nodes) when the FEM has more than 200 000 nodes;
    /// smaller FEMs always get one.
    #[arg(long)]
    pub fem_vtu: bool,
}

/// FEMs up to this many nodes get a `fem.vtu` without `--fem-vtu`.
pub const FEM_VTU_AUTO_MAX: usize = 200_000;

/// FEM nodes read and joined, with the reports of each file.
pub struct LoadedFem {
    pub nodes: FemNodes,
    pub reports: Vec<FemReadReport>,
}

/// Reads every `--fem` file with the shared options and joins them.
pub fn load_fem(args: &FemArgs) -> anyhow::Result<LoadedFem> {
    if args.fem.is_empty() {
        bail!("give the FEM node file(s) with --fem FILE");
    }
    let columns = match &args.columns {
        Some(s) => {
            fem_csv::parse_columns_option(s).map_err(|e| anyhow::anyhow!("--columns: {e}"))?
        }
        None => Vec::new(),
    };
    let units = match &args.fem_units {
        Some(s) => {
            fem_csv::parse_units_option(s).map_err(|e| anyhow::anyhow!("--fem-units: {e}"))?
        }
        None => Default::default(),
    };
    let options = CsvOptions {
        columns,
        units,
        sign: match args.fem_sign {
            SignArg::Geostudio => SignConvention::GeoStudio,
            SignArg::TensionPositive => SignConvention::TensionPositive,
        },
    };
    let mut parts = Vec::new();
    let mut reports = Vec::new();
    let mesh = args
        .fem_mesh
        .as_deref()
        .map(crate::formats::ply::read_ply_nodes)
        .transpose()?;
    for path in &args.fem {
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gsz"))
        {
            let step: crate::formats::gsz::StepChoice = args
                .step
                .parse()
                .map_err(|e| anyhow::anyhow!("--step {e}"))?;
            let (nodes, report, _) =
                crate::formats::gsz::read_step(path, args.analysis.as_deref(), &step, &options)?;
            parts.push(nodes);
            reports.push(report);
            continue;
        }
        let (mut nodes, report) = fem_csv::read_csv(path, &options)?;
        if !report.has_coordinates {
            match &mesh {
                Some(mesh) => fem_csv::attach_mesh(&mut nodes, path, mesh)?,
                None => bail!(
                    "{}: no X and Y columns; give the GeoStudio mesh with --fem-mesh Mesh.ply",
                    path.display()
                ),
            }
        }
        parts.push(nodes);
        reports.push(report);
    }
    let nodes = join(parts, &args.fem)?;
    Ok(LoadedFem { nodes, reports })
}

/// Joins several node files: by id when every file has ids in the same set, the
/// same quantity in two files must agree.
fn join(mut parts: Vec<FemNodes>, paths: &[PathBuf]) -> anyhow::Result<FemNodes> {
    let mut out = parts.remove(0);
    for (k, part) in parts.into_iter().enumerate() {
        let path = &paths[k + 1];
        if part.len() != out.len() {
            bail!(
                "{}: {} nodes, but {} has {}: the files do not describe the same nodes",
                path.display(),
                part.len(),
                paths[0].display(),
                out.len()
            );
        }
        let mut order: Vec<usize> = (0..out.len()).collect();
        let pos_of: std::collections::HashMap<i64, usize> = part
            .ids
            .iter()
            .enumerate()
            .map(|(i, id)| (*id, i))
            .collect();
        for (i, id) in out.ids.iter().enumerate() {
            match pos_of.get(id) {
                Some(&j) => order[i] = j,
                None => bail!(
                    "{}: node {id} of {} is missing",
                    path.display(),
                    paths[0].display()
                ),
            }
            let (a, b) = (out.positions[i], part.positions[order[i]]);
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            if d > 1e-6 * (1.0 + a[0].abs() + a[1].abs()) {
                bail!(
                    "{}: node {id} is at {:?} but at {:?} in {}",
                    path.display(),
                    b,
                    a,
                    paths[0].display()
                );
            }
        }
        for (q, values) in part.fields {
            let reordered: Vec<f64> = order.iter().map(|&j| values[j]).collect();
            if let Some(existing) = out.field(q) {
                if let Some(i) = (0..existing.len()).find(|&i| {
                    (existing[i] - reordered[i]).abs() > 1e-9 * (1.0 + existing[i].abs())
                }) {
                    bail!(
                        "{}: {} of node {} is {} but {} in {}",
                        path.display(),
                        q.name(),
                        out.ids[i],
                        reordered[i],
                        existing[i],
                        paths[0].display()
                    );
                }
            } else {
                out.fields.push((q, reordered));
            }
        }
        if out.region.is_none() {
            out.region = part
                .region
                .map(|r| order.iter().map(|&j| r[j].clone()).collect());
        }
    }
    Ok(out)
}

#[derive(Serialize)]
struct InputFile {
    path: PathBuf,
    bytes: u64,
    sha256: String,
}

fn describe(path: &Path) -> anyhow::Result<InputFile> {
    use sha2::{Digest, Sha256};
    use std::io::Read;
    // Streamed: a large FEM table is not held in memory a second time.
    let context = || format!("reading {}", path.display());
    let mut file = std::fs::File::open(path).with_context(context)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut len = 0u64;
    loop {
        let n = file.read(&mut buf).with_context(context)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
        len += n as u64;
    }
    let digest = hasher.finalize();
    Ok(InputFile {
        path: path.to_path_buf(),
        bytes: len,
        sha256: digest.iter().map(|b| format!("{b:02x}")).collect(),
    })
}

#[derive(Serialize)]
struct MaterialCount {
    index: u32,
    name: String,
    mps: usize,
    fem_nodes: Option<usize>,
}

#[derive(Serialize)]
pub struct MapReport {
    tool: String,
    inputs: Vec<InputFile>,
    fem: Vec<FemReadReport>,
    conventions: Vec<String>,
    kernel: String,
    smoothing_length: f64,
    smoothing_length_rule: String,
    fem_spacing: f64,
    gaussian_truncated_mass: Option<f64>,
    stress_source: String,
    calibration: Option<super::calibrate::Outcome>,
    material_separation: String,
    materials: Vec<MaterialCount>,
    fem_nodes: usize,
    material_points: usize,
    null_points: usize,
    null_point_policy: OutsideArg,
    mapf_smoothing_length: f64,
    min_mp_spacing: f64,
    pwp_range: (f64, f64),
    sigma_yy_range: (f64, f64),
    notes: Vec<String>,
    warnings: Vec<String>,
    timings_ms: Vec<(String, f64)>,
}

/// Assigns FEM nodes and MPs to groups (GOM material indices) when the FEM has a
/// region column; returns (node groups, description).
fn groups(
    project: &LoadedProject,
    fem: &FemNodes,
    material_map: Option<&str>,
) -> anyhow::Result<(Option<Vec<u32>>, String)> {
    let Some(regions) = &fem.region else {
        return Ok((None, "none: the FEM file has no region column, so nodes of every material were used for every MP".into()));
    };
    let materials = &project.model.materials;
    let mut explicit: Vec<(String, u32)> = Vec::new();
    if let Some(spec) = material_map {
        for pair in spec.split(',').filter(|s| !s.trim().is_empty()) {
            let (r, m) = pair.split_once('=').ok_or_else(|| {
                anyhow::anyhow!("--material-map: `{pair}`: expected region=material")
            })?;
            let m = m.trim();
            let index = m
                .parse::<u32>()
                .ok()
                .filter(|&i| i >= 1 && i as usize <= materials.len())
                .or_else(|| {
                    materials
                        .iter()
                        .find(|x| x.name.eq_ignore_ascii_case(m))
                        .map(|x| x.index)
                })
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "--material-map: no GOM material `{m}` (materials: {})",
                        materials
                            .iter()
                            .map(|x| x.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                })?;
            explicit.push((r.trim().to_string(), index));
        }
    }
    let resolve = |region: &str| -> Option<u32> {
        explicit
            .iter()
            .find(|(r, _)| r == region)
            .map(|(_, i)| *i)
            .or_else(|| {
                materials
                    .iter()
                    .find(|m| m.name.eq_ignore_ascii_case(region))
                    .map(|m| m.index)
            })
            .or_else(|| {
                region
                    .parse::<u32>()
                    .ok()
                    .filter(|&i| i >= 1 && i as usize <= materials.len())
            })
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
        bail!(
            "FEM regions {} match no GOM material (materials: {}); map them with --material-map region=material",
            unknown
                .iter()
                .map(|s| format!("`{s}`"))
                .collect::<Vec<_>>()
                .join(", "),
            materials
                .iter()
                .map(|m| format!("{} {}", m.index, m.name))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok((Some(out), "by region: each MP takes only FEM nodes of its own material (no smoothing across material boundaries)".into()))
}

/// Maps the points whose group is not in `excluded`; excluded points get zero
/// values and status `Mapped` with no neighbours (they are dry and need no pwp).
fn map_subset(
    cloud: &NodeCloud<'_>,
    points: &[[f64; 3]],
    groups: Option<&[u32]>,
    settings: &MapSettings,
    excluded: &[u32],
) -> anyhow::Result<mapper::MapResult> {
    let keep: Vec<usize> = (0..points.len())
        .filter(|&i| groups.is_none_or(|g| !excluded.contains(&g[i])))
        .collect();
    if keep.len() == points.len() {
        return mapper::map_points(cloud, points, groups, settings)
            .map_err(|e| anyhow::anyhow!("{e}"));
    }
    let sub_points: Vec<[f64; 3]> = keep.iter().map(|&i| points[i]).collect();
    let sub_groups: Option<Vec<u32>> = groups.map(|g| keep.iter().map(|&i| g[i]).collect());
    let sub = mapper::map_points(cloud, &sub_points, sub_groups.as_deref(), settings)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let nf = cloud.n_fields;
    let mut full = mapper::MapResult {
        values: vec![0.0; points.len() * nf],
        n_neighbours: vec![0; points.len()],
        shepard: vec![0.0; points.len()],
        status: vec![PointStatus::Mapped; points.len()],
    };
    for (k, &i) in keep.iter().enumerate() {
        full.values[i * nf..(i + 1) * nf].copy_from_slice(&sub.values[k * nf..(k + 1) * nf]);
        full.n_neighbours[i] = sub.n_neighbours[k];
        full.shepard[i] = sub.shepard[k];
        full.status[i] = sub.status[k];
    }
    Ok(full)
}

fn min_spacing(points: &[[f64; 3]], dim: usize) -> f64 {
    mapper::min_spacing(points, dim)
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// Everything `map` computes before writing.
pub struct Mapped {
    pub project: LoadedProject,
    pub fem: LoadedFem,
    pub states: Vec<MpState>,
    pub diagnostics: Vec<MpDiagnostics>,
    pub report: MapReport,
    pub mapf_h: f64,
}

/// Runs the mapping (no output written).
pub fn compute(args: &MapArgs) -> anyhow::Result<Mapped> {
    let mut timings = Vec::new();
    let t0 = Instant::now();
    let project = load_project(&args.mpm)?;
    timings.push((
        "read model and place MPs".to_string(),
        t0.elapsed().as_secs_f64() * 1e3,
    ));
    let t1 = Instant::now();
    let fem = load_fem(&args.fem)?;
    timings.push(("read FEM".to_string(), t1.elapsed().as_secs_f64() * 1e3));
    let mut warnings: Vec<String> = project.info.warnings.clone();
    for r in &fem.reports {
        warnings.extend(
            r.warnings
                .iter()
                .map(|w| format!("{}: {w}", r.path.display())),
        );
    }
    let dim = project.model.mesh.dimension.n_dim();
    if fem.nodes.dim != dim {
        bail!(
            "{}: the FEM nodes are {}D but the Anura3D model is {} ({}D)",
            args.fem.fem[0].display(),
            fem.nodes.dim,
            project.model.mesh.dimension.gom_name(),
            dim
        );
    }
    if fem.nodes.len() < 3 {
        bail!(
            "{}: at least 3 FEM nodes are needed, found {}",
            args.fem.fem[0].display(),
            fem.nodes.len()
        );
    }
    let pwp = fem.nodes.field(Quantity::Pwp);
    if pwp.is_none() && !fem.nodes.has_total_stress() {
        bail!(
            "{}: no pore-water pressure or total stress columns found",
            args.fem.fem[0].display()
        );
    }
    let kernel = KernelKind::parse(&args.kernel, dim).ok_or_else(|| {
        anyhow::anyhow!(
            "--kernel {}: expected cubic, gaussian or wendland",
            args.kernel
        )
    })?;
    let spacing = mapper::median_spacing(&fem.nodes.positions, dim);
    let mut calibration = None;
    let (h, rule) = match args.h.as_deref() {
        Some("auto") => {
            let fields: Vec<Quantity> = if stress_source_wants_fem(args, &fem.nodes) {
                fem.nodes.fields.iter().map(|(q, _)| *q).collect()
            } else {
                vec![Quantity::Pwp]
            };
            let t = Instant::now();
            let outcome = super::calibrate::run_calibration(
                &fem.nodes,
                &fields,
                kernel,
                args.seed,
                super::calibrate::NormArg::L1,
            )?;
            timings.push(("calibration".to_string(), t.elapsed().as_secs_f64() * 1e3));
            let rule = format!(
                "calibrated by leave-one-out (paper Eq. 4) on {}: h/l = {:.3}, LOO R² = {:.5}, seed {}{}",
                outcome.fields.join(", "),
                outcome.h_over_l,
                outcome.stats.r2,
                args.seed,
                outcome
                    .fallback
                    .as_deref()
                    .map(|f| format!("; {f}"))
                    .unwrap_or_default()
            );
            let h = outcome.h;
            calibration = Some(outcome);
            (h, rule)
        }
        Some(text) => match text.parse::<f64>() {
            Ok(h) if h > 0.0 && h.is_finite() => (h, "given with --h".to_string()),
            _ => bail!(
                "--h {text}: the smoothing length must be a positive number of metres, or auto"
            ),
        },
        None => {
            let factor = if matches!(kernel, KernelKind::Gaussian { .. }) {
                0.8
            } else {
                1.0
            };
            (
                factor * spacing,
                format!(
                    "spacing rule h = {factor}·l with l = {spacing:.6} m, the median nearest-node spacing (paper §2.2, triangle meshes)"
                ),
            )
        }
    };
    fn stress_source_wants_fem(args: &MapArgs, nodes: &FemNodes) -> bool {
        matches!(args.stress, StressArg::Fem)
            || (matches!(args.stress, StressArg::Auto) && nodes.has_total_stress())
    }
    let stress_source = match args.stress {
        StressArg::Auto if fem.nodes.has_total_stress() => StressArg::Fem,
        StressArg::Auto => StressArg::Geostatic,
        StressArg::Fem if !fem.nodes.has_total_stress() => bail!(
            "--stress fem: the FEM files have no total stress columns (sxx, syy, sxy{})",
            if dim == 3 { ", szz, syz, sxz" } else { "" }
        ),
        s => s,
    };
    if stress_source != StressArg::Fem && pwp.is_none() {
        bail!(
            "{}: --stress {:?} needs a pore-water pressure column",
            args.fem.fem[0].display(),
            stress_source
        );
    }
    let (node_groups, separation) = groups(&project, &fem.nodes, args.material_map.as_deref())?;

    // Fields mapped: pwp and (for --stress fem) the total stresses.
    let mut quantities: Vec<Quantity> = Vec::new();
    if pwp.is_some() {
        quantities.push(Quantity::Pwp);
    }
    if stress_source == StressArg::Fem {
        for c in StressComponent::ALL {
            if fem.nodes.field(Quantity::TotalStress(c)).is_some() {
                quantities.push(Quantity::TotalStress(c));
            }
        }
    }
    let n_fields = quantities.len();
    let mut values = vec![0.0; fem.nodes.len() * n_fields];
    for (k, q) in quantities.iter().enumerate() {
        for (i, v) in fem.nodes.field(*q).unwrap_or(&[]).iter().enumerate() {
            values[i * n_fields + k] = *v;
        }
    }
    let cloud = NodeCloud {
        positions: &fem.nodes.positions,
        dim,
        values: &values,
        n_fields,
        group: node_groups.as_deref(),
        node_volume: spacing.powi(dim as i32),
    };
    let settings = MapSettings {
        kernel,
        h,
        min_shepard: args.min_shepard,
        outside: match args.outside {
            OutsideArg::Error => OutsidePolicy::Error,
            OutsideArg::Nearest => OutsidePolicy::Nearest,
            OutsideArg::Skip => OutsidePolicy::Skip,
        },
    };
    let points = &project.points;
    let positions: Vec<[f64; 3]> = points.iter().map(|p| p.position).collect();
    let point_groups: Option<Vec<u32>> = node_groups
        .as_ref()
        .map(|_| points.iter().map(|p| p.material).collect());
    // Dry materials without FEM nodes of their own (e.g. an impermeable base the
    // seepage model left out) get pwp = 0 and no kernel mapping.
    let mut notes: Vec<String> = Vec::new();
    let mut dry_without_nodes: Vec<u32> = Vec::new();
    if let (Some(ng), Some(pg)) = (&node_groups, &point_groups) {
        for m in &project.model.materials {
            if pg.contains(&m.index) && !ng.contains(&m.index) {
                if !m.has_water() && stress_source != StressArg::Fem {
                    dry_without_nodes.push(m.index);
                    notes.push(format!(
                        "material {} `{}` is dry and has no FEM nodes: its MPs take pwp = 0 (no mapping)",
                        m.index, m.name
                    ));
                } else if settings.outside == OutsidePolicy::Error {
                    bail!(
                        "material {} `{}` has MPs but no FEM nodes of its region; give its nodes, map a region to it with --material-map, or use --outside nearest|skip",
                        m.index,
                        m.name
                    );
                }
            }
        }
    }
    let t2 = Instant::now();
    let result = map_subset(
        &cloud,
        &positions,
        point_groups.as_deref(),
        &settings,
        &dry_without_nodes,
    )?;
    timings.push((
        "kernel mapping".to_string(),
        t2.elapsed().as_secs_f64() * 1e3,
    ));

    let g = project
        .cps
        .as_ref()
        .map_or(crate::model::DEFAULT_GRAVITY, CpsDocument::gravity);
    let column = |q: Quantity| quantities.iter().position(|x| *x == q);
    let mut states: Vec<MpState> = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let material = project.model.materials.get(p.material as usize - 1);
        let row = &result.values[i * n_fields..(i + 1) * n_fields];
        let pwp = column(Quantity::Pwp).map_or(0.0, |k| row[k]);
        let mut total = [0.0; 6];
        if stress_source == StressArg::Fem {
            for c in StressComponent::ALL {
                if let Some(k) = column(Quantity::TotalStress(c)) {
                    total[c.index()] = row[k];
                }
            }
            if dim == 2 && column(Quantity::TotalStress(StressComponent::Zz)).is_none() {
                // Plane strain, elastic: σ'zz = ν(σ'xx + σ'yy).
                let s = state::saturation(material, pwp);
                let nu = material.and_then(|m| m.poisson_ratio).unwrap_or(0.3);
                total[2] = nu * (total[0] - s * pwp + total[1] - s * pwp) + s * pwp;
            }
        }
        states.push(MpState {
            pwp,
            total,
            saturation: state::saturation(material, pwp),
        });
    }
    let mut notes = Vec::new();
    if stress_source == StressArg::Fem
        && dim == 2
        && column(Quantity::TotalStress(StressComponent::Zz)).is_none()
    {
        notes.push("σzz was not in the FEM file: set from plane-strain elasticity, σ'zz = ν(σ'xx + σ'yy), with each material's ν".into());
    }
    if stress_source == StressArg::Geostatic {
        let t3 = Instant::now();
        let model = &project.model;
        let index = geostatic::VerticalIndex::new(&model.mesh, |e| model.element_material[e] > 0);
        let columns = index.columns(&positions, 4);
        let sample_pts: Vec<[f64; 3]> = columns.samples.iter().map(|s| s.midpoint).collect();
        let sample_groups: Option<Vec<u32>> = node_groups.as_ref().map(|_| {
            columns
                .samples
                .iter()
                .map(|s| model.element_material[s.element as usize])
                .collect()
        });
        let sample_settings = MapSettings {
            outside: OutsidePolicy::Nearest,
            ..settings
        };
        let sampled = map_subset(
            &cloud,
            &sample_pts,
            sample_groups.as_deref(),
            &sample_settings,
            &dry_without_nodes,
        )?;
        let k_pwp = column(Quantity::Pwp).unwrap_or(0);
        let gamma: Vec<f64> = columns
            .samples
            .iter()
            .enumerate()
            .map(|(s, sample)| {
                let m = model.material_of(sample.element as usize);
                let p = sampled.values[s * n_fields + k_pwp];
                let saturation = match m {
                    Some(m) if p > 0.0 && !m.is_unsaturated() => 0.0,
                    other => state::saturation(other, p),
                };
                m.map_or(0.0, |m| m.gamma_at_saturation(saturation, g))
            })
            .collect();
        let sigma_v = geostatic::vertical_stress(&columns, &gamma);
        for (i, p) in points.iter().enumerate() {
            let m = model.materials.get(p.material as usize - 1);
            let k0 = m.and_then(|m| m.k0).unwrap_or(0.5);
            states[i].total =
                geostatic::geostatic_tensor(sigma_v[i], k0, states[i].pwp, states[i].saturation);
        }
        notes.push(format!("total stress from the overburden of the GOM materials along the vertical (g = {g} m/s²; γ saturated below the water table, from the retention curve or dry above), σh = K0·σ'v + S·p with each material's K0"));
        timings.push((
            "geostatic stress".to_string(),
            t3.elapsed().as_secs_f64() * 1e3,
        ));
    }
    if stress_source == StressArg::Zero {
        warnings.push("--stress zero: all total stresses are 0; the MPs start unstressed".into());
    }
    if dim == 2 {
        notes.push("Anura3D's MAPF reader puts τxy into σ'zz in 2D (a kernel defect); mps.csv holds the intended σzz".into());
    } else {
        notes.push("3D MAPF: τyz is written under SigXZ[kPa] and τxz under SigYZ[kPa], cancelling Anura3D's swapped reader".into());
    }

    let diagnostics: Vec<MpDiagnostics> = (0..points.len())
        .map(|i| MpDiagnostics {
            neighbours: result.n_neighbours[i],
            shepard: result.shepard[i],
            status: match result.status[i] {
                PointStatus::Mapped => "mapped",
                PointStatus::Nearest => "nearest",
                PointStatus::Skipped => "skipped",
            },
        })
        .collect();
    let null_points = result
        .status
        .iter()
        .filter(|s| **s != PointStatus::Mapped)
        .count();
    if null_points > 0 {
        warnings.push(format!("{null_points} MP(s) had no FEM node inside the support: handled with --outside {:?}", args.outside).to_lowercase());
    }
    // Skipped MPs keep zero state in the outputs rather than NaN.
    for (s, st) in states.iter_mut().zip(&result.status) {
        if *st == PointStatus::Skipped {
            *s = MpState {
                pwp: 0.0,
                total: [0.0; 6],
                saturation: 1.0,
            };
        }
    }
    if let Some(bad) = states
        .iter()
        .position(|s| !s.pwp.is_finite() || s.total.iter().any(|v| !v.is_finite()))
    {
        bail!("MP {} got a non-finite value; nothing was written", bad + 1);
    }
    let min_mp = min_spacing(&positions, dim);
    let mapf_h = mapf::exact_point_smoothing_length(min_mp);

    let mut inputs = vec![describe(&project.files.gom)?];
    if let Some(c) = &project.files.cps {
        inputs.push(describe(c)?);
    }
    for f in &args.fem.fem {
        inputs.push(describe(f)?);
    }
    let materials = project
        .model
        .materials
        .iter()
        .map(|m| MaterialCount {
            index: m.index,
            name: m.name.clone(),
            mps: points.iter().filter(|p| p.material == m.index).count(),
            fem_nodes: node_groups
                .as_ref()
                .map(|g| g.iter().filter(|&&x| x == m.index).count()),
        })
        .collect();
    let sign = match args.fem.fem_sign {
        SignArg::Geostudio => {
            "FEM sign geostudio: stresses compression positive and pwp positive below the water table in the file; all were negated into Anura3D's convention"
        }
        SignArg::TensionPositive => "FEM sign tension-positive: values kept as in the file",
    };
    let report = MapReport {
        tool: format!("a3d-init {}", env!("CARGO_PKG_VERSION")),
        inputs,
        fem: fem.reports.clone(),
        conventions: vec![
            "units: m, kPa, kN/m³, s".into(),
            "output signs (Anura3D): tension positive, pore pressure negative in compression"
                .into(),
            sign.into(),
            "MAPF Sig* columns are total stresses; Anura3D forms σ' = σ − S·p (Bishop)".into(),
        ],
        kernel: kernel.name().into(),
        smoothing_length: h,
        smoothing_length_rule: rule,
        fem_spacing: spacing,
        gaussian_truncated_mass: match kernel {
            KernelKind::Gaussian { cutoff } => {
                Some(crate::kernel::Gaussian { cutoff }.truncated_mass(dim))
            }
            _ => None,
        },
        stress_source: format!("{stress_source:?}").to_lowercase(),
        calibration,
        material_separation: separation,
        materials,
        fem_nodes: fem.nodes.len(),
        material_points: points.len(),
        null_points,
        null_point_policy: args.outside,
        mapf_smoothing_length: mapf_h,
        min_mp_spacing: min_mp,
        pwp_range: range(states.iter().map(|s| s.pwp)),
        sigma_yy_range: range(states.iter().map(|s| s.total[1])),
        notes,
        warnings,
        timings_ms: timings,
    };
    Ok(Mapped {
        project,
        fem,
        states,
        diagnostics,
        report,
        mapf_h,
    })
}

/// The file name Anura3D expects for the GOM of this project.
fn gom_name(project: &LoadedProject) -> String {
    match project.files.stage {
        Some(k) => format!("{}.GOM_stage{k}", project.files.name),
        None => format!("{}.GOM", project.files.name),
    }
}

/// Writes the ready-to-run project and the diagnostics into `out`.
pub fn write(mapped: &Mapped, out: &OutputDir) -> anyhow::Result<Vec<String>> {
    write_with(mapped, out, false)
}

/// [`write()`], with `fem.vtu` forced on (`--fem-vtu`) or left to the FEM's size.
pub fn write_with(mapped: &Mapped, out: &OutputDir, fem_vtu: bool) -> anyhow::Result<Vec<String>> {
    let project = &mapped.project;
    let name = &project.files.name;
    let dim = project.model.mesh.dimension.n_dim();
    let mut written = Vec::new();
    out.copy(&project.files.gom, &gom_name(project))?;
    written.push(gom_name(project));
    let (cps_name, mut cps) = match &project.files.cps {
        Some(path) => (
            path.file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| format!("{name}.CPS_001")),
            CpsDocument::read(path)?,
        ),
        None => (
            format!("{name}.CPS_001"),
            CpsDocument::parse(
                Path::new("generated.CPS_001"),
                "### Anura3D_2023 ###\n$$END\n".to_string(),
            )?,
        ),
    };
    cps.set("$$K0_PROCEDURE", &["0"]);
    cps.set("$$MP_STRESS_INITIALIZATION_FROMFILE", &["1"]);
    let text = cps.to_text();
    out.write(&cps_name, |w| w.write_all(text.as_bytes()))?;
    written.push(cps_name);
    if let Some(opd) = &project.files.opd {
        let file = opd
            .file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        out.copy(opd, &file)?;
        written.push(file);
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
        vtu::ArrayFn::scalar("shepard", |i| diags[i].shepard),
    ];
    out.write("mps.vtu", |w| {
        vtu::write_points_with(w, points.len(), &|i| points[i].position, &arrays)
    })?;
    written.push("mps.vtu".into());
    if fem_vtu || mapped.fem.nodes.len() <= FEM_VTU_AUTO_MAX {
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
    let json = serde_json::to_string_pretty(&mapped.report)?;
    out.write("report.json", |w| w.write_all(json.as_bytes()))?;
    written.push("report.json".into());
    Ok(written)
}

/// Default output folder: `<project>.a3d-init/` beside the model.
pub fn default_out(project_dir: &Path, name: &str) -> PathBuf {
    project_dir.join(format!("{name}.a3d-init"))
}

pub fn run(args: MapArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let progress = super::progress::show();
    let mapped = compute(&args)?;
    let target = args
        .out
        .clone()
        .unwrap_or_else(|| default_out(&mapped.project.files.dir, &mapped.project.files.name));
    let mut inputs: Vec<&Path> = vec![&mapped.project.files.gom];
    if let Some(c) = &mapped.project.files.cps {
        inputs.push(c);
    }
    inputs.extend(args.fem.fem.iter().map(PathBuf::as_path));
    let out = OutputDir::create(&target, args.force, &inputs)?;
    let written = write_with(&mapped, &out, args.fem_vtu)?;
    let target = out.commit()?;
    drop(progress);
    let r = &mapped.report;
    eprintln!(
        "a3d-init map: {} FEM nodes → {} MPs ({} kernel, h = {:.4} m; {})",
        r.fem_nodes, r.material_points, r.kernel, r.smoothing_length, r.smoothing_length_rule
    );
    eprintln!(
        "  stress: {}; material separation: {}",
        r.stress_source, r.material_separation
    );
    eprintln!(
        "  pwp {:.3} .. {:.3} kPa, σyy {:.3} .. {:.3} kPa (Anura3D signs)",
        r.pwp_range.0, r.pwp_range.1, r.sigma_yy_range.0, r.sigma_yy_range.1
    );
    for w in &r.warnings {
        eprintln!("  warning: {w}");
    }
    eprintln!(
        "  wrote {}/ : {} ({:.2} s)",
        target.display(),
        written.join(", "),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
