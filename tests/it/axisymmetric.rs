//! 2D-axisymmetric MPM check (#13): laterally confined cylinders (solid, around
//! the axis, and hollow) settling under gravity against the analytic column
//! (σyy = −γ·depth, σrr = σθθ = ν/(1−ν)·σyy) and the plane-strain column; a
//! geostatic axisymmetric column in equilibrium and a 20 %-low one out of
//! balance; the shipped `CC_AXI` sample, confined (in equilibrium) and as
//! shipped through `map` and `verify` (a collapsing column: out of balance at
//! its free face); thread-count independence.
//!
//! MPs come from the real placement (`place`), so their volumes and masses are
//! per radian (weight × det J × radius), as in Anura3D.

use crate::common;
use common::column::*;
use common::{assert_contains, fixture, run as cli};

use a3d_init::formats::gom::GomDocument;
use a3d_init::model::{AnuraModel, Dimension, MaterialPoint, MpState, gamma_water};
use a3d_init::mpm::{RunSettings, verify};
use a3d_init::place::place_material_points;
use a3d_testkit::{column_tri3, elastic_material, zero_states};

const HEIGHT: f64 = 10.0;
const LAYERS: usize = 20;

/// A `width` × 10 m column of `nx` × 20 cells, both sides on rollers, base
/// fixed, starting at radius `inner` (0: a solid cylinder around the axis).
fn cylinder(
    dimension: Dimension,
    inner: f64,
    width: f64,
    nx: usize,
) -> (AnuraModel, Vec<MaterialPoint>) {
    let mut model = column_tri3(
        width,
        HEIGHT,
        nx,
        LAYERS,
        elastic_material(YOUNG, POISSON, RHO_S, POROSITY),
    );
    model.mesh.dimension = dimension;
    for node in &mut model.mesh.nodes {
        node[0] += inner;
    }
    let points = place_material_points(&model).expect("valid mesh");
    (model, points)
}

/// Layer averages of σxx, σyy, σzz (MPs grouped by their initial element;
/// `per_layer` elements per layer).
fn layer_averages(
    points: &[MaterialPoint],
    stresses: &[[f64; 6]],
    per_layer: usize,
) -> Vec<[f64; 3]> {
    let mut sums = vec![[0.0; 3]; LAYERS];
    let mut counts = vec![0usize; LAYERS];
    for (p, s) in points.iter().zip(stresses) {
        let layer = p.element as usize / per_layer;
        for k in 0..3 {
            sums[layer][k] += s[k];
        }
        counts[layer] += 1;
    }
    sums.iter()
        .zip(&counts)
        .map(|(s, &n)| [s[0] / n as f64, s[1] / n as f64, s[2] / n as f64])
        .collect()
}

/// A confined cylinder released from zero stress settles to the analytic
/// column: σyy = −γ·depth at mid-layer, σrr = σθθ = K0·σyy with K0 = ν/(1−ν)
/// (u_r = 0 everywhere, so ε_θθ = 0 and the hoop stress is the lateral one),
/// all within 1 %, and equal to the plane-strain column within 1 %. The top
/// 20 % is left out, as in `tests/it/mpm.rs`: MPs that moved by u inside the
/// fixed mesh shift lumped weight between nodes, an error of about γ·u that
/// is large only relative to the small stresses near the free surface.
#[test]
fn confined_cylinder_settles_to_the_k0_column() {
    let (plane_model, plane_points) = cylinder(Dimension::PlaneStrain, 0.0, 1.0, 2);
    let plane = verify(
        &plane_model,
        &plane_points,
        &zero_states(&plane_points),
        &RunSettings::verify(),
    )
    .expect("valid");
    let plane_layers = layer_averages(&plane_points, &plane.final_stresses, 4);
    for inner in [0.0, 2.0] {
        let (model, points) = cylinder(Dimension::Axisymmetric, inner, 1.0, 2);
        let report = verify_from_zero(&model, &points);
        assert!(report.final_residual_ratio < 1e-2, "inner radius {inner}");
        let layers = layer_averages(&points, &report.final_stresses, 4);
        let h = HEIGHT / LAYERS as f64;
        for (layer, (axi, flat)) in layers.iter().zip(&plane_layers).enumerate() {
            let mid = (layer as f64 + 0.5) * h;
            if mid > 0.8 * HEIGHT {
                continue;
            }
            let vertical = -gamma() * (HEIGHT - mid);
            let expected = [k0() * vertical, vertical, k0() * vertical];
            for k in 0..3 {
                for (reference, what) in [(expected[k], "analytic"), (flat[k], "plane strain")] {
                    let error = ((axi[k] - reference) / reference).abs();
                    assert!(
                        error < 1e-2,
                        "inner {inner}, layer {layer}, component {k}: {} vs {what} {reference}",
                        axi[k]
                    );
                }
            }
        }
    }
}

