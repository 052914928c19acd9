//! The seed paper's application end to end on the shipped slope fixture
//! (`fixtures/slope/`), composed of library calls: the rain computed by
//! OpenGeoSys (`fixtures/slope/ogs/`) → FS(t) by limit equilibrium and the
//! failure time → the OGS output at that time: calibrate h → map (the stress
//! solved for equilibrium) → verify, with the geostatic map of the same slope
//! beside it for comparison → factors of safety → the same output mapped onto
//! the paper's MPM model for the run-out, leaving a ready-to-run Anura3D
//! project with plots of the mapped fields (cf. the paper's Fig. 9), the FS(t)
//! curve, the calibration curve and the verify history. Every line it says
//! is what was run and measured; the caller prints them.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::PipelineError;
use crate::formats::fem::StepChoice;
use crate::kernel::KernelKind;
use crate::model::{MpState, Quantity};
use crate::pipeline::check::start::{Start, StateSource};
use crate::pipeline::check::{self, VerifyOptions};
use crate::pipeline::fem::{FemOptions, LoadedFem};
use crate::pipeline::io::output::{Destination, OutputDir, ReadLog};
use crate::pipeline::io::plot;
use crate::pipeline::map::job::{self, MapJob};
use crate::pipeline::map::{MapConfig, SmoothingLength, StressSource};
use crate::pipeline::stability::fos;
use crate::pipeline::stability::fos_time::{self, FosTimeOptions, FosTimeReport, SeriesInput};
use crate::pipeline::{Project, calibrate};

/// What the demo is asked for.
#[derive(Clone, Debug)]
pub struct DemoOptions {
    /// The output folder.
    pub out: PathBuf,
    /// Replace an existing output folder.
    pub force: bool,
    /// A quick look: no factors of safety of the mapped state, and verify
    /// stopped after [`SHORT_VERIFY_STEPS`] explicit steps.
    pub no_fos: bool,
}

/// One line of the demo's account, as the step it describes ends.
#[derive(Clone, Debug, PartialEq)]
pub enum DemoLine {
    /// A line of text, to print as it is.
    Text(String),
    /// A command the user can run next, which the caller spells in its own
    /// way (the command line's flags, or Python's calls).
    Command(DemoCommand),
}

/// The commands the demo suggests.
#[derive(Clone, Debug, PartialEq)]
pub enum DemoCommand {
    /// The same MAPF in one step: `map` of the OpenGeoSys series `fem` at
    /// the failure step onto the slope `model`, h calibrated, the stress
    /// solved for equilibrium, region 0 as `silty_sand`.
    MapAtFailure { fem: PathBuf, model: PathBuf },
    /// The run-out of the flume folder: `run` for 3 s with snapshots at 0.3,
    /// 0.8, 1.2 and 3 s (the monitored MPs A–E, the time to rest;
    /// docs/slope.md compares them with the kernel and the paper).
    RunFlume { folder: PathBuf },
}

/// One folder the demo wrote, and the files in it.
#[derive(Clone, Debug)]
pub struct WrittenFolder {
    pub path: PathBuf,
    pub files: Vec<String>,
}

/// What the demo measured, for the caller's closing lines.
#[derive(Clone, Debug)]
pub struct DemoReport {
    /// The failure time FS(t) found (h).
    pub failure_time_h: f64,
    /// The limit-equilibrium method of FS(t).
    pub method: &'static str,
    /// The folders written, in the order the steps wrote them.
    pub folders: Vec<WrittenFolder>,
    /// Wall time of the whole demo (s).
    pub seconds: f64,
}

/// The shipped slope fixture: in the repository the sources were built from
/// (two folders above this crate's), else under the current folder.
fn fixture_dir() -> Result<PathBuf, PipelineError> {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let repository = crate_dir
        .parent()
        .and_then(Path::parent)
        .unwrap_or(crate_dir);
    let built_in = repository.join("fixtures/slope");
    for dir in [built_in, PathBuf::from("fixtures/slope")] {
        if dir.join("slope.GOM").exists() {
            return Ok(dir);
        }
    }
    Err(PipelineError::Input(
        "fixtures/slope not found: run the demo from the a3d-init repository".into(),
    ))
}

/// Explicit steps of the demo's shorter verify runs.
pub const SHORT_VERIFY_STEPS: usize = 2_000;

