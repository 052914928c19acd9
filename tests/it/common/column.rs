//! The elastic soil column of the MPM tests (plane strain, 3D and
//! axisymmetric): its constants, geostatic checks and a run in a thread pool.

use a3d_init::model::{AnuraModel, Material, MaterialPoint, MpState};
use a3d_init::mpm::{Reason, RunOutput, RunReport, RunSettings, Verdict, run, verify};
use a3d_testkit::{elastic_material, geostatic_states, zero_states};

pub const G: f64 = 9.81;
/// Stiff enough that the settling displacements stay far below an element.
pub const YOUNG: f64 = 1e5;
pub const POISSON: f64 = 0.3;
pub const RHO_S: f64 = 2650.0;
pub const POROSITY: f64 = 0.3;

pub fn k0() -> f64 {
    POISSON / (1.0 - POISSON)
}

pub fn elastic() -> Material {
    elastic_material(YOUNG, POISSON, RHO_S, POROSITY)
}

/// Dry unit weight (kN/m³).
pub fn gamma() -> f64 {
    (1.0 - POROSITY) * RHO_S * G / 1000.0
}

/// Verifies the exact geostatic state of `model` and checks that it is the
/// discrete equilibrium: initial residual ratio and displacement below 1e-12.
#[track_caller]
pub fn verify_exact_geostatic(model: &AnuraModel, points: &[MaterialPoint]) -> RunReport {
    let states = geostatic_states(model, points, G, k0(), None);
    let report = verify(model, points, &states, &RunSettings::verify()).expect("valid model");
    assert!(
        report.initial_residual_ratio < 1e-12,
        "{}",
        report.initial_residual_ratio
    );
    assert!(
        report.max_displacement < 1e-12,
        "{}",
        report.max_displacement
    );
    report
}

/// Verifies the geostatic state of `model` with every stress 20 % low and
/// checks that the missing 20 % of the weight is out of balance at the first
/// step.
#[track_caller]
pub fn verify_twenty_percent_low(model: &AnuraModel, points: &[MaterialPoint]) -> RunReport {
    let mut states = geostatic_states(model, points, G, k0(), None);
    for s in &mut states {
        for c in &mut s.total {
            *c *= 0.8;
        }
    }
    let report = verify(model, points, &states, &RunSettings::verify()).expect("valid");
    let Verdict::NotInEquilibrium { reasons } = &report.verdict else {
        panic!("expected no equilibrium, got {:?}", report.verdict);
    };
    assert!(
        reasons.iter().any(
            |r| matches!(r, Reason::InitialResidual { ratio, .. } if (ratio - 0.2).abs() < 1e-6)
        ),
        "{reasons:?}"
    );
    report
}

/// Results of a run inside a rayon pool of `threads` threads.
pub fn run_in_pool(
    threads: usize,
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    settings: &RunSettings,
) -> RunOutput {
    super::random::in_pool(threads, || run(model, points, states, settings)).expect("valid")
}

/// Verifies `model` released from zero stress.
pub fn verify_from_zero(model: &AnuraModel, points: &[MaterialPoint]) -> RunReport {
    verify(model, points, &zero_states(points), &RunSettings::verify()).expect("valid")
}

/// Runs `model` from zero stress for 60 steps in pools of 1 and 2 threads and
/// checks that it moves and that both outputs are the same to the bit (JSON
/// text, shortest round-trip digits).
#[track_caller]
pub fn assert_zero_stress_runs_bit_identical(model: &AnuraModel, points: &[MaterialPoint]) {
    let states = zero_states(points);
    let settings = RunSettings {
        max_steps: 60,
        ..RunSettings::verify()
    };
    let one = run_in_pool(1, model, points, &states, &settings);
    let two = run_in_pool(2, model, points, &states, &settings);
    assert!(one.report.max_displacement > 0.0);
    let json = |o: &RunOutput| serde_json::to_string(o).expect("serialisable");
    assert_eq!(json(&one), json(&two));
}

/// Verifies `states` and checks that they are in equilibrium with an initial
/// residual ratio below `tolerance`.
#[track_caller]
pub fn verify_in_equilibrium(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    tolerance: f64,
) -> RunReport {
    let report = verify(model, points, states, &RunSettings::verify()).expect("valid");
    assert!(
        report.initial_residual_ratio < tolerance,
        "{}",
        report.initial_residual_ratio
    );
    assert!(report.verdict.is_equilibrium(), "{:?}", report.verdict);
    report
}
