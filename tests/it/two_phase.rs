//! The coupled two-phase runner (#27) against closed forms: a saturated
//! column at rest (hydrostatic pore pressure and geostatic stress held),
//! Terzaghi's 1D consolidation (degree of consolidation against time factor)
//! and undrained compression (Δp = K_w/n·Δε_v, the load shared between the
//! skeleton and the water in the ratio of their stiffnesses).

use crate::common;
use common::kernel_run::{run_kernel, vtk_scalars, vtk_vectors};
use common::{anura3d_kernel_or_skip, run_map, run_ok, soil_spec};

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::model::{AnuraModel, MaterialPoint, MpState};
use a3d_init::mpm::{Formulation, RunSettings, Simulation};
use a3d_testkit::generate;
use a3d_testkit::{
    column_tri3, coupled, elastic_material, geostatic_states, impermeable_where_fixed,
    place_points, zero_states,
};

const G: f64 = 9.81;
const GAMMA_W: f64 = 9.81;

/// A 0.1 m wide, `height` tall column of `ny` cells of coupled linear
/// elastic soil (ν = 0, so the constrained modulus is E), n = 0.4,
/// impermeable sides and base, drained top.
fn column(height: f64, ny: usize, young: f64, kappa: f64, bulk: f64) -> AnuraModel {
    let soil = coupled(elastic_material(young, 0.0, 2650.0, 0.4), kappa, bulk);
    let mut model = column_tri3(0.1, height, 1, ny, soil);
    impermeable_where_fixed(&mut model);
    model
}

/// Consistent nodal forces of a uniform pressure `q` (kPa) on the top edge.
fn top_load(model: &AnuraModel, q: f64) -> Vec<(u32, [f64; 3])> {
    let top = model.mesh.bounding_box().1[1];
    let mut top_nodes: Vec<(u32, f64)> = model
        .mesh
        .nodes
        .iter()
        .enumerate()
        .filter(|(_, p)| (p[1] - top).abs() < 1e-12)
        .map(|(i, p)| (i as u32, p[0]))
        .collect();
    top_nodes.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut loads: Vec<(u32, [f64; 3])> = top_nodes.iter().map(|&(i, _)| (i, [0.0; 3])).collect();
    for k in 0..top_nodes.len() - 1 {
        let half = 0.5 * q * (top_nodes[k + 1].1 - top_nodes[k].1);
        loads[k].1[1] -= half;
        loads[k + 1].1[1] -= half;
    }
    loads
}

fn settings(gravity: f64) -> RunSettings {
    RunSettings {
        gravity,
        ..RunSettings::dynamic(1.0)
    }
}

/// `a3d-init run` of the map folder `dir` undamped for `time` s into `out`;
/// its `run.json`.
pub(crate) fn run_undamped(
    dir: &std::path::Path,
    out: &std::path::Path,
    time: f64,
) -> serde_json::Value {
    run_ok(&[
        "run",
        dir.to_str().unwrap(),
        "--time",
        &time.to_string(),
        "--damping",
        "0",
        "--snapshots",
        "",
        "--out",
        out.to_str().unwrap(),
    ]);
    serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap()
}

/// Volume-weighted mean of `values` over the MPs.
fn mean(points: &[MaterialPoint], values: &[f64]) -> f64 {
    let v: f64 = points.iter().map(|p| p.volume).sum();
    points
        .iter()
        .zip(values)
        .map(|(p, x)| p.volume * x)
        .sum::<f64>()
        / v
}

/// Terzaghi: U(T) = 1 − Σ 2/M² exp(−M² T), M = π(2m + 1)/2.
fn terzaghi(t: f64) -> f64 {
    let mut sum = 0.0;
    for m in 0..200 {
        let big_m = std::f64::consts::PI * (2 * m + 1) as f64 / 2.0;
        sum += 2.0 / (big_m * big_m) * (-big_m * big_m * t).exp();
    }
    1.0 - sum
}

