//! `a3d-init fos` (and `a3d-init verify DIR --fos`): the factor of safety of a
//! mapped state by strength reduction on the built-in runner
//! ([`crate::mpm::fos`]), with the mapped pore pressures frozen. Writes
//! `fos.json` (every trial, the materials reduced and left alone),
//! `fos_mechanism.svg` (displacement magnitude at the first F that did not
//! settle), `fos_mechanism.vtu` (the same MPs with displacement, velocity and an
//! `in_motion` flag) and `fos_trials.svg` (largest displacement per trial F).
//! The library call lives in `mpm`; this file loads, prints and writes.

use std::path::{Path, PathBuf};

use plotters::style::RGBColor;

use super::args::{StateInputs, StateSource};
use super::output::OutputDir;
use super::plot::{self, Series};
use crate::formats::cps::CpsDocument;
use crate::formats::{mps_table, vtu};
use crate::model::{AnuraModel, MaterialPoint, MpState};
use crate::mpm::fos::{FosOutcome, FosReport, FosSettings, strength_reduction};

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

impl FosArgs {
    /// The arguments of `verify DIR --fos`: same inputs, damping and output
    /// options, default tolerance and window.
    pub fn from_verify(args: &super::verify::VerifyArgs) -> FosArgs {
        FosArgs {
            inputs: args.inputs.clone(),
            damping: args.damping,
            tolerance: 0.01,
            window: None,
            zero_pwp: false,
            out: args.out.clone(),
            force: args.force,
        }
    }
}

/// What `fos` analyses: the model, its MPs with their states, and where to
/// write.
struct Loaded {
    model_path: PathBuf,
    project: super::inspect::LoadedProject,
    points: Vec<MaterialPoint>,
    states: Vec<MpState>,
    out: PathBuf,
}

/// Reads the model and the MP states and checks that they belong together.
fn load(args: &FosArgs) -> anyhow::Result<Loaded> {
    let (model_path, state_path) = match args.inputs.source()? {
        StateSource::Folder(dir) => (dir.to_path_buf(), dir.join("mps.csv")),
        StateSource::Table { model, state } => (model.to_path_buf(), state.to_path_buf()),
    };
    let project = super::inspect::load_project(&model_path)?;
    let (points, states) = mps_table::read_states_for(&state_path, &project.points)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| state_path.parent().unwrap_or(Path::new(".")).join("fos"));
    Ok(Loaded {
        model_path,
        project,
        points,
        states,
        out,
    })
}

/// Strength-reduction settings from the CPS (gravity, Courant number, local
/// damping) and the command line.
pub fn settings(
    cps: Option<&CpsDocument>,
    damping: Option<f64>,
    tolerance: f64,
    window: Option<f64>,
) -> FosSettings {
    let mut s = FosSettings::default();
    s.run = super::verify::with_cps(s.run, cps, damping);
    s.tolerance = tolerance;
    s.window = window;
    s
}

/// The states with every pore pressure set to zero (σ′ = σ; weights kept).
pub fn without_pore_pressure(states: &[MpState]) -> Vec<MpState> {
    states.iter().map(|s| MpState { pwp: 0.0, ..*s }).collect()
}

/// Runs the analysis and writes its outputs into `out` (created with
/// `force`); returns the report and the folder written.
pub fn analyse_and_write(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &FosSettings,
    out: &Path,
    force: bool,
    inputs: &[&Path],
) -> anyhow::Result<(FosReport, PathBuf)> {
    let report =
        strength_reduction(model, points, states, settings).map_err(|e| anyhow::anyhow!("{e}"))?;
    let dir = OutputDir::create(out, force, inputs)?;
    let json = serde_json::to_string_pretty(&report)?;
    dir.write("fos.json", |w| w.write_all(json.as_bytes()))?;
    trials_plot(&dir.path("fos_trials.svg"), &report)?;
    if let Some(m) = &report.mechanism {
        let field: Vec<(f64, f64, f64)> = m
            .positions
            .iter()
            .zip(&m.displacements)
            .map(|(p, u)| (p[0], p[1], norm(u)))
            .collect();
        plot::field_map(
            &dir.path("fos_mechanism.svg"),
            &format!(
                "Failure mechanism: displacement at F = {:.3} (first F that does not settle), t = {:.2} s",
                m.factor, m.time
            ),
            "|u| (m)",
            &field,
        )?;
        let arrays = vec![
            vtu::PointArray {
                name: "displacement".into(),
                components: 3,
                values: m.displacements.iter().flat_map(|d| *d).collect(),
            },
            vtu::PointArray {
                name: "velocity".into(),
                components: 3,
                values: m.velocities.iter().flat_map(|v| *v).collect(),
            },
            vtu::PointArray {
                name: "in_motion".into(),
                components: 1,
                values: m
                    .in_motion
                    .iter()
                    .map(|&b| f64::from(u8::from(b)))
                    .collect(),
            },
            vtu::PointArray {
                name: "plastic".into(),
                components: 1,
                values: m.plastic.iter().map(|&b| f64::from(u8::from(b))).collect(),
            },
            vtu::PointArray {
                name: "effective_stress".into(),
                components: 9,
                values: m.stresses.iter().flat_map(vtu::tensor9).collect(),
            },
        ];
        dir.write("fos_mechanism.vtu", |w| {
            vtu::write_points(w, &m.positions, &arrays)
        })?;
    }
    let target = dir.commit()?;
    Ok((report, target))
}

fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn trials_plot(path: &Path, report: &FosReport) -> anyhow::Result<()> {
    let pick = |settled: bool| -> Vec<(f64, f64)> {
        report
            .trials
            .iter()
            .filter(|t| t.settled == settled)
            .map(|t| (t.factor, t.max_displacement.max(1e-12)))
            .collect()
    };
    plot::line_chart(
        path,
        "Strength reduction: largest MP displacement per trial",
        "strength reduction factor F (–)",
        "largest MP displacement (m)",
        &[
            Series {
                label: "settles",
                points: pick(true),
                color: RGBColor(44, 160, 44),
                markers: true,
            },
            Series {
                label: "does not settle",
                points: pick(false),
                color: RGBColor(214, 39, 40),
                markers: true,
            },
        ],
        true,
    )
}

/// One line: the factor with its bracket, or the bound reached.
pub fn factor_line(report: &FosReport) -> String {
    match (report.outcome, report.lower, report.upper) {
        (FosOutcome::Bracketed, Some(lo), Some(hi)) => format!(
            "FS = {:.2} ± {:.2} (settles at F = {lo:.4}, not at F = {hi:.4}; {} trials)",
            report.factor,
            0.5 * (hi - lo),
            report.iterations
        ),
        (FosOutcome::AboveRange, Some(lo), _) => format!(
            "FS > {lo} (still settles at the largest F tried; {} trials)",
            report.iterations
        ),
        _ => format!(
            "FS < {} (does not settle at the smallest F tried; {} trials)",
            report.factor, report.iterations
        ),
    }
}

pub fn print_report(report: &FosReport, target: &Path, elapsed: f64) {
    println!("factor     {}", factor_line(report));
    println!(
        "method     strength reduction: tan φ′/F, c′/F, ψ ≤ φ′_F; pwp frozen; {} MPs, window {:.2} s per trial, dt = {:.3e} s, damping α = {}",
        report.n_points, report.window, report.time_step, report.settings.run.damping
    );
    let names = |v: &[crate::mpm::fos::MaterialNote]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|m| format!("{} {} ({})", m.index, m.name, m.model))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    println!("reduced    {}", names(&report.reduced_materials));
    println!("unreduced  {}", names(&report.unreduced_materials));
    for t in &report.trials {
        println!(
            "  F = {:.4}  {:<17} max |u| = {:.3e} m after {:.2} s ({} steps), {} MPs yielded",
            t.factor,
            format!("{:?}", t.end),
            t.max_displacement,
            t.time,
            t.steps,
            t.plastic_points
        );
    }
    if let Some(m) = &report.mechanism {
        println!(
            "mechanism  F = {:.4}: {} MPs in motion (fos_mechanism.svg, fos_mechanism.vtu)",
            m.factor, m.points_in_motion
        );
    }
    let mut files = vec!["fos.json", "fos_trials.svg"];
    if report.mechanism.is_some() {
        files.extend(["fos_mechanism.svg", "fos_mechanism.vtu"]);
    }
    println!("{} in {elapsed:.1} s", super::output::wrote(target, &files));
}

/// The demo's two analyses of one mapped state: with every pore pressure set
/// to zero, and with the mapped pore pressures. Writes `fos_zero_pwp/` and
/// `fos_mapped/` under `target`; returns both reports with their folders.
pub fn zero_and_mapped(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    cps: Option<&CpsDocument>,
    target: &Path,
) -> anyhow::Result<[(FosReport, PathBuf); 2]> {
    let settings = settings(cps, None, 0.01, None);
    let inputs: Vec<&Path> = Vec::new();
    let zero = analyse_and_write(
        model,
        points,
        &without_pore_pressure(states),
        &settings,
        &target.join("fos_zero_pwp"),
        true,
        &inputs,
    )?;
    let mapped = analyse_and_write(
        model,
        points,
        states,
        &settings,
        &target.join("fos_mapped"),
        true,
        &inputs,
    )?;
    Ok([zero, mapped])
}

pub fn run(args: FosArgs) -> anyhow::Result<()> {
    let started = std::time::Instant::now();
    let Loaded {
        model_path,
        project,
        points,
        states,
        out,
    } = load(&args)?;
    let states = if args.zero_pwp {
        without_pore_pressure(&states)
    } else {
        states
    };
    let settings = settings(
        project.cps.as_ref(),
        args.damping,
        args.tolerance,
        args.window,
    );
    let inputs: Vec<&Path> = vec![&model_path];
    let (report, target) = analyse_and_write(
        &project.model,
        &points,
        &states,
        &settings,
        &out,
        args.force,
        &inputs,
    )?;
    print_report(&report, &target, started.elapsed().as_secs_f64());
    Ok(())
}
