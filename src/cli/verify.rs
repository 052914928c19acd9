//! `a3d-init verify` and `a3d-init run`: load what `map` wrote (or any MP state
//! table), run the built-in explicit MPM solver on the Anura3D mesh under
//! gravity, and say whether the mapped state is in equilibrium — and where it is
//! not. `run` keeps the same solver going for a given time with snapshots (a
//! demonstration of run-out, not a replacement for Anura3D).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use plotters::style::RGBColor;

use super::Verdict as ExitVerdict;
use super::args::{StateInputs, StateSource};
use super::output::OutputDir;
use super::plot::{self, Series};
use crate::formats::cps::CpsDocument;
use crate::formats::{mps_table, vtu};
use crate::model::{MaterialPoint, MpState};
use crate::mpm::{self, RunSettings};
use crate::pipeline::Project as LoadedProject;
use crate::pipeline::{self, verify::KernelCheck};

#[derive(Debug, clap::Args)]
pub struct VerifyArgs {
    #[command(flatten)]
    pub inputs: StateInputs,
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
    /// Find the factor of safety by strength reduction instead (as `a3d-init fos`).
    #[arg(long)]
    pub fos: bool,
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
    project: LoadedProject,
    points: Vec<MaterialPoint>,
    /// The state the runner starts from: what Anura3D holds at t = 0 (with the
    /// MPM-MIXED collapse of the first step applied), or the given state table.
    states: Vec<MpState>,
    /// How the state was obtained and what it shows.
    kernel: Option<KernelCheck>,
    /// The state at t = 0 as Anura3D holds it (before the MIXED collapse).
    start: Vec<MpState>,
    /// Per MP: MAPF rows in reach (empty for a state table).
    rows_in_reach: Vec<u32>,
    out: PathBuf,
    /// The output folder is verify's own default subfolder: rerunning replaces it.
    own_subfolder: bool,
    inputs: Vec<PathBuf>,
}

fn load(args: &VerifyArgs, default_out: &str) -> anyhow::Result<Loaded> {
    match args.inputs.source()? {
        StateSource::Folder(dir) => load_folder(args, dir, default_out),
        StateSource::Table { model, state } => load_state_table(args, model, state, default_out),
    }
}

/// `verify DIR`: the GOM, CPS and MAPF of the folder, read as Anura3D reads them.
fn load_folder(args: &VerifyArgs, dir: &Path, default_out: &str) -> anyhow::Result<Loaded> {
    let project = LoadedProject::load(dir)?;
    let judged = pipeline::verify::judge_folder(&project)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| project.files.dir.join(default_out));
    Ok(Loaded {
        points: project.points.clone(),
        project,
        states: judged.run_start,
        kernel: Some(judged.check),
        start: judged.start,
        rows_in_reach: judged.rows_in_reach,
        out,
        own_subfolder: args.out.is_none(),
        inputs: judged.inputs,
    })
}

/// `verify --mpm MODEL --state TABLE`: a state table as given (no MAPF).
fn load_state_table(
    args: &VerifyArgs,
    model_path: &Path,
    state_path: &Path,
    default_out: &str,
) -> anyhow::Result<Loaded> {
    let project = LoadedProject::load(model_path)?;
    let (points, states) = mps_table::read_states_for(state_path, &project.points)?;
    let out = args.out.clone().unwrap_or_else(|| {
        state_path
            .parent()
            .unwrap_or(Path::new("."))
            .join(default_out)
    });
    let mut inputs: Vec<PathBuf> = super::args::project_inputs(&project.files)
        .into_iter()
        .map(Path::to_path_buf)
        .collect();
    inputs.extend([model_path.to_path_buf(), state_path.to_path_buf()]);
    Ok(Loaded {
        project,
        points,
        start: states.clone(),
        rows_in_reach: Vec::new(),
        states,
        kernel: None,
        out,
        own_subfolder: false,
        inputs,
    })
}

/// `s` with the CPS's gravity and Courant number (capped at 0.9) and the local
/// damping α: `damping`, else the CPS `$$HOMOGENEOUS_LOCAL_DAMPING`, else 0.75.
pub(super) fn with_cps(
    mut s: RunSettings,
    cps: Option<&CpsDocument>,
    damping: Option<f64>,
) -> RunSettings {
    if let Some(cps) = cps {
        s.gravity = cps.gravity();
        if let Some(c) = cps.get_real("$$COURANT_NUMBER", 0) {
            s.courant = c.min(0.9);
        }
    }
    s.damping = damping
        .or_else(|| cps.and_then(CpsDocument::local_damping))
        .unwrap_or(0.75)
        .clamp(0.0, 0.99);
    s
}

