//! `a3d-init diff`: identical inputs, numbers below and above tolerance, a
//! reordered GOM block (equal), a changed keyword, MAPF rows swapped, folders.

use crate::common;
use common::*;

use std::path::Path;
use std::process::Command;

fn diff(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_a3d-init"))
        .arg("diff")
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr),
    )
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn gom_and_cps_semantics() {
    let tmp = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(fixture("anura3d-mini/TwoMat.GOM")).unwrap();
    let a = write(tmp.path(), "a.GOM", &base);
    let same = write(
        tmp.path(),
        "same.GOM",
        &base.replace("1.0 1.0\n", "1.0 1.0000000000001\n"),
    );
    // moved: a block moved to the end; changed: a value and a material type.
    let [moved, changed] = [
        (
            "moved.GOM",
            [
                ("$$FORMULATION\nsingle-point\n", ""),
                ("$$FINISH", "$$FORMULATION\nsingle-point\n$$FINISH"),
            ],
        ),
        (
            "changed.GOM",
            [
                ("1.0 1.0\n", "1.0 1.01\n"),
                ("mohr_coulomb", "linear_elasticity_x"),
            ],
        ),
    ]
    .map(|(name, [(a, b), (c, d)])| write(tmp.path(), name, &base.replace(a, b).replace(c, d)));
    assert_eq!(diff(&[&a, &a]).0, 0);
    let (code, out) = diff(&[&a, &same]);
    assert_eq!(code, 0, "a change below tolerance is equal: {out}");
    let (code, out) = diff(&[&a, &same, "--rtol", "0", "--atol", "0"]);
    assert_eq!(code, 1, "{out}");
    assert_contains(&out, &["$$STARTNODES: 1 number(s) beyond tolerance"]);
    let (code, out) = diff(&[&a, &moved]);
    assert_eq!(code, 0, "block order is free: {out}");
    let (code, out) = diff(&[&a, &changed]);
    assert_eq!(code, 1);
    assert_contains(
        &out,
        &["$$STARTNODES: 1 number(s) beyond tolerance (max |Δ| = 1.0"],
    );
    assert_contains(
        &out,
        &[
            "$$MATERIAL_MODEL_SOLID: 0 number(s) beyond tolerance (max |Δ| = 0.000000e0), 1 text change(s); first: `mohr_coulomb` → `linear_elasticity_x`",
        ],
    );
    // CPS keywords compare without regard to case.
    let c1 = write(
        tmp.path(),
        "x.CPS_001",
        "### Anura3D_2023 ###\n$$K0_PROCEDURE\n1\n$$END\n",
    );
    let c2 = write(
        tmp.path(),
        "y.CPS_001",
        "### Anura3D_2023 ###\n$$k0_procedure\n0\n$$END\n",
    );
    let (code, out) = diff(&[&c1, &c2, "--json"]);
    assert_eq!(code, 1);
    let v: serde_json::Value = serde_json::from_str(
        out.lines()
            .take_while(|l| *l != "differences found")
            .collect::<Vec<_>>()
            .join("\n")
            .as_str(),
    )
    .unwrap();
    assert_eq!(v["equal"], false);
    assert!(
        v["files"][0]["findings"][0]
            .as_str()
            .unwrap()
            .starts_with("$$K0_PROCEDURE: 1 number(s) beyond tolerance")
    );
}

#[test]
fn mapf_rows_swapped_and_mps_by_id() {
    let tmp = tempfile::tempdir().unwrap();
    let head = "X[m] Y[m] Pwp[kPa] SigX[kPa] SigY[kPa] SigXY[kPa] SmoothLength[m]\n";
    let a = write(
        tmp.path(),
        "a.MAPF",
        &format!("{head}0 0 -1 -2 -3 0 0.1\n1 0 -4 -5 -6 0 0.1\n"),
    );
    let b = write(
        tmp.path(),
        "b.MAPF",
        &format!("{head}1 0 -4 -5 -6 0 0.1\n0 0 -1 -2 -3 0 0.1\n"),
    );
    let (code, out) = diff(&[&a, &b]);
    assert_eq!(code, 1);
    assert_contains(
        &out,
        &["Pwp[kPa]: 2 value(s) beyond tolerance, max |Δ| = 3.000000e0"],
    );
    let c = write(tmp.path(), "a.csv", "id,x,pwp\n1,0,-1\n2,1,-4\n");
    let d = write(tmp.path(), "b.csv", "id,x,pwp\n2,1,-4\n1,0,-1.5\n");
    let (code, out) = diff(&[&c, &d, "--by", "id"]);
    assert_eq!(code, 1);
    assert_contains(
        &out,
        &[
            "pwp: 1 value(s) beyond tolerance, max |Δ| = 5.000000e-1",
            "id 1: -1 → -1.5",
        ],
    );
}

#[test]
fn folders_compare_file_by_file() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    for dir in [&a, &b] {
        std::fs::copy(fixture("anura3d-mini/TwoMat.GOM"), dir.join("TwoMat.GOM")).unwrap();
    }
    std::fs::copy(
        fixture("anura3d-mini/TwoMat.CPS_001"),
        a.join("TwoMat.CPS_001"),
    )
    .unwrap();
    let (code, out) = diff(&[a.to_str().unwrap(), b.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert_contains(&out, &["TwoMat.CPS_001: only in"]);
    assert_eq!(diff(&[a.to_str().unwrap(), "/nonexistent"]).0, 2);
}
