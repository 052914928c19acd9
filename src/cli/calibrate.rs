//! `a3d-init calibrate`: the smoothing length h from the FEM data itself, by
//! minimising the leave-one-out error (paper Eq. 4) with simulated annealing and
//! a golden-section refinement. Also used by `map --h auto`.

use std::path::PathBuf;

use anyhow::bail;
use plotters::style::RGBColor;
use serde::Serialize;

use super::map::{FemArgs, load_fem};
use super::output::OutputDir;
use super::plot::{self, Series};
use crate::calibrate::{AnnealSettings, Calibration, try_calibrate};
use crate::kernel::loo::{LooObjective, LooStats, Norm};
use crate::kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy};
use crate::kernel::{Kernel, KernelKind};
use crate::model::{FemNodes, Quantity};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
pub enum NormArg {
    L1,
    L2,
    Relative,
}

#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    #[command(flatten)]
    pub fem: FemArgs,
    /// Field to calibrate on: pwp, sxx, syy, …, or `all` (joint, each field normalised by its standard deviation).
    #[arg(long, default_value = "pwp")]
    pub field: String,
    /// Kernel: cubic, gaussian or wendland.
    #[arg(long, default_value = "cubic")]
    pub kernel: String,
    /// Seed of the annealer's random numbers (recorded in calibration.json).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Error norm: l1 (the paper's Eq. 4), l2 or relative.
    #[arg(long, value_enum, default_value_t = NormArg::L1)]
    pub norm: NormArg,
    /// Validation: predict the nodes of a second (finer) FEM file and report R², MAE.
    #[arg(long, value_name = "FILE")]
    pub check: Option<PathBuf>,
    /// Output folder for calibration.json and the SVG plots.
    #[arg(long, default_value = "calibration")]
    pub out: PathBuf,
    /// Replace an existing output folder.
    #[arg(long)]
    pub force: bool,
}

/// The outcome of a calibration.
#[derive(Clone, Debug, Serialize)]
pub struct Outcome {
    pub h: f64,
    /// Median nearest-node spacing l.
    pub spacing: f64,
    pub h_over_l: f64,
    pub kernel: String,
    pub fields: Vec<String>,
    pub norm: NormArg,
    pub stats: LooStats,
    pub calibration: Calibration,
    /// Set when every h is optimal (constant field): h then follows the spacing rule.
    pub fallback: Option<String>,
    /// (h, objective) on an even grid over the bracket, for plotting.
    pub curve: Vec<(f64, f64)>,
}