/// An unconfined cylinder on a frictionless base (rollers; only the axis fixed
/// radially) carries its weight uniaxially: σyy = −γ·depth, σrr = σθθ = 0,
/// with the radial expansion u_r = ν·γ·depth·r/E held by the hoop strain
/// ε_θθ = u_r/r alone. The hollow cylinder (r from 2 to 3 m) has no radial
/// support at all. (Plane strain would keep σzz = ν·σyy instead.) Checked
/// on layer averages: σyy within 1 % of the local value, σrr and σθθ within
/// 1 % of γH, leaving out the top 20 % (see above) and the base layer, where
/// the rollers (u_y = 0) clash with the uniaxial solution's u_y ∝ ν·γ·r²/2E.
#[test]
fn unconfined_cylinder_carries_its_weight_uniaxially() {
    for inner in [0.0, 2.0] {
        let (mut model, points) = cylinder(Dimension::Axisymmetric, inner, 1.0, 2);
        for (node, fixed) in model.mesh.nodes.iter().zip(model.solid_fixity.iter_mut()) {
            *fixed = [node[0] == 0.0, node[1] == 0.0, false];
        }
        let report = verify_from_zero(&model, &points);
        assert!(report.final_residual_ratio < 1e-2, "inner radius {inner}");
        let layers = layer_averages(&points, &report.final_stresses, 4);
        let h = HEIGHT / LAYERS as f64;
        let base = gamma() * HEIGHT;
        for (layer, axi) in layers.iter().enumerate().skip(1) {
            let mid = (layer as f64 + 0.5) * h;
            if mid > 0.8 * HEIGHT {
                continue;
            }
            let vertical = -gamma() * (HEIGHT - mid);
            assert!(
                ((axi[1] - vertical) / vertical).abs() < 1e-2,
                "inner {inner}, layer {layer}: σyy {} vs {vertical}",
                axi[1]
            );
            assert!(
                axi[0].abs() < 1e-2 * base && axi[2].abs() < 1e-2 * base,
                "inner {inner}, layer {layer}: σrr {}, σθθ {} (γH = {base})",
                axi[0],
                axi[2]
            );
        }
    }
}

/// The exact geostatic state is also the discrete equilibrium in axisymmetry:
/// the 3-point rule integrates the radius-weighted products (quadratic) and
/// the hoop term N·σθθ exactly, so the radial balance (σrr − σθθ)/r = 0 and
/// the vertical one hold to round-off. Without the hoop force the radial
/// residual would be of the order of the lateral stress.
#[test]
fn geostatic_axisymmetric_column_is_in_equilibrium() {
    for inner in [0.0, 2.0] {
        let (model, points) = cylinder(Dimension::Axisymmetric, inner, 1.0, 2);
        let report = verify_exact_geostatic(&model, &points);
        assert!(report.steps > 100, "{} steps", report.steps);
        assert!(report.verdict.is_equilibrium(), "{:?}", report.verdict);
        for (p, s) in points.iter().zip(&report.final_stresses) {
            let v = -gamma() * (HEIGHT - p.position[1]);
            assert!((s[1] - v).abs() < 1e-9 * gamma() * HEIGHT);
            assert!((s[2] - k0() * v).abs() < 1e-9 * gamma() * HEIGHT);
        }
    }
}

#[test]
fn axisymmetric_stresses_twenty_percent_low_are_not_in_equilibrium() {
    let (model, points) = cylinder(Dimension::Axisymmetric, 0.0, 1.0, 2);
    // The missing 20 % of the weight is out of balance at the first step
    // (the radial balance stays exact: 0.8 × zero).
    let report = verify_twenty_percent_low(&model, &points);
    assert!(report.final_residual_ratio < 1e-2);
    // Settlement: u_r = 0 keeps the column one-dimensional, so the top takes
    // up 20 % of the geostatic strain, 0.2·γH²/(2M), as in plane strain.
    let m = YOUNG * (1.0 - POISSON) / ((1.0 + POISSON) * (1.0 - 2.0 * POISSON));
    let settlement = 0.2 * gamma() * HEIGHT * HEIGHT / (2.0 * m);
    assert!(
        (report.max_displacement - settlement).abs() < 0.05 * settlement,
        "{} vs {settlement}",
        report.max_displacement
    );
}

