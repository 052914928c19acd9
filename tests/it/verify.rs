//! `a3d-init verify` and `run` on what `map` wrote: a flat saturated block with a
//! geostatic state is in equilibrium (exit 0); the K0 slope sample is reported
//! out of balance with the places named (exit 1); a state from another model is
//! refused (exit 2).

use crate::common;
use common::*;

use std::path::{Path, PathBuf};

use a3d_testkit::generate;

fn mapped_block(dir: &Path) -> PathBuf {
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 4.0, 10.0, 4, 10);
    let gom = dir.join("block.GOM");
    write_gom(&gom, mesh, &soil_spec(0.3 / 0.7, 2e4, 1e-10));
    let fem = dir.join("seep.csv");
    std::fs::write(&fem, hydrostatic_grid_csv("X,Y,PWP", 8, 20, 9.81, 10.0)).unwrap();
    let out = dir.join("mapped");
    let (code, text) = run_map(&gom, &fem, &out, &["--generate-cps"]);
    assert_eq!(code, 0, "{text}");
    out
}

#[test]
fn flat_geostatic_block_is_in_equilibrium() {
    let tmp = tempfile::tempdir().unwrap();
    let out = mapped_block(tmp.path());
    let text = verify_ok(&out);
    assert_contains(&text, &["verdict    IN EQUILIBRIUM"]);
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
    let model = fixture("anura3d/K0_phreaticSurf_Geom");
    let (code, text) = run_map(&model, &fem, &out, &["--stress", "geostatic"]);
    assert_eq!(code, 0, "{text}");
    let (code, text) = run(&["verify", out.to_str().unwrap()]);
    assert_eq!(code, 1, "{text}");
    assert_contains(&text, &["NOT IN EQUILIBRIUM", "largest residual: element"]);
    // A geostatic K0 state on a slope is out of balance but close: it settles within 1 mm.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("verify/verify.json")).unwrap())
            .unwrap();
    assert!(report["run"]["max_displacement"].as_f64().unwrap() < 1e-3);
    assert_eq!(report["run"]["stop"], "Settled");

    // `auto` (pore pressures only, ground not flat) solves for equilibrium
    // instead (#25): verify finds it balanced to round-off.
    let auto = tmp.path().join("auto");
    let (code, text) = run_map(&model, &fem, &auto, &[]);
    assert_eq!(code, 0, "{text}");
    assert_contains(&text, &["stress: equilibrium"]);
    let text = verify_ok(&auto);
    assert_contains(&text, &["verdict    IN EQUILIBRIUM"]);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(auto.join("verify/verify.json")).unwrap())
            .unwrap();
    assert!(report["run"]["initial_residual_ratio"].as_f64().unwrap() < 1e-9);
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
    assert_contains(&text, &["MPs, but the model places"]);
}