/// A field plot: file name, title, colour-bar label and the quantity.
type FieldPlot<'a> = (&'a str, &'a str, &'a str, &'a dyn Fn(&MpState) -> f64);

/// The (min, max) of one quantity over the states.
fn range(states: &[MpState], f: impl Fn(&MpState) -> f64) -> (f64, f64) {
    states
        .iter()
        .map(f)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        })
}

/// The factor of FS(t) at the saved output at time `t` (NaN if none).
fn factor_at(curve: &FosTimeReport, t: f64) -> f64 {
    curve
        .curve
        .iter()
        .find(|p| p.time == t)
        .map_or(f64::NAN, |p| p.factor)
}

/// FS(t) and where it first falls to 1.
struct FailureTime {
    series: Vec<(f64, LoadedFem)>,
    curve: FosTimeReport,
    /// The first saved output at or past the failure (as `map --step failure`
    /// chooses it).
    output: usize,
    /// The failure time (h).
    time_h: f64,
}

/// Step 2: FS(t) over the OGS outputs by limit equilibrium, and the failure
/// time.
fn failure_time(
    project: &Project,
    pvd: &Path,
    say: &mut dyn FnMut(DemoLine),
) -> Result<FailureTime, PipelineError> {
    let series = fos_time::load_series(&SeriesInput::Pvd {
        path: pvd.to_path_buf(),
        vtu: Default::default(),
    })?;
    let curve = fos_time::fos_over_time(
        project,
        &series,
        &FosTimeOptions {
            srm: false,
            ..FosTimeOptions::default()
        },
    )?;
    let Some(crossing) = &curve.crossing else {
        return Err(PipelineError::Input(format!(
            "FS(t) never falls to 1 on {}",
            pvd.display()
        )));
    };
    // The first output at or past the failure, as `map --step failure`
    // chooses it (the same curve: FS(t)'s defaults).
    let k = curve.first_failing_output().ok_or_else(|| {
        PipelineError::Numerical("FS(t) crosses 1 but no saved output has FS ≤ 1".into())
    })?;
    let fs_at = |t: f64| factor_at(&curve, t);
    say(DemoLine::Text(format!(
        "2 FS(t)      {} OGS outputs over {:.1} h, {} ({:.1} s): FS = {:.3} at t = 0, first FS ≤ 1 at t = {:.3} h; paper (SLOPE/W on SEEP/W): 1.56 h, {:+.0} %",
        series.len(),
        series.last().map_or(0.0, |s| s.0) / 3600.0,
        curve.method,
        curve.limit_equilibrium_runtime_s,
        fs_at(series[0].0),
        crossing.time_h,
        100.0 * (crossing.time_h / 1.56 - 1.0)
    )));

    let time_h = crossing.time_h;
    Ok(FailureTime {
        series,
        curve,
        output: k,
        time_h,
    })
}

/// The figures beside the mapped project: the mapped fields (cf. the paper's
/// Fig. 9), the calibration curve and FS(t); their names are added to
/// `written`.
fn write_figures(
    out: &OutputDir<'_>,
    mapped: &crate::pipeline::map::Mapped,
    outcome: &calibrate::Outcome,
    curve: &FosTimeReport,
    series: &[(f64, LoadedFem)],
    written: &mut Vec<String>,
) -> Result<(), PipelineError> {
    calibrate::plot_curve(&out.path("calibration.svg"), outcome)?;
    let pts = &mapped.project.points;
    let field = |f: &dyn Fn(&MpState) -> f64| -> Vec<(f64, f64, f64)> {
        pts.iter()
            .zip(&mapped.states)
            .map(|(p, s)| (p.position[0], p.position[1], f(s)))
            .collect()
    };
    let plots: [FieldPlot<'_>; 3] = [
        (
            "pwp.svg",
            "Mapped pore-water pressure (OpenGeoSys at the failure time)",
            "pwp (kPa)",
            &|s| s.pwp,
        ),
        (
            "effective_stress_yy.svg",
            "Mapped vertical effective stress σ'yy",
            "σ'yy (kPa)",
            &|s| s.effective()[1],
        ),
        (
            "total_stress_yy.svg",
            "Mapped vertical total stress σyy",
            "σyy (kPa)",
            &|s| s.total[1],
        ),
    ];
    for (name, title, unit, f) in plots {
        plot::field_map(&out.path(name), title, unit, &field(f))?;
        written.push(name.to_string());
    }
    written.push("calibration.svg".into());
    fos_time::write_outputs(out, curve, series)?;
    for name in [
        "fos_time.json",
        "fos_vs_time.csv",
        "fos_vs_time.svg",
        "fos_crossing.svg",
    ] {
        written.push(name.to_string());
    }
    Ok(())
}

