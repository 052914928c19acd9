//! `a3d-init fos-time`: arguments and printing around
//! [`pipeline::stability::fos_time::fos_time`], the factor of safety over a time series of
//! FEM pore-pressure fields (every saved step of a `.gsz` analysis, or node
//! tables with `--times`) by limit equilibrium, the first time it falls to 1
//! (bisected between saved times), and strength reduction at that time.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, bail};

use super::args::{FemArgs, LeArgs, MethodArg};
use super::print::wrote;
use a3d_init::pipeline::io::output::Destination;
use a3d_init::pipeline::stability::fos_time::{self, FosTimeOptions, SeriesInput};

#[derive(Debug, clap::Args)]
pub struct FosTimeArgs {
    /// Anura3D model (GOM, CPS or folder).
    #[arg(long)]
    pub mpm: PathBuf,
    /// The FEM fields: one `.gsz` (every saved step of its analysis), or node
    /// tables with `--times`. `--step` does not apply.
    #[command(flatten)]
    pub fem: FemArgs,
    /// The time of each node table, in s, comma separated.
    #[arg(long, value_name = "T1,T2,…")]
    pub times: Option<String>,
    /// Method of slices (strength reduction runs at the crossing only).
    #[arg(long, value_enum, default_value_t = MethodArg::MorgensternPrice)]
    pub method: MethodArg,
    #[command(flatten)]
    pub le: LeArgs,
    /// Width of the final time bracket around FS = 1, in s (default: 1 % of
    /// the narrowest saved interval).
    #[arg(long, value_name = "S")]
    pub bisect_tol: Option<f64>,
    /// Skip strength reduction at the crossing.
    #[arg(long)]
    pub no_srm: bool,
    /// Strength reduction: local damping α (default: the CPS, else 0.75).
    #[arg(long)]
    pub damping: Option<f64>,
    /// Output folder (default `<model folder>/fos_time`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub force: bool,
}

pub fn run(args: FosTimeArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    if args.method == MethodArg::Srm {
        bail!(
            "fos-time draws its curve by limit equilibrium; strength reduction runs at the crossing (drop --method srm)"
        );
    }
    if args.fem.step != "last" {
        bail!("fos-time reads every saved step; --step does not apply");
    }
    let fem_options = args.fem.options()?;
    let (csv, vtu) = (fem_options.csv, fem_options.vtu);
    let input = match (args.fem.fem.as_slice(), &args.times) {
        ([one], None)
            if a3d_init::pipeline::fem::reader_for(one)
                == a3d_init::pipeline::fem::FemReader::Gsz =>
        {
            SeriesInput::Gsz {
                path: one.clone(),
                analysis: args.fem.analysis.clone(),
                csv,
            }
        }
        ([one], None)
            if one
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("pvd")) =>
        {
            SeriesInput::Pvd {
                path: one.clone(),
                vtu,
            }
        }
        (files, Some(times)) => {
            let times: Vec<f64> = times
                .split(',')
                .map(|t| t.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .with_context(|| format!("--times `{times}`: expected seconds, comma separated"))?;
            if times.len() != files.len() {
                bail!(
                    "--times gives {} times for {} --fem files",
                    times.len(),
                    files.len()
                );
            }
            SeriesInput::Tables {
                files: times.into_iter().zip(files.iter().cloned()).collect(),
                csv,
                mesh: args.fem.fem_mesh.clone(),
                vtu,
            }
        }
        _ => bail!(
            "give one .gsz or .pvd with --fem, or node tables (or .vtu files) with --fem … --times T1,T2,…"
        ),
    };
    let options = FosTimeOptions {
        le: args.le.options(args.method)?,
        bisect_tolerance: args.bisect_tol,
        srm: !args.no_srm,
        srm_damping: args.damping,
    };
    let to = Destination::new(args.out.as_deref(), args.force);
    let (report, target) = fos_time::fos_time(&args.mpm, &input, &options, to)?;
    say!(
        "curve      {} saved times, {} bisected, by {} in {:.2} s",
        report.curve.iter().filter(|p| p.kind == "saved").count(),
        report.curve.iter().filter(|p| p.kind == "bisected").count(),
        report.method,
        report.limit_equilibrium_runtime_s
    );
    for p in &report.curve {
        say!(
            "  t = {:>10.1} s ({:>7.4} h)  FS = {:.4}  {}",
            p.time,
            p.time / 3600.0,
            p.factor,
            p.kind
        );
    }
    match &report.crossing {
        Some(c) => say!(
            "crossing   first FS ≤ 1 at t = {:.1} s ({:.4} h): FS = {:.4}, bracket {:.1}..{:.1} s ({})",
            c.time,
            c.time_h,
            c.factor,
            c.bracket.0,
            c.bracket.1,
            report.interpolation
        ),
        None => say!("crossing   FS stays above 1 at every saved time"),
    }
    if let Some(s) = &report.strength_reduction {
        say!(
            "srm        at t = {:.1} s: FS = {:.3} ({} trials) in {:.1} s",
            s.time,
            s.factor,
            s.trials,
            s.runtime_s
        );
    }
    for n in &report.notes {
        say!("note       {n}");
    }
    say!(
        "{} in {:.1} s",
        wrote(&target, &fos_time::file_names(&report)),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