#[test]
fn saturated_column_at_rest_holds_hydrostatic_pressure_and_geostatic_stress() {
    let model = column(2.0, 20, 1e4, 1e-10, 1e6);
    let points = place_points(&model);
    // Water table at the top: p = −γw·depth, σ′v = −γ′·depth, K0 = 0 (ν = 0).
    let states = geostatic_states(&model, &points, G, 0.0, Some(2.0));
    let mut sim = Simulation::new(&model, &points, &states, &settings(G)).unwrap();
    assert_eq!(sim.formulations(), vec![(1, Formulation::Coupled)]);
    let p0 = sim.pore_pressures();
    let s0 = sim.effective_stresses();
    for _ in 0..2000 {
        sim.step();
    }
    let load = 2.0 * GAMMA_W; // the largest pore pressure, kPa
    let dp = sim
        .pore_pressures()
        .iter()
        .zip(&p0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let ds = sim
        .effective_stresses()
        .iter()
        .zip(&s0)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max);
    assert!(dp < 1e-6 * load, "pore pressure moved {dp:e} kPa");
    assert!(ds < 1e-6 * load, "effective stress moved {ds:e} kPa");
}

#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn terzaghi_consolidation_within_two_percent() {
    // H = 1 m drained at the top; E_oed = 1e4 kPa; k = 1e-3 m/s.
    let (h, young, bulk, n) = (1.0, 1e4, 1e6, 0.4);
    let k = 1e-3;
    let kappa = k * 1e-6 / (1.0 * G);
    let model = column(h, 20, young, kappa, bulk);
    let points = place_points(&model);
    let states: Vec<MpState> = zero_states(&points);
    let mut sim = Simulation::new(&model, &points, &states, &settings(0.0)).unwrap();
    let q = 10.0;
    sim.set_nodal_loads(&top_load(&model, q)).unwrap();
    // Compressible water: c_v = k / (γw (1/M + n/K_w)); the undrained
    // pressure p0 = q·(K_w/n)/(M + K_w/n).
    let cv = k / (GAMMA_W * (1.0 / young + n / bulk));
    let p0 = q * (bulk / n) / (young + bulk / n);
    for target in [0.1, 0.5, 1.0] {
        let time = target * h * h / cv;
        while sim.time() < time {
            sim.step();
        }
        let t = cv * sim.time() / (h * h);
        let p = mean(&points, &sim.pore_pressures());
        let u = 1.0 - (-p) / p0;
        let exact = terzaghi(t);
        eprintln!("T = {t:.4}: U = {u:.4}, Terzaghi {exact:.4}");
        assert!(
            (u - exact).abs() < 0.02 * exact,
            "T = {t:.3}: U = {u:.4} against Terzaghi's {exact:.4}"
        );
    }
}

/// The volume-weighted mean pore pressure of `model` under a top pressure
/// `q`, undamped: `q` ramped up over 0.2 s, then held and the mean pressure
/// averaged over 0.2 s (the small oscillation the ramp leaves averages
/// out), so that the test holds whichever way the mixture is damped: as
/// the kernel damps it (`run`), in two parts that oppose at the loaded face,
/// local damping holds the column short of equilibrium (2.5 % here at
/// α = 0.75), as friction would.
fn settled_mean_pressure(model: &AnuraModel, q: f64) -> f64 {
    let points = place_points(model);
    let mut sim = Simulation::new(model, &points, &zero_states(&points), &settings(0.0)).unwrap();
    let ramp = 0.2;
    while sim.time() < ramp {
        let f = (sim.time() / ramp).min(1.0);
        sim.set_nodal_loads(&top_load(model, q * f)).unwrap();
        sim.step();
    }
    sim.set_nodal_loads(&top_load(model, q)).unwrap();
    let (mut sum, mut n) = (0.0, 0);
    while sim.time() < 2.0 * ramp {
        sim.step();
        sum += mean(&points, &sim.pore_pressures());
        n += 1;
    }
    sum / n as f64
}

