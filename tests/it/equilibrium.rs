//! Start in equilibrium (#25): the equilibrium solve against closed forms
//! (a flat layered column gives σ'v = γ'·depth and σ'h = K0·σ'v with the
//! K0-consistent ν; a column with a water table holds its pore pressures), an
//! elastic embankment whose residual is round-off and whose stresses converge
//! under refinement, a Mohr–Coulomb slope that needs plastic iterations, a
//! slope too steep to stand (no equilibrium, named), and the runner's own
//! first step agreeing that the solved state is balanced. The CLI side
//! (`--stress equilibrium`, `auto`, exit 1, report.json, verify) and the real
//! Anura3D kernel (several hundred undamped steps, where built) are at the end.

use crate::common;
use common::kernel_run::kernel_displacement;
use common::*;

use std::path::{Path, PathBuf};

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::model::{AnuraModel, ComputationMethod, Material, MaterialPoint, MpState};
use a3d_init::mpm::equilibrium::{self, EquilibriumOutcome, EquilibriumSettings};
use a3d_init::mpm::{Elasticity, ReturnMap, RunSettings, Simulation, SolidModel};
use a3d_testkit::generate::{self, MaterialSpec};

const G: f64 = 9.81;

fn spec(name: &str, mohr_coulomb: Option<(f64, f64, f64)>, water: bool) -> MaterialSpec {
    MaterialSpec {
        name: name.into(),
        porosity: 0.4,
        density_solid: 2650.0,
        density_liquid: water.then_some(1000.0),
        k0: 0.5,
        young_modulus: 2e4,
        poisson_ratio: 0.3,
        mohr_coulomb,
        retention: None,
        permeability: 1e-10,
    }
}

/// The solve's law of `m` with ν = K0/(1 + K0).
fn k0_law(m: &Material) -> SolidModel {
    let k0 = m.k0.unwrap();
    let elasticity = Elasticity::from_young_poisson(m.young_modulus.unwrap(), k0 / (1.0 + k0))
        .expect("valid elasticity");
    let gom = SolidModel::from_material(m).expect("supported material");
    SolidModel {
        elasticity,
        plasticity: gom
            .plasticity
            .map(|r| ReturnMap::new(r.criterion, elasticity)),
    }
}

fn laws(model: &AnuraModel) -> Vec<Option<SolidModel>> {
    model.materials.iter().map(|m| Some(k0_law(m))).collect()
}

fn points(model: &AnuraModel) -> Vec<MaterialPoint> {
    a3d_init::place::place_material_points_for(model, ComputationMethod::MpmMp).expect("placed")
}

fn dry_states(points: &[MaterialPoint]) -> Vec<MpState> {
    a3d_testkit::zero_states(points)
}

fn solve(model: &AnuraModel, points: &[MaterialPoint], states: &[MpState]) -> EquilibriumOutcome {
    equilibrium::solve(
        model,
        points,
        states,
        &laws(model),
        &EquilibriumSettings::default(),
    )
    .expect("solved")
}

/// The runner's out-of-balance ratio at its first step from `effective`
/// stresses with the pore state of `states`.
fn runner_ratio(
    model: &AnuraModel,
    points: &[MaterialPoint],
    states: &[MpState],
    effective: &[[f64; 6]],
) -> f64 {
    let started: Vec<MpState> = states
        .iter()
        .zip(effective)
        .map(|(s, e)| {
            let mut total = *e;
            for v in total.iter_mut().take(3) {
                *v += s.saturation * s.pwp;
            }
            MpState { total, ..*s }
        })
        .collect();
    let mut sim = Simulation::new(model, points, &started, &RunSettings::verify()).expect("runs");
    sim.step().residual_ratio
}

/// Volume-weighted means of σ'yy and σ'xx (σ'zz in 3D) over the MPs of
/// each 0.5 m row of a column, bottom row first.
fn row_means(
    points: &[MaterialPoint],
    effective: &[[f64; 6]],
    rows: usize,
    lateral: usize,
) -> Vec<(f64, f64)> {
    let mut sums = vec![(0.0, 0.0, 0.0); rows];
    for (p, s) in points.iter().zip(effective) {
        let row = ((p.position[1] / 0.5).floor() as usize).min(rows - 1);
        sums[row].0 += p.volume * s[1];
        sums[row].1 += p.volume * s[lateral];
        sums[row].2 += p.volume;
    }
    sums.iter().map(|(v, h, w)| (v / w, h / w)).collect()
}

