//! `a3d-bench runner`: the explicit runner's throughput on a
//! generated saturated column of about `--points` MPs (TRI3, 3 MPs per
//! element, a hydrostatic, geostatic state), drained (pore pressure frozen)
//! and two-phase coupled (`saturated_material_coupled`, κ = 1e-12 m²,
//! K_w = 2.2e6 kPa): particle-steps per second and the time step each takes
//! (the liquid's wave speed shortens the coupled one). Printed, never
//! asserted.

use std::time::Instant;

use crate::BenchArgs;
use a3d_init::model::{ComputationMethod, MpState};
use a3d_init::mpm::{RunSettings, Simulation};
use a3d_testkit::generate;

const G: f64 = 9.81;

pub fn runner(args: &BenchArgs) -> anyhow::Result<()> {
    let threads = rayon::current_num_threads();
    // Cells 1:1, two TRI3 per cell, 3 MPs each, a column 1 wide × 2 high.
    let nx = ((args.points as f64 / 12.0).sqrt().round() as usize).max(1);
    let (width, height) = (10.0, 20.0);
    let mesh = generate::structured_tri_mesh(0.0, 0.0, width, height, nx, 2 * nx);
    let spec = generate::MaterialSpec {
        density_liquid: Some(1000.0),
        ..generate::MaterialSpec::dry_soil("soil")
    };
    let mut model = generate::single_material_model(mesh, &spec, 3);
    generate::make_coupled(&mut model.materials[0], 1e-12, 2.2e6, 1e-6);
    model.liquid_fixity = model.solid_fixity.clone();
    let points = a3d_init::place::place_material_points_for(&model, ComputationMethod::MpmMp)
        .map_err(|e| anyhow::anyhow!("placing the MPs: {} errors", e.0.len()))?;
    let m = &model.materials[0];
    let gamma = m.gamma_at_saturation(1.0, G);
    let k0 = m.k0.unwrap_or(0.5);
    let states: Vec<MpState> = points
        .iter()
        .map(|p| {
            let depth = height - p.position[1];
            let pwp = -G * depth;
            let effective = -(gamma - G) * depth;
            MpState {
                pwp,
                total: [
                    k0 * effective + pwp,
                    effective + pwp,
                    k0 * effective + pwp,
                    0.0,
                    0.0,
                    0.0,
                ],
                saturation: 1.0,
            }
        })
        .collect();
    say!(
        "runner: {} elements, {} MPs, {threads} thread(s)",
        model.mesh.n_elements(),
        points.len()
    );
    let steps = 200;
    for (label, frozen) in [("drained (pwp frozen)", true), ("two-phase coupled", false)] {
        let settings = RunSettings {
            frozen_pore_pressure: frozen,
            ..RunSettings::dynamic(1.0)
        };
        let mut best = f64::INFINITY;
        let mut dt = 0.0;
        for _ in 0..args.repeat.max(1) {
            let mut sim = Simulation::new(&model, &points, &states, &settings)?;
            dt = sim.time_step();
            let t = Instant::now();
            for _ in 0..steps {
                sim.step();
            }
            best = best.min(t.elapsed().as_secs_f64());
        }
        let rate = (steps * points.len()) as f64 / best;
        say!(
            "  {label:<22} {:>6.2} M particle-steps/s ({steps} steps in {best:.3} s), dt = {dt:.3e} s",
            rate / 1e6
        );
    }
    Ok(())
}