#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn undrained_compression_shares_the_load_by_stiffness() {
    // Too impermeable to drain in 0.1 s (c_v·t/H² ≈ 1e-12): the skeleton
    // (M = 1e4 kPa) and the water (K_w/n = 2.5e5 kPa) share the load q
    // in the ratio of their stiffnesses, Δp = (K_w/n)·Δε_v = −q·(K_w/n)/(M + K_w/n),
    // in the coupled formulation and in the one-phase undrained-effective one.
    let (young, bulk, n, q) = (1e4, 1e5, 0.4, 10.0);
    let expect = -q * (bulk / n) / (young + bulk / n);
    let coupled_model = column(1.0, 10, young, 1e-16, bulk);
    let mut effective_model = coupled_model.clone();
    let m = &mut effective_model.materials[0];
    m.material_type = "saturated_material_undrained_effective".into();
    // K_w/n from ν_u as the kernel forms it: with ν = 0, ν_u/(1 − 2ν_u)·E.
    let ratio = bulk / n / young;
    let nu_u = ratio / (1.0 + 2.0 * ratio);
    m.properties
        .push(("$$POISSON_RATIO_UNDRAINED".into(), nu_u.to_string()));
    for (model, formulation) in [
        (coupled_model, Formulation::Coupled),
        (effective_model, Formulation::UndrainedEffective),
    ] {
        let points = place_points(&model);
        let sim = Simulation::new(&model, &points, &zero_states(&points), &settings(0.0)).unwrap();
        assert_eq!(sim.formulations(), vec![(1, formulation)]);
        let p = settled_mean_pressure(&model, q);
        eprintln!("{formulation:?}: mean p = {p:.5} kPa, expected {expect:.5}");
        assert!(
            (p / expect - 1.0).abs() < 1e-3,
            "{formulation:?}: p {p} vs {expect}"
        );
    }
    // Frozen on request: the drained runner keeps p at 0 and the skeleton
    // takes the whole load.
    let model = column(1.0, 10, young, 1e-16, bulk);
    let points = place_points(&model);
    let frozen = RunSettings {
        frozen_pore_pressure: true,
        ..settings(0.0)
    };
    let sim = Simulation::new(&model, &points, &zero_states(&points), &frozen).unwrap();
    assert_eq!(sim.formulations(), vec![(1, Formulation::Drained)]);
}

/// The real kernel and this runner on the same project: a saturated
/// two-phase column (`saturated_material_coupled`, κ = 1e-10 m²,
/// K_w = 1e5 kPa, E = 1e4 kPa, ν = 0.3; 0.2 × 1 m, impermeable sides and
/// base, drained top) mapped with the hydrostatic pore pressure and zero
/// effective stress (σ = p): under gravity the skeleton loads the water,
/// which then drains through the top. Both run 0.1 s undamped; the largest
/// displacement and the pore pressure change at three monitored MPs within
/// 20 % of the kernel's. Skips without the kernel unless
/// `A3D_INIT_REQUIRE_KERNEL` is set.
#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn anura3d_kernel_two_phase_column_within_twenty_percent() {
    let Some(bin) = anura3d_kernel_or_skip("anura3d_kernel_two_phase_column_within_twenty_percent")
    else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 0.2, 1.0, 2, 10);
    let mut model = generate::single_material_model(mesh, &soil_spec(0.5, 1e4, 0.0), 3);
    generate::make_coupled(&mut model.materials[0], 1e-10, 1e5, 1e-6);
    model.liquid_fixity = model.solid_fixity.clone();
    let folder = tmp.path().join("model");
    std::fs::create_dir_all(&folder).unwrap();
    std::fs::write(folder.join("slope.GOM"), model_to_text(&model, "2023")).unwrap();
    std::fs::write(
        folder.join("slope.CPS_001"),
        "### Anura3D_2023 ###\n$$COMPUTATION_METHOD\nMPM-MP\n$$GRAVITY_ACCELERATION\n9.81\n\
         $$COURANT_NUMBER\n0.5\n$$HOMOGENEOUS_LOCAL_DAMPING\n0 0.0\n$$END\n",
    )
    .unwrap();
    // σ = p: compression-positive FEM stresses equal to the pore pressure.
    let fem = tmp.path().join("fem.csv");
    let mut csv = String::from("X,Y,PWP,SXX,SYY,SXY\n");
    for i in 0..=8 {
        for j in 0..=40 {
            let (x, y) = (0.2 * i as f64 / 8.0, j as f64 / 40.0);
            let p = GAMMA_W * (1.0 - y);
            csv.push_str(&format!("{x},{y},{p},{p},{p},0\n"));
        }
    }
    std::fs::write(&fem, csv).unwrap();
    let out = tmp.path().join("out");
    let (code, text) = run_map(&folder, &fem, &out, &["--stress", "fem"]);
    assert_eq!(code, 0, "{text}");
    let time = 0.1;
    let vtk = run_kernel(&bin, &out, &tmp.path().join("kernel"), time);
    let kernel_u = vtk_vectors(&vtk, "displacement_solid");
    let scalars = vtk.with_file_name("slope_MPScalar_001.vtk");
    if !scalars.is_file() {
        let names: Vec<_> = std::fs::read_dir(vtk.parent().unwrap())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        panic!("no {} among {names:?}", scalars.display());
    }
    let kernel_p = vtk_scalars(&scalars, "pressure_liquid");
    let report = run_undamped(&out, &tmp.path().join("ours"), time);
    let our_u: Vec<f64> = report["final_displacements"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| {
            let v: Vec<f64> = v
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            (v[0] * v[0] + v[1] * v[1]).sqrt()
        })
        .collect();
    let our_p: Vec<f64> = report["final_pore_pressures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(our_p.len(), kernel_p.len());
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let kernel_max = max(&kernel_u
        .iter()
        .map(|v| (v[0] * v[0] + v[1] * v[1]).sqrt())
        .collect::<Vec<_>>());
    let our_max = max(&our_u);
    eprintln!("largest displacement: kernel {kernel_max:.4e} m, ours {our_max:.4e} m");
    assert!(
        (our_max / kernel_max - 1.0).abs() < 0.2,
        "largest displacement: kernel {kernel_max:.4e} m, ours {our_max:.4e} m"
    );
    // Monitored MPs near the axis at a quarter, half and three quarters of
    // the height: the change of pore pressure from the hydrostatic start.
    let project = a3d_init::pipeline::Project::load(&out).unwrap();
    for y in [0.25, 0.5, 0.75] {
        let (k, point) = project
            .points
            .iter()
            .enumerate()
            .min_by(|a, b| {
                let d =
                    |p: &MaterialPoint| (p.position[0] - 0.1).powi(2) + (p.position[1] - y).powi(2);
                d(a.1).total_cmp(&d(b.1))
            })
            .unwrap();
        let p0 = -GAMMA_W * (1.0 - point.position[1]);
        let (dk, dours) = (kernel_p[k] - p0, our_p[k] - p0);
        eprintln!(
            "MP {} at y = {:.3}: p kernel {:.4} kPa, ours {:.4} kPa (change {dk:.4} vs {dours:.4})",
            point.id, point.position[1], kernel_p[k], our_p[k]
        );
        assert!(
            (dours / dk - 1.0).abs() < 0.2,
            "MP {}: pore pressure change kernel {dk:.4} kPa, ours {dours:.4} kPa",
            point.id
        );
    }
}

