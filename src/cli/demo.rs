//! `a3d-init demo`: the paper's application end to end on the shipped slope
//! fixture (`fixtures/slope/`), composed of library calls: inspect → calibrate
//! h → map (the stress solved for equilibrium) → verify, with the geostatic
//! map of the same slope beside it for comparison → factors of safety,
//! leaving a ready-to-run Anura3D project with plots of the mapped fields
//! (cf. the paper's Fig. 9), the calibration curve and the verify history. The pore pressures are a
//! documented stand-in field, not a SEEP/W result. Everything printed is what
//! was run and measured.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::bail;

use super::args::FemArgs;
use super::print::wrote;
use crate::kernel::KernelKind;
use crate::model::{MpState, Quantity};
use crate::pipeline::check::{self, VerifyOptions};
use crate::pipeline::map::{MapConfig, SmoothingLength, StressSource};
use crate::pipeline::mapping::{self, MapJob};
use crate::pipeline::output::{Destination, OutputDir, ReadLog};
use crate::pipeline::start::{Start, StateSource};
use crate::pipeline::{Project, calibrate, fos, plot};

#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "a3d-init-demo")]
    pub out: PathBuf,
    /// Replace an existing output folder.
    #[arg(long)]
    pub force: bool,
    /// Skip step 5, the two factors of safety (strength reduction, about 30 s).
    #[arg(long)]
    pub no_fos: bool,
}

fn fixture_dir() -> anyhow::Result<PathBuf> {
    let built_in = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/slope");
    for dir in [built_in, PathBuf::from("fixtures/slope")] {
        if dir.join("slope.GOM").exists() {
            return Ok(dir);
        }
    }
    bail!("fixtures/slope not found: run the demo from the a3d-init repository")
}

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

