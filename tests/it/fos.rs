//! Strength reduction (`mpm::fos`, issue #18) against closed-form stability
//! references: dry and seeping infinite slopes (periodic layers on a fixed
//! base) and the critical height of a vertical cut in a cohesive soil; and the
//! same factor on one and two threads.

use crate::common;

use a3d_init::model::{AnuraModel, MaterialPoint, MpState};
use a3d_init::mpm::{FosOutcome, FosReport, FosSettings, strength_reduction};
use a3d_testkit::{
    cut_geostatic_states, inclined_layer_tri3, infinite_slope_states, mohr_coulomb_material,
    place_points, saturated, vertical_cut_tri3,
};

const G: f64 = 9.81;

/// Slope angle and friction angle of the infinite-slope cases.
const BETA: f64 = 20.0;
const PHI: f64 = 35.0;
const THICKNESS: f64 = 1.0;

fn layer(saturated_soil: bool) -> (AnuraModel, Vec<MaterialPoint>, Vec<MpState>, FosSettings) {
    layer_with_dilatancy(saturated_soil, PHI)
}

/// A periodic layer 1 m thick (0.25 m long, 2 × 8 cells) at β = 20° on a
/// fixed base, φ′ = 35°, c′ = 0, with the exact infinite-slope stresses.
fn layer_with_dilatancy(
    saturated_soil: bool,
    dilatancy: f64,
) -> (AnuraModel, Vec<MaterialPoint>, Vec<MpState>, FosSettings) {
    // The limit-equilibrium references assume slip on planes parallel to the
    // surface with τ/σ′n = tan φ′ there: the continuum collapse state of an
    // associated material (ψ = φ′). With ψ = 0 the continuum fails at
    // τ/σ′n = sin φ′ instead (Davis 1968), which has its own test.
    let dry = mohr_coulomb_material(2e4, 0.3, 2650.0, 0.4, PHI, 0.0, dilatancy);
    // A seeping layer needs Anura3D's two-phase (coupled) analysis: its
    // one-phase drained analysis balances σ′ against the buoyant weight and
    // has no seepage force (`mpm::loading`).
    let material = if saturated_soil {
        a3d_init::model::Material {
            material_type: "saturated_material_coupled".into(),
            ..saturated(dry)
        }
    } else {
        dry
    };
    let (model, tied) = inclined_layer_tri3(BETA, THICKNESS, 0.25, 2, 8, material);
    let points = place_points(&model);
    let surface_y0 = THICKNESS / BETA.to_radians().cos();
    let states = infinite_slope_states(&model, &points, BETA, surface_y0, 1.0, G, saturated_soil);
    let settings = FosSettings {
        tied_nodes: tied,
        ..FosSettings::default()
    };
    (model, points, states, settings)
}

fn show(report: &FosReport) -> String {
    let trials: Vec<String> = report
        .trials
        .iter()
        .map(|t| {
            format!(
                "F={:.4} {:?} δ={:.3e} u={:.3e}",
                t.factor, t.end, t.measure, t.max_displacement
            )
        })
        .collect();
    format!(
        "F = {:.4} ({:?}, {} trials, W = {:.3} s)\n  {}",
        report.factor,
        report.outcome,
        report.iterations,
        report.window,
        trials.join("\n  ")
    )
}

/// Checks that the search bracketed a factor within `tolerance` (relative) of
/// `reference`, the value of `what`.
#[track_caller]
fn assert_bracketed_near(report: &FosReport, reference: f64, tolerance: f64, what: &str) {
    assert_eq!(report.outcome, FosOutcome::Bracketed);
    assert!(
        (report.factor / reference - 1.0).abs() < tolerance,
        "FS = {} vs {what} = {reference}\n{}",
        report.factor,
        show(report)
    );
}

