//! Acceptance tests of the explicit MPM check (`a3d_init::mpm`): analytic
//! geostatic columns in 2D and 3D, convergence from zero stress, detection of
//! an out-of-balance state, the undamped period of a bar, Mohr–Coulomb return
//! mapping properties, a collapsing Mohr–Coulomb block, Bishop effective
//! stress with water, thread-count independence and input errors.
//!
//! Every oracle is analytic or a second code path; tolerances are stated where
//! they are used.

use crate::common;
use common::column::*;

use a3d_init::model::{AnuraModel, MaterialPoint, MpState};
use a3d_init::mpm::{
    Elasticity, MohrCoulomb, MpmError, Reason, ReturnKind, RunSettings, Simulation, SolidModel,
    Verdict, run, verify,
};
use a3d_testkit::{
    column_tet, column_tri3, geostatic_states, mohr_coulomb_material, place_points, saturated,
    zero_states,
};
use proptest::prelude::*;

/// Checks every MP's effective stress against σ′v = −γ′(H − y), σ′h = K0·σ′v
/// (y of the MP's initial position) within `relative` of the local value.
fn assert_geostatic(
    points: &[MaterialPoint],
    stresses: &[[f64; 6]],
    gamma_eff: f64,
    height: f64,
    relative: f64,
) {
    for (p, s) in points.iter().zip(stresses) {
        let v = -gamma_eff * (height - p.position[1]);
        let h = k0() * v;
        let expected = [h, v, h, 0.0, 0.0, 0.0];
        for k in 0..6 {
            let tol = relative * v.abs() + 1e-9;
            assert!(
                (s[k] - expected[k]).abs() <= tol,
                "MP {} at y = {}: component {k} is {} instead of {}",
                p.id,
                p.position[1],
                s[k],
                expected[k]
            );
        }
    }
}

#[test]
fn geostatic_column_2d_stays_in_equilibrium() {
    let model = column_tri3(1.0, 10.0, 2, 20, elastic());
    let points = place_points(&model);
    // The exact state is also the discrete equilibrium: the 3-point rule
    // integrates the linear stress field and the linear shape functions exactly.
    let report = verify_exact_geostatic(&model, &points);
    assert!(
        report.steps > 100,
        "the run must actually run: {} steps",
        report.steps
    );
    assert_geostatic(&points, &report.final_stresses, gamma(), 10.0, 1e-2);
    assert!(report.verdict.is_equilibrium(), "{:?}", report.verdict);
    assert!(report.plastic_elements.is_empty());
}

#[test]
fn geostatic_column_3d_stays_in_equilibrium() {
    let model = column_tet(1.0, 10.0, 1.0, 2, 20, 2, elastic());
    let points = place_points(&model);
    let report = verify_exact_geostatic(&model, &points);
    assert_geostatic(&points, &report.final_stresses, gamma(), 10.0, 1e-2);
    assert!(report.verdict.is_equilibrium(), "{:?}", report.verdict);
}

#[test]
fn time_step_follows_the_courant_condition() {
    let model = column_tri3(1.0, 10.0, 2, 20, elastic());
    let points = place_points(&model);
    let states = geostatic_states(&model, &points, G, k0(), None);
    let simulation =
        Simulation::new(&model, &points, &states, &RunSettings::verify()).expect("valid");
    let e = Elasticity::from_young_poisson(YOUNG, POISSON).expect("valid");
    let rho = (1.0 - POROSITY) * RHO_S / 1000.0;
    let c = (e.p_wave_modulus() / rho).sqrt();
    // Right triangles with 0.5 m legs: smallest altitude 0.5/√2.
    let expected = 0.9 * 0.5 / 2.0_f64.sqrt() / c;
    assert!((simulation.time_step() - expected).abs() < 1e-12 * expected);
}