fn settings(args: &VerifyArgs, cps: Option<&CpsDocument>) -> RunSettings {
    let mut s = with_cps(RunSettings::verify(), cps, args.damping);
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

/// What `verify` found: every cause named separately, the Anura3D-side checks
/// and the runner's report.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VerifyOutcome {
    pub equilibrium: bool,
    pub causes: Vec<String>,
    pub anura3d: Option<KernelCheck>,
    /// `None` when the run could not start (NaN MPs).
    pub run: Option<mpm::RunReport>,
}

/// The causes behind a verdict, each on its own.
fn causes(check: Option<&KernelCheck>, run: Option<&mpm::RunReport>) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(k) = check {
        if k.nan_points > 0 {
            out.push(format!(
                "{} MPs will hold NaN in Anura3D: no row of {} within 2h = {:.3e} m (first ids: {:?})",
                k.nan_points,
                k.mapf.display(),
                2.0 * k.smoothing_length,
                k.nan_ids
            ));
        }
        if let Some(d) = &k.sigma_zz_defect
            && d.outside_because_of_defect > 0
        {
            out.push(format!(
                "{} MPs start outside their yield surface only because Anura3D's 2D MAPF reader sets σ'zz := SigXY; its first step return-maps them, changing σ'xx, σ'yy, σ'zz, τxy by up to {:.3}, {:.3}, {:.3}, {:.3} kPa",
                d.outside_because_of_defect,
                d.first_step_change[0],
                d.first_step_change[1],
                d.first_step_change[2],
                d.first_step_change[3]
            ));
        }
        if k.intended_outside_yield > 0 {
            out.push(format!(
                "{} MPs are outside their yield surface in the intended state itself",
                k.intended_outside_yield
            ));
        }
    }
    if let Some(r) = run
        && let mpm::Verdict::NotInEquilibrium { reasons } = &r.verdict
    {
        for reason in reasons {
            if check.is_some() && matches!(reason, mpm::Reason::InadmissibleStress { .. }) {
                continue; // split into the two causes above
            }
            out.push(reason.to_string());
        }
    }
    out
}

/// Runs the check and writes its outputs; the verdict is in the outcome.
pub fn verify_core(args: &VerifyArgs) -> anyhow::Result<(VerifyOutcome, PathBuf)> {
    let l = load(args, "verify")?;
    let settings = settings(args, l.project.cps.as_ref());
    let runnable = l.states.iter().all(|s| {
        s.pwp.is_finite() && s.saturation.is_finite() && s.total.iter().all(|v| v.is_finite())
    });
    // A model the runner cannot simulate still gets its Anura3D-side checks
    // and start.csv; the verdict then says why no run was made.
    let mut run_error = None;
    let report = if runnable {
        match mpm::verify(&l.project.model, &l.points, &l.states, &settings) {
            Ok(r) => Some(r),
            Err(
                e
                @ (mpm::MpmError::Unsupported(_) | mpm::MpmError::UnsupportedMaterialModel { .. }),
            ) if l.kernel.is_some() => {
                run_error = Some(format!("no equilibrium run: {e}"));
                None
            }
            Err(e) => return Err(anyhow::anyhow!("{e}")),
        }
    } else {
        None
    };
    let mut causes = causes(l.kernel.as_ref(), report.as_ref());
    causes.extend(run_error);
    let equilibrium = report.as_ref().is_some_and(|r| r.verdict.is_equilibrium())
        && l.kernel.as_ref().is_none_or(|k| k.nan_points == 0);
    let outcome = VerifyOutcome {
        equilibrium,
        causes,
        anura3d: l.kernel.clone(),
        run: report,
    };
    let inputs: Vec<&Path> = l.inputs.iter().map(PathBuf::as_path).collect();
    // Rerunning `verify DIR` replaces its own default subfolder.
    let force = args.force || (l.own_subfolder && l.out.join("verify.json").is_file());
    let out = OutputDir::create(&l.out, force, &inputs)?;
    let json = serde_json::to_string_pretty(&outcome)?;
    out.write("verify.json", |w| w.write_all(json.as_bytes()))?;
    let diagnostics: Vec<mps_table::MpDiagnostics> = l
        .start
        .iter()
        .enumerate()
        .map(|(i, s)| mps_table::MpDiagnostics {
            neighbours: l.rows_in_reach.get(i).copied().unwrap_or(0),
            shepard: 0.0,
            status: if s.pwp.is_finite() && s.total.iter().all(|v| v.is_finite()) {
                "anura3d"
            } else {
                "nan"
            },
        })
        .collect();
    out.write("start.csv", |w| {
        mps_table::write_states(w, &l.points, &l.start, &diagnostics)
    })?;
    let positions: Vec<[f64; 3]> = l.points.iter().map(|p| p.position).collect();
    let start_stress: Vec<[f64; 6]> = l.start.iter().map(MpState::effective).collect();
    write_snapshot(
        &out,
        "mps_start.vtu",
        &positions,
        &vec![[0.0; 3]; positions.len()],
        &start_stress,
        &vec![false; positions.len()],
    )?;
    if let Some(report) = &outcome.run {
        history_plot(&out.path("verify_history.svg"), report)?;
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
    }
    let target = out.commit()?;
    Ok((outcome, target))
}