/// Reference: dry cohesionless infinite slope, FS = tan φ′ / tan β
/// (e.g. Duncan, Wright & Brandon 2014, *Soil Strength and Slope Stability*,
/// §6.2). Within 5 %.
#[test]
fn dry_infinite_slope_matches_tan_phi_over_tan_beta() {
    let (model, points, states, settings) = layer(false);
    let report = strength_reduction(&model, &points, &states, &settings).unwrap();
    let reference = PHI.to_radians().tan() / BETA.to_radians().tan();
    assert_bracketed_near(&report, reference, 0.05, "tan φ′/tan β");
}

/// Reference: the same dry slope of a non-associated material (ψ = 0)
/// collapses in simple shear at τ/σ′n = sin φ′_F on planes parallel to the
/// surface (Davis 1968, "Theories of plasticity and the failure of soil
/// masses"): sin φ′_F = tan β, so FS = tan φ′ / tan(asin(tan β)). Within 5 %.
#[test]
fn non_associated_infinite_slope_matches_davis() {
    let (model, points, states, settings) = layer_with_dilatancy(false, 0.0);
    let report = strength_reduction(&model, &points, &states, &settings).unwrap();
    let reference = PHI.to_radians().tan() / BETA.to_radians().tan().asin().tan();
    assert_bracketed_near(&report, reference, 0.05, "tan φ′/tan(asin(tan β))");
}

/// Reference: cohesionless infinite slope with seepage parallel to the
/// surface and the water table at the surface, pore pressure
/// p = −γw·z·cos²β, in a coupled (two-phase) material whose total stress
/// σ′ + p carries the water: FS = (γ′/γsat)·tan φ′ / tan β (Duncan, Wright &
/// Brandon 2014, §6.2). Within 5 %.
#[test]
fn seeping_infinite_slope_matches_buoyant_ratio() {
    let (model, points, states, settings) = layer(true);
    let report = strength_reduction(&model, &points, &states, &settings).unwrap();
    let gamma_sat = model.materials[0].gamma_at_saturation(1.0, G);
    let gamma_buoyant = gamma_sat - a3d_init::model::gamma_water(G);
    let reference = gamma_buoyant / gamma_sat * PHI.to_radians().tan() / BETA.to_radians().tan();
    assert_bracketed_near(&report, reference, 0.05, "(γ′/γsat)·tan φ′/tan β");
}

/// A vertical cut of `height` in a Tresca soil (φ = 0, c, no tension
/// cut-off), 1.5 H of ground behind it, 1 H in front, a foundation 0.5 H
/// deep; K0 = 1 so that the level ground carries no deviatoric stress.
fn cut(
    height: f64,
    cohesion: f64,
    cell: f64,
) -> (AnuraModel, Vec<MaterialPoint>, Vec<MpState>, f64) {
    let mut material = mohr_coulomb_material(2e4, 0.3, 2650.0, 0.3, 0.0, cohesion, 0.0);
    material.tensile_strength = None;
    let (behind, front) = (1.5 * height, 1.0 * height);
    let model = vertical_cut_tri3(height, behind, front, 0.5 * height, cell, material);
    let points = place_points(&model);
    let states = cut_geostatic_states(&model, &points, height, behind, 1.0, G);
    (model, points, states, behind)
}

/// Reference: the critical height of a vertical cut in a purely cohesive soil
/// (φ = 0, no tension cut-off), Hc = 3.83·c/γ (Taylor 1948, *Fundamentals of
/// Soil Mechanics*, stability number Ns = 3.83 for a vertical face; the
/// limit-analysis bounds are 3.64 ≤ γHc/c ≤ 3.83, Pastor et al. 2000). A cut of
/// height H then has FS = 3.83·c/(γH). Within 10 %.
#[test]
fn vertical_cut_matches_critical_height() {
    let (height, cohesion) = (2.0, 10.0);
    let (model, points, states, behind) = cut(height, cohesion, 0.2);
    let report = strength_reduction(&model, &points, &states, &FosSettings::default()).unwrap();
    let gamma = model.materials[0].gamma_at_saturation(1.0, G);
    let reference = 3.83 * cohesion / (gamma * height);
    assert_bracketed_near(&report, reference, 0.10, "3.83 c/(γH)");
    let mechanism = report.mechanism.as_ref().unwrap();
    assert!(mechanism.factor > report.factor);
    // The mechanism is at the face: the MPs in motion lie near the cut.
    let moving: Vec<&[f64; 3]> = points
        .iter()
        .zip(&mechanism.in_motion)
        .filter(|(_, m)| **m)
        .map(|(p, _)| &p.position)
        .collect();
    assert!(!moving.is_empty());
    assert!(
        moving
            .iter()
            .all(|p| p[0] > behind - 1.5 * height && p[1] > -0.5 * height),
        "moving MPs far from the cut"
    );
}

