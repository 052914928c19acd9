//! `a3d-init verify` and `a3d-init run`: arguments and printing around
//! [`pipeline::check::verify`] (is the mapped state in equilibrium under
//! gravity, and where not) and [`pipeline::check::runout::run`] (the same solver kept
//! going for a given time, with snapshots). `verify --fos` runs
//! [`pipeline::stability::fos::fos`] instead.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;

use super::Verdict as ExitVerdict;
use super::args::StateInputs;
use super::print;
use a3d_init::mpm;
use a3d_init::pipeline::io::output::Destination;
use a3d_init::pipeline::{
    self, check::VerifyOptions, check::runout::RunOptions, stability::fos::FosOptions,
};

/// What `verify` and `run` share: the mapped state, the damping, the output
/// and the water's treatment.
#[derive(Debug, clap::Args)]
pub struct SolverArgs {
    #[command(flatten)]
    pub inputs: StateInputs,
    /// Local damping α (default: the CPS `$$HOMOGENEOUS_LOCAL_DAMPING`; without
    /// one, 0.75 for `verify`, 0.05 for `run`).
    #[arg(long)]
    pub damping: Option<f64>,
    /// Output folder (default `<dir>/verify`; `<dir>/run` for `run`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub force: bool,
    /// Hold every pore pressure at its mapped value (drained). Without it,
    /// `saturated_material_coupled` materials run Anura3D's two-phase
    /// formulation (the water flows) and `saturated_material_undrained_effective`
    /// ones update p from their volumetric strain.
    #[arg(long)]
    pub drained: bool,
}

#[derive(Debug, clap::Args)]
pub struct VerifyArgs {
    #[command(flatten)]
    pub solver: SolverArgs,
    /// Maximum number of explicit steps.
    #[arg(long, default_value_t = 20_000)]
    pub max_steps: usize,
    /// Find the factor of safety by strength reduction instead (as `a3d-init fos`).
    #[arg(long)]
    pub fos: bool,
}

/// `run`'s options: `verify`'s solver without its step cap or `--fos` (a
/// run lasts `--time`; `a3d-init fos` gives the factor of safety).
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub solver: SolverArgs,
    /// Simulated time (s); the paper's run-out, 3 s.
    #[arg(long, default_value_t = 3.0)]
    pub time: f64,
    /// Snapshot times (s), comma separated; the paper's Fig. 11.
    #[arg(long, default_value = "0.3,0.8,1.2,3.0")]
    pub snapshots: String,
}

impl SolverArgs {
    /// `--out` and `--force`.
    fn destination(&self) -> Destination<'_> {
        Destination::new(self.out.as_deref(), self.force)
    }
}

pub fn run_verify(args: VerifyArgs) -> anyhow::Result<()> {
    let VerifyArgs {
        solver: args,
        max_steps,
        fos,
    } = args;
    let source = args.inputs.source()?;
    if fos {
        let started = Instant::now();
        // Pore pressures held, as `fos` holds them.
        let options = FosOptions {
            damping: args.damping,
            ..FosOptions::srm()
        };
        let (report, target) =
            pipeline::stability::fos::fos(&source, &options, args.destination())?;
        print::fos_report(&report, &target, started.elapsed().as_secs_f64());
        return Ok(());
    }
    let options = VerifyOptions {
        max_steps,
        damping: args.damping,
        drained: args.drained,
    };
    let (outcome, target) = pipeline::check::verify(&source, &options, args.destination())?;
    print::verify_outcome(&outcome, &target);
    ExitVerdict::check(
        outcome.equilibrium,
        "not in equilibrium (see verify.json for where)",
    )
}

/// `--snapshots 0.3,0.8`: every entry a number of seconds.
fn snapshot_times(text: &str) -> anyhow::Result<Vec<f64>> {
    text.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<f64>()
                .with_context(|| format!("--snapshots: `{s}` is not a number of seconds"))
        })
        .collect()
}

pub fn run_run(args: RunArgs) -> anyhow::Result<()> {
    let source = args.solver.inputs.source()?;
    let options = RunOptions {
        time: args.time,
        snapshots: snapshot_times(&args.snapshots)?,
        damping: args.solver.damping,
        drained: args.solver.drained,
    };
    let outcome = pipeline::check::runout::run(&source, &options, args.solver.destination())?;
    let r = &outcome.report;
    say!(
        "run        {} MPs, {} steps, t = {:.3} s, damping α = {}",
        r.n_points,
        r.steps,
        r.time,
        r.damping
    );
    print::water(r);
    say!(
        "final      max displacement {:.4} m, {} MPs yielded",
        r.max_displacement,
        r.plastic_points
    );
    match &r.rest {
        Some(rest) => say!("rest       at t = {:.2} s: {}", rest.time, rest.criterion),
        None => say!(
            "rest       not reached by t = {:.3} s (the kinetic energy is not below {:.0} % of its peak)",
            r.time,
            100.0 * mpm::REST_FRACTION
        ),
    }
    for m in &r.monitored {
        if let Some((_, u)) = m.history.last() {
            say!(
                "monitored  MP {} from ({:.3}, {:.3}): displacement ({:+.4}, {:+.4}) m, |u| = {:.4} m",
                m.id,
                m.start[0],
                m.start[1],
                u[0],
                u[1],
                (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt()
            );
        }
    }
    say!("lost       {} MPs left the mesh", r.lost_points);
    let snapshots = format!("{} snapshots, .vtu and .svg", outcome.snapshots.len());
    say!(
        "{}",
        print::wrote(
            &outcome.folder,
            &["run.json", "run_history.svg", &snapshots]
        )
    );
    Ok(())
}