/// Average σ′yy per horizontal layer of 2 × 2 triangles (MPs grouped by their
/// initial element), compared with the analytic σ′v at the layer's mid-height:
/// the static FE solution of the laterally confined column is nodally exact, so
/// the constant layer stress equals the exact stress at mid-height. The top
/// 20 % of the column is left out: there MPs that moved by u inside the fixed
/// mesh shift lumped weight between nodes, an error of about γ·u that is large
/// only relative to the small stresses near the free surface.
fn assert_layers_converged(
    points: &[MaterialPoint],
    stresses: &[[f64; 6]],
    layers: usize,
    per_layer: usize,
) {
    let h = 10.0 / layers as f64;
    for layer in 0..layers {
        let mid = (layer as f64 + 0.5) * h;
        if mid > 8.0 {
            continue;
        }
        let values: Vec<f64> = points
            .iter()
            .zip(stresses)
            .filter(|(p, _)| p.element as usize / per_layer == layer)
            .map(|(_, s)| s[1])
            .collect();
        let average = values.iter().sum::<f64>() / values.len() as f64;
        let exact = -gamma() * (10.0 - mid);
        assert!(
            ((average - exact) / exact).abs() < 1e-2,
            "layer {layer}: σ′yy = {average}, analytic {exact}"
        );
    }
}

#[test]
fn column_from_zero_stress_converges_to_geostatic_2d() {
    let model = column_tri3(1.0, 10.0, 2, 20, elastic());
    let points = place_points(&model);
    let report = verify_from_zero(&model, &points);
    assert!(report.final_residual_ratio < 1e-2);
    assert_layers_converged(&points, &report.final_stresses, 20, 4);
    // Zero stress under gravity is as far from equilibrium as it gets.
    assert!((report.initial_residual_ratio - 1.0).abs() < 1e-9);
    assert!(!report.verdict.is_equilibrium());
}

#[test]
fn column_from_zero_stress_converges_to_geostatic_3d() {
    let model = column_tet(1.0, 10.0, 1.0, 1, 10, 1, elastic());
    let points = place_points(&model);
    let report = verify_from_zero(&model, &points);
    assert!(report.final_residual_ratio < 1e-2);
    assert_layers_converged(&points, &report.final_stresses, 10, 6);
}

#[test]
fn stresses_twenty_percent_low_are_not_in_equilibrium_and_settle() {
    let model = column_tri3(1.0, 10.0, 2, 20, elastic());
    let points = place_points(&model);
    // The missing 20 % of the weight is out of balance at the first step.
    let report = verify_twenty_percent_low(&model, &points);
    // Settlement: the top takes up 20 % of the geostatic strain,
    // 0.2·γH²/(2M) = 1.35 mm; the exact state moved less than 1e-12 m.
    let m = Elasticity::from_young_poisson(YOUNG, POISSON)
        .expect("valid")
        .p_wave_modulus();
    let settlement = 0.2 * gamma() * 100.0 / (2.0 * m);
    assert!(
        (report.max_displacement - settlement).abs() < 0.1 * settlement,
        "{} vs {settlement}",
        report.max_displacement
    );
    // Kinetic energy rises, then decays by orders of magnitude.
    let peak = report
        .records
        .iter()
        .map(|r| r.kinetic_energy)
        .fold(0.0, f64::max);
    let last = report.records.last().expect("records").kinetic_energy;
    assert!(peak > 0.0 && last < 1e-3 * peak, "peak {peak}, last {last}");
    // The first-step residual sits at the top of the column's elements.
    assert!(!report.worst_residual_elements.is_empty());
}

/// Upward crossings of `u − mean` (linear interpolation), as times.
fn upward_crossings(times: &[f64], values: &[f64], mean: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 1..values.len() {
        let (a, b) = (values[k - 1] - mean, values[k] - mean);
        if a < 0.0 && b >= 0.0 {
            let f = a / (a - b);
            out.push(times[k - 1] + f * (times[k] - times[k - 1]));
        }
    }
    out
}

