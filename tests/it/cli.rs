//! The real binary, run in temporary folders: exit codes, positioned errors on
//! stderr, and output files that are complete or absent.

use crate::common;
use common::*;

#[test]
fn inspect_a_sample_project() {
    let dir = fixture("anura3d/K0_phreaticSurf_Geom");
    let (code, stdout, stderr) = run_split(&["inspect", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{stderr}");
    assert_contains(&stdout, &["MPs        993"]);
    assert!(stdout.contains("K0_phreaticSurf_Geom.CPS_001"));
    let (code, json, _) = run_split(&[
        "inspect",
        "--json",
        dir.join("K0_phreaticSurf_Geom.CPS_001").to_str().unwrap(),
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["material_points"], 993);
    assert_eq!(v["materials"][0]["name"], "Sand");
}

#[test]
fn inspect_writes_the_mp_table_and_refuses_to_overwrite() {
    let tmp = tempfile::tempdir().unwrap();
    let csv = tmp.path().join("mps.csv");
    let gom = fixture("anura3d/test-1005_3D/test-1005_3D.GOM");
    let (code, _, stderr) = run_split(&[
        "inspect",
        gom.to_str().unwrap(),
        "--mps",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 241);
    assert!(text.starts_with("id,element,material,local,x,y,z,volume\n1,"));
    let (code, _, stderr) = run_split(&[
        "inspect",
        gom.to_str().unwrap(),
        "--mps",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert_contains(&stderr, &["exists; pass --force"]);
}

#[test]
fn malformed_inputs_exit_2_with_a_positioned_message() {
    let tmp = tempfile::tempdir().unwrap();
    // Every malformed GOM the library tests read, and one the placement refuses.
    let mut cases = malformed::gom_cases();
    cases.push((
        "clockwise",
        malformed::two_mat().replacen("1 2 5\n", "1 5 2\n", 1),
        "TwoMat.GOM:18:1: element 1: clockwise or degenerate triangle",
    ));
    for (name, text, expected) in cases {
        let dir = tmp.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        let gom = dir.join("TwoMat.GOM");
        std::fs::write(&gom, text).unwrap();
        let (code, _, stderr) = run_split(&[
            "inspect",
            gom.to_str().unwrap(),
            "--mps",
            dir.join("mps.csv").to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{name}: {stderr}");
        assert!(
            stderr.contains(expected),
            "{name}: expected `{expected}` in {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
        assert!(
            !dir.join("mps.csv").exists(),
            "{name}: no output after an error"
        );
    }
}

#[test]
fn unknown_file_kind_and_missing_file_exit_2() {
    let (code, _, stderr) = run_split(&["inspect", "/nonexistent/x.GOM"]);
    assert_eq!(code, 2);
    assert!(stderr.starts_with("error: /nonexistent/x.GOM"), "{stderr}");
    let (code, _, _) = run_split(&["inspect", fixture("anura3d/README.md").to_str().unwrap()]);
    assert_eq!(code, 2);
}