/// A two-layer column (8 rows of 0.5 m; the lower 4 denser, K0 0.6 below
/// and 0.5 above), sides on rollers. Each row's mean σ'v is the overburden to
/// the row's mid-height to round-off (the discrete vertical balance of
/// everything above a horizontal cut), and its mean σ'h is K0·σ'v, with K0
/// from the K0-consistent ν, to the discretisation's 1e-2 (exact in the
/// continuum: flat ground under gravity loading reproduces K0). The runner's
/// first step agrees that the state is balanced.
#[test]
fn flat_layered_column_gives_the_overburden_and_k0() {
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 2.0, 4.0, 4, 8);
    let mut model = generate::single_material_model(mesh, &spec("upper", None, false), 3);
    let mut lower = generate::material(2, &spec("lower", None, false));
    lower.density_solid = Some(3000.0);
    lower.k0 = Some(0.6);
    model.materials.push(lower);
    for e in 0..model.mesh.n_elements() {
        if e / 8 < 4 {
            model.element_material[e] = 2;
        }
    }
    let points = points(&model);
    let states = dry_states(&points);
    let out = solve(&model, &points, &states);
    assert!(out.equilibrium && out.residual_ratio < 1e-12, "{out:?}");
    assert_eq!(out.plastic_iterations, 0);
    let gamma = |m: usize| model.materials[m - 1].gamma_dry(G);
    for (row, (v, h)) in row_means(&points, &out.effective, 8, 0)
        .into_iter()
        .enumerate()
    {
        let material = if row < 4 { 2 } else { 1 };
        let above: f64 = ((row + 1)..8)
            .map(|r| 0.5 * gamma(if r < 4 { 2 } else { 1 }))
            .sum();
        let expect = -(above + 0.25 * gamma(material));
        assert!(
            (v - expect).abs() < 1e-9 * expect.abs(),
            "row {row}: {v} vs {expect}"
        );
        let k0 = model.materials[material - 1].k0.unwrap();
        assert!((h / v - k0).abs() < 1e-2, "row {row}: σ'h/σ'v = {}", h / v);
    }
    assert!(runner_ratio(&model, &points, &states, &out.effective) < 1e-12);
}

/// A 3D column (tetrahedral_old): the rows' mean σ'v is the overburden, and
/// σ'h = K0·σ'v in both horizontal directions.
#[test]
fn flat_tet_column_gives_k0_in_both_directions() {
    let mesh = generate::structured_tet_mesh(2.0, 0.0, 2.0, 2.0, 4, 4, 4);
    let model = generate::single_material_model(mesh, &spec("soil", None, false), 4);
    let points = points(&model);
    let states = dry_states(&points);
    let out = solve(&model, &points, &states);
    assert!(out.equilibrium && out.residual_ratio < 1e-12, "{out:?}");
    let gamma = model.materials[0].gamma_dry(G);
    for lateral in [0, 2] {
        for (row, (v, h)) in row_means(&points, &out.effective, 4, lateral)
            .into_iter()
            .enumerate()
        {
            let expect = -gamma * (2.0 - (0.5 * row as f64 + 0.25));
            assert!(
                (v - expect).abs() < 1e-9 * expect.abs(),
                "row {row}: {v} vs {expect}"
            );
            assert!((h / v - 0.5).abs() < 2e-2, "row {row}: σ'h/σ'v = {}", h / v);
        }
    }
    assert!(runner_ratio(&model, &points, &states, &out.effective) < 1e-12);
}