/// Step 5: verify with the explicit MPM runner, then the intended state
/// (mps.csv, without Anura3D's 2D reading) and the geostatic map of the same
/// slope for comparison. Returns the state's source and the four folders
/// written (verify, verify-intended, geostatic, geostatic/verify).
fn verify_steps(
    target: &Path,
    job: &MapJob,
    no_fos: bool,
    n_points: usize,
    say: &mut dyn FnMut(DemoLine),
) -> Result<(StateSource, Vec<WrittenFolder>), PipelineError> {
    // 5. Verify with the explicit MPM runner. The two comparisons (the
    // intended state, the geostatic map) are judged at their first steps and
    // run 2,000 steps; with --no-fos the main verify too.
    let verify_short = VerifyOptions {
        max_steps: SHORT_VERIFY_STEPS,
        ..VerifyOptions::default()
    };
    let verify_main = if no_fos {
        verify_short.clone()
    } else {
        VerifyOptions::default()
    };
    let source = StateSource::Folder(target.to_path_buf());
    let verify_dir = target.join("verify");
    let (outcome, verify_dir) = check::verify(
        &source,
        &verify_main,
        Destination::new(Some(&verify_dir), true),
    )?;
    match &outcome.run {
        Some(r) => say(DemoLine::Text(format!(
            "5 verify     {}: initial residual {:.2e}, {} MPs yielded, max displacement {:.3} m after {:.3} s",
            if outcome.equilibrium {
                "IN EQUILIBRIUM"
            } else {
                "NOT IN EQUILIBRIUM"
            },
            r.initial_residual_ratio,
            r.plastic_points,
            r.max_displacement,
            r.time
        ))),
        None => say(DemoLine::Text(
            "5 verify     NOT IN EQUILIBRIUM: the run could not start".into(),
        )),
    }
    for c in &outcome.causes {
        say(DemoLine::Text(format!("             - {c}")));
    }
    if let Some(d) = outcome
        .anura3d
        .as_ref()
        .and_then(|k| k.sigma_zz_defect.as_ref())
    {
        say(DemoLine::Text(format!(
            "             σ'zz: Anura3D's 2D MAPF reader sets σ'zz := τxy on {} of the {} MPs; {} of them start outside the yield surface because of it (README: \"The 2D σ'zz defect\")",
            d.affected, n_points, d.outside_because_of_defect
        )));
    }
    // The state a3d-init intended (mps.csv), without Anura3D's 2D reading.
    let (intended, intended_verify) = check::verify(
        &StateSource::Table {
            model: target.to_path_buf(),
            state: target.join("mps.csv"),
        },
        &verify_short,
        Destination::new(Some(&target.join("verify-intended")), true),
    )?;
    if let Some(r) = &intended.run {
        say(DemoLine::Text(format!(
            "             the intended state (mps.csv, σ'zz as solved): {}, initial residual {:.2e}, max displacement {:.1e} m after {} steps",
            if intended.equilibrium {
                "IN EQUILIBRIUM"
            } else {
                "NOT IN EQUILIBRIUM"
            },
            r.initial_residual_ratio,
            r.max_displacement,
            r.steps
        )));
    }
    // The geostatic column formula on the same slope, for comparison.
    let geostatic_job = MapJob {
        config: MapConfig {
            stress: StressSource::Geostatic,
            ..job.config.clone()
        },
        ..job.clone()
    };
    let geostatic = target.join("geostatic");
    let (_, geostatic_written) =
        job::map(&geostatic_job, Destination::new(Some(&geostatic), true))?;
    let (geostatic_outcome, geostatic_verify) = check::verify(
        &StateSource::Folder(geostatic.clone()),
        &verify_short,
        Destination::new(None, true),
    )?;
    let ratio = |o: &check::VerifyOutcome| {
        o.run
            .as_ref()
            .map_or(f64::NAN, |r| r.initial_residual_ratio)
    };
    say(DemoLine::Text(format!(
        "             out-of-balance force ratio geostatic {:.3} vs equilibrium {:.2e} (verify's first step; geostatic/ holds the geostatic map)",
        ratio(&geostatic_outcome),
        ratio(&outcome)
    )));
    let folders = vec![
        folder(&verify_dir, &check::file_names(&outcome)),
        folder(&intended_verify, &check::file_names(&intended)),
        WrittenFolder {
            path: geostatic_written.folder.clone(),
            files: geostatic_written.files.clone(),
        },
        folder(&geostatic_verify, &check::file_names(&geostatic_outcome)),
    ];
    Ok((source, folders))
}

