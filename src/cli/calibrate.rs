//! `a3d-init calibrate`: the smoothing length h from the FEM data itself, by
//! minimising the leave-one-out error (paper Eq. 4) with simulated annealing and
//! a golden-section refinement. Also used by `map --h auto`.

use std::path::PathBuf;

use plotters::style::RGBColor;
use serde::Serialize;

use super::args::FemArgs;
use super::output::OutputDir;
use super::plot::{self, Series};
use crate::kernel::KernelKind;
use crate::kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy};
use crate::pipeline::calibrate::{Outcome, calibrate_h, select_fields};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
pub enum NormArg {
    L1,
    L2,
    Relative,
}

impl From<NormArg> for crate::kernel::loo::Norm {
    fn from(n: NormArg) -> Self {
        match n {
            NormArg::L1 => crate::kernel::loo::Norm::L1,
            NormArg::L2 => crate::kernel::loo::Norm::L2,
            NormArg::Relative => crate::kernel::loo::Norm::Relative,
        }
    }
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
    let fem = args.fem.load()?;
    let files = crate::diagnose::file_list(&fem.paths);
    let fields = select_fields(&fem.nodes, &args.field, &files)?;
    let kernel = KernelKind::parse(&args.kernel, fem.nodes.dim).ok_or_else(|| {
        anyhow::anyhow!(
            "--kernel {}: expected cubic, gaussian or wendland",
            args.kernel
        )
    })?;
    let outcome = calibrate_h(&fem.nodes, &fields, kernel, args.seed, args.norm.into())?;
    let check = match &args.check {
        Some(path) => {
            let other = FemArgs {
                fem: vec![path.clone()],
                ..args.fem.clone()
            }
            .load()?;
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
    let mut files = vec!["calibration.json", "calibration.svg"];
    if check.is_some() {
        files.push("check.svg");
    }
    println!("{}", super::output::wrote(&target, &files));
    Ok(())
}