/// A 2D-axisymmetric hollow cylinder (radii 1 to 3 m, 4 m high, rollers
/// on both radii): balanced in the runner's equations with per-MP hoop
/// terms (MPM-MP) and with one integration point per element carrying the
/// element's mean hoop term (MPM-MIXED, all MPs holding one state); the rows'
/// mean σ'v is the overburden.
#[test]
fn axisymmetric_cylinder_is_balanced_per_mp_and_per_element() {
    let mut mesh = generate::structured_tri_mesh(1.0, 0.0, 2.0, 4.0, 4, 8);
    mesh.dimension = a3d_init::model::Dimension::Axisymmetric;
    let model = generate::single_material_model(mesh, &spec("soil", None, false), 3);
    let points = points(&model);
    let states = dry_states(&points);
    let gamma = model.materials[0].gamma_dry(G);
    for mixed in [false, true] {
        let settings = EquilibriumSettings {
            mixed,
            ..EquilibriumSettings::default()
        };
        let out = equilibrium::solve(&model, &points, &states, &laws(&model), &settings).unwrap();
        assert!(out.equilibrium && out.residual_ratio < 1e-12, "{out:?}");
        assert!(runner_ratio(&model, &points, &states, &out.effective) < 1e-12);
        let means = row_means(&points, &out.effective, 8, 0);
        // Volumes are per radian: the row means weigh by radius, and the
        // overburden holds for every radius of a confined column.
        for (row, (v, h)) in means.into_iter().enumerate() {
            let expect = -gamma * (4.0 - (0.5 * row as f64 + 0.25));
            assert!(
                (v - expect).abs() < 1e-3 * expect.abs(),
                "mixed {mixed} row {row}: {v}"
            );
            assert!((h / v - 0.5).abs() < 2e-2, "row {row}: σ'h/σ'v = {}", h / v);
        }
    }
}

/// Hydrostatic pore pressure below a water table at y = 3 m in a 4 m column.
fn water_table_states(points: &[MaterialPoint], saturation: f64) -> Vec<MpState> {
    points
        .iter()
        .map(|p| MpState {
            pwp: -G * (3.0 - p.position[1]).max(0.0),
            total: [0.0; 6],
            saturation,
        })
        .collect()
}

/// A column with a water table, pore pressures held. One-phase
/// (saturated_material_drained): Anura3D balances σ' against the buoyant
/// weight, so σ'v = −γ_sub·depth at the rows' mid-heights whatever the pore
/// pressure, and the total stress written is σ' + S·p. Multiphase
/// (saturated_material_coupled): Bishop's total stress balances the
/// saturated weight, σv = −γ_sat·depth and σ' = σ − p.
#[test]
fn column_with_a_water_table_holds_its_pore_pressures() {
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 1.0, 4.0, 2, 8);
    let mut model = generate::single_material_model(mesh, &spec("soil", None, true), 3);
    let points = points(&model);
    let states = water_table_states(&points, 1.0);
    let out = solve(&model, &points, &states);
    assert!(out.equilibrium && out.residual_ratio < 1e-12, "{out:?}");
    let sat = model.materials[0].gamma_at_saturation(1.0, G);
    let sub = sat - G;
    for (row, (v, _)) in row_means(&points, &out.effective, 8, 0)
        .into_iter()
        .enumerate()
    {
        let depth = 4.0 - (0.5 * row as f64 + 0.25);
        assert!(
            (v + sub * depth).abs() < 1e-9 * sub * depth,
            "row {row}: {v}"
        );
    }
    assert!(runner_ratio(&model, &points, &states, &out.effective) < 1e-12);

    model.materials[0].material_type = "saturated_material_coupled".into();
    let out = solve(&model, &points, &states);
    assert!(out.equilibrium && out.residual_ratio < 1e-12, "{out:?}");
    // Each row's mean total stress σ'yy + p is the saturated overburden.
    let totals: Vec<[f64; 6]> = out
        .effective
        .iter()
        .zip(&states)
        .map(|(e, st)| [0.0, e[1] + st.pwp, 0.0, 0.0, 0.0, 0.0])
        .collect();
    for (row, (v, _)) in row_means(&points, &totals, 8, 0).into_iter().enumerate() {
        let depth = 4.0 - (0.5 * row as f64 + 0.25);
        assert!(
            (v + sat * depth).abs() < 1e-9 * sat * depth,
            "row {row}: {v}"
        );
    }
    assert!(runner_ratio(&model, &points, &states, &out.effective) < 1e-12);
}

/// A 2D slope (embankment face) of `nx` × `ny` cells, 10 m wide, crest 5 m
/// for x ≤ 3, toe `toe` m for x ≥ 7.
fn slope_model(nx: usize, ny: usize, toe: f64, material: &MaterialSpec) -> AnuraModel {
    let mut mesh = generate::structured_tri_mesh(0.0, 0.0, 10.0, 5.0, nx, ny);
    generate::slope_profile(&mut mesh, 5.0, 5.0, toe, 3.0, 7.0);
    generate::single_material_model(mesh, material, 3)
}