/// The partially saturated path (`unsaturated_two_phase`, on by default): a
/// column whose pore pressure is hydrostatic about a table at mid-height
/// (suction above it, S < 1 from the van Genuchten curve) runs, keeps its
/// degree of saturation on the retention curve, and under damping its pore
/// pressures stay within 1 kPa of the start; with the switch off the
/// material runs drained.
#[test]
fn unsaturated_two_phase_switch_runs_the_partially_saturated_path() {
    let curve = a3d_init::model::RetentionCurve::VanGenuchten {
        s_min: 0.1,
        s_max: 1.0,
        p0: 2.0,
        lambda: 0.6,
    };
    let soil = coupled(elastic_material(1e4, 0.0, 2650.0, 0.4), 1e-11, 4.5e4);
    let soil = a3d_init::model::Material {
        material_type: "unsaturated_material_2phase_suction".into(),
        retention: Some(curve),
        ..soil
    };
    let mut model = column_tri3(0.2, 2.0, 2, 20, soil);
    impermeable_where_fixed(&mut model);
    let points = place_points(&model);
    // σv = −∫ γ(S) dy from the top, σ′ = σ − S·p, σ′h = 0 (ν = 0).
    let m = model.materials[0].clone();
    let pwp_at = |y: f64| GAMMA_W * (y - 1.0);
    let states: Vec<MpState> = points
        .iter()
        .map(|p| {
            let y = p.position[1];
            let steps = 400;
            let dy = (2.0 - y) / steps as f64;
            let sigma_v: f64 = -(0..steps)
                .map(|i| {
                    let yi = y + (i as f64 + 0.5) * dy;
                    m.gamma_at_saturation(curve.saturation(pwp_at(yi)), G) * dy
                })
                .sum::<f64>();
            let pwp = pwp_at(y);
            let s = curve.saturation(pwp);
            MpState {
                pwp,
                total: [s * pwp, sigma_v, s * pwp, 0.0, 0.0, 0.0],
                saturation: s,
            }
        })
        .collect();
    let damped = RunSettings {
        damping: 0.75,
        ..settings(G)
    };
    let off = RunSettings {
        unsaturated_two_phase: false,
        ..damped.clone()
    };
    let drained = Simulation::new(&model, &points, &states, &off).unwrap();
    assert_eq!(drained.formulations(), vec![(1, Formulation::Drained)]);
    assert!(damped.unsaturated_two_phase, "on by default");
    let mut sim = Simulation::new(&model, &points, &states, &damped).unwrap();
    assert_eq!(sim.formulations(), vec![(1, Formulation::Coupled)]);
    while sim.time() < 0.05 {
        sim.step();
    }
    let p = sim.pore_pressures();
    let s = sim.saturations();
    for (k, state) in states.iter().enumerate() {
        assert!(
            (p[k] - state.pwp).abs() < 1.0,
            "MP {k}: p {} from {}",
            p[k],
            state.pwp
        );
        let expect = curve.anura3d_saturation(p[k]).1;
        assert!(
            (s[k] - expect).abs() < 1e-12,
            "MP {k}: S {} vs {expect}",
            s[k]
        );
    }
    assert!(
        s.iter().any(|&v| v < 0.99),
        "some MPs are partially saturated"
    );
}