/// The same inputs give the same factor, trial by trial, on one and on two
/// threads (the runner sums in a fixed order). The model has more than two
/// rayon chunks of MPs, so two threads do split the work.
#[test]
fn same_factor_on_one_and_two_threads() {
    let (model, points, states, _) = cut(2.0, 10.0, 0.25);
    assert!(points.len() > 2048);
    let settings = FosSettings {
        tolerance: 0.05,
        ..FosSettings::default()
    };
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| strength_reduction(&model, &points, &states, &settings).unwrap())
    };
    let (one, two) = (on(1), on(2));
    assert_eq!(one.factor.to_bits(), two.factor.to_bits());
    assert_eq!(one.trials, two.trials);
    assert_eq!(one.mechanism, two.mechanism);
}

/// Materials that are not Mohr–Coulomb keep their strength and are named;
/// a model without any Mohr–Coulomb material is an error.
#[test]
fn elastic_materials_are_left_alone_and_named() {
    use a3d_init::mpm::FosError;
    use a3d_testkit::{column_tri3, elastic_material, geostatic_states};
    let model = column_tri3(1.0, 1.0, 2, 2, elastic_material(1e4, 0.3, 2650.0, 0.4));
    let points = place_points(&model);
    let states = geostatic_states(&model, &points, G, 0.43, None);
    let error = strength_reduction(&model, &points, &states, &FosSettings::default());
    assert_eq!(error.unwrap_err(), FosError::NothingToReduce);

    // The layer of the dry slope on an elastic base element row: the base
    // material is named, the slope's factor is unchanged in substance.
    let (mut model, points, states, settings) = layer(false);
    let mut base = elastic_material(2e4, 0.3, 2650.0, 0.4);
    base.index = 2;
    base.name = "base".into();
    model.materials.push(base);
    let mut points = points;
    let lowest = points
        .iter()
        .map(|p| p.position[1] + p.position[0] * BETA.to_radians().tan())
        .fold(f64::INFINITY, f64::min);
    for p in &mut points {
        if p.position[1] + p.position[0] * BETA.to_radians().tan() < lowest + 0.05 {
            p.material = 2;
        }
    }
    let settings = FosSettings {
        tolerance: 0.05,
        ..settings
    };
    let report = strength_reduction(&model, &points, &states, &settings).unwrap();
    assert_eq!(report.reduced_materials.len(), 1);
    assert_eq!(report.unreduced_materials.len(), 1);
    assert_eq!(report.unreduced_materials[0].name, "base");
    assert_eq!(report.unreduced_materials[0].model, "linear_elasticity");
}

/// `a3d-init fos` without inputs is a usage error (exit 2) that says what to
/// give; `verify --fos` takes the same route.
#[test]
fn fos_command_without_inputs_is_a_usage_error() {
    for args in [vec!["fos"], vec!["verify", "--fos"]] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_a3d-init"))
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.contains("give a folder written by `map`"),
            "{stderr}"
        );
    }
}