/// The shipped axisymmetric column-collapse sample with its outer face
/// (x = 1 m) put on rollers: a hydrostatic, K0-geostatic state on Anura3D's
/// own mesh, fixities and per-radian MP volumes is in equilibrium.
#[test]
fn cc_axi_sample_confined_is_in_equilibrium() {
    let gom = fixture("anura3d/CC_AXI_MC_2Phase_K0_MPM-MP/CC_AXI_MC_2Phase_K0_MPM-MP.GOM");
    let mut model = GomDocument::read(&gom)
        .expect("sample")
        .model()
        .expect("model")
        .0;
    assert_eq!(model.mesh.dimension, Dimension::Axisymmetric);
    // The sample fixes the axis radially itself.
    for (node, fixed) in model.mesh.nodes.iter().zip(&model.solid_fixity) {
        if node[0] == 0.0 {
            assert!(
                fixed[0],
                "axis node at y = {} is not fixed radially",
                node[1]
            );
        }
    }
    // The outer face on rollers, and impermeable: the sample's coupled
    // material runs two-phase, and a free face would drain the column.
    for (k, node) in model.mesh.nodes.iter().enumerate() {
        if (node[0] - 1.0).abs() < 1e-9 {
            model.solid_fixity[k][0] = true;
            model.liquid_fixity[k][0] = true;
        }
    }
    let points = place_material_points(&model).expect("sample places");
    let material = &model.materials[0];
    let k0 = material.k0.expect("K0");
    let top = points.iter().map(|p| p.position[1]).fold(0.0, f64::max);
    // Column top: the MPs' highest row sits 1/60 m below it.
    let top = (top * 10.0).ceil() / 10.0;
    let gamma_sat = material.gamma_at_saturation(1.0, G);
    let states: Vec<MpState> = points
        .iter()
        .map(|p| {
            let depth = top - p.position[1];
            let pwp = -gamma_water(G) * depth;
            let vertical = -gamma_sat * depth;
            let horizontal = k0 * (vertical - pwp) + pwp;
            MpState {
                pwp,
                total: [horizontal, vertical, horizontal, 0.0, 0.0, 0.0],
                saturation: 1.0,
            }
        })
        .collect();
    verify_in_equilibrium(&model, &points, &states, 1e-9);
}

/// `map` then `verify` on the shipped sample as it is: a free-standing,
/// saturated, cohesionless column (the benchmark lets it collapse). The
/// mapped geostatic state is out of balance at the free face x = 1 m, not at
/// the axis; mps.csv holds per-radian volumes (Σ V = ∫x dA = 0.5 m³/rad).
#[test]
fn cc_axi_sample_verifies_as_a_collapsing_column() {
    let tmp = tempfile::tempdir().expect("temp dir");
    let mut csv = String::from("X,Y,PWP\n");
    for j in 0..=22 {
        for i in 0..=30 {
            let (x, y) = (i as f64 * 0.1, j as f64 * 0.05);
            csv.push_str(&format!("{x},{y},{}\n", (9.81 * (1.0 - y)).max(0.0)));
        }
    }
    let fem = tmp.path().join("seep.csv");
    std::fs::write(&fem, csv).expect("write");
    let out = tmp.path().join("mapped");
    let (code, text) = cli(&[
        "map",
        "--fem",
        fem.to_str().expect("utf-8"),
        "--mpm",
        fixture("anura3d/CC_AXI_MC_2Phase_K0_MPM-MP")
            .to_str()
            .expect("utf-8"),
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert_eq!(code, 0, "{text}");
    let (points, _) =
        a3d_init::formats::mps_table::read_states(&out.join("mps.csv")).expect("mps.csv");
    let total: f64 = points.iter().map(|p| p.volume).sum();
    assert!((total - 0.5).abs() < 1e-12, "Σ V = {total}");

    let (code, text) = cli(&["verify", out.to_str().expect("utf-8")]);
    assert_eq!(code, 1, "{text}");
    assert_contains(&text, &["NOT IN EQUILIBRIUM"]);
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("verify/verify.json")).expect("verify.json"),
    )
    .expect("json");
    let report = &report["run"];
    assert_eq!(report["dimension"], "Axisymmetric");
    assert!(report["initial_residual_ratio"].as_f64().expect("ratio") > 0.1);
    let worst = report["worst_residual_elements"]
        .as_array()
        .expect("elements");
    assert!(!worst.is_empty());
    for element in worst {
        let x = element["centroid"][0].as_f64().expect("x");
        assert!(
            (x - 1.0).abs() < 0.1,
            "residual away from the free face: {element}"
        );
    }
}

#[test]
fn serial_and_parallel_axisymmetric_runs_are_bit_identical() {
    // 20 × 20 cells: 2400 MPs, more than one rayon chunk of 1024.
    let (model, points) = cylinder(Dimension::Axisymmetric, 0.0, 2.0, 20);
    assert_zero_stress_runs_bit_identical(&model, &points);
}

#[test]
fn a_point_on_the_axis_is_refused() {
    let (model, mut points) = cylinder(Dimension::Axisymmetric, 0.0, 1.0, 2);
    points[0].position[0] = 0.0;
    let states = zero_states(&points);
    assert!(matches!(
        verify(&model, &points, &states, &RunSettings::verify()),
        Err(a3d_init::mpm::MpmError::InvalidPoint { id: 1, .. })
    ));
}
