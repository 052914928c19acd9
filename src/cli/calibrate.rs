//! `a3d-init calibrate`: arguments and printing around
//! [`pipeline::calibrate::calibrate`], the smoothing length h from the FEM data
//! itself (leave-one-out error, paper Eq. 4, minimised by simulated annealing
//! and a golden-section refinement), checked on a finer FEM with `--check`.

use std::path::PathBuf;

use super::args::FemArgs;
use super::print::wrote;
use a3d_init::kernel::KernelKind;
use a3d_init::pipeline::{self, calibrate::CalibrateOptions};

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NormArg {
    L1,
    L2,
    Relative,
}

impl From<NormArg> for a3d_init::kernel::loo::Norm {
    fn from(n: NormArg) -> Self {
        match n {
            NormArg::L1 => a3d_init::kernel::loo::Norm::L1,
            NormArg::L2 => a3d_init::kernel::loo::Norm::L2,
            NormArg::Relative => a3d_init::kernel::loo::Norm::Relative,
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

pub fn run(args: CalibrateArgs) -> anyhow::Result<()> {
    let kernel = KernelKind::parse(&args.kernel, 2).ok_or_else(|| {
        anyhow::anyhow!(
            "--kernel {}: expected cubic, gaussian or wendland",
            args.kernel
        )
    })?;
    let options = CalibrateOptions {
        fem: args.fem.options()?,
        field: args.field.clone(),
        kernel,
        seed: args.seed,
        norm: args.norm.into(),
        check: args.check.clone(),
    };
    let (calibrated, target) = pipeline::calibrate::calibrate(&options, &args.out, args.force)?;
    let outcome = &calibrated.outcome;
    say!(
        "h          {:.6} m ({} kernel, fields: {})",
        outcome.h,
        outcome.kernel,
        outcome.fields.join(", ")
    );
    say!(
        "h/l        {:.4} (l = {:.6} m, median nearest-node spacing)",
        outcome.h_over_l,
        outcome.spacing
    );
    say!(
        "objective  {:.6e} ({:?} norm, seed {}, {} evaluations)",
        outcome.calibration.value,
        outcome.norm,
        outcome.calibration.seed,
        outcome.calibration.evaluations
    );
    say!(
        "LOO        R² = {:.6}, MAE = {:.6} kPa, max error = {:.6} kPa",
        outcome.stats.r2,
        outcome.stats.mae,
        outcome.stats.max_error
    );
    if let Some(f) = &outcome.fallback {
        say!("note       {f}");
    }
    if let Some(c) = &calibrated.check {
        say!(
            "check      {} nodes of {}: R² = {:.6}, MAE = {:.6} kPa, max error = {:.6} kPa",
            c.nodes,
            c.file.display(),
            c.r2,
            c.mae,
            c.max_error
        );
    }
    say!("{}", wrote(&target, &calibrated.file_names()));
    Ok(())
}