/// A folder and the names of its files.
fn folder(path: &Path, files: &[&str]) -> WrittenFolder {
    WrittenFolder {
        path: path.to_path_buf(),
        files: files.iter().map(|f| f.to_string()).collect(),
    }
}

/// Step 7: the same output mapped onto the paper's MPM model
/// (fixtures/flume: empty elements above the ground and in front of the toe),
/// ready for `run`.
fn runout(
    dir: &Path,
    job: &MapJob,
    target: &Path,
    say: &mut dyn FnMut(DemoLine),
) -> Result<WrittenFolder, PipelineError> {
    let flume_job = MapJob {
        model: dir.with_file_name("flume"),
        ..job.clone()
    };
    let flume = target.join("flume");
    let (flume_mapped, flume_written) = job::map(&flume_job, Destination::new(Some(&flume), true))?;
    say(DemoLine::Text(format!(
        "7 run-out    the same output mapped onto the paper's MPM model (fixtures/flume: {} MPs, {} elements of which {} empty) in {}",
        flume_mapped.project.points.len(),
        flume_mapped.project.model.mesh.n_elements(),
        flume_mapped
            .project
            .model
            .element_material
            .iter()
            .filter(|&&m| m == 0)
            .count(),
        flume_written.folder.display()
    )));
    say(DemoLine::Command(DemoCommand::RunFlume {
        folder: flume_written.folder.clone(),
    }));
    Ok(WrittenFolder {
        path: flume_written.folder,
        files: flume_written.files,
    })
}