/// Field selection: one quantity or every field of the file.
pub fn select_fields(fem: &FemNodes, field: &str) -> anyhow::Result<Vec<Quantity>> {
    if field == "all" {
        return Ok(fem.fields.iter().map(|(q, _)| *q).collect());
    }
    let q = Quantity::from_name(field).ok_or_else(|| {
        anyhow::anyhow!(
            "--field {field}: expected pwp, sxx, syy, szz, sxy, syz, sxz, esxx, … or all"
        )
    })?;
    if fem.field(q).is_none() {
        bail!(
            "--field {field}: the FEM file has no such column (it has: {})",
            fem.fields
                .iter()
                .map(|(q, _)| q.name())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(vec![q])
}

/// Calibrates h on `fields` of `fem`.
pub fn run_calibration(
    fem: &FemNodes,
    fields: &[Quantity],
    kernel: KernelKind,
    seed: u64,
    norm: NormArg,
) -> anyhow::Result<Outcome> {
    let n = fem.len();
    let nf = fields.len();
    let mut values = vec![0.0; n * nf];
    for (k, q) in fields.iter().enumerate() {
        for (i, v) in fem.field(*q).unwrap_or(&[]).iter().enumerate() {
            values[i * nf + k] = *v;
        }
    }
    let spacing = mapper::median_spacing(&fem.positions, fem.dim);
    let (lo, hi) = (0.3 * spacing, 2.5 * spacing);
    let objective = LooObjective::new(&fem.positions, fem.dim, &values, nf, kernel, hi)
        .map_err(|e| anyhow::anyhow!("calibration: {e}"))?;
    let norm_kind = match norm {
        NormArg::L1 => Norm::L1,
        NormArg::L2 => Norm::L2,
        NormArg::Relative => Norm::Relative,
    };
    let settings = AnnealSettings {
        seed,
        ..AnnealSettings::default()
    };
    let f = |h: f64| objective.evaluate(h, norm_kind);
    let mut calibration =
        try_calibrate(f, lo, hi, &settings).map_err(|e| anyhow::anyhow!("calibration: {e}"))?;
    let mut fallback = None;
    if objective.is_constant() {
        let factor = if matches!(kernel, KernelKind::Gaussian { .. }) {
            0.8
        } else {
            1.0
        };
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
        kernel: kernel.name().into(),
        fields: fields.iter().map(|q| q.name()).collect(),
        norm,
        stats,
        calibration,
        fallback,
        curve,
    })
}

/// Writes the objective-against-h plot with the optimum marked.
pub fn plot_curve(path: &std::path::Path, outcome: &Outcome) -> anyhow::Result<()> {
    let unit = if outcome.fields.len() == 1 {
        "kPa"
    } else {
        "normalised"
    };
    plot::line_chart(
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

#[derive(Serialize)]
struct Check {
    file: PathBuf,
    nodes: usize,
    r2: f64,
    mae: f64,
    max_error: f64,
}

pub fn run(args: CalibrateArgs) -> anyhow::Result<()> {
    let fem = load_fem(&args.fem)?;
    let fields = select_fields(&fem.nodes, &args.field)?;
    let kernel = KernelKind::parse(&args.kernel, fem.nodes.dim).ok_or_else(|| {
        anyhow::anyhow!(
            "--kernel {}: expected cubic, gaussian or wendland",
            args.kernel
        )
    })?;
    let outcome = run_calibration(&fem.nodes, &fields, kernel, args.seed, args.norm)?;
    let check = match &args.check {
        Some(path) => {
            let other = load_fem(&FemArgs {
                fem: vec![path.clone()],
                ..args.fem.clone()
            })?;
            let q = fields[0];
            let observed = other
                .nodes
                .field(q)
                .ok_or_else(|| anyhow::anyhow!("{}: no {} column", path.display(), q.name()))?;
            let values = fem.nodes.field(q).unwrap_or(&[]).to_vec();
            let cloud = NodeCloud {
                positions: &fem.nodes.positions,
                dim: fem.nodes.dim,
                values: &values,
                n_fields: 1,
                group: None,
                node_volume: outcome.spacing.powi(fem.nodes.dim as i32),
            };
            let settings = MapSettings {
                kernel,
                h: outcome.h,
                min_shepard: 0.0,
                outside: OutsidePolicy::Nearest,
            };
            let predicted = mapper::map_points(&cloud, &other.nodes.positions, None, &settings)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            let mean = observed.iter().sum::<f64>() / observed.len() as f64;
            let (mut sse, mut sst, mut mae, mut max_error) = (0.0, 0.0, 0.0, 0.0f64);
            for (o, p) in observed.iter().zip(&predicted.values) {
                sse += (o - p).powi(2);
                sst += (o - mean).powi(2);
                mae += (o - p).abs();
                max_error = max_error.max((o - p).abs());
            }
            let pairs: Vec<(f64, f64)> = observed
                .iter()
                .copied()
                .zip(predicted.values.iter().copied())
                .collect();
            Some((
                Check {
                    file: path.clone(),
                    nodes: observed.len(),
                    r2: if sst > 0.0 { 1.0 - sse / sst } else { 1.0 },
                    mae: mae / observed.len() as f64,
                    max_error,
                },
                pairs,
            ))
        }
        None => None,
    };
    let mut inputs = args.fem.input_paths();
    inputs.extend(args.check.as_deref());
    let out = OutputDir::create(&args.out, args.force, &inputs)?;
    plot_curve(&out.path("calibration.svg"), &outcome)?;
    if let Some((_, pairs)) = &check {
        plot::scatter_1to1(
            &out.path("check.svg"),
            &format!(
                "Validation: {} predicted at the check nodes",
                fields[0].name()
            ),
            "kPa",
            pairs,
        )?;
    }
    #[derive(Serialize)]
    struct Json<'a> {
        #[serde(flatten)]
        outcome: &'a Outcome,
        check: Option<&'a Check>,
    }
    let json = serde_json::to_string_pretty(&Json {
        outcome: &outcome,
        check: check.as_ref().map(|c| &c.0),
    })?;
    out.write("calibration.json", |w| w.write_all(json.as_bytes()))?;
    let target = out.commit()?;
    println!(
        "h          {:.6} m ({} kernel, fields: {})",
        outcome.h,
        outcome.kernel,
        outcome.fields.join(", ")
    );
    println!(
        "h/l        {:.4} (l = {:.6} m, median nearest-node spacing)",
        outcome.h_over_l, outcome.spacing
    );
    println!(
        "objective  {:.6e} ({:?} norm, seed {}, {} evaluations)",
        outcome.calibration.value,
        outcome.norm,
        outcome.calibration.seed,
        outcome.calibration.evaluations
    );
    println!(
        "LOO        R² = {:.6}, MAE = {:.6} kPa, max error = {:.6} kPa",
        outcome.stats.r2, outcome.stats.mae, outcome.stats.max_error
    );
    if let Some(f) = &outcome.fallback {
        println!("note       {f}");
    }
    if let Some((c, _)) = &check {
        println!(
            "check      {} nodes of {}: R² = {:.6}, MAE = {:.6} kPa, max error = {:.6} kPa",
            c.nodes,
            c.file.display(),
            c.r2,
            c.mae,
            c.max_error
        );
    }
    println!(
        "wrote      {}/ (calibration.json, calibration.svg{})",
        target.display(),
        if check.is_some() { ", check.svg" } else { "" }
    );
    Ok(())
}
