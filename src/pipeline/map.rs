//! The mapping step as a library call: [`map`] takes a loaded [`Project`], the
//! FEM nodes and a typed [`MapConfig`] and returns the state of every MP with
//! its diagnostics and the report. Nothing is written here
//! ([`super::write::write_project`] does that) and nothing is printed.
//!
//! Physics lives in [`crate::state`] (geostatic stress, Bishop, MPM-MIXED
//! means, dry materials); the kernel interpolation in [`crate::kernel`].

use std::time::Instant;

use super::PipelineError;
use super::Project;
use super::Project as LoadedProject;
use super::fem::LoadedFem;
use super::regions::groups;
use super::report::describe_in_background;
pub use super::report::{InputFile, MapReport, MaterialCount, Smoothing};
use crate::formats::cps::CpsDocument;
use crate::formats::fem_csv::SignConvention;
use crate::formats::mapf;
use crate::formats::mps_table::MpDiagnostics;
use crate::kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy, PointStatus};
use crate::kernel::{Kernel, KernelKind};
use crate::model::{FemNodes, MpState, Quantity, StressComponent};
use crate::state::{self, geostatic};

macro_rules! input_err {
    ($($t:tt)*) => { PipelineError::Input(format!($($t)*)) };
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum Outside {
    Error,
    Nearest,
    Skip,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum StressSource {
    /// `fem` when the FEM file has total stresses, otherwise `geostatic`.
    Auto,
    /// Map the FEM total stresses.
    Fem,
    /// Overburden of the GOM materials along the vertical, σh = K0·σ'v + S·p.
    Geostatic,
    /// Zero total stress (warned).
    Zero,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
pub enum MixedState {
    /// Each fully filled element's volume-weighted mean state on all its MPs.
    Mean,
    /// Keep every MP's own mapped value (Anura3D MPM-MIXED keeps only MP 1's after the first step).
    PerMp,
}

/// How the smoothing length h is chosen.
#[derive(Clone, Debug)]
pub enum SmoothingLength {
    /// The paper's spacing rule (§2.2): [`KernelKind::spacing_factor`] × the
    /// median nearest-node spacing.
    SpacingRule,
    /// A given h in metres.
    Metres(f64),
    /// Leave-one-out calibration (paper Eq. 4) with this annealer seed.
    Calibrate { seed: u64 },
    /// A calibration already run on these nodes (reported as calibrated).
    Calibrated {
        outcome: Box<super::calibrate::Outcome>,
        seed: u64,
    },
}

/// Everything that decides how the FEM fields become MP states.
#[derive(Clone, Debug)]
pub struct MapConfig {
    pub kernel: KernelKind,
    pub h: SmoothingLength,
    /// MPs no FEM node reaches.
    pub outside: Outside,
    /// Null-point threshold on the Shepard ratio Σw·l^dim.
    pub min_shepard: f64,
    pub stress: StressSource,
    /// FEM region → GOM material, `region=material,…` (names or indices).
    pub material_map: Option<String>,
    /// MPM-MIXED models: element means or per-MP values.
    pub mixed_state: MixedState,
    /// Keep the FEM fields in [`Mapped::fem`] after mapping (for `fem.vtu`);
    /// without it they are freed once copied for the kernel (memory).
    pub keep_fem_fields: bool,
}

impl Default for MapConfig {
    fn default() -> Self {
        MapConfig {
            kernel: KernelKind::Cubic,
            h: SmoothingLength::SpacingRule,
            outside: Outside::Error,
            min_shepard: 0.02,
            stress: StressSource::Auto,
            material_map: None,
            mixed_state: MixedState::Mean,
            keep_fem_fields: true,
        }
    }
}

/// Maps the points whose group is not in `excluded`; excluded points get zero
/// values and status `Mapped` with no neighbours (they are dry and need no pwp).
/// `owned`: node values handed over in place of `cloud.values` (see
/// [`mapper::map_points_taking`]), or `None` to map with `cloud.values`.
fn map_subset(
    cloud: &NodeCloud<'_>,
    owned: Option<Vec<f64>>,
    points: &[[f64; 3]],
    groups: Option<&[u32]>,
    settings: &MapSettings,
    excluded: &[u32],
) -> Result<mapper::MapResult, PipelineError> {
    let map = |points: &[[f64; 3]], groups: Option<&[u32]>| {
        match owned {
            Some(values) => mapper::map_points_taking(cloud, values, points, groups, settings),
            None => mapper::map_points(cloud, points, groups, settings),
        }
        .map_err(|e| input_err!("{e}"))
    };
    let keep: Vec<usize> = (0..points.len())
        .filter(|&i| groups.is_none_or(|g| !excluded.contains(&g[i])))
        .collect();
    if keep.len() == points.len() {
        return map(points, groups);
    }
    let sub_points: Vec<[f64; 3]> = keep.iter().map(|&i| points[i]).collect();
    let sub_groups: Option<Vec<u32>> = groups.map(|g| keep.iter().map(|&i| g[i]).collect());
    let sub = map(&sub_points, sub_groups.as_deref())?;
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

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// How a calibrated h is described in the report.
fn calibrated_rule(outcome: &crate::pipeline::calibrate::Outcome, seed: u64) -> String {
    format!(
        "calibrated by leave-one-out (paper Eq. 4) on {}: h/l = {:.3}, LOO R² = {:.5}, seed {}{}",
        outcome.fields.join(", "),
        outcome.h_over_l,
        outcome.stats.r2,
        seed,
        outcome
            .fallback
            .as_deref()
            .map(|f| format!("; {f}"))
            .unwrap_or_default()
    )
}

/// Everything `map` computes before writing.
pub struct Mapped {
    /// The model, its files and its MPs.
    pub project: LoadedProject,
    /// The FEM nodes (their fields dropped unless `fem.vtu` is wanted).
    pub fem: LoadedFem,
    /// The state of each MP, in MP order.
    pub states: Vec<MpState>,
    /// How each MP was mapped.
    pub diagnostics: Vec<MpDiagnostics>,
    /// What report.json says, the exact-point MAPF's h among it.
    pub report: MapReport,
}

/// Maps the FEM fields onto the project's MPs (no output written): the state
/// per MP, the mapping diagnostics and the report.
pub fn map(
    project: Project,
    mut fem: LoadedFem,
    config: &MapConfig,
) -> Result<Mapped, PipelineError> {
    // The inputs' SHA-256 for the report, read and hashed beside the mapping
    // (a serial pass over every input file, which would otherwise come last).
    let hashing = describe_in_background(
        std::iter::once(&project.files.gom)
            .chain(&project.files.cps)
            .chain(&fem.paths)
            .cloned()
            .collect(),
    );
    let mut timings = Vec::new();
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
    let pwp = fem.nodes.field(Quantity::Pwp);
    if pwp.is_none() && !fem.nodes.has_total_stress() {
        return Err(input_err!(
            "{}: no pore-water pressure or total stress columns found",
            fem.paths[0].display()
        ));
    }
    let kernel = config.kernel;
    let spacing = mapper::median_spacing(&fem.nodes.positions, dim);
    let mut calibration = None;
    let (h, rule) = match &config.h {
        SmoothingLength::Calibrated { outcome, seed } => {
            let rule = calibrated_rule(outcome, *seed);
            let h = outcome.h;
            calibration = Some((**outcome).clone());
            (h, rule)
        }
        SmoothingLength::Calibrate { seed } => {
            let fields: Vec<Quantity> = if stress_source_wants_fem(config.stress, &fem.nodes) {
                fem.nodes.fields.iter().map(|(q, _)| *q).collect()
            } else {
                vec![Quantity::Pwp]
            };
            let t = Instant::now();
            let outcome = crate::pipeline::calibrate::calibrate_h(
                &fem.nodes,
                &fields,
                kernel,
                *seed,
                crate::kernel::loo::Norm::L1,
            )?;
            timings.push(("calibration".to_string(), t.elapsed().as_secs_f64() * 1e3));
            let rule = calibrated_rule(&outcome, *seed);
            let h = outcome.h;
            calibration = Some(outcome);
            (h, rule)
        }
        SmoothingLength::Metres(h) if *h > 0.0 && h.is_finite() => {
            // A support wider than the whole FEM makes every MP weigh every
            // node (a global average at O(MPs × nodes) cost): refused.
            let diagonal =
                crate::diagnose::Extent::of(&fem.nodes.positions, dim).map_or(0.0, |e| {
                    (0..dim)
                        .map(|k| (e.hi[k] - e.lo[k]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                });
            if diagonal > 0.0 && kernel.support() * h > 2.0 * diagonal {
                return Err(input_err!(
                    "--h {h}: the kernel support {:.4} m is more than twice the FEM's extent ({diagonal:.4} m across), so every MP would average every node; give an h near the node spacing l = {spacing:.4} m, or --h auto",
                    kernel.support() * h
                ));
            }
            // A support far below the node spacing reaches no node (#24).
            if spacing > 0.0 && kernel.support() * h < 1e-3 * spacing {
                return Err(input_err!(
                    "--h {h:?}: the kernel support {:e} m is below a thousandth of the node spacing l = {spacing:.4} m, so no MP would have a FEM node in reach; give an h near l, or --h auto",
                    kernel.support() * h
                ));
            }
            (*h, "given with --h".to_string())
        }
        SmoothingLength::Metres(h) => {
            return Err(input_err!(
                "--h {h}: the smoothing length must be a positive number of metres, or auto"
            ));
        }
        SmoothingLength::SpacingRule => {
            let factor = kernel.spacing_factor();
            (
                factor * spacing,
                format!(
                    "spacing rule h = {factor}·l with l = {spacing:.6} m, the median nearest-node spacing (paper §2.2, {})",
                    if dim == 2 {
                        "fitted on triangle meshes"
                    } else {
                        "fitted on 2D triangle meshes; on this 3D model a rule of thumb, use --h auto to calibrate"
                    }
                ),
            )
        }
    };
    fn stress_source_wants_fem(stress: StressSource, nodes: &FemNodes) -> bool {
        matches!(stress, StressSource::Fem)
            || (matches!(stress, StressSource::Auto) && nodes.has_total_stress())
    }
    let stress_source = match config.stress {
        StressSource::Auto if fem.nodes.has_total_stress() => StressSource::Fem,
        StressSource::Auto => StressSource::Geostatic,
        StressSource::Fem if !fem.nodes.has_total_stress() => {
            return Err(input_err!(
                "--stress fem: the FEM files have no total stress columns (sxx, syy, sxy{})",
                if dim == 3 { ", szz, syz, sxz" } else { "" }
            ));
        }
        s => s,
    };
    if stress_source != StressSource::Fem && pwp.is_none() {
        return Err(input_err!(
            "{}: --stress {:?} needs a pore-water pressure column",
            fem.paths[0].display(),
            stress_source
        ));
    }
    let (node_groups, separation) = groups(&project, &fem.nodes, config.material_map.as_deref())?;

    // Fields mapped: pwp and (for --stress fem) the total stresses.
    let mut quantities: Vec<Quantity> = Vec::new();
    if pwp.is_some() {
        quantities.push(Quantity::Pwp);
    }
    if stress_source == StressSource::Fem {
        for c in StressComponent::ALL {
            if fem.nodes.field(Quantity::TotalStress(c)).is_some() {
                quantities.push(Quantity::TotalStress(c));
            }
        }
    }
    let points = &project.points;
    let positions: Vec<[f64; 3]> = points.iter().map(|p| p.position).collect();
    // The exact-point MAPF's h needs the MP spacing: measured now, before the
    // FEM values are copied, so its search index is not held at the peak.
    let min_mp = mapper::min_spacing(&positions, dim);
    let n_fields = quantities.len();
    let mut values = vec![0.0; fem.nodes.len() * n_fields];
    for (k, q) in quantities.iter().enumerate() {
        for (i, v) in fem.nodes.field(*q).unwrap_or(&[]).iter().enumerate() {
            values[i * n_fields + k] = *v;
        }
    }
    if !config.keep_fem_fields {
        fem.nodes.fields = Vec::new();
    }
    // The values go to the mapper, which frees them once its grid holds a
    // copy, unless the geostatic stress maps the cloud a second time.
    let (owned, kept) = if stress_source == StressSource::Geostatic {
        (None, values)
    } else {
        (Some(values), Vec::new())
    };
    let cloud = NodeCloud {
        positions: &fem.nodes.positions,
        dim,
        values: &kept,
        n_fields,
        group: node_groups.as_deref(),
        node_volume: spacing.powi(dim as i32),
    };
    let settings = MapSettings {
        kernel,
        h,
        min_shepard: config.min_shepard,
        outside: match config.outside {
            Outside::Error => OutsidePolicy::Error,
            Outside::Nearest => OutsidePolicy::Nearest,
            Outside::Skip => OutsidePolicy::Skip,
        },
    };
    let point_groups: Option<Vec<u32>> = node_groups
        .as_ref()
        .map(|_| points.iter().map(|p| p.material).collect());
    // Dry materials without FEM nodes of their own (e.g. an impermeable base the
    // seepage model left out) get pwp = 0 and no kernel mapping.
    let mut notes: Vec<String> = fem.notes.clone();
    let mut dry_without_nodes: Vec<u32> = Vec::new();
    if let (Some(ng), Some(pg)) = (&node_groups, &point_groups) {
        for m in &project.model.materials {
            if pg.contains(&m.index) && !ng.contains(&m.index) {
                if !m.has_water() && stress_source != StressSource::Fem {
                    dry_without_nodes.push(m.index);
                    notes.push(format!(
                        "material {} `{}` is dry and has no FEM nodes: its MPs take pwp = 0 (no mapping)",
                        m.index, m.name
                    ));
                } else if settings.outside == OutsidePolicy::Error {
                    return Err(input_err!(
                        "material {} `{}` has MPs but no FEM nodes of its region; give its nodes, map a region to it with --material-map, or use --outside nearest|skip",
                        m.index,
                        m.name
                    ));
                }
            }
        }
    }
    // A FEM that does not reach the model: name the file, both extents and a
    // unit or offset hint (#14).
    let reach = {
        // The MPs the kernel maps; a copy only when some are left out.
        let reached: std::borrow::Cow<'_, [[f64; 3]]> = match &point_groups {
            Some(g) if !dry_without_nodes.is_empty() => (0..positions.len())
                .filter(|&i| !dry_without_nodes.contains(&g[i]))
                .map(|i| positions[i])
                .collect(),
            _ => std::borrow::Cow::Borrowed(&positions),
        };
        crate::diagnose::reach(
            &fem.nodes.positions,
            &project.model.mesh.nodes,
            &reached,
            dim,
            kernel.support() * h,
        )
    };
    let files = crate::diagnose::file_list(&fem.paths);
    if let Some(r) = reach.as_ref().filter(|r| r.is_poor()) {
        match config.outside {
            Outside::Error => return Err(input_err!("{}", r.message(&files))),
            _ => warnings.push(r.message(&files)),
        }
    }
    let t2 = Instant::now();
    let mut result = map_subset(
        &cloud,
        owned,
        &positions,
        point_groups.as_deref(),
        &settings,
        &dry_without_nodes,
    )
    .map_err(|e| match &reach {
        Some(r) => input_err!("{files}: {e} ({})", r.extents()),
        None => e,
    })?;
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
        if stress_source == StressSource::Fem {
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
    // The mapped rows are in `states` now; the diagnostics keep the rest.
    result.values = Vec::new();
    if stress_source == StressSource::Fem
        && dim == 2
        && column(Quantity::TotalStress(StressComponent::Zz)).is_none()
    {
        notes.push("σzz was not in the FEM file: set from plane-strain elasticity, σ'zz = ν(σ'xx + σ'yy), with each material's ν".into());
    }
    let dropped =
        state::drop_pore_water_of_dry_materials(&project.model.materials, points, &mut states);
    if !dropped.is_empty() {
        let list: Vec<String> = dropped
            .iter()
            .map(|d| {
                format!(
                    "{} `{}` ({} MPs, |pwp| up to {:.3} kPa)",
                    d.material, d.name, d.points, d.max_abs_pwp
                )
            })
            .collect();
        notes.push(format!(
            "FEM pore pressure dropped on MPs of materials without a liquid phase (dry_material): {}; they carry pwp = 0 and σ' = σ, as Anura3D would otherwise subtract the MAPF's Pwp from their stress",
            list.join(", ")
        ));
    }
    if stress_source == StressSource::Geostatic {
        let t3 = Instant::now();
        let model = &project.model;
        let active = |e: usize| model.element_material[e] > 0;
        // γ per element, averaged over a few points inside it (pwp mapped there).
        let (sample_pts, sample_elements) = geostatic::element_samples(&model.mesh, active);
        let sample_groups: Option<Vec<u32>> = node_groups.as_ref().map(|_| {
            sample_elements
                .iter()
                .map(|&e| model.element_material[e as usize])
                .collect()
        });
        let sample_settings = MapSettings {
            outside: OutsidePolicy::Nearest,
            ..settings
        };
        let sampled = map_subset(
            &cloud,
            None,
            &sample_pts,
            sample_groups.as_deref(),
            &sample_settings,
            &dry_without_nodes,
        )?;
        let k_pwp = column(Quantity::Pwp).unwrap_or(0);
        let mut gamma_sum = vec![(0.0f64, 0usize); model.mesh.n_elements()];
        for (s, &e) in sample_elements.iter().enumerate() {
            let m = model.material_of(e as usize);
            let p = sampled.values[s * n_fields + k_pwp];
            let saturation = match m {
                Some(m) if p > 0.0 && !m.is_unsaturated() => 0.0,
                other => state::saturation(other, p),
            };
            let slot = &mut gamma_sum[e as usize];
            slot.0 += m.map_or(0.0, |m| m.gamma_at_saturation(saturation, g));
            slot.1 += 1;
        }
        let gamma: Vec<f64> = gamma_sum
            .iter()
            .map(|&(sum, n)| if n > 0 { sum / n as f64 } else { 0.0 })
            .collect();
        let sigma_v = geostatic::overburden(&model.mesh, active, &gamma, &positions);
        for (i, p) in points.iter().enumerate() {
            let m = model.materials.get(p.material as usize - 1);
            let k0 = m.and_then(|m| m.k0).unwrap_or(0.5);
            states[i].total =
                geostatic::geostatic_tensor(sigma_v[i], k0, states[i].pwp, states[i].saturation);
        }
        notes.push(format!("total stress from the overburden of the GOM materials along the vertical (g = {g} m/s²; γ per element, averaged over 4–5 points inside it: saturated below the water table, from the retention curve or dry above), σh = K0·σ'v + S·p with each material's K0"));
        timings.push((
            "geostatic stress".to_string(),
            t3.elapsed().as_secs_f64() * 1e3,
        ));
    }
    // The FEM values' row-major copy is no longer needed.
    drop(kept);
    if stress_source == StressSource::Zero {
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
        warnings.push(format!("{null_points} MP(s) had no FEM node inside the support: handled with --outside {:?}", config.outside).to_lowercase());
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
    // Plausibility of the mapped pwp: warnings, never errors (#14).
    if stress_source != StressSource::Zero {
        let found = state::plausibility::check(&positions, &states, dim, g);
        warnings.extend(found.into_iter().map(|f| f.message));
    }
    let mixed = if project.method == crate::model::ComputationMethod::MpmMixed {
        let spread = state::mixed::element_spread(points, &states);
        match config.mixed_state {
            MixedState::Mean => {
                state::mixed::average_elements(&project.model, points, &mut states);
                notes.push(format!(
                    "MPM-MIXED: each of the {} fully filled elements carries its volume-weighted mean state on all its MPs (Anura3D integrates such an element at one point and gives every MP the state of its first MP after the first step); the largest spread inside an element was {:.3} kPa in pwp and {:.3} kPa in total stress; use $$COMPUTATION_METHOD MPM-MP when per-MP detail matters",
                    spread.elements, spread.pwp, spread.stress
                ));
            }
            MixedState::PerMp => {
                warnings.push(format!(
                    "MPM-MIXED with --mixed-state per-mp: Anura3D will replace the state of every MP of the {} fully filled elements by that of the element's first MP after the first step (largest spread inside an element: {:.3} kPa pwp, {:.3} kPa stress); use $$COMPUTATION_METHOD MPM-MP to keep per-MP detail",
                    spread.elements, spread.pwp, spread.stress
                ));
            }
        }
        Some(config.mixed_state)
    } else {
        None
    };
    if let Some(bad) = states
        .iter()
        .position(|s| !s.pwp.is_finite() || s.total.iter().any(|v| !v.is_finite()))
    {
        return Err(input_err!(
            "MP {} got a non-finite value; nothing was written",
            bad + 1
        ));
    }
    let mapf_h = mapf::exact_point_smoothing_length(min_mp);

    let inputs = hashing
        .join()
        .map_err(|_| input_err!("hashing the input files failed"))??;
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
    let sign = match fem.sign {
        SignConvention::GeoStudio => {
            "FEM sign geostudio: stresses compression positive and pwp positive below the water table in the file; all were negated into Anura3D's convention"
        }
        SignConvention::TensionPositive => "FEM sign tension-positive: values kept as in the file",
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
        smoothing: Smoothing::new(kernel, h, rule, spacing, dim),
        stress_source: format!("{stress_source:?}").to_lowercase(),
        computation_method: project.method,
        mixed_state: mixed,
        calibration,
        material_separation: separation,
        materials,
        fem_nodes: fem.nodes.len(),
        material_points: points.len(),
        null_points,
        null_point_policy: config.outside,
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
    })
}