/// The mean σ'yy of the MPs within 0.5 m of (x, y).
fn stress_near(points: &[MaterialPoint], effective: &[[f64; 6]], x: f64, y: f64) -> f64 {
    let near: Vec<f64> = points
        .iter()
        .zip(effective)
        .filter(|(p, _)| (p.position[0] - x).hypot(p.position[1] - y) < 0.5)
        .map(|(_, s)| s[1])
        .collect();
    near.iter().sum::<f64>() / near.len() as f64
}

/// An elastic embankment: the residual is round-off (≤ 1e-9 of the load) and
/// the stresses converge under refinement of the same discrete system (the
/// change from a 2× to a 4× finer mesh is smaller than from 1× to 2×).
#[test]
fn elastic_embankment_is_balanced_and_converges() {
    let material = spec("fill", None, false);
    let mut near = Vec::new();
    for k in [1, 2, 4] {
        let model = slope_model(10 * k, 5 * k, 1.0, &material);
        let points = points(&model);
        let states = dry_states(&points);
        let out = solve(&model, &points, &states);
        assert!(out.equilibrium && out.residual_ratio < 1e-9, "{out:?}");
        assert!(runner_ratio(&model, &points, &states, &out.effective) < 1e-9);
        near.push(stress_near(&points, &out.effective, 5.0, 1.5));
    }
    let (d1, d2) = ((near[1] - near[0]).abs(), (near[2] - near[1]).abs());
    assert!(d2 < d1, "σ'yy near (5, 1.5): {near:?}");
}

/// A Mohr–Coulomb slope whose elastic state yields: plastic iterations reach
/// the tolerance with every MP on or inside its surface, and the runner's
/// first step agrees.
#[test]
fn mohr_coulomb_slope_needs_plastic_iterations() {
    let material = spec("sand", Some((30.0, 2.0, 0.0)), false);
    let model = slope_model(20, 10, 1.0, &material);
    let points = points(&model);
    let states = dry_states(&points);
    let out = solve(&model, &points, &states);
    assert!(out.equilibrium, "{out:?}");
    assert!(
        out.plastic_iterations > 0 && out.yielding_points > 0,
        "{out:?}"
    );
    assert!(out.residual_ratio < 1e-6, "{out:?}");
    let gom = SolidModel::from_material(&model.materials[0]).unwrap();
    for s in &out.effective {
        assert!(gom.is_admissible(s, true), "{s:?}");
    }
    assert!(runner_ratio(&model, &points, &states, &out.effective) < 1e-6);
}

/// A slope of cohesionless sand at 51° (φ' = 25°) cannot stand: no
/// equilibrium, the gravity multiplier it holds is below 1, and the elements
/// that keep yielding are named.
#[test]
fn slope_too_steep_to_stand_is_reported() {
    let material = spec("sand", Some((25.0, 0.0, 0.0)), false);
    let mut mesh = generate::structured_tri_mesh(0.0, 0.0, 10.0, 5.0, 20, 10);
    generate::slope_profile(&mut mesh, 5.0, 5.0, 0.5, 3.0, 6.6);
    let model = generate::single_material_model(mesh, &material, 3);
    let points = points(&model);
    let states = dry_states(&points);
    let settings = EquilibriumSettings {
        max_iterations: 800,
        ..EquilibriumSettings::default()
    };
    let out = equilibrium::solve(&model, &points, &states, &laws(&model), &settings).unwrap();
    assert!(!out.equilibrium, "{out:?}");
    assert!(out.load_factor < 1.0, "{out:?}");
    assert!(out.yielding_points > 0 && !out.yielding_elements.is_empty());
    assert!(out.residual_ratio > 1e-6);
}

/// The solve is deterministic: the same stresses to the bit in pools of one
/// and two threads.
#[test]
fn solve_is_bit_identical_for_any_thread_count() {
    let material = spec("sand", Some((30.0, 2.0, 0.0)), false);
    let model = slope_model(16, 8, 1.0, &material);
    let points = points(&model);
    let states = dry_states(&points);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| solve(&model, &points, &states).effective)
    };
    assert_eq!(run(1), run(2));
}

// ---- the command line -------------------------------------------------

