//! `a3d-init fos`: arguments and printing around [`pipeline::fos::fos`], the
//! factor of safety by strength reduction on the built-in runner, on the same
//! state `verify` judges (for a map folder, the state Anura3D will hold).

use std::path::PathBuf;
use std::time::Instant;

use super::args::StateInputs;
use super::print;
use crate::pipeline::output::Destination;
use crate::pipeline::{self, fos::FosOptions};

#[derive(Debug, clap::Args)]
pub struct FosArgs {
    #[command(flatten)]
    pub inputs: StateInputs,
    /// Local damping α of the trial runs (default: the CPS
    /// `$$HOMOGENEOUS_LOCAL_DAMPING`, else 0.75).
    #[arg(long)]
    pub damping: Option<f64>,
    /// Half-width of the final bracket on F.
    #[arg(long, default_value_t = 0.01)]
    pub tolerance: f64,
    /// Time window of one trial (s); default max(20 T₀, 4 √(H/g)).
    #[arg(long)]
    pub window: Option<f64>,
    /// Set every pore pressure to zero (σ′ = σ) before the analysis.
    #[arg(long)]
    pub zero_pwp: bool,
    /// Output folder (default `<dir>/fos`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: FosArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let options = FosOptions {
        damping: args.damping,
        tolerance: args.tolerance,
        window: args.window,
        zero_pwp: args.zero_pwp,
    };
    let to = Destination::new(args.out.as_deref(), args.force);
    let (report, target) = pipeline::fos::fos(&args.inputs.source()?, &options, to)?;
    print::fos_report(&report, &target, started.elapsed().as_secs_f64());
    Ok(())
}