/// Runs the demo into `options.out`, handing each line of its account to
/// `say` as the step it describes ends.
pub fn demo(
    options: &DemoOptions,
    say: &mut dyn FnMut(DemoLine),
) -> Result<DemoReport, PipelineError> {
    let started = Instant::now();
    let reads = ReadLog::start();
    let dir = fixture_dir()?;
    // The output folder is checked (and its staging folder made) before any
    // work: a `--out` that names a file, or a folder without `--force`, is
    // refused at once rather than after the minutes of steps 1 to 4. The
    // commit checks it against every input read again.
    let out = OutputDir::create(&options.out, options.force, &reads, "demo")?;
    let pvd = dir.join("ogs/results/rain.pvd");
    say(DemoLine::Text(
        "a3d-init demo: the rainfall-loaded slope of the seed paper (Lora et al. 2016)".into(),
    ));
    say(DemoLine::Text(
        "  FEM stage: OpenGeoSys RichardsFlow, 150 mm/h on the sand layer, Table 1 (fixtures/slope/ogs/README.md)".into(),
    ));

    // 1. Inspect.
    let project = Project::load(&dir)?;
    say(DemoLine::Text(format!(
        "1 inspect    {}: {} nodes, {} {} elements ({}), {} MPs; materials {}",
        project.files.gom.display(),
        project.model.mesh.n_nodes(),
        project.model.mesh.n_elements(),
        project.model.mesh.element_type.gom_name(),
        project.method.cps_name(),
        project.points.len(),
        project
            .model
            .materials
            .iter()
            .map(|m| m.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    )));

    // 2. FS(t) over the OGS outputs by limit equilibrium; the failure time.
    let FailureTime {
        series,
        curve,
        output: k,
        time_h,
    } = failure_time(&project, &pvd, say)?;
    let (t_map, fem_at) = &series[k];
    let fs_at = |t: f64| factor_at(&curve, t);

    // 3. Calibrate h on the pore pressures of the first output with FS ≤ 1.
    let outcome = calibrate::calibrate_h(
        &fem_at.nodes,
        &[Quantity::Pwp],
        KernelKind::Cubic,
        1,
        crate::kernel::loo::Norm::L1,
    )?;
    say(DemoLine::Text(format!(
        "3 calibrate  OGS output t = {:.2} h (FS = {:.3}), {} FEM nodes: h = {:.4} m, h/l = {:.3} (paper: h = 0.046 m on a 0.05 m mesh, h/l 0.7–1.0); LOO R² = {:.5}",
        t_map / 3600.0,
        fs_at(*t_map),
        fem_at.nodes.len(),
        outcome.h,
        outcome.h_over_l,
        outcome.stats.r2
    )));
    let fem_options = FemOptions {
        step: StepChoice::Time(*t_map),
        ..FemOptions::files(vec![pvd.clone()])
    };

    // 4. Map with that h, the stress solved for equilibrium.
    let job = MapJob {
        model: dir.clone(),
        fem: fem_options,
        config: MapConfig {
            kernel: KernelKind::Cubic,
            h: SmoothingLength::Calibrated {
                outcome: Box::new(outcome.clone()),
                seed: 1,
            },
            stress: StressSource::Equilibrium,
            // OGS's one material region is the sand layer.
            material_map: Some("mat0=silty_sand".parse().map_err(
                |e: crate::formats::material_map::MaterialMapError| {
                    PipelineError::Option(e.to_string())
                },
            )?),
            ..MapConfig::default()
        },
        generate_cps: false,
        fem_vtu: false,
    };
    let mapped = job::compute(&job)?;
    let mut written = crate::pipeline::map::write::write_project(&mapped, &out.staging(), false)?;
    write_figures(&out, &mapped, &outcome, &curve, &series, &mut written)?;
    let target = out.commit()?;
    let pts = &mapped.project.points;
    let (pwp_lo, pwp_hi) = range(&mapped.states, |s| s.pwp);
    let (syy_lo, syy_hi) = range(&mapped.states, |s| s.total[1]);
    say(DemoLine::Text(format!(
        "4 map        {} MPs, pwp {pwp_lo:.2} .. {pwp_hi:.2} kPa, σyy {syy_lo:.2} .. {syy_hi:.2} kPa (Anura3D signs, {}); MAPF h = {:.2e} m",
        pts.len(),
        mapped.report.stress_source,
        mapped.report.mapf_smoothing_length
    )));
    say(DemoLine::Command(DemoCommand::MapAtFailure {
        fem: pvd.to_path_buf(),
        model: dir.to_path_buf(),
    }));
    if let Some(e) = &mapped.report.equilibrium {
        let o = &e.outcome;
        say(DemoLine::Text(format!(
            "             equilibrium solve: {}, out-of-balance force ratio {:.2e} after {} plastic iterations ({} MPs on their yield surface), {:.2} s",
            if o.equilibrium {
                "IN EQUILIBRIUM"
            } else {
                "NO EQUILIBRIUM"
            },
            o.residual_ratio,
            o.plastic_iterations,
            o.yielding_points,
            o.assembly_s + o.factorisation_s + o.elastic_solve_s + o.plastic_s
        )));
    }

    // 5. Verify with the explicit MPM runner, beside the intended state and
    // the geostatic map.
    let (source, verify_folders) = verify_steps(&target, &job, options.no_fos, pts.len(), say)?;
    // 6. Factor of safety by strength reduction on the state Anura3D will
    // hold: zero pwp, then the mapped pwp.
    let mut fos_folders = Vec::new();
    if !options.no_fos {
        let start = Start::load(&source)?;
        let [(zero, zero_dir), (with_pwp, mapped_dir)] =
            fos::zero_and_mapped(&start, &target, &reads)?;
        say(DemoLine::Text(format!(
            "6 fos        zero pwp:   {}",
            fos::factor_line(&zero)
        )));
        say(DemoLine::Text(format!(
            "             mapped pwp: {}",
            fos::factor_line(&with_pwp)
        )));
        fos_folders.push((zero_dir, fos::file_names(&zero)));
        fos_folders.push((mapped_dir, fos::file_names(&with_pwp)));
    }
    // 7. The run-out: the same output mapped onto the paper's MPM model.
    let flume = runout(&dir, &job, &target, say)?;
    let mut folders = vec![WrittenFolder {
        path: target.clone(),
        files: written,
    }];
    folders.extend(verify_folders);
    for (path, files) in &fos_folders {
        folders.push(folder(path, files));
    }
    folders.push(flume);
    Ok(DemoReport {
        failure_time_h: time_h,
        method: curve.method,
        folders,
        seconds: started.elapsed().as_secs_f64(),
    })
}