/// A project folder with `model` (GOM 2023), a CPS with `method`, and a
/// hydrostatic FEM table (water table at y = `water_table`) beside it.
fn project(dir: &Path, model: &AnuraModel, method: &str, water_table: f64) -> (PathBuf, PathBuf) {
    let folder = dir.join("model");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(folder.join("slope.GOM"), model_to_text(model, "2023")).unwrap();
    std::fs::write(
        folder.join("slope.CPS_001"),
        format!(
            "### Anura3D_2023 ###\n$$COMPUTATION_METHOD\n{method}\n$$GRAVITY_ACCELERATION\n9.81\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75\n$$END\n"
        ),
    )
    .unwrap();
    let fem = dir.join("seep.csv");
    let (lo, hi) = model.mesh.bounding_box();
    let three_d = model.mesh.dimension.n_dim() == 3;
    let mut csv = String::from(if three_d { "X,Y,Z,PWP\n" } else { "X,Y,PWP\n" });
    let (n, nz) = if three_d { (20, 4) } else { (40, 0) };
    for k in 0..=nz {
        for j in 0..=n {
            for i in 0..=n {
                let x = lo[0] + (hi[0] - lo[0]) * i as f64 / n as f64;
                let y = lo[1] + (hi[1] - lo[1]) * j as f64 / n as f64;
                let pwp = (G * (water_table - y)).max(0.0);
                if three_d {
                    let z = lo[2] + (hi[2] - lo[2]) * k as f64 / nz as f64;
                    csv.push_str(&format!("{x},{y},{z},{pwp}\n"));
                } else {
                    csv.push_str(&format!("{x},{y},{pwp}\n"));
                }
            }
        }
    }
    std::fs::write(&fem, csv).unwrap();
    (folder, fem)
}

fn report(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap()
}

/// `map --stress equilibrium` on a saturated slope: report.json names each
/// material's ν and where it came from, the residual reached and the
/// iterations; verify says IN EQUILIBRIUM with a ratio below 1e-6. `auto`
/// chooses equilibrium on this slope and says why; on flat ground it keeps
/// the geostatic stress.
#[test]
fn map_stress_equilibrium_is_verified() {
    let tmp = tempfile::tempdir().unwrap();
    let model = slope_model(20, 10, 1.0, &spec("soil", None, true));
    let (folder, fem) = project(tmp.path(), &model, "MPM-MIXED", 2.0);
    let out = tmp.path().join("eq");
    let (code, text) = run_map(&folder, &fem, &out, &["--stress", "equilibrium"]);
    assert_eq!(code, 0, "{text}");
    assert_contains(&text, &["equilibrium: IN EQUILIBRIUM"]);
    let r = report(&out);
    assert_eq!(r["stress_source"], "equilibrium");
    let e = &r["equilibrium"];
    assert_eq!(e["equilibrium"], true);
    assert!(e["residual_ratio"].as_f64().unwrap() < 1e-9);
    assert_eq!(e["materials"][0]["poisson_from"], "k0");
    assert!((e["materials"][0]["poisson_ratio"].as_f64().unwrap() - 0.5 / 1.5).abs() < 1e-12);
    assert_eq!(e["chosen_because"], "requested");
    let text = verify_ok(&out);
    assert_contains(&text, &["IN EQUILIBRIUM"]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("verify/verify.json")).unwrap())
            .unwrap();
    assert!(v["run"]["initial_residual_ratio"].as_f64().unwrap() < 1e-6);

    // --no-k0-consistent: the GOM's ν.
    let gom_nu = tmp.path().join("gom-nu");
    let (code, text) = run_map(
        &folder,
        &fem,
        &gom_nu,
        &["--stress", "equilibrium", "--no-k0-consistent"],
    );
    assert_eq!(code, 0, "{text}");
    let e = &report(&gom_nu)["equilibrium"];
    assert_eq!(e["materials"][0]["poisson_from"], "gom");
    assert_eq!(e["materials"][0]["poisson_ratio"], 0.3);

    // auto: equilibrium on the slope, saying why.
    let auto = tmp.path().join("auto");
    let (code, text) = run_map(&folder, &fem, &auto, &[]);
    assert_eq!(code, 0, "{text}");
    let r = report(&auto);
    assert_eq!(r["stress_source"], "equilibrium");
    assert_contains(
        &r["equilibrium"]["chosen_because"].to_string(),
        &["auto: the FEM gives pore pressure only and the ground surface is not flat"],
    );
}