/// Gravity drains a partially saturated column of uniform suction (no
/// suction gradient): the water sinks at Darcy's n·S·(v_w − v_s) = k·k_r(S)
/// with k_r from the GOM's conductivity curve (constant, Hillel, Mualem),
/// measured at mid-height once the drag has settled the liquid's velocity.
#[test]
fn gravity_drainage_follows_the_conductivity_curve() {
    let curve = a3d_init::model::RetentionCurve::VanGenuchten {
        s_min: 0.1,
        s_max: 1.0,
        p0: 2.0,
        lambda: 0.6,
    };
    let (kappa, mu, n) = (1e-12, 1e-6, 0.4);
    let k_sat = 1.0 * G * kappa / mu;
    let suction = 3.0;
    let s = curve.saturation(suction);
    let lambda = 0.6_f64;
    let mualem = {
        let w = 1.0 - (1.0 - s.powf(1.0 / lambda)).powf(lambda);
        s.sqrt() * w * w
    };
    let pair = |k: &str, v: &str| (format!("$${k}"), v.to_string());
    for (curve_lines, kr) in [
        (vec![pair("HYDR_CONDUCTIVITY_CURVE", "constant")], 1.0),
        (
            vec![pair("HYDR_CONDUCTIVITY_CURVE", "hillel"), pair("r", "3")],
            s.powi(3),
        ),
        (
            vec![
                pair("HYDR_CONDUCTIVITY_CURVE", "mualem"),
                pair("Smin", "0.1"),
                pair("Smax", "1"),
                pair("P0", "2"),
                pair("lambda", "0.6"),
            ],
            mualem,
        ),
    ] {
        let soil = coupled(elastic_material(1e6, 0.0, 2650.0, n), kappa, 4.5e4);
        let mut properties = soil.properties.clone();
        properties.retain(|(k, _)| !k.contains("HYDR_CONDUCTIVITY"));
        properties.extend(curve_lines);
        let soil = a3d_init::model::Material {
            material_type: "unsaturated_material_2phase_suction".into(),
            retention: Some(curve),
            properties,
            ..soil
        };
        let mut model = column_tri3(0.1, 2.0, 1, 20, soil);
        impermeable_where_fixed(&mut model);
        let points = place_points(&model);
        let m = model.materials[0].clone();
        let gamma = m.gamma_at_saturation(s, G);
        let states: Vec<MpState> = points
            .iter()
            .map(|p| {
                let sigma_v = -gamma * (2.0 - p.position[1]);
                MpState {
                    pwp: suction,
                    total: [s * suction, sigma_v, s * suction, 0.0, 0.0, 0.0],
                    saturation: s,
                }
            })
            .collect();
        let mut sim = Simulation::new(&model, &points, &states, &settings(G)).unwrap();
        for _ in 0..200 {
            sim.step();
        }
        let w = sim.liquid_velocities();
        let v = sim.velocities();
        let mid: Vec<usize> = (0..points.len())
            .filter(|&k| (points[k].position[1] - 1.0).abs() < 0.25)
            .collect();
        let flux = mid
            .iter()
            .map(|&k| n * s * (w[k][1] - v[k][1]))
            .sum::<f64>()
            / mid.len() as f64;
        let expected = -k_sat * kr;
        assert!(
            (flux / expected - 1.0).abs() < 0.02,
            "k_r {kr:.4}: Darcy flux {flux:.4e} m/s, expected {expected:.4e} m/s"
        );
    }
}