#[test]
fn undamped_bar_oscillates_with_the_analytic_period() {
    // A strip of 1 × 20 cells (40 triangles) released from zero stress under
    // gravity, no damping: fixed base, free top, rollers on the sides.
    let length = 10.0;
    let model = column_tri3(0.5, length, 1, 20, elastic());
    let points = place_points(&model);
    let states = zero_states(&points);
    let e = Elasticity::from_young_poisson(YOUNG, POISSON).expect("valid");
    let rho = (1.0 - POROSITY) * RHO_S / 1000.0;
    let period = 4.0 * length / (e.p_wave_modulus() / rho).sqrt();
    let settings = RunSettings::dynamic(3.6 * period);
    let mut simulation = Simulation::new(&model, &points, &states, &settings).expect("valid");
    let top = points
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.position[1].total_cmp(&b.1.position[1]))
        .map(|(i, _)| i)
        .expect("points");
    let mut times = vec![0.0];
    let mut uy = vec![0.0];
    while simulation.time() < 3.6 * period {
        simulation.step();
        times.push(simulation.time());
        uy.push(simulation.displacements()[top][1]);
    }
    let high = uy.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let low = uy.iter().copied().fold(f64::INFINITY, f64::min);
    let crossings = upward_crossings(&times, &uy, 0.5 * (high + low));
    assert!(crossings.len() >= 3, "{crossings:?}");
    let measured = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    assert!(
        ((measured - period) / period).abs() < 0.02,
        "period {measured} s, analytic 4L/c = {period} s"
    );
    // Undamped: the amplitude does not decay (the top swings to about twice
    // the static settlement γL²/(2M)).
    let settlement = gamma() * length * length / (2.0 * e.p_wave_modulus());
    assert!(
        (low + 2.0 * settlement).abs() < 0.1 * settlement,
        "low {low}, 2·static {}",
        2.0 * settlement
    );
}

#[test]
fn saturated_column_with_hydrostatic_pore_pressure_is_in_equilibrium() {
    // Water table at the surface: total σv = −γsat·depth, p = −γw·depth,
    // σ′ = σ − p = −γ′·depth, which the one-phase drained analysis balances
    // against the buoyant weight γ′.
    let material = saturated(elastic());
    let model = column_tri3(1.0, 10.0, 2, 20, material.clone());
    let points = place_points(&model);
    let states = geostatic_states(&model, &points, G, k0(), Some(10.0));
    let report = verify_in_equilibrium(&model, &points, &states, 1e-12);
    let submerged = material.gamma_at_saturation(1.0, G) - G;
    assert_geostatic(&points, &report.final_stresses, submerged, 10.0, 1e-2);
    // A one-phase drained analysis balances σ′ against the buoyant weight, as
    // Anura3D does: the pore pressure only told σ′ from the total stress, so
    // the same σ′ without it is balanced too.
    let mut dropped = states.clone();
    for s in &mut dropped {
        s.total = s.effective();
        s.pwp = 0.0;
    }
    verify_in_equilibrium(&model, &points, &dropped, 1e-12);
    // In a coupled (two-phase) analysis the total stress σ′ + p carries the
    // water's weight: the same state holds, and forgetting the pore pressure
    // leaves the water's weight unbalanced.
    let mut coupled = model.clone();
    coupled.materials[0].material_type = "saturated_material_coupled".into();
    verify_in_equilibrium(&coupled, &points, &states, 1e-12);
    let report = verify(&coupled, &points, &dropped, &RunSettings::verify()).expect("valid");
    assert!(!report.verdict.is_equilibrium());
}

#[test]
fn unsupported_block_falls_freely_and_leaves_the_mesh() {
    // Nothing fixed and no stress: every node accelerates at g. With the
    // symplectic Euler update, u_n = −g·Δt²·n(n+1)/2 = −½·g·t(t + Δt) exactly,
    // while MPs cross element boundaries. Once they pass y = 0 they are lost.
    // The block fills the upper half of the mesh and falls through the
    // empty lower half.
    let mut model = column_tri3(1.0, 2.0, 2, 4, elastic());
    for f in &mut model.solid_fixity {
        *f = [false; 3];
    }
    for e in 0..model.mesh.n_elements() {
        if model
            .mesh
            .corner_coords(e)
            .iter()
            .take(3)
            .all(|c| c[1] <= 1.0)
        {
            model.element_material[e] = 0;
        }
    }
    let points = place_points(&model);
    let states = zero_states(&points);
    let mut simulation =
        Simulation::new(&model, &points, &states, &RunSettings::dynamic(1.0)).expect("valid");
    let dt = simulation.time_step();
    let start = simulation.elements();
    while simulation.time() < 0.25 {
        simulation.step();
    }
    let t = simulation.time();
    let expected = -0.5 * G * t * (t + dt);
    for u in simulation.displacements() {
        assert!(u[0].abs() < 1e-12);
        assert!(
            (u[1] - expected).abs() < 1e-9 * expected.abs(),
            "{} vs {expected}",
            u[1]
        );
    }
    let moved = simulation
        .elements()
        .iter()
        .zip(&start)
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        moved > 0,
        "some MPs must have changed element after {expected} m"
    );
    // A full run: the block falls out of the mesh within 1 s.
    let report = verify(&model, &points, &states, &RunSettings::dynamic(1.0)).expect("valid");
    assert_eq!(report.lost_points, points.len());
    let Verdict::NotInEquilibrium { reasons } = &report.verdict else {
        panic!("a falling block is not in equilibrium");
    };
    assert!(
        reasons
            .iter()
            .any(|r| matches!(r, Reason::LostPoints { .. })),
        "{reasons:?}"
    );
}

