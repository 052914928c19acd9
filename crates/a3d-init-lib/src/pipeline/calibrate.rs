//! The smoothing length h from the FEM data itself (paper Eq. 4): used by
//! `calibrate`, by `map --h auto` and by the demo.

use serde::Serialize;

use super::PipelineError;
use crate::calibrate::{AnnealSettings, Calibration, try_calibrate};
use crate::kernel::loo::{LooObjective, LooStats, Norm};
use crate::kernel::mapper;
use crate::kernel::{Kernel, KernelKind};
use crate::model::{FemNodes, Quantity};

/// The outcome of a calibration.
#[derive(Clone, Debug, Serialize)]
pub struct Outcome {
    pub h: f64,
    /// Median nearest-node spacing l.
    pub spacing: f64,
    pub h_over_l: f64,
    /// The kernel's short name (`cubic`, `gaussian`, `wendland`).
    pub kernel: &'static str,
    pub fields: Vec<String>,
    pub norm: Norm,
    pub stats: LooStats,
    pub calibration: Calibration,
    /// Set when every h is optimal (constant field): h then follows the spacing rule.
    pub fallback: Option<String>,
    /// (h, objective) on an even grid over the bracket, for plotting.
    pub curve: Vec<(f64, f64)>,
}

/// Field selection: one quantity or every field of the file. `files` names
/// the FEM file(s) in errors; a table without any field is an error.
pub fn select_fields(
    fem: &FemNodes,
    field: &str,
    files: &str,
) -> Result<Vec<Quantity>, PipelineError> {
    if fem.fields.is_empty() {
        return Err(PipelineError::Input(format!(
            "{files}: no field to calibrate on: the table has no pore-water pressure or stress column (only coordinates{})",
            if fem.region.is_some() {
                " and regions"
            } else {
                ""
            }
        )));
    }
    if field == "all" {
        return Ok(fem.fields.iter().map(|(q, _)| *q).collect());
    }
    let q = Quantity::from_name(field).ok_or_else(|| {
        PipelineError::Option(format!(
            "field `{field}`: expected pwp, sxx, syy, szz, sxy, syz, sxz, esxx, … or all"
        ))
    })?;
    if fem.field(q).is_none() {
        return Err(PipelineError::Input(format!(
            "field `{field}`: {files} has no such column (it has: {})",
            fem.fields
                .iter()
                .map(|(q, _)| q.name())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    Ok(vec![q])
}

/// Calibrates h on `fields` of `fem` (paper Eq. 4): the leave-one-out error
/// minimised by seeded simulated annealing and a golden-section refinement
/// over [0.3 l, 2.5 l], l the median nearest-node spacing.
pub fn calibrate_h(
    fem: &FemNodes,
    fields: &[Quantity],
    kernel: KernelKind,
    seed: u64,
    norm: Norm,
) -> Result<Outcome, PipelineError> {
    let names: Vec<String> = fields.iter().map(|q| q.name()).collect();
    let values = field_values(fem, fields);
    calibrate_values(&fem.positions, fem.dim, &values, &names, kernel, seed, norm)
}

/// [`calibrate_h`] on plain arrays: `values` row-major, one column per name
/// in `fields` (node i's value of field k at `i * fields.len() + k`).
pub fn calibrate_values(
    positions: &[[f64; 3]],
    dim: usize,
    values: &[f64],
    fields: &[String],
    kernel: KernelKind,
    seed: u64,
    norm: Norm,
) -> Result<Outcome, PipelineError> {
    let spacing = mapper::median_spacing(positions, dim);
    let (lo, hi) = (0.3 * spacing, 2.5 * spacing);
    let objective = LooObjective::new(positions, dim, values, fields.len(), kernel, hi)
        .map_err(|e| PipelineError::Input(format!("calibration: {e}")))?;
    let settings = AnnealSettings {
        seed,
        ..AnnealSettings::default()
    };
    let f = |h: f64| objective.evaluate(h, norm);
    let mut calibration = try_calibrate(f, lo, hi, &settings)
        .map_err(|e| PipelineError::Numerical(format!("calibration: {e}")))?;
    let mut fallback = None;
    if objective.is_constant() {
        let factor = kernel.spacing_factor();
        calibration.h = factor * spacing;
        fallback = Some(format!(
            "the field is constant, so every h predicts it exactly; h follows the spacing rule {factor}·l"
        ));
    }
    let curve = (0..=120)
        .map(|k| lo + (hi - lo) * k as f64 / 120.0)
        .map(|h| (h, f(h)))
        .collect();
    let stats = objective.stats(calibration.h);
    Ok(Outcome {
        h: calibration.h,
        spacing,
        h_over_l: calibration.h / spacing,
        kernel: kernel.name(),
        fields: fields.to_vec(),
        norm,
        stats,
        calibration,
        fallback,
        curve,
    })
}

/// The values of `fields` at every node, row-major: node i's value of
/// `fields[k]` at `i * fields.len() + k` (0 where the file lacks the field).
fn field_values(fem: &FemNodes, fields: &[Quantity]) -> Vec<f64> {
    let n = fem.len();
    let nf = fields.len();
    let mut values = vec![0.0; n * nf];
    for (k, q) in fields.iter().enumerate() {
        for (i, v) in fem.field(*q).unwrap_or(&[]).iter().enumerate() {
            values[i * nf + k] = *v;
        }
    }
    values
}

/// How well h, calibrated on one FEM, predicts the nodes of another (finer)
/// FEM of the same field: `calibrate --check`.
#[derive(Clone, Debug, Serialize)]
pub struct Check {
    pub file: std::path::PathBuf,
    pub nodes: usize,
    pub r2: f64,
    pub mae: f64,
    pub max_error: f64,
    /// (observed, predicted) at every check node, for the 1:1 plot.
    #[serde(skip)]
    pub pairs: Vec<(f64, f64)>,
}

/// Predicts field `q` at the nodes of `other` from `fem` with the calibrated
/// h (MPs beyond every node's support take the nearest node's value) and
/// compares with `other`'s own values.
pub fn check(
    fem: &FemNodes,
    outcome: &Outcome,
    kernel: KernelKind,
    q: Quantity,
    other: &FemNodes,
    other_path: &std::path::Path,
) -> Result<Check, PipelineError> {
    let observed = other.field(q).ok_or_else(|| {
        PipelineError::Input(format!("{}: no {} column", other_path.display(), q.name()))
    })?;
    let values = fem.field(q).unwrap_or(&[]).to_vec();
    let cloud = mapper::NodeCloud {
        positions: &fem.positions,
        dim: fem.dim,
        values: &values,
        n_fields: 1,
        group: None,
        node_volume: outcome.spacing.powi(fem.dim as i32),
    };
    let settings = mapper::MapSettings {
        kernel,
        h: outcome.h,
        min_shepard: 0.0,
        outside: mapper::OutsidePolicy::Nearest,
    };
    let predicted = mapper::map_points(&cloud, &other.positions, None, &settings)
        .map_err(|e| PipelineError::Numerical(e.to_string()))?;
    let mean = observed.iter().sum::<f64>() / observed.len() as f64;
    let (mut sse, mut sst, mut mae, mut max_error) = (0.0, 0.0, 0.0, 0.0f64);
    for (o, p) in observed.iter().zip(&predicted.values) {
        sse += (o - p).powi(2);
        sst += (o - mean).powi(2);
        mae += (o - p).abs();
        max_error = max_error.max((o - p).abs());
    }
    Ok(Check {
        file: other_path.to_path_buf(),
        nodes: observed.len(),
        r2: if sst > 0.0 { 1.0 - sse / sst } else { 1.0 },
        mae: mae / observed.len() as f64,
        max_error,
        pairs: observed
            .iter()
            .copied()
            .zip(predicted.values.iter().copied())
            .collect(),
    })
}

/// Writes the objective-against-h plot with the optimum marked (SVG).
pub fn plot_curve(path: &std::path::Path, outcome: &Outcome) -> Result<(), PipelineError> {
    use super::io::plot::{Series, line_chart};
    use plotters::style::RGBColor;
    let unit = if outcome.fields.len() == 1 {
        "kPa"
    } else {
        "normalised"
    };
    line_chart(
        path,
        &format!(
            "Leave-one-out error, {} kernel (h = {:.4} m, h/l = {:.3})",
            outcome.kernel, outcome.h, outcome.h_over_l
        ),
        "smoothing length h (m)",
        &format!("LOO objective Σ|e| ({unit})"),
        &[
            Series {
                label: "objective",
                points: outcome.curve.clone(),
                color: RGBColor(31, 119, 180),
                markers: false,
            },
            Series {
                label: "annealer samples",
                points: outcome.calibration.trace.clone(),
                color: RGBColor(200, 200, 200),
                markers: true,
            },
            Series {
                label: "optimum",
                points: vec![(outcome.h, outcome.calibration.value)],
                color: RGBColor(214, 39, 40),
                markers: true,
            },
        ],
        false,
    )
}

/// What `calibrate` runs on.
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    /// The FEM files the field comes from.
    pub fem: super::fem::FemOptions,
    /// `pwp`, `sxx`, … or `all`.
    pub field: String,
    pub kernel: KernelKind,
    pub seed: u64,
    pub norm: Norm,
    /// A second (finer) FEM file to check the calibrated h on, read with the
    /// same options.
    pub check: Option<std::path::PathBuf>,
}

/// What `calibrate` found and wrote.
#[derive(Clone, Debug, Serialize)]
pub struct Calibrated {
    #[serde(flatten)]
    pub outcome: Outcome,
    pub check: Option<Check>,
}

impl Calibrated {
    /// The files [`calibrate`] writes, in order.
    pub fn file_names(&self) -> Vec<&'static str> {
        let mut files = vec!["calibration.json", "calibration.svg"];
        if self.check.is_some() {
            files.push("check.svg");
        }
        files
    }
}

/// `calibrate`: reads the FEM, calibrates h, checks it on a second FEM where
/// one is given, and writes `calibration.json`, `calibration.svg` and
/// `check.svg` into `out` (replaced under `force`).
pub fn calibrate(
    options: &CalibrateOptions,
    out: &std::path::Path,
    force: bool,
) -> Result<(Calibrated, std::path::PathBuf), PipelineError> {
    let reads = super::io::output::ReadLog::start();
    let fem = super::fem::load(&options.fem)?;
    let files = crate::diagnose::file_list(&fem.paths);
    let fields = select_fields(&fem.nodes, &options.field, &files)?;
    let kernel = options.kernel.for_dim(fem.nodes.dim);
    let outcome = calibrate_h(&fem.nodes, &fields, kernel, options.seed, options.norm)?;
    let check = match &options.check {
        Some(path) => {
            let other = super::fem::load(&super::fem::FemOptions {
                paths: vec![path.clone()],
                ..options.fem.clone()
            })?;
            Some(self::check(
                &fem.nodes,
                &outcome,
                kernel,
                fields[0],
                &other.nodes,
                path,
            )?)
        }
        None => None,
    };
    let dir = super::io::output::OutputDir::create(out, force, &reads, "calibrate")?;
    plot_curve(&dir.path("calibration.svg"), &outcome)?;
    if let Some(c) = &check {
        super::io::plot::scatter_1to1(
            &dir.path("check.svg"),
            &format!(
                "Validation: {} predicted at the check nodes",
                fields[0].name()
            ),
            "kPa",
            &c.pairs,
        )?;
    }
    let calibrated = Calibrated { outcome, check };
    let json = serde_json::to_string_pretty(&calibrated)
        .map_err(|e| PipelineError::Output(format!("calibration.json: {e}")))?;
    dir.write("calibration.json", |w| w.write_all(json.as_bytes()))?;
    Ok((calibrated, dir.commit()?))
}