/// A partially saturated column of uniform suction with a free top, sides
/// and base impermeable: its water volume Σ n·S·V grows only through the top.
/// Free (the natural condition p = 0, a ponded surface) the top takes water
/// in; as a seepage face it takes none; under infiltration at the rate q it
/// takes q per unit area.
#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn seepage_face_and_infiltration_bound_what_the_surface_takes_in() {
    use a3d_init::mpm::seepage::HydraulicBoundaries;
    let curve = a3d_init::model::RetentionCurve::VanGenuchten {
        s_min: 0.1,
        s_max: 1.0,
        p0: 2.0,
        lambda: 0.6,
    };
    let n = 0.4;
    let soil = coupled(elastic_material(1e6, 0.0, 2650.0, n), 1e-11, 4.5e4);
    let soil = a3d_init::model::Material {
        material_type: "unsaturated_material_2phase_suction".into(),
        retention: Some(curve),
        ..soil
    };
    let (width, height) = (0.1, 1.0);
    let mut model = column_tri3(width, height, 1, 10, soil);
    impermeable_where_fixed(&mut model);
    let points = place_points(&model);
    let suction = 3.0;
    let s0 = curve.saturation(suction);
    let gamma = model.materials[0].gamma_at_saturation(s0, G);
    let states: Vec<MpState> = points
        .iter()
        .map(|p| MpState {
            pwp: suction,
            total: [
                s0 * suction,
                -gamma * (height - p.position[1]) + s0 * suction,
                s0 * suction,
                0.0,
                0.0,
                0.0,
            ],
            saturation: s0,
        })
        .collect();
    let whole = [[f64::NEG_INFINITY, f64::INFINITY]; 3];
    let time = 0.05;
    let water_taken = |hydraulic: HydraulicBoundaries| -> f64 {
        let settings = RunSettings {
            hydraulic,
            ..settings(G)
        };
        let mut sim = Simulation::new(&model, &points, &states, &settings).unwrap();
        while sim.time() < time {
            sim.step();
        }
        let s = sim.saturations();
        points
            .iter()
            .zip(&s)
            .map(|(p, s)| n * (s - s0) * p.volume)
            .sum::<f64>()
    };
    let free = water_taken(HydraulicBoundaries::default());
    let seepage = water_taken(HydraulicBoundaries {
        seepage_area: Some(whole),
        infiltration: None,
    });
    let q = 2e-4;
    let infiltration = water_taken(HydraulicBoundaries {
        seepage_area: None,
        infiltration: Some((whole, [0.0, -q, 0.0])),
    });
    let expected = q * width * time;
    eprintln!(
        "water taken in over {time} s: free {free:.3e}, seepage face {seepage:.3e}, \
         infiltration {infiltration:.3e} (q·w·t = {expected:.3e}) m³/m"
    );
    assert!(
        free > 2.0 * expected,
        "the free surface takes in {free:.3e}"
    );
    // Measured: free 3.9e-6, seepage face 9.0e-8, infiltration 1.09e-6
    // against q·w·t = 1.0e-6 m³/m (the rate is held at the nodes, the water
    // counted at the MPs).
    assert!(
        seepage.abs() < 0.1 * expected,
        "a seepage face takes in {seepage:.3e}"
    );
    assert!(
        (infiltration / expected - 1.0).abs() < 0.15,
        "infiltration takes in {infiltration:.3e}, expected {expected:.3e}"
    );
}

