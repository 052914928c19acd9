//! `a3d-init verify` and `a3d-init run`: load what `map` wrote (or any MP state
//! table), run the built-in explicit MPM solver on the Anura3D mesh under
//! gravity, and say whether the mapped state is in equilibrium — and where it is
//! not. `run` keeps the same solver going for a given time with snapshots (a
//! demonstration of run-out, not a replacement for Anura3D).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use plotters::style::RGBColor;

use super::Verdict as ExitVerdict;
use super::inspect::load_project;
use super::output::OutputDir;
use super::plot::{self, Series};
use crate::formats::cps::CpsDocument;
use crate::formats::{mps_table, vtu};
use crate::model::{MaterialPoint, MpState};
use crate::mpm::{self, RunSettings};

#[derive(Debug, clap::Args)]
pub struct VerifyArgs {
    /// A folder written by `map` (model and mps.csv are taken from it).
    pub dir: Option<PathBuf>,
    /// Anura3D model (GOM, CPS or folder), when not using a map folder.
    #[arg(long)]
    pub mpm: Option<PathBuf>,
    /// MP state table (mps.csv written by `map`).
    #[arg(long)]
    pub state: Option<PathBuf>,
    /// Maximum number of explicit steps.
    #[arg(long, default_value_t = 20_000)]
    pub max_steps: usize,
    /// Local damping α (default: the CPS `$$HOMOGENEOUS_LOCAL_DAMPING`, else 0.75).
    #[arg(long)]
    pub damping: Option<f64>,
    /// Output folder (default `<dir>/verify`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[arg(long)]
    pub force: bool,
}

#[derive(Debug, clap::Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub verify: VerifyArgs,
    /// Simulated time (s).
    #[arg(long, default_value_t = 2.0)]
    pub time: f64,
    /// Snapshot times (s), comma separated.
    #[arg(long, default_value = "0.3,0.8,1.2,2.0")]
    pub snapshots: String,
}

struct Loaded {
    model_path: PathBuf,
    state_path: PathBuf,
    project: super::inspect::LoadedProject,
    points: Vec<MaterialPoint>,
    states: Vec<MpState>,
    out: PathBuf,
}

fn load(args: &VerifyArgs, default_out: &str) -> anyhow::Result<Loaded> {
    let (model_path, state_path) = match (&args.dir, &args.mpm, &args.state) {
        (Some(dir), None, None) => (dir.clone(), dir.join("mps.csv")),
        (None, Some(m), Some(s)) => (m.clone(), s.clone()),
        _ => bail!("give a folder written by `map`, or --mpm MODEL --state mps.csv"),
    };
    let project = load_project(&model_path)?;
    let (points, states) = mps_table::read_states_for(&state_path, &project.points)?;
    let out = args.out.clone().unwrap_or_else(|| {
        state_path
            .parent()
            .unwrap_or(Path::new("."))
            .join(default_out)
    });
    Ok(Loaded {
        model_path,
        state_path,
        project,
        points,
        states,
        out,
    })
}

fn settings(args: &VerifyArgs, cps: Option<&CpsDocument>) -> RunSettings {
    let mut s = RunSettings::verify();
    if let Some(cps) = cps {
        s.gravity = cps.gravity();
        if let Some(c) = cps.get_real("$$COURANT_NUMBER", 0) {
            s.courant = c.min(0.9);
        }
    }
    s.damping = args
        .damping
        .or_else(|| cps.and_then(CpsDocument::local_damping))
        .unwrap_or(0.75)
        .clamp(0.0, 0.99);
    s.max_steps = args.max_steps;
    s.record_every = 10;
    s
}

fn write_snapshot(
    out: &OutputDir,
    name: &str,
    positions: &[[f64; 3]],
    displacements: &[[f64; 3]],
    stresses: &[[f64; 6]],
    plastic: &[bool],
) -> anyhow::Result<()> {
    let arrays = vec![
        vtu::PointArray {
            name: "displacement".into(),
            components: 3,
            values: displacements.iter().flat_map(|d| *d).collect(),
        },
        vtu::PointArray {
            name: "effective_stress".into(),
            components: 9,
            values: stresses.iter().flat_map(vtu::tensor9).collect(),
        },
        vtu::PointArray {
            name: "plastic".into(),
            components: 1,
            values: plastic.iter().map(|&p| if p { 1.0 } else { 0.0 }).collect(),
        },
    ];
    out.write(name, |w| vtu::write_points(w, positions, &arrays))
}

fn history_plot(path: &Path, report: &mpm::RunReport) -> anyhow::Result<()> {
    let ke: Vec<(f64, f64)> = report
        .records
        .iter()
        .map(|r| (r.time, r.kinetic_energy))
        .collect();
    let res: Vec<(f64, f64)> = report
        .records
        .iter()
        .map(|r| (r.time, r.residual_ratio))
        .collect();
    plot::line_chart(
        path,
        "Kinetic energy and out-of-balance force ratio",
        "time t (s)",
        "kinetic energy (kJ/m) · residual ratio (–)",
        &[
            Series {
                label: "kinetic energy (kJ/m)",
                points: ke,
                color: RGBColor(31, 119, 180),
                markers: false,
            },
            Series {
                label: "residual ratio (–)",
                points: res,
                color: RGBColor(214, 39, 40),
                markers: false,
            },
        ],
        true,
    )
}

pub fn run_verify(args: VerifyArgs) -> anyhow::Result<()> {
    let (report, target) = verify_core(&args)?;
    print_report(&report, &target);
    if report.verdict.is_equilibrium() {
        Ok(())
    } else {
        Err(ExitVerdict {
            message: "not in equilibrium (see verify.json for where)".into(),
            code: 1,
        }
        .into())
    }
}

