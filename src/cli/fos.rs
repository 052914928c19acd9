//! `a3d-init fos`: arguments and printing around [`pipeline::stability::fos::fos`], the
//! factor of safety of the state `verify` judges (for a map folder, the state
//! Anura3D will hold): by limit equilibrium (`--method`, default
//! Morgenstern–Price) or by strength reduction on the built-in runner
//! (`--method srm`).

use std::path::PathBuf;
use std::time::Instant;

use super::args::{LeArgs, MethodArg, StateInputs};
use super::print;
use a3d_init::pipeline::io::output::Destination;
use a3d_init::pipeline::{
    self,
    stability::fos::{FosMethod, FosOptions},
};

#[derive(Debug, clap::Args)]
pub struct FosArgs {
    #[command(flatten)]
    pub inputs: StateInputs,
    /// Method: a method of slices (limit equilibrium), or strength reduction.
    #[arg(long, value_enum, default_value_t = MethodArg::MorgensternPrice)]
    pub method: MethodArg,
    #[command(flatten)]
    pub le: LeArgs,
    /// With a method of slices, run strength reduction too and compare.
    #[arg(long)]
    pub with_srm: bool,
    /// Strength reduction: local damping α of the trial runs (default: the
    /// CPS `$$HOMOGENEOUS_LOCAL_DAMPING`, else 0.75).
    #[arg(long)]
    pub damping: Option<f64>,
    /// Strength reduction: half-width of the final bracket on F (at least 1e-4).
    #[arg(long, default_value_t = 0.01)]
    pub tolerance: f64,
    /// Strength reduction: time window of one trial (s).
    #[arg(long)]
    pub window: Option<f64>,
    /// Set every pore pressure to zero (σ′ = σ) before the analysis.
    #[arg(long)]
    pub zero_pwp: bool,
    /// Strength reduction: hold every pore pressure, as limit equilibrium
    /// does (the default; the flag is kept for scripts).
    #[arg(long, conflicts_with = "coupled")]
    pub drained: bool,
    /// Strength reduction: let two-phase coupled and undrained-effective
    /// materials run with their water (docs/two-phase.md) instead of
    /// holding the pore pressures (not with `--zero-pwp`: a dry slope has
    /// no water to run).
    #[arg(long, conflicts_with = "zero_pwp")]
    pub coupled: bool,
    /// Output folder (default `<dir>/fos`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: FosArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let method = match args.le.method(args.method) {
        Some(m) => FosMethod::Le(m),
        None => FosMethod::Srm,
    };
    let options = FosOptions {
        method,
        le: args.le.options(args.method)?,
        with_srm: args.with_srm,
        damping: args.damping,
        tolerance: args.tolerance,
        window: args.window,
        zero_pwp: args.zero_pwp,
        drained: !args.coupled,
    };
    let to = Destination::new(args.out.as_deref(), args.force);
    let (analysis, target) = pipeline::stability::fos::fos(&args.inputs.source()?, &options, to)?;
    print::fos_report(&analysis, &target, started.elapsed().as_secs_f64());
    Ok(())
}