/// A 2 m wide, 3 m high block of cohesionless Mohr–Coulomb soil (φ = 30°)
/// standing on the left of a 6 m wide mesh, the rest of the mesh empty; only
/// the left side is on rollers, so the right face of the block is free.
fn collapsing_block(cell: f64) -> (AnuraModel, Vec<MaterialPoint>, Vec<MpState>) {
    let material = mohr_coulomb_material(1e4, 0.3, RHO_S, POROSITY, 30.0, 0.0, 0.0);
    let (nx, ny) = ((6.0 / cell) as usize, (3.0 / cell) as usize);
    let mut model = column_tri3(6.0, 3.0, nx, ny, material);
    for e in 0..model.mesh.n_elements() {
        let c = model.mesh.corner_coords(e);
        if (c[0][0] + c[1][0] + c[2][0]) / 3.0 > 2.0 {
            model.element_material[e] = 0;
            model.mp_counts[e] = (0, 0);
        }
    }
    let points = place_points(&model);
    let states = geostatic_states(&model, &points, G, 0.5, None);
    (model, points, states)
}

#[test]
fn mohr_coulomb_block_collapses() {
    let (model, points, states) = collapsing_block(0.25);
    let settings = RunSettings {
        max_steps: 600,
        ..RunSettings::verify()
    };
    let report = verify(&model, &points, &states, &settings).expect("valid");
    // K0 = 0.5 lies inside the cohesionless surface (active limit 1/3).
    assert_eq!(report.inadmissible_points, 0);
    let Verdict::NotInEquilibrium { reasons } = &report.verdict else {
        panic!("expected collapse, got {:?}", report.verdict);
    };
    assert!(
        reasons
            .iter()
            .any(|r| matches!(r, Reason::PlasticGrowth { .. })),
        "{reasons:?}"
    );
    assert!(
        reasons
            .iter()
            .any(|r| matches!(r, Reason::InitialResidual { .. })),
        "{reasons:?}"
    );
    assert!(
        report.plastic_points > points.len() / 10,
        "{} plastic",
        report.plastic_points
    );
    // Plastic MPs appear during the run and the plastic zone is reported.
    let first = report.records.first().expect("records").plastic_total;
    let last = report.records.last().expect("records").plastic_total;
    assert!(last > first, "{first} → {last}");
    assert!(!report.plastic_elements.is_empty());
    assert!(
        report
            .plastic_elements
            .iter()
            .all(|e| e.centroid[0] < 6.0 && e.value >= 1.0)
    );
    // The block spreads to the right into the empty elements.
    let moved = report
        .final_displacements
        .iter()
        .map(|u| u[0])
        .fold(0.0, f64::max);
    assert!(moved > 0.01, "largest x displacement {moved}");
}