/// Runs the check and writes its outputs; the verdict is in the report.
pub fn verify_core(args: &VerifyArgs) -> anyhow::Result<(mpm::RunReport, PathBuf)> {
    let l = load(args, "verify")?;
    let settings = settings(args, l.project.cps.as_ref());
    let report = mpm::verify(&l.project.model, &l.points, &l.states, &settings)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut inputs = super::map::project_inputs(&l.project.files);
    inputs.extend([l.model_path.as_path(), l.state_path.as_path()]);
    let out = OutputDir::create(&l.out, args.force, &inputs)?;
    let json = serde_json::to_string_pretty(&report)?;
    out.write("verify.json", |w| w.write_all(json.as_bytes()))?;
    history_plot(&out.path("verify_history.svg"), &report)?;
    let start_stress: Vec<[f64; 6]> = l.states.iter().map(MpState::effective).collect();
    let positions: Vec<[f64; 3]> = l.points.iter().map(|p| p.position).collect();
    write_snapshot(
        &out,
        "mps_start.vtu",
        &positions,
        &vec![[0.0; 3]; positions.len()],
        &start_stress,
        &vec![false; positions.len()],
    )?;
    let end_positions: Vec<[f64; 3]> = positions
        .iter()
        .zip(&report.final_displacements)
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
        .collect();
    write_snapshot(
        &out,
        "mps_end.vtu",
        &end_positions,
        &report.final_displacements,
        &report.final_stresses,
        &report.final_plastic,
    )?;
    let target = out.commit()?;
    Ok((report, target))
}

pub fn print_report(r: &mpm::RunReport, target: &Path) {
    println!(
        "MPM check  {} MPs on {} elements, dt = {:.3e} s, {} steps, t = {:.4} s ({:?})",
        r.n_points, r.n_elements, r.time_step, r.steps, r.time, r.stop
    );
    println!(
        "           g = {} m/s², local damping α = {}, Courant {}",
        r.gravity, r.damping, r.courant
    );
    println!(
        "residual   start {:.3e}, end {:.3e} (limit {:.0e})",
        r.initial_residual_ratio, r.final_residual_ratio, r.thresholds.residual_ratio
    );
    println!(
        "movement   max displacement {:.3e} m (limit {:.0e} × height {:.3} m)",
        r.max_displacement, r.thresholds.displacement_fraction, r.model_height
    );
    println!(
        "plastic    {} MPs start outside the yield surface, {} yielded during the run",
        r.inadmissible_points, r.plastic_points
    );
    match &r.verdict {
        mpm::Verdict::Equilibrium { .. } => println!("verdict    IN EQUILIBRIUM"),
        mpm::Verdict::NotInEquilibrium { reasons } => {
            println!("verdict    NOT IN EQUILIBRIUM");
            for reason in reasons {
                println!(
                    "           - {}",
                    serde_json::to_string(reason).unwrap_or_default()
                );
            }
            for e in r.worst_residual_elements.iter().take(5) {
                println!(
                    "           largest residual: element {} at ({:.3}, {:.3}): {:.3e}",
                    e.id, e.centroid[0], e.centroid[1], e.value
                );
            }
            for e in r.plastic_elements.iter().take(5) {
                println!(
                    "           plastic flow: element {} at ({:.3}, {:.3}): {} MPs",
                    e.id, e.centroid[0], e.centroid[1], e.value
                );
            }
        }
    }
    println!(
        "wrote      {}/ (verify.json, verify_history.svg, mps_start.vtu, mps_end.vtu)",
        target.display()
    );
}

pub fn run_run(args: RunArgs) -> anyhow::Result<()> {
    if !(args.time.is_finite() && args.time > 0.0) {
        bail!(
            "--time {}: expected a positive number of seconds",
            args.time
        );
    }
    let l = load(&args.verify, "run")?;
    let mut settings = settings(&args.verify, l.project.cps.as_ref());
    settings.end_time = Some(args.time);
    settings.stop_at_equilibrium = false;
    settings.max_steps = usize::MAX;
    if args.verify.damping.is_none() {
        settings.damping = 0.05;
    }
    settings.snapshot_times = args
        .snapshots
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    let output = mpm::run(&l.project.model, &l.points, &l.states, &settings)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut inputs = super::map::project_inputs(&l.project.files);
    inputs.extend([l.model_path.as_path(), l.state_path.as_path()]);
    let out = OutputDir::create(&l.out, args.verify.force, &inputs)?;
    let json = serde_json::to_string_pretty(&output.report)?;
    out.write("run.json", |w| w.write_all(json.as_bytes()))?;
    history_plot(&out.path("run_history.svg"), &output.report)?;
    for s in &output.snapshots {
        write_snapshot(
            &out,
            &format!("mps_t{:.2}.vtu", s.time),
            &s.positions,
            &s.displacements,
            &s.stresses,
            &s.plastic,
        )
        .with_context(|| format!("snapshot at {} s", s.time))?;
    }
    let target = out.commit()?;
    let r = &output.report;
    println!(
        "run        {} MPs, {} steps, t = {:.3} s, damping α = {}",
        r.n_points, r.steps, r.time, r.damping
    );
    println!(
        "final      max displacement {:.4} m, {} MPs yielded",
        r.max_displacement, r.plastic_points
    );
    println!(
        "wrote      {}/ (run.json, run_history.svg, {} snapshots)",
        target.display(),
        output.snapshots.len()
    );
    Ok(())
}