/// Smoothness (#31): the seeping layer with every pore pressure 1 % higher.
/// Limit equilibrium moves the factor by (γsat − 1.01 γw)/(γsat − γw) − 1
/// (about −1 %); strength reduction must move it by as much, within half a
/// percentage point, and never by the 5–10 % jumps of a settle/does-not-
/// settle criterion on a start out of balance.
#[test]
fn one_percent_more_pore_pressure_moves_the_factor_by_about_one_percent() {
    let (model, points, states, settings) = layer(true);
    let settings = FosSettings {
        tolerance: 0.002,
        ..settings
    };
    let wetter: Vec<MpState> = states
        .iter()
        .map(|s| MpState {
            pwp: 1.01 * s.pwp,
            ..*s
        })
        .collect();
    let base = strength_reduction(&model, &points, &states, &settings).unwrap();
    let wet = strength_reduction(&model, &points, &wetter, &settings).unwrap();
    let gamma_sat = model.materials[0].gamma_at_saturation(1.0, G);
    let gamma_w = a3d_init::model::gamma_water(G);
    let expected = (gamma_sat - 1.01 * gamma_w) / (gamma_sat - gamma_w) - 1.0;
    let change = wet.factor / base.factor - 1.0;
    assert!(
        (change - expected).abs() < 0.005,
        "FS {:.4} → {:.4}: {:+.2} % against {:+.2} %\n{}\n{}",
        base.factor,
        wet.factor,
        100.0 * change,
        100.0 * expected,
        show(&base),
        show(&wet)
    );
}

/// Density scaling (#39): the slope's layer on a base twenty times stiffer.
/// Unscaled, the base sets the time step; scaled, every MP moves at the
/// layer's wave speed (the base's inertia raised, its weight kept), so the
/// step is several times longer, and the factor, a property of the state at
/// rest, is the same within the bracket's tolerance.
#[test]
fn density_scaling_keeps_the_factor_with_a_longer_step() {
    use a3d_testkit::elastic_material;
    let (mut model, mut points, states, settings) = layer(false);
    let mut base = elastic_material(4e5, 0.3, 2650.0, 0.4);
    base.index = 2;
    base.name = "stiff_base".into();
    model.materials.push(base);
    let tan = BETA.to_radians().tan();
    let lowest = points
        .iter()
        .map(|p| p.position[1] + p.position[0] * tan)
        .fold(f64::INFINITY, f64::min);
    for p in &mut points {
        if p.position[1] + p.position[0] * tan < lowest + 0.05 {
            p.material = 2;
        }
    }
    let run = |scaled: bool| {
        let mut s = settings.clone();
        s.run.mass_scaling = scaled;
        strength_reduction(&model, &points, &states, &s).unwrap()
    };
    let (plain, scaled) = (run(false), run(true));
    assert!(
        scaled.time_step > 3.0 * plain.time_step,
        "time step {} scaled against {}",
        scaled.time_step,
        plain.time_step
    );
    assert_eq!(
        scaled.window, plain.window,
        "the window is the physical one"
    );
    assert!(
        (scaled.factor - plain.factor).abs() <= 2.0 * settings.tolerance,
        "scaled {} against {}",
        show(&scaled),
        show(&plain)
    );
    let reference = PHI.to_radians().tan() / tan;
    assert_bracketed_near(&scaled, reference, 0.05, "tan φ′/tan β on a stiff base");
}

