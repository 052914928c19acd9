//! `a3d-init demo`: the paper's application end to end on the shipped slope
//! fixture (`fixtures/slope/`): inspect → calibrate h → map → verify, leaving a
//! ready-to-run Anura3D project with plots of the mapped fields (cf. the paper's
//! Fig. 9), the calibration curve and the verify history. The pore pressures are
//! a documented stand-in field, not a SEEP/W result.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::bail;

use super::args::FemArgs;
use super::args::StateInputs;
use super::calibrate::plot_curve;
use super::map::{self, MapArgs, MixedStateArg, OutsideArg, StressArg};
use super::output::OutputDir;
use super::plot;
use super::verify::{self, VerifyArgs};
use crate::kernel::KernelKind;
use crate::model::Quantity;
use crate::pipeline::calibrate::calibrate_h;
use crate::pipeline::map::SmoothingLength;

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

pub fn run(args: DemoArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let dir = fixture_dir()?;
    let fem_file = dir.join("sand-nodes.csv");
    println!("a3d-init demo: the rainfall-loaded slope of the seed paper (Lora et al. 2016)");
    println!(
        "  NOTE: the pore pressures are a documented STAND-IN field (fixtures/slope/README.md), not SEEP/W results."
    );

    // 1. Inspect.
    let project = super::inspect::load_project(&dir)?;
    println!(
        "1 inspect    {}: {} nodes, {} TRI3 elements, {} MPs; materials {}",
        project.files.gom.display(),
        project.model.mesh.n_nodes(),
        project.model.mesh.n_elements(),
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
    let fem_args = FemArgs::files(vec![fem_file.clone()]);
    let fem = fem_args.load()?;
    let outcome = calibrate_h(
        &fem.nodes,
        &[Quantity::Pwp],
        KernelKind::Cubic,
        1,
        crate::kernel::loo::Norm::L1,
    )?;
    println!(
        "2 calibrate  {} FEM nodes: h = {:.4} m, h/l = {:.3} (paper: h = 0.046 m on a 0.05 m mesh, h/l 0.7–1.0); LOO R² = {:.5}",
        fem.nodes.len(),
        outcome.h,
        outcome.h_over_l,
        outcome.stats.r2
    );

    // 3. Map with that h.
    let map_args = MapArgs {
        fem: fem_args,
        mpm: dir.clone(),
        kernel: "cubic".into(),
        h: None,
        seed: 1,
        outside: OutsideArg::Error,
        min_shepard: 0.02,
        stress: StressArg::Geostatic,
        material_map: None,
        mixed_state: MixedStateArg::Mean,
        out: Some(args.out.clone()),
        force: args.force,
        generate_cps: false,
        fem_vtu: false,
    };
    let mapped = map::compute(
        &map_args,
        Some(SmoothingLength::Calibrated {
            outcome: Box::new(outcome.clone()),
            seed: 1,
        }),
    )?;
    let mut inputs = super::args::project_inputs(&mapped.project.files);
    inputs.push(&fem_file);
    let out = OutputDir::create(&args.out, args.force, &inputs)?;
    map::write(&mapped, &out, false)?;
    plot_curve(&out.path("calibration.svg"), &outcome)?;
    let pts = &mapped.project.points;
    let field = |f: &dyn Fn(&crate::model::MpState) -> f64| -> Vec<(f64, f64, f64)> {
        pts.iter()
            .zip(&mapped.states)
            .map(|(p, s)| (p.position[0], p.position[1], f(s)))
            .collect()
    };
    plot::field_map(
        &out.path("pwp.svg"),
        "Mapped pore-water pressure (stand-in field)",
        "pwp (kPa)",
        &field(&|s| s.pwp),
    )?;
    plot::field_map(
        &out.path("effective_stress_yy.svg"),
        "Mapped vertical effective stress σ'yy",
        "σ'yy (kPa)",
        &field(&|s| s.effective()[1]),
    )?;
    plot::field_map(
        &out.path("total_stress_yy.svg"),
        "Mapped vertical total stress σyy",
        "σyy (kPa)",
        &field(&|s| s.total[1]),
    )?;
    let target = out.commit()?;
    println!(
        "3 map        {} MPs, pwp {:.2} .. {:.2} kPa, σyy {:.2} .. {:.2} kPa (Anura3D signs); MAPF h = {:.2e} m",
        pts.len(),
        mapped
            .states
            .iter()
            .map(|s| s.pwp)
            .fold(f64::INFINITY, f64::min),
        mapped
            .states
            .iter()
            .map(|s| s.pwp)
            .fold(f64::NEG_INFINITY, f64::max),
        mapped
            .states
            .iter()
            .map(|s| s.total[1])
            .fold(f64::INFINITY, f64::min),
        mapped
            .states
            .iter()
            .map(|s| s.total[1])
            .fold(f64::NEG_INFINITY, f64::max),
        mapped.report.mapf_smoothing_length
    );

    // 4. Verify with the explicit MPM runner.
    let verify_args = VerifyArgs {
        inputs: StateInputs::folder(target.clone()),
        max_steps: 20_000,
        damping: None,
        out: Some(target.join("verify")),
        force: true,
        fos: false,
    };
    let (outcome, verify_dir) = verify::verify_core(&verify_args)?;
    match &outcome.run {
        Some(r) => println!(
            "4 verify     {}: initial residual {:.3}, {} MPs yielded, max displacement {:.3} m after {:.3} s",
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
        None => println!("4 verify     NOT IN EQUILIBRIUM: the run could not start"),
    }
    for c in &outcome.causes {
        println!("             - {c}");
    }
    if let Some(d) = outcome
        .anura3d
        .as_ref()
        .and_then(|k| k.sigma_zz_defect.as_ref())
    {
        println!(
            "             σ'zz: Anura3D's 2D MAPF reader sets σ'zz := τxy on all {} MPs; {} of them start outside the yield surface because of it (README: \"The 2D σ'zz defect\")",
            d.affected, d.outside_because_of_defect
        );
    }
    // 5. Factor of safety by strength reduction: zero pwp, then the mapped pwp.
    if !args.no_fos {
        let [(zero, _), (with_pwp, _)] = super::fos::zero_and_mapped(
            &mapped.project.model,
            pts,
            &mapped.states,
            mapped.project.cps.as_ref(),
            &target,
        )?;
        println!(
            "5 fos        zero pwp:   {}",
            super::fos::factor_line(&zero)
        );
        println!(
            "             mapped pwp: {}",
            super::fos::factor_line(&with_pwp)
        );
    }
    println!(
        "\nfiles in {}/ ({:.1} s):",
        target.display(),
        started.elapsed().as_secs_f64()
    );
    println!("  Anura3D project  slope.GOM, slope.CPS_001 (MAPF on, K0 off), slope.MAPF");
    println!("  tables, ParaView mps.csv, mps.vtu, fem.vtu, report.json");
    println!(
        "  plots            pwp.svg, effective_stress_yy.svg, total_stress_yy.svg, calibration.svg"
    );
    println!(
        "  MPM check        {}/verify.json, verify_history.svg, mps_start.vtu, mps_end.vtu",
        verify_dir.display()
    );
    if !args.no_fos {
        println!(
            "  factor of safety fos_zero_pwp/, fos_mapped/ (fos.json, fos_trials.svg, fos_mechanism.svg, fos_mechanism.vtu)"
        );
    }
    println!(
        "  run-out          a3d-init run {} --time 2 --snapshots 0.3,0.8,1.2,2.0",
        target.display()
    );
    Ok(())
}