/// The GOM's hydraulic areas are read as bounding boxes (and the rate as a
/// vector); a bad bound is an error naming its line.
#[test]
fn hydraulic_areas_are_read_from_the_gom() {
    use a3d_init::formats::gom::GomDocument;
    // A material record with its properties (the testkit's carries none, and
    // a record without them is not one Anura3D reads).
    let column = column_tri3(0.1, 1.0, 1, 4, elastic_material(1e4, 0.0, 2650.0, 0.4));
    let model = generate::single_material_model(column.mesh, &soil_spec(0.0, 1e4, 1e-10), 3);
    let text = model_to_text(&model, "2023");
    GomDocument::parse(std::path::Path::new("plain.GOM"), text.clone())
        .unwrap()
        .model()
        .unwrap();
    let blocks = "$$BOUNDARY_SEEPAGE_AREA\n0.0 0.1\n0.5 1.0\n\
                  $$BOUNDARY_INFILTRATION_AREA\n-1 1\n0.99 1.01\n\
                  $$INFILTRATION_RATE\n0.0 -1e-5\n$$NUMBER_OF_MATERIALS";
    let with = text.replacen("$$NUMBER_OF_MATERIALS", blocks, 1);
    let path = std::path::Path::new("column.GOM");
    let (_, info) = GomDocument::parse(path, with.clone())
        .unwrap()
        .model()
        .unwrap();
    let h = info.hydraulic;
    assert_eq!(h.seepage.unwrap()[1], [0.5, 1.0]);
    assert_eq!(h.infiltration.unwrap()[0], [-1.0, 1.0]);
    assert_eq!(h.infiltration_rate.unwrap(), [0.0, -1e-5, 0.0]);
    assert!(h.hydraulic_head.is_none());
    let bad = with.replacen("0.5 1.0", "1.0 0.5", 1);
    let line = bad.lines().position(|l| l == "1.0 0.5").unwrap();
    let err = GomDocument::parse(path, bad).unwrap().model().unwrap_err();
    let message = err.to_string();
    assert!(
        message.contains(&format!("column.GOM:{}:", line + 1)) && message.contains("above max"),
        "{message}"
    );
}

/// What the CPS asks for and the GOM lacks is said, not dropped (a seepage
/// face or a head from a file without their areas); the GOM loads the CPS
/// switches on (test-1001: nodal solid loads under `$$SOLID_TRACTION step`)
/// are applied, not noted.
#[test]
fn what_the_gom_lacks_is_noted_and_its_loads_are_read() {
    use a3d_init::pipeline::Project;
    use a3d_init::pipeline::check::runner;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/anura3d/test-1001");
    let mut project = Project::load(&dir).unwrap();
    let (boundaries, notes) = runner::hydraulic(&project);
    assert!(boundaries.is_empty());
    assert!(notes.is_empty(), "{notes:?}");
    let (loads, _) = runner::loads(&project).unwrap();
    assert_eq!(loads.blocks.len(), 1);
    assert_eq!(loads.blocks[0].keyword, "$$START_LOAD_ON_NODES_SOLID");
    assert_eq!(loads.blocks[0].sides[0].corners, vec![3, 2]);
    assert_eq!(loads.blocks[0].sides[0].values[1], [0.0, -20.0, 0.0]);
    assert_eq!(
        loads.multiplier(a3d_init::model::loads::LoadPhase::Solid, 0, 0.05),
        1.0
    );
    let cps = project.cps.as_ref().unwrap().to_text();
    let cps = cps.replacen(
        "$$END",
        "$$HYDRAULIC_HEAD\nfile 1.0\n$$APPLY_SEEPAGE_FACE\n1\n$$END",
        1,
    );
    project.cps = Some(
        a3d_init::formats::cps::CpsDocument::parse(&dir.join("test-1001.CPS_001"), cps).unwrap(),
    );
    let (_, notes) = runner::hydraulic(&project);
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].contains("$$BOUNDARY_SEEPAGE_AREA"), "{notes:?}");
    // A head from a file needs the GOM's area; without it, a note; and
    // test-1001's `$$GRAVITY_LOAD off` is said too.
    let (loads, notes) = runner::loads(&project).unwrap();
    assert!(loads.head.is_none());
    assert_eq!(notes.len(), 2, "{notes:?}");
    assert!(
        notes[0].contains("$$BOUNDARY_HYDRAULIC_HEAD_AREA"),
        "{notes:?}"
    );
    assert!(
        notes[1].contains("gravity starts at 0.000·g")
            && notes[1].contains("test-1001.CPS_001:16: `$$GRAVITY_LOAD off"),
        "{notes:?}"
    );
}