pub fn run_verify(args: VerifyArgs) -> anyhow::Result<()> {
    if args.fos {
        return super::fos::run(super::fos::FosArgs::from_verify(&args));
    }
    let (outcome, target) = verify_core(&args)?;
    print_outcome(&outcome, &target);
    if outcome.equilibrium {
        Ok(())
    } else {
        Err(ExitVerdict {
            message: "not in equilibrium (see verify.json for where)".into(),
            code: 1,
        }
        .into())
    }
}

/// Prints the Anura3D-side checks, the run and the verdict with its causes.
pub fn print_outcome(o: &VerifyOutcome, target: &Path) {
    if let Some(k) = &o.anura3d {
        println!(
            "Anura3D    {} ({}), MAPF {} rows, h = {:.3e} m{}",
            k.gom.display(),
            k.computation_method,
            k.mapf_rows,
            k.smoothing_length,
            if k.mapf_read {
                ""
            } else {
                " (not read: switch off)"
            }
        );
        if let Some(t) = &k.mps_csv {
            if t.differing == 0 {
                println!(
                    "           mps.csv agrees with what Anura3D reads from the MAPF ({} MPs)",
                    t.rows
                );
            } else {
                println!(
                    "           mps.csv and the MAPF disagree on {} of {} MPs (worst: {})",
                    t.differing,
                    t.rows,
                    t.worst
                        .iter()
                        .take(5)
                        .map(|(id, d)| format!("MP {id} by {:.2}% of range", d * 100.0))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            }
        }
        if let Some(m) = &k.mixed
            && m.elements > 0
            && (m.pwp > 0.0 || m.stress > 0.0)
        {
            println!(
                "           MPM-MIXED: the first step gives every MP of {} elements its element's first-MP state (spread up to {:.3} kPa pwp, {:.3} kPa stress)",
                m.elements, m.pwp, m.stress
            );
        }
        for n in &k.notes {
            println!("           {n}");
        }
    }
    if let Some(r) = &o.run {
        print_report(r);
    }
    if o.equilibrium {
        println!("verdict    IN EQUILIBRIUM");
    } else {
        println!("verdict    NOT IN EQUILIBRIUM");
        for c in &o.causes {
            println!("           - {c}");
        }
        if let Some(r) = &o.run
            && !r.verdict.is_equilibrium()
        {
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
    let mut files = vec!["verify.json", "start.csv", "mps_start.vtu"];
    if o.run.is_some() {
        files.extend(["verify_history.svg", "mps_end.vtu"]);
    }
    println!("{}", super::output::wrote(target, &files));
}

/// Prints the runner's figures (no verdict).
pub fn print_report(r: &mpm::RunReport) {
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
    let inputs: Vec<&Path> = l.inputs.iter().map(PathBuf::as_path).collect();
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
    let snapshots = format!("{} snapshots", output.snapshots.len());
    println!(
        "{}",
        super::output::wrote(&target, &["run.json", "run_history.svg", &snapshots])
    );
    Ok(())
}