/// A 3D Mohr–Coulomb slope through the command line: the solve needs plastic
/// iterations, and `verify` finds the folder IN EQUILIBRIUM with a ratio below
/// 1e-3 and no MP outside its surface in the intended state (3D: no σ'zz
/// defect).
#[test]
fn mohr_coulomb_3d_slope_is_verified_in_equilibrium() {
    let tmp = tempfile::tempdir().unwrap();
    let mut mesh = generate::structured_tet_mesh(10.0, 0.0, 5.0, 2.0, 10, 5, 2);
    generate::slope_profile(&mut mesh, 5.0, 5.0, 2.0, 3.0, 7.0);
    let model =
        generate::single_material_model(mesh, &spec("sand", Some((30.0, 2.0, 0.0)), false), 4);
    let (folder, fem) = project(tmp.path(), &model, "MPM-MIXED", -1.0);
    let out = tmp.path().join("out");
    let (code, text) = run_map(&folder, &fem, &out, &["--stress", "equilibrium"]);
    assert_eq!(code, 0, "{text}");
    let e = &report(&out)["equilibrium"];
    assert!(e["plastic_iterations"].as_u64().unwrap() > 0, "{e}");
    assert!(e["yielding_points"].as_u64().unwrap() > 0, "{e}");
    let text = verify_ok(&out);
    assert_contains(&text, &["verdict    IN EQUILIBRIUM"]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("verify/verify.json")).unwrap())
            .unwrap();
    assert!(v["run"]["initial_residual_ratio"].as_f64().unwrap() < 1e-3);
    assert_eq!(v["anura3d"]["intended_outside_yield"], 0);
    assert_eq!(v["run"]["inadmissible_points"], 0);
}

/// `auto` on flat ground keeps the geostatic stress, says why, and writes
/// no `equilibrium` field.
#[test]
fn auto_keeps_geostatic_on_flat_ground() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 4.0, 4.0, 4, 4);
    let model = generate::single_material_model(mesh, &spec("soil", None, true), 3);
    let (folder, fem) = project(tmp.path(), &model, "MPM-MP", 3.0);
    let out = tmp.path().join("out");
    let (code, text) = run_map(&folder, &fem, &out, &[]);
    assert_eq!(code, 0, "{text}");
    let r = report(&out);
    assert_eq!(r["stress_source"], "geostatic");
    assert!(r.get("equilibrium").is_none());
    assert!(
        r["notes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n.as_str().unwrap().contains("the ground surface is flat")),
        "{r}"
    );
}

/// A slope too steep to stand: `map --stress equilibrium` exits 1, still
/// writes the folder with the verdict (NO EQUILIBRIUM, the gravity multiplier
/// held, the elements that keep yielding) in report.json; `--stress auto`
/// exits 0 with the same folder; the state written is no further out of
/// balance than the geostatic one.
#[test]
fn map_exits_1_when_no_equilibrium_exists() {
    let tmp = tempfile::tempdir().unwrap();
    let mut mesh = generate::structured_tri_mesh(0.0, 0.0, 10.0, 5.0, 20, 10);
    generate::slope_profile(&mut mesh, 5.0, 5.0, 0.5, 3.0, 6.6);
    let model =
        generate::single_material_model(mesh, &spec("sand", Some((25.0, 0.0, 0.0)), false), 3);
    let (folder, fem) = project(tmp.path(), &model, "MPM-MP", -1.0);
    let out = tmp.path().join("out");
    let (code, text) = run_map(&folder, &fem, &out, &["--stress", "equilibrium"]);
    assert_eq!(code, 1, "{text}");
    assert_contains(&text, &["NO EQUILIBRIUM"]);
    let e = &report(&out)["equilibrium"];
    assert_eq!(e["equilibrium"], false);
    assert!(e["load_factor"].as_f64().unwrap() < 1.0);
    assert!(!e["yielding_elements"].as_array().unwrap().is_empty());
    assert!(out.join("slope.MAPF").is_file());

    // #39: under `--stress auto` (which chooses the solve on this slope) a
    // slope that cannot stand is a finding: exit 0, the same warning, the
    // same folder, so that a script goes on to `verify`.
    let auto = tmp.path().join("auto");
    let (code, text) = run_map(&folder, &fem, &auto, &["--stress", "auto"]);
    assert_eq!(code, 0, "{text}");
    assert_contains(
        &text,
        &["NO EQUILIBRIUM (a finding, exit 0 under --stress auto)"],
    );
    assert_eq!(report(&auto)["equilibrium"]["equilibrium"], false);
    assert_eq!(
        std::fs::read(auto.join("slope.MAPF")).unwrap(),
        std::fs::read(out.join("slope.MAPF")).unwrap()
    );

    // #39: the state written is never further out of balance than the
    // geostatic start, as verify measures both at its first step.
    let geostatic = tmp.path().join("geostatic");
    let (code, text) = run_map(&folder, &fem, &geostatic, &["--stress", "geostatic"]);
    assert_eq!(code, 0, "{text}");
    let first_ratio = |dir: &Path| -> f64 {
        let v = tmp.path().join(format!(
            "verify-{}",
            dir.file_name().unwrap().to_str().unwrap()
        ));
        let (_, text, _) = run_split(&[
            "verify",
            dir.to_str().unwrap(),
            "--max-steps",
            "1",
            "--out",
            v.to_str().unwrap(),
        ]);
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(v.join("verify.json")).unwrap())
                .unwrap_or_else(|e| panic!("{e}: {text}"));
        r["run"]["initial_residual_ratio"].as_f64().unwrap()
    };
    let (solved, start) = (first_ratio(&out), first_ratio(&geostatic));
    assert!(solved <= start, "written {solved} > geostatic {start}");
}