pub fn run(args: DemoArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let reads = ReadLog::start();
    let dir = fixture_dir()?;
    let fem_file = dir.join("sand-nodes.csv");
    say!("a3d-init demo: the rainfall-loaded slope of the seed paper (Lora et al. 2016)");
    say!(
        "  NOTE: the pore pressures are a documented STAND-IN field (fixtures/slope/README.md), not SEEP/W results."
    );

    // 1. Inspect.
    let project = Project::load(&dir)?;
    say!(
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
    );

    // 2. Calibrate h on the FEM pore pressures.
    let fem_options = FemArgs::files(vec![fem_file.clone()]).options()?;
    let fem = crate::pipeline::fem::load(&fem_options)?;
    let outcome = calibrate::calibrate_h(
        &fem.nodes,
        &[Quantity::Pwp],
        KernelKind::Cubic,
        1,
        crate::kernel::loo::Norm::L1,
    )?;
    say!(
        "2 calibrate  {} FEM nodes: h = {:.4} m, h/l = {:.3} (paper: h = 0.046 m on a 0.05 m mesh, h/l 0.7–1.0); LOO R² = {:.5}",
        fem.nodes.len(),
        outcome.h,
        outcome.h_over_l,
        outcome.stats.r2
    );

    // 3. Map with that h, the stress solved for equilibrium.
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
            ..MapConfig::default()
        },
        generate_cps: false,
        fem_vtu: false,
    };
    let mapped = mapping::compute(&job)?;
    let out = OutputDir::create(&args.out, args.force, &reads)?;
    let mut written = crate::pipeline::write::write_project(&mapped, &out.staging(), false)?;
    calibrate::plot_curve(&out.path("calibration.svg"), &outcome)?;
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
            "Mapped pore-water pressure (stand-in field)",
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
    let target = out.commit()?;
    let (pwp_lo, pwp_hi) = range(&mapped.states, |s| s.pwp);
    let (syy_lo, syy_hi) = range(&mapped.states, |s| s.total[1]);
    say!(
        "3 map        {} MPs, pwp {pwp_lo:.2} .. {pwp_hi:.2} kPa, σyy {syy_lo:.2} .. {syy_hi:.2} kPa (Anura3D signs, {}); MAPF h = {:.2e} m",
        pts.len(),
        mapped.report.stress_source,
        mapped.report.mapf_smoothing_length
    );
    if let Some(e) = &mapped.report.equilibrium {
        let o = &e.outcome;
        say!(
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
        );
    }

    // 4. Verify with the explicit MPM runner.
    let source = StateSource::Folder(target.clone());
    let verify_dir = target.join("verify");
    let (outcome, verify_dir) = check::verify(
        &source,
        &VerifyOptions::default(),
        Destination::new(Some(&verify_dir), true),
    )?;
    match &outcome.run {
        Some(r) => say!(
            "4 verify     {}: initial residual {:.2e}, {} MPs yielded, max displacement {:.3} m after {:.3} s",
            if outcome.equilibrium {
                "IN EQUILIBRIUM"
            } else {
                "NOT IN EQUILIBRIUM"
            },
            r.initial_residual_ratio,
            r.plastic_points,
            r.max_displacement,
            r.time
        ),
        None => say!("4 verify     NOT IN EQUILIBRIUM: the run could not start"),
    }
    for c in &outcome.causes {
        say!("             - {c}");
    }
    if let Some(d) = outcome
        .anura3d
        .as_ref()
        .and_then(|k| k.sigma_zz_defect.as_ref())
    {
        say!(
            "             σ'zz: Anura3D's 2D MAPF reader sets σ'zz := τxy on {} of the {} MPs; {} of them start outside the yield surface because of it (README: \"The 2D σ'zz defect\")",
            d.affected,
            pts.len(),
            d.outside_because_of_defect
        );
    }
    // The state a3d-init intended (mps.csv), without Anura3D's 2D reading.
    let (intended, intended_verify) = check::verify(
        &StateSource::Table {
            model: target.clone(),
            state: target.join("mps.csv"),
        },
        &VerifyOptions::default(),
        Destination::new(Some(&target.join("verify-intended")), true),
    )?;
    if let Some(r) = &intended.run {
        say!(
            "             the intended state (mps.csv, σ'zz as solved): {}, initial residual {:.2e}, max displacement {:.1e} m",
            if intended.equilibrium {
                "IN EQUILIBRIUM"
            } else {
                "NOT IN EQUILIBRIUM"
            },
            r.initial_residual_ratio,
            r.max_displacement
        );
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
        mapping::map(&geostatic_job, Destination::new(Some(&geostatic), true))?;
    let (geostatic_outcome, geostatic_verify) = check::verify(
        &StateSource::Folder(geostatic.clone()),
        &VerifyOptions::default(),
        Destination::new(None, true),
    )?;
    let ratio = |o: &check::VerifyOutcome| {
        o.run
            .as_ref()
            .map_or(f64::NAN, |r| r.initial_residual_ratio)
    };
    say!(
        "             out-of-balance force ratio geostatic {:.3} vs equilibrium {:.2e} (verify's first step; geostatic/ holds the geostatic map)",
        ratio(&geostatic_outcome),
        ratio(&outcome)
    );
    // 5. Factor of safety by strength reduction on the state Anura3D will
    // hold: zero pwp, then the mapped pwp.
    let mut fos_folders = Vec::new();
    if !args.no_fos {
        let start = Start::load(&source)?;
        let [(zero, zero_dir), (with_pwp, mapped_dir)] =
            fos::zero_and_mapped(&start, &target, &reads)?;
        say!("5 fos        zero pwp:   {}", fos::factor_line(&zero));
        say!("             mapped pwp: {}", fos::factor_line(&with_pwp));
        fos_folders.push((zero_dir, fos::file_names(&zero)));
        fos_folders.push((mapped_dir, fos::file_names(&with_pwp)));
    }
    say!("\nfiles ({:.1} s):", started.elapsed().as_secs_f64());
    let names: Vec<&str> = written.iter().map(String::as_str).collect();
    say!("  {}", wrote(&target, &names));
    say!("  {}", wrote(&verify_dir, &check::file_names(&outcome)));
    say!(
        "  {}",
        wrote(&intended_verify, &check::file_names(&intended))
    );
    let geostatic_files: Vec<&str> = geostatic_written.files.iter().map(String::as_str).collect();
    say!("  {}", wrote(&geostatic_written.folder, &geostatic_files));
    say!(
        "  {}",
        wrote(&geostatic_verify, &check::file_names(&geostatic_outcome))
    );
    for (folder, files) in &fos_folders {
        say!("  {}", wrote(folder, files));
    }
    say!(
        "  run-out: a3d-init run {} --time 2 --snapshots 0.3,0.8,1.2,2.0",
        target.display()
    );
    Ok(())
}