/// ACADS 1(a) (`fixtures/acads-1a/`, c′ = 3 kPa, φ′ = 19.6°, referee 1.00),
/// mapped dry and run by `fos --method srm` as docs/slope-stability.md gives
/// the commands: the four measures agree within 1 % (limit equilibrium,
/// strength reduction, the equilibrium solve), the Davis variant lies below,
/// and the table quotes what the run gives (#39).
#[test]
fn four_measures_on_acads_1a_agree_and_are_the_docs_table() {
    let tmp = tempfile::tempdir().unwrap();
    let mapped = tmp.path().join("acads-1a");
    let fixture = common::fixture("acads-1a");
    let (code, out) = common::run_map(&fixture, &fixture.join("nodes.csv"), &mapped, &[]);
    assert_eq!(code, 0, "{out}");
    let srm = tmp.path().join("fos");
    let (text, fos) = common::fos(&mapped, &srm, &["--method", "srm"]);
    let c = &fos["comparison"];
    let le = c["limit_equilibrium"].as_f64().unwrap();
    let solve = c["equilibrium_solve"]["holds"].as_f64().unwrap();
    let factor = fos["factor"].as_f64().unwrap();
    for (name, f) in [("strength reduction", factor), ("equilibrium solve", solve)] {
        assert!(
            (f / le - 1.0).abs() < 0.01,
            "{name} {f} against limit equilibrium {le}: {text}"
        );
    }
    assert!(
        c["limit_equilibrium_davis"].as_f64().unwrap() < factor,
        "{text}"
    );
    common::assert_four_measures_quoted("ACADS 1(a)", &srm.join("fos.json"));
}

/// `fixtures/slope/ogs/fos_vs_time.csv` is what docs/slope.md's table and
/// the OGS README quote, and its 1.2 h row is what `map` then
/// `fos --method srm` give now, as `fos_vs_time.sh` runs them (#39).
#[test]
fn fos_vs_time_table_is_the_csv_and_its_row_reruns() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let csv = std::fs::read_to_string(root.join("fixtures/slope/ogs/fos_vs_time.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let cell = |v: &str| match v.parse::<f64>() {
        Ok(x) => format!("{x:.3}"),
        Err(_) => "—".to_string(),
    };
    let docs = std::fs::read_to_string(root.join("docs/slope.md")).unwrap();
    for row in &rows {
        let quoted = format!(
            "| {} | {} | {} / {} | {} | {} | {} | {} |",
            row[col("t_h")],
            cell(row[col("fs")]),
            cell(row[col("fs_lower")]),
            cell(row[col("fs_upper")]),
            cell(row[col("le")]),
            cell(row[col("le_davis")]),
            cell(row[col("equilibrium_solve")]),
            row[col("equilibrium")].to_lowercase()
        );
        assert!(
            docs.contains(&quoted),
            "docs/slope.md should quote `{quoted}`"
        );
    }
    let at = |t: &str| rows.iter().find(|r| r[0] == t).unwrap();
    let readme = std::fs::read_to_string(root.join("fixtures/slope/ogs/README.md")).unwrap();
    let fs = |t: &str| cell(at(t)[col("fs")]);
    let quoted = format!(
        "reduction {} at 0.5 h, {} at 1.2 h, first below 1 at 1.27 h ({}; {} at 1.26 h),\n{} at 1.4 h",
        fs("0.5"),
        fs("1.2"),
        fs("1.27"),
        fs("1.26"),
        fs("1.4")
    );
    assert!(
        readme.contains(&quoted),
        "the OGS README should quote `{quoted}`"
    );

    let tmp = tempfile::tempdir().unwrap();
    let mapped = tmp.path().join("t1.2");
    let ogs = common::fixture("slope/ogs/results/rain.pvd");
    let extra = ["--step", "time=1.2h", "--material-map", "mat0=silty_sand"];
    let (code, out) = common::run_map(&common::fixture("slope"), &ogs, &mapped, &extra);
    assert_eq!(code, 0, "{out}");
    let (_, fos) = common::fos(&mapped, &tmp.path().join("fos"), &["--method", "srm"]);
    let c = &fos["comparison"];
    let row = at("1.2");
    for (name, value) in [
        ("fs", fos["factor"].as_f64()),
        ("le", c["limit_equilibrium"].as_f64()),
        ("le_davis", c["limit_equilibrium_davis"].as_f64()),
        (
            "equilibrium_solve",
            c["equilibrium_solve"]["holds"].as_f64(),
        ),
    ] {
        assert_eq!(
            format!("{:.4}", value.unwrap()),
            row[col(name)],
            "fos_vs_time.csv's 1.2 h {name} drifted from the run"
        );
    }
}