#[test]
fn serial_and_parallel_runs_are_bit_identical() {
    // 2D: a collapsing block (plasticity, MPs changing element, empty nodes);
    // large enough (2304 MPs) that rayon really splits the work.
    let (model, points, states) = collapsing_block(0.125);
    let settings = RunSettings {
        max_steps: 150,
        record_every: 10,
        snapshot_times: vec![0.01],
        ..RunSettings::verify()
    };
    let one = run_in_pool(1, &model, &points, &states, &settings);
    let two = run_in_pool(2, &model, &points, &states, &settings);
    assert!(one.report.plastic_points > 0);
    assert_eq!(one.snapshots.len(), 1);
    // PartialEq on f64 fields: bit-identical up to the sign of zero; the JSON
    // text (shortest round-trip digits) pins every bit.
    assert_eq!(one, two);
    let json = |o: &a3d_init::mpm::RunOutput| serde_json::to_string(o).expect("serialisable");
    assert_eq!(json(&one), json(&two));

    // 3D: a column released from zero stress.
    let model = column_tet(1.0, 4.0, 1.0, 2, 8, 2, elastic());
    let points = place_points(&model);
    assert_zero_stress_runs_bit_identical(&model, &points);
}

#[test]
fn snapshots_are_taken_at_the_requested_times() {
    let model = column_tri3(1.0, 10.0, 2, 20, elastic());
    let points = place_points(&model);
    let settings = RunSettings {
        snapshot_times: vec![0.05, 0.01],
        ..RunSettings::dynamic(0.06)
    };
    let output = run(&model, &points, &zero_states(&points), &settings).expect("valid");
    let times: Vec<f64> = output.snapshots.iter().map(|s| s.time).collect();
    assert_eq!(times.len(), 2);
    let dt = output.report.time_step;
    assert!(times[0] >= 0.01 && times[0] < 0.01 + dt);
    assert!(times[1] >= 0.05 && times[1] < 0.05 + dt);
    assert!(output.report.time >= 0.06);
    let snap = &output.snapshots[1];
    for ((x, u), p) in snap.positions.iter().zip(&snap.displacements).zip(&points) {
        for k in 0..3 {
            assert!((x[k] - p.position[k] - u[k]).abs() < 1e-12);
        }
    }
}

#[test]
fn bad_inputs_are_errors() {
    let model = column_tri3(1.0, 2.0, 1, 2, elastic());
    let points = place_points(&model);
    let states = zero_states(&points);
    let settings = RunSettings::verify();
    assert!(matches!(
        verify(&model, &points, &states[1..], &settings),
        Err(MpmError::LengthMismatch { .. })
    ));
    let mut outside = points.clone();
    outside[0].position = [5.0, 5.0, 0.0];
    assert!(matches!(
        verify(&model, &outside, &states, &settings),
        Err(MpmError::InvalidPoint { id: 1, .. })
    ));
    let mut unknown = model.clone();
    unknown.materials[0].model = Some("hypoplasticity".into());
    assert!(matches!(
        verify(&unknown, &points, &states, &settings),
        Err(MpmError::UnsupportedMaterialModel { .. })
    ));
    let bad_damping = RunSettings {
        damping: 1.5,
        ..RunSettings::verify()
    };
    assert!(matches!(
        verify(&model, &points, &states, &bad_damping),
        Err(MpmError::InvalidSettings(_))
    ));
    // An MP whose element id is wrong but whose position is inside the mesh
    // is located again rather than rejected.
    let mut misplaced = points.clone();
    misplaced[0].element = 3;
    assert!(verify(&model, &misplaced, &states, &settings).is_ok());
}

// ---------------------------------------------------------------------------
// Mohr–Coulomb return mapping.

fn elasticity() -> Elasticity {
    Elasticity::from_young_poisson(2e4, 0.3).expect("valid")
}

fn sorted(mut s: [f64; 3]) -> [f64; 3] {
    s.sort_by(|a, b| b.total_cmp(a));
    s
}

/// Mohr–Coulomb and cut-off values of a principal stress triple.
fn yield_of(mc: &MohrCoulomb, s: [f64; 3]) -> f64 {
    mc.yield_value(&[s[0], s[1], s[2], 0.0, 0.0, 0.0], false)
}

#[test]
fn elastic_states_are_untouched() {
    let mc = MohrCoulomb::new(30.0, 5.0, 0.0, Some(0.0)).expect("valid");
    let mut s = [-50.0, -80.0, -60.0, 5.0, -3.0, 2.0];
    let before = s;
    assert_eq!(
        mc.return_stress(&elasticity(), &mut s, false),
        ReturnKind::Elastic
    );
    assert_eq!(s, before);
    let mut p = [-50.0, -80.0, -60.0, 5.0, 0.0, 0.0];
    let before = p;
    assert_eq!(
        mc.return_stress(&elasticity(), &mut p, true),
        ReturnKind::Elastic
    );
    assert_eq!(p, before);
}