// ---- the real Anura3D kernel --------------------------------------------

/// Sets a Mohr–Coulomb material's tensile strength (typed and verbatim).
fn set_tensile_strength(m: &mut Material, value: f64) {
    m.tensile_strength = Some(value);
    for (k, v) in &mut m.properties {
        if k.contains("TENSILE_STRENGTH") {
            *v = value.to_string();
        }
    }
}

/// The real kernel, several hundred undamped steps on an elastic 2D slope of
/// saturated soil (one-phase, submerged weight) and on a dry 3D embankment:
/// the equilibrium map stays at rest, at least 100× closer to it than the
/// geostatic map of the same project. Skips without the kernel unless
/// `A3D_INIT_REQUIRE_KERNEL` is set.
#[test]
#[allow(clippy::print_stderr)] // the measured displacements belong in the test output
fn anura3d_kernel_stays_at_rest_on_the_equilibrium_map() {
    let Some(bin) = anura3d_kernel_or_skip("anura3d_kernel_stays_at_rest_on_the_equilibrium_map")
    else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let slope2d = slope_model(20, 10, 1.0, &spec("soil", None, true));
    let mut slope2d_mc = slope_model(20, 10, 2.0, &spec("clay", Some((30.0, 20.0, 0.0)), true));
    set_tensile_strength(&mut slope2d_mc.materials[0], 100.0);
    let slope3d = |material: &MaterialSpec| {
        let mut mesh = generate::structured_tet_mesh(10.0, 0.0, 5.0, 2.0, 10, 5, 2);
        generate::slope_profile(&mut mesh, 5.0, 5.0, 2.0, 3.0, 7.0);
        generate::single_material_model(mesh, material, 4)
    };
    let cases = [
        (
            "3d-mohr-coulomb",
            slope3d(&spec("sand", Some((30.0, 2.0, 0.0)), false)),
        ),
        ("2d-mohr-coulomb", slope2d_mc),
        ("2d", slope2d),
        ("3d", slope3d(&spec("fill", None, false))),
    ];
    for (name, model) in cases {
        let dir = tmp.path().join(name);
        let (folder, fem) = project(&dir, &model, "MPM-MIXED", 2.0);
        let mut moved = Vec::new();
        for stress in ["geostatic", "equilibrium"] {
            let out = dir.join(stress);
            let (code, text) = run_map(&folder, &fem, &out, &["--stress", stress]);
            assert_eq!(code, 0, "{text}");
            moved.push(kernel_displacement(
                &bin,
                &out,
                &dir.join(format!("run-{stress}")),
                0.2,
            ));
        }
        eprintln!(
            "{name}: kernel displacement geostatic {:.3e} m, equilibrium {:.3e} m",
            moved[0], moved[1]
        );
        assert!(
            moved[1] * 100.0 < moved[0],
            "{name}: kernel displacement geostatic {:.3e} m, equilibrium {:.3e} m",
            moved[0],
            moved[1]
        );
    }
}
