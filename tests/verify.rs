//! `a3d-init verify` and `run` on what `map` wrote: a flat saturated block with a
//! geostatic state is in equilibrium (exit 0); the K0 slope sample is reported
//! out of balance with the places named (exit 1); a state from another model is
//! refused (exit 2).

mod common;
use common::*;

use std::path::{Path, PathBuf};

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::model::generate::{self, MaterialSpec};

fn mapped_block(dir: &Path) -> PathBuf {
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 4.0, 10.0, 4, 10);
    let spec = MaterialSpec {
        name: "soil".into(),
        porosity: 0.4,
        density_solid: 2650.0,
        density_liquid: Some(1000.0),
        k0: 0.3 / 0.7,
        young_modulus: 2e4,
        poisson_ratio: 0.3,
        mohr_coulomb: None,
        retention: None,
        permeability: 1e-10,
    };
    let gom = dir.join("block.GOM");
    std::fs::write(
        &gom,
        model_to_text(&generate::single_material_model(mesh, &spec, 3), "2023"),
    )
    .unwrap();
    let mut csv = String::from("X,Y,PWP\n");
    for j in 0..=20 {
        for i in 0..=8 {
            let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
            csv.push_str(&format!("{x},{y},{}\n", 9.81 * (10.0 - y)));
        }
    }
    std::fs::write(dir.join("seep.csv"), csv).unwrap();
    let out = dir.join("mapped");
    let (code, text) = run(&[
        "map",
        "--fem",
        dir.join("seep.csv").to_str().unwrap(),
        "--mpm",
        gom.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--generate-cps",
    ]);
    assert_eq!(code, 0, "{text}");
    out
}

#[test]
fn flat_geostatic_block_is_in_equilibrium() {
    let tmp = tempfile::tempdir().unwrap();
    let out = mapped_block(tmp.path());
    let (code, text) = run(&["verify", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("verdict    IN EQUILIBRIUM"), "{text}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("verify/verify.json")).unwrap())
            .unwrap();
    assert!(report["run"]["initial_residual_ratio"].as_f64().unwrap() < 1e-2);
    assert_eq!(report["equilibrium"], serde_json::json!(true));
    for f in ["verify_history.svg", "mps_start.vtu", "mps_end.vtu"] {
        assert!(out.join("verify").join(f).exists(), "{f}");
    }
    // `run` keeps going and takes snapshots.
    let (code, text) = run(&[
        "run",
        out.to_str().unwrap(),
        "--time",
        "0.05",
        "--snapshots",
        "0.02,0.04",
    ]);
    assert_eq!(code, 0, "{text}");
    assert!(
        out.join("run/run.json").exists() && out.join("run/mps_t0.02.vtu").exists(),
        "{text}"
    );
}

#[test]
fn k0_slope_is_reported_out_of_balance_with_places() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("slope");
    let fem = fixture("geostudio-csv/k0-slope-hydrostatic.csv");
    let (code, text) = run(&[
        "map",
        "--fem",
        fem.to_str().unwrap(),
        "--mpm",
        fixture("anura3d/K0_phreaticSurf_Geom").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{text}");
    let (code, text) = run(&["verify", out.to_str().unwrap()]);
    assert_eq!(code, 1, "{text}");
    assert!(
        text.contains("NOT IN EQUILIBRIUM") && text.contains("largest residual: element"),
        "{text}"
    );
    // A geostatic K0 state on a slope is out of balance but close: it settles within 1 mm.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("verify/verify.json")).unwrap())
            .unwrap();
    assert!(report["run"]["max_displacement"].as_f64().unwrap() < 1e-3);
    assert_eq!(report["run"]["stop"], "Settled");
}

#[test]
fn a_state_of_another_model_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = mapped_block(tmp.path());
    let (code, text) = run(&[
        "verify",
        "--mpm",
        fixture("anura3d-mini/TwoMat.GOM").to_str().unwrap(),
        "--state",
        out.join("mps.csv").to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("MPs, but the model places"), "{text}");
}