#[test]
fn plane_return_with_zero_dilatancy_keeps_the_mean_stress() {
    let mc = MohrCoulomb::new(30.0, 5.0, 0.0, None).expect("valid");
    let trial = [-20.0, -50.0, -120.0];
    let (s, kind) = mc.return_principal(&elasticity(), &trial);
    assert_eq!(kind, ReturnKind::Plane);
    assert!(yield_of(&mc, s).abs() < 1e-9 * 120.0);
    // ψ = 0: the plastic strain increment C·(σtrial − σ) has no volumetric part.
    let change = [
        trial[0] - s[0],
        trial[1] - s[1],
        trial[2] - s[2],
        0.0,
        0.0,
        0.0,
    ];
    let plastic = elasticity().strain_of(&change);
    let volumetric = plastic[0] + plastic[1] + plastic[2];
    let deviatoric = plastic.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(deviatoric > 0.0);
    assert!(
        volumetric.abs() < 1e-12 * deviatoric,
        "{volumetric} vs {deviatoric}"
    );
    // The intermediate stress is untouched when ψ = 0.
    assert!((s[1] - trial[1]).abs() < 1e-12 * 120.0);
}

#[test]
fn returns_to_both_edges() {
    let mc = MohrCoulomb::new(30.0, 0.0, 0.0, Some(0.0)).expect("valid");
    // Triaxial compression: σ1 = σ2 > σ3 stays on the edge σ1 = σ2.
    let (s, kind) = mc.return_principal(&elasticity(), &[-10.0, -10.0, -100.0]);
    assert_eq!(kind, ReturnKind::CompressionEdge);
    assert!((s[0] - s[1]).abs() < 1e-9 * 100.0, "{s:?}");
    assert!(yield_of(&mc, s).abs() < 1e-9 * 100.0);
    // ψ = 0 on the edge too: mean stress kept.
    assert!(((s[0] + s[1] + s[2]) - (-120.0)).abs() < 1e-9 * 120.0);
    // Triaxial extension: σ1 > σ2 = σ3 stays on the edge σ2 = σ3.
    let (s, kind) = mc.return_principal(&elasticity(), &[-10.0, -100.0, -100.0]);
    assert_eq!(kind, ReturnKind::ExtensionEdge);
    assert!((s[1] - s[2]).abs() < 1e-9 * 100.0, "{s:?}");
    assert!(yield_of(&mc, s).abs() < 1e-9 * 100.0);
}

#[test]
fn returns_to_the_apex() {
    let e = elasticity();
    // No cut-off: hydrostatic tension returns to c·cot φ.
    let mc = MohrCoulomb::new(30.0, 10.0, 10.0, None).expect("valid");
    let apex = 10.0 / 30.0_f64.to_radians().tan();
    let (s, kind) = mc.return_principal(&e, &[60.0, 50.0, 40.0]);
    assert_eq!(kind, ReturnKind::Apex);
    for v in s {
        assert!((v - apex).abs() < 1e-9 * 60.0, "{s:?}");
    }
    // With ψ = 0 the apex is still reached (the only admissible point nearby).
    let mc0 = MohrCoulomb::new(30.0, 10.0, 0.0, None).expect("valid");
    let (s, _) = mc0.return_principal(&e, &[60.0, 50.0, 40.0]);
    for v in s {
        assert!((v - apex).abs() < 1e-9 * 60.0, "{s:?}");
    }
    // A cut-off below the apex caps it: σ1 = σ2 = σ3 = σt.
    let cut = MohrCoulomb::new(30.0, 10.0, 10.0, Some(5.0)).expect("valid");
    let (s, kind) = cut.return_principal(&e, &[60.0, 50.0, 40.0]);
    assert_eq!(kind, ReturnKind::TensionApex);
    for v in s {
        assert!((v - 5.0).abs() < 1e-9 * 60.0, "{s:?}");
    }
    // Cohesionless soil in tension returns to zero stress.
    let sand = MohrCoulomb::new(30.0, 0.0, 0.0, Some(0.0)).expect("valid");
    let mut full = [3.0, 1.0, 2.0, 0.5, 0.2, -0.1];
    sand.return_stress(&e, &mut full, false);
    for v in full {
        assert!(v.abs() < 1e-9 * 3.0, "{full:?}");
    }
}

#[test]
fn tension_cutoff_plane() {
    let mc = MohrCoulomb::new(30.0, 20.0, 0.0, Some(2.0)).expect("valid");
    let (s, kind) = mc.return_principal(&elasticity(), &[8.0, -5.0, -10.0]);
    assert_eq!(kind, ReturnKind::TensionPlane);
    assert!((s[0] - 2.0).abs() < 1e-12 * 10.0);
    assert!(yield_of(&mc, s).abs() < 1e-9 * 10.0);
}

fn stress_strategy() -> impl Strategy<Value = [f64; 6]> {
    proptest::array::uniform6(-1.0f64..1.0).prop_map(|u| {
        [
            -100.0 + 120.0 * u[0],
            -100.0 + 120.0 * u[1],
            -100.0 + 120.0 * u[2],
            40.0 * u[3],
            40.0 * u[4],
            40.0 * u[5],
        ]
    })
}

fn material_strategy() -> impl Strategy<Value = MohrCoulomb> {
    (
        10.0f64..45.0,
        0.0f64..1.0,
        0.0f64..20.0,
        proptest::option::of(0.0f64..15.0),
    )
        .prop_map(|(phi, psi_share, c, t)| {
            MohrCoulomb::new(phi, c, phi * psi_share, t).expect("valid")
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any trial stress ends on or inside the surface; one outside ends on it
    /// (|f| ≤ 1e-9 relative); one inside is returned bit for bit.
    #[test]
    fn every_return_lands_on_the_yield_surface(trial in stress_strategy(), mc in material_strategy(), plane in any::<bool>()) {
        let e = elasticity();
        let mut s = trial;
        if plane {
            s[4] = 0.0;
            s[5] = 0.0;
        }
        let before = s;
        let scale = before.iter().fold(mc.cohesion, |m, v| m.max(v.abs()));
        let f_trial = mc.yield_value(&before, plane);
        let kind = mc.return_stress(&e, &mut s, plane);
        let f = mc.yield_value(&s, plane);
        if f_trial <= -1e-9 * scale {
            prop_assert_eq!(kind, ReturnKind::Elastic);
            prop_assert_eq!(s, before);
        } else if f_trial > 1e-9 * scale {
            prop_assert!(kind.is_plastic());
            prop_assert!(f.abs() <= 1e-9 * scale, "f = {} after {:?}", f, kind);
        }
        if plane {
            prop_assert!(s[4] == 0.0 && s[5] == 0.0);
        }
    }

    /// Associative flow (ψ = φ) makes the return the closest admissible point
    /// in the energy norm: (σtr − σ)·C·(σ* − σ) ≤ 0 for every admissible σ*
    /// (checked on random coaxial σ*, which suffices for isotropic C).
    #[test]
    fn associative_return_is_the_energy_projection(
        trial in proptest::array::uniform3(-150.0f64..60.0),
        others in proptest::collection::vec(proptest::array::uniform3(-150.0f64..30.0), 32),
        phi in 10.0f64..45.0,
        c in 0.0f64..20.0,
        t in proptest::option::of(0.0f64..15.0),
    ) {
        let e = elasticity();
        let mc = MohrCoulomb::new(phi, c, phi, t).expect("valid");
        let trial = sorted(trial);
        let (s, _) = mc.return_principal(&e, &trial);
        let compliance = |x: [f64; 3]| e.strain_of(&[x[0], x[1], x[2], 0.0, 0.0, 0.0]);
        let r = compliance([trial[0] - s[0], trial[1] - s[1], trial[2] - s[2]]);
        for other in others {
            if yield_of(&mc, sorted(other)) > 0.0 {
                continue;
            }
            let inner: f64 = (0..3).map(|k| r[k] * (other[k] - s[k])).sum();
            prop_assert!(inner <= 1e-9 * (1.0 + r.iter().map(|v| v.abs()).sum::<f64>() * 150.0), "inner product {}", inner);
        }
    }

    /// Rotation covariance: for σ = R·diag(p)·Rᵀ the 3D return equals
    /// R·diag(return of sorted p)·Rᵀ. Principal triples include exactly
    /// repeated values (states on the edges' axes, as geostatic K0 states with
    /// σxx = σzz are), which take the Jacobi path.
    #[test]
    fn three_d_return_is_rotation_covariant(
        p in proptest::array::uniform3(-150.0f64..40.0),
        repeat in 0usize..3,
        q in proptest::array::uniform4(-1.0f64..1.0),
        mc in material_strategy(),
    ) {
        let mut p = p;
        match repeat {
            1 => p[1] = p[0],
            2 => p[2] = p[1],
            _ => {}
        }
        let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        prop_assume!(norm > 0.1);
        let [w, x, y, z] = q.map(|v| v / norm);
        let r = [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
            [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
            [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
        ];
        let rotate = |d: [f64; 3]| -> [f64; 6] {
            let m = |i: usize, j: usize| (0..3).map(|k| r[i][k] * d[k] * r[j][k]).sum::<f64>();
            [m(0, 0), m(1, 1), m(2, 2), m(0, 1), m(1, 2), m(0, 2)]
        };
        let e = elasticity();
        let mut full = rotate(p);
        mc.return_stress(&e, &mut full, false);
        let (principal, _) = mc.return_principal(&e, &sorted(p));
        // Map the sorted result back to the slots of p (ties: same value).
        let order = {
            let mut idx = [0usize, 1, 2];
            idx.sort_by(|&a, &b| p[b].total_cmp(&p[a]));
            idx
        };
        let mut back = [0.0; 3];
        for (slot, &o) in order.iter().enumerate() {
            back[o] = principal[slot];
        }
        let expected = rotate(back);
        let scale = p.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        for k in 0..6 {
            prop_assert!((full[k] - expected[k]).abs() < 1e-8 * scale, "{:?} vs {:?}", full, expected);
        }
        prop_assert!(mc.yield_value(&full, false) <= 1e-9 * scale);
    }

    /// The plane-strain path (2×2 eigen-solution plus σzz) and the general 3D
    /// path (Jacobi) return the same stress.
    #[test]
    fn plane_strain_and_3d_returns_agree(trial in stress_strategy(), mc in material_strategy()) {
        let e = elasticity();
        let mut a = trial;
        a[4] = 0.0;
        a[5] = 0.0;
        let mut b = a;
        let ka = mc.return_stress(&e, &mut a, true);
        let kb = mc.return_stress(&e, &mut b, false);
        let scale = trial.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        prop_assert_eq!(ka.is_plastic(), kb.is_plastic());
        for k in 0..6 {
            prop_assert!((a[k] - b[k]).abs() < 1e-9 * scale, "{:?} vs {:?}", a, b);
        }
    }
}

#[test]
fn material_models_are_built_from_gom_materials() {
    let m = mohr_coulomb_material(1e4, 0.3, RHO_S, POROSITY, 30.0, 5.0, 0.0);
    let model = SolidModel::from_material(&m).expect("valid");
    let mc = model.plasticity.expect("plastic").criterion;
    assert!((mc.sin_phi - 0.5).abs() < 1e-15);
    assert!(mc.tension == 0.0 && mc.apex() == 0.0);
    let mut bad = m.clone();
    bad.friction_angle = None;
    assert!(matches!(
        SolidModel::from_material(&bad),
        Err(MpmError::MissingProperty {
            property: "FRICTION_ANGLE",
            ..
        })
    ));
    let mut softening = m;
    softening.model = Some("strain_softening_mohr_coulomb".into());
    softening.properties = vec![
        ("$$PEAK_COHESION".into(), "7.5".into()),
        ("$$PEAK_FRICTION_ANGLE".into(), "35".into()),
    ];
    let mc = SolidModel::from_material(&softening)
        .expect("valid")
        .plasticity
        .expect("plastic")
        .criterion;
    assert!((mc.cohesion - 7.5).abs() < 1e-15);
}
