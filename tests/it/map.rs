//! `a3d-init map` end to end: an analytic hydrostatic/geostatic block, a real
//! Anura3D sample (MAPF parsed back row by row, CPS changed in two keywords only,
//! GOM byte-identical), and bad inputs that exit 2 and leave nothing behind.

use crate::common;
use common::*;

use std::path::{Path, PathBuf};

use a3d_init::formats::cps::CpsDocument;
use a3d_init::formats::gom::write::model_to_text;
use a3d_init::formats::{mapf, mps_table};
use a3d_testkit::generate::{self, MaterialSpec};

const GAMMA_W: f64 = 9.807;

fn block_spec() -> MaterialSpec {
    soil_spec(0.5, 1e4, 1e-10)
}

/// A 20 × 10 m block (TRI3, 1 m cells, 3 MPs each) and FEM nodes on a 0.5 m grid
/// with hydrostatic pwp, water table at the top (y = 10).
fn write_block(dir: &Path) -> (PathBuf, PathBuf) {
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 20.0, 10.0, 20, 10);
    let model = generate::single_material_model(mesh, &block_spec(), 3);
    let gom = dir.join("block.GOM");
    std::fs::write(&gom, model_to_text(&model, "2023")).unwrap();
    std::fs::write(
        dir.join("block.CPS_001"),
        "### Anura3D_2023 ###\n$$GRAVITY_ACCELERATION\n9.81\n$$K0_PROCEDURE\n1\n$$END\n",
    )
    .unwrap();
    let fem = dir.join("seep.csv");
    let csv = hydrostatic_grid_csv("X (m),Y (m),PWP (kPa)", 40, 20, GAMMA_W, 10.0);
    std::fs::write(&fem, csv).unwrap();
    (gom, fem)
}

#[test]
fn hydrostatic_block_maps_to_the_analytic_state() {
    let tmp = tempfile::tempdir().unwrap();
    let (gom, fem) = write_block(tmp.path());
    let out = tmp.path().join("out");
    let (code, stderr) = run_map(
        &gom,
        &fem,
        &out,
        // Per-MP values are what this test checks against the analytic field.
        &["--mixed-state", "per-mp"],
    );
    assert_eq!(code, 0, "{stderr}");
    let (points, states) = mps_table::read_states(&out.join("mps.csv")).unwrap();
    assert_eq!(points.len(), 20 * 10 * 2 * 3);
    let g = 9.81;
    let gamma_sat = (0.6 * 2650.0 + 0.4 * 1000.0) * g / 1000.0;
    let (mut interior, mut worst_interior, mut worst_edge) = (0, 0.0f64, 0.0f64);
    for (p, s) in points.iter().zip(&states) {
        let [x, y, _] = p.position;
        let depth = 10.0 - y;
        let pwp = -GAMMA_W * depth;
        let err = (s.pwp - pwp).abs();
        if x > 1.0 && x < 19.0 && y > 1.0 && y < 9.0 {
            interior += 1;
            worst_interior = worst_interior.max(err);
        } else {
            worst_edge = worst_edge.max(err);
        }
        // Geostatic: σv = −γsat·depth exactly (saturated everywhere), σh = K0·σ'v + p.
        let sigma_v = -gamma_sat * depth;
        assert!(
            (s.total[1] - sigma_v).abs() < 1e-9 * (1.0 + sigma_v.abs()),
            "σv at {:?}: {} vs {sigma_v}",
            p.position,
            s.total[1]
        );
        let sigma_h = 0.5 * (sigma_v - s.pwp) + s.pwp;
        assert!((s.total[0] - sigma_h).abs() < 1e-9 * (1.0 + sigma_h.abs()));
    }
    assert!(interior > 500);
    // Shepard interpolation reproduces a linear field exactly only on symmetric
    // stencils; at the MP positions of 1 m triangles over a 0.5 m node grid the
    // interior error stays below 0.01 kPa (1e-4 of the 98 kPa range); at the
    // edges the one-sided stencil is off by at most γw·h.
    assert!(
        worst_interior < 0.01,
        "interior pwp error {worst_interior} kPa"
    );
    assert!(
        worst_edge < GAMMA_W * 0.5,
        "edge pwp error {worst_edge} kPa"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["fem_nodes"], 41 * 21);
    assert_eq!(report["material_points"], 1200);
    assert_eq!(report["null_points"], 0);
    assert_eq!(report["stress_source"], "geostatic");
    assert!((report["smoothing_length"].as_f64().unwrap() - 0.5).abs() < 1e-12);
}

#[test]
fn sample_project_round_trip_through_map() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("slope");
    let fem = fixture("geostudio-csv/k0-slope-hydrostatic.csv");
    let model_dir = fixture("anura3d/K0_phreaticSurf_Geom");
    let (code, stderr) = run_map(&model_dir, &fem, &out, &["--mixed-state", "per-mp"]);
    assert_eq!(code, 0, "{stderr}");
    // GOM byte-identical.
    assert_eq!(
        std::fs::read(out.join("K0_phreaticSurf_Geom.GOM")).unwrap(),
        std::fs::read(model_dir.join("K0_phreaticSurf_Geom.GOM")).unwrap()
    );
    // CPS differs only in the two keywords.
    let cps = CpsDocument::read(&out.join("K0_phreaticSurf_Geom.CPS_001")).unwrap();
    assert_eq!(cps.get("$$K0_PROCEDURE"), Some(vec!["0"]));
    assert_eq!(
        cps.get("$$MP_STRESS_INITIALIZATION_FROMFILE"),
        Some(vec!["1"])
    );
    let original = CpsDocument::read(&model_dir.join("K0_phreaticSurf_Geom.CPS_001")).unwrap();
    for block in original.document().blocks() {
        let k = block.keyword.to_ascii_uppercase();
        if k != "$$K0_PROCEDURE" && k != "$$MP_STRESS_INITIALIZATION_FROMFILE" {
            assert_eq!(cps.get(&block.keyword), original.get(&block.keyword), "{k}");
        }
    }
    // MAPF: one row per MP, in MP order, exactly the mapped values.
    let table = mapf::read(&out.join("K0_phreaticSurf_Geom.MAPF")).unwrap();
    let (points, states) = mps_table::read_states(&out.join("mps.csv")).unwrap();
    assert_eq!(table.rows.len(), 993);
    assert_eq!(table.headers, mapf::headers(2));
    let h = table.rows[0][6];
    for ((row, p), s) in table.rows.iter().zip(&points).zip(&states) {
        assert_eq!((row[0], row[1]), (p.position[0], p.position[1]));
        assert_eq!(
            (row[2], row[3], row[4], row[5]),
            (s.pwp, s.total[0], s.total[1], s.total[3])
        );
        assert!(row.iter().all(|v| v.is_finite()));
        assert_eq!(row[6], h);
    }
    // Exact-point mode: 2h below half the smallest MP spacing.
    let mut min_d = f64::INFINITY;
    for (i, a) in points.iter().enumerate() {
        for b in &points[i + 1..] {
            min_d = min_d.min(
                ((a.position[0] - b.position[0]).powi(2) + (a.position[1] - b.position[1]).powi(2))
                    .sqrt(),
            );
        }
    }
    assert!(2.0 * h < 0.5 * min_d, "h = {h}, min spacing {min_d}");
    // The fixture is the hydrostatic field it claims to be (GeoStudio sign).
    let text = std::fs::read_to_string(&fem).unwrap();
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        assert!((f[3] - GAMMA_W * (1.0 - f[2])).abs() < 1e-9);
    }
    // Below the water table (y = 1) pwp is compressive (negative), above it suction;
    // Shepard's one-sided stencils under the slope surface bias the value by up to
    // a quarter of γw·h (h = 0.5 m here).
    for (p, s) in points.iter().zip(&states) {
        assert!(
            (s.pwp - (-GAMMA_W * (1.0 - p.position[1]))).abs() < 0.25 * GAMMA_W * 0.5,
            "{:?}: {}",
            p.position,
            s.pwp
        );
    }
    // Refuses to overwrite without --force, and leaves the old folder intact.
    let (code, stderr) = run_map(&model_dir, &fem, &out, &[]);
    assert_eq!(code, 2);
    assert!(stderr.contains("exists; pass --force"));
    assert!(out.join("report.json").exists());
}

#[test]
fn bad_inputs_exit_2_and_leave_no_output() {
    let tmp = tempfile::tempdir().unwrap();
    let (gom, good) = write_block(tmp.path());
    let good_text = std::fs::read_to_string(&good).unwrap();
    let with_line = |k: usize, line: &str| {
        let mut lines: Vec<String> = good_text.lines().map(String::from).collect();
        lines[k] = line.to_string();
        lines.join("\n") + "\n"
    };
    let far: String = "X (m),Y (m),PWP (kPa)\n".to_string()
        + &(0..10)
            .map(|i| format!("{},{},1\n", 100.0 + i as f64, 100.0 + (i % 3) as f64))
            .collect::<String>();
    // Bad files, read with the default options.
    let bad_files: Vec<(&str, String, &str)> = vec![
        (
            "missing_coordinate_column",
            good_text.replace("X (m),", "A,"),
            "seep.csv:1:1: no header with X and Y",
        ),
        (
            "unknown_unit",
            good_text.replace("PWP (kPa)", "PWP (bar)"),
            "seep.csv:1:13: unknown pressure unit `bar`",
        ),
        (
            "non_numeric_cell",
            with_line(5, "2,0,abc"),
            "seep.csv:6:5: expected a number for pwp, found `abc`",
        ),
        (
            "nan_cell",
            with_line(5, "2,0,NaN"),
            "seep.csv:6:5: expected a number for pwp, found `NaN`",
        ),
        (
            "duplicate_nodes",
            with_line(5, "0,0,98.07"),
            "seep.csv:6:1: duplicate node: same coordinates as line 2",
        ),
        (
            "missing_y",
            with_line(5, "2"),
            "seep.csv:6:2: missing y coordinate",
        ),
        (
            "mixed_2d_3d",
            "X,Y,Z,PWP\n0,0,0,1\n1,0,0,1\n0,1\n".into(),
            "seep.csv:4:4: missing z: some rows are 3D and this one is 2D",
        ),
        ("empty_file", String::new(), "seep.csv:1:1: empty file"),
        (
            "header_only",
            "X,Y,PWP\n".into(),
            "seep.csv:1:1: the table has a header but no data rows",
        ),
        (
            "every_node_outside",
            far,
            "seep.csv: the FEM nodes do not reach the model: 1200 of 1200 MPs",
        ),
        (
            "utf16",
            String::from_utf8_lossy(&[0xFF, 0xFE, b'X', 0]).into_owned(),
            "seep.csv:1:1:",
        ),
        (
            "too_few_nodes",
            "X,Y,PWP\n0,0,1\n1,0,1\n".into(),
            "at least 3 FEM nodes are needed",
        ),
    ];
    // Bad options, with the good file.
    let bad_options: [(&str, &[&str], &str); 6] = [
        (
            "bad_columns_override",
            &["--columns", "pwp=Pressure"],
            "seep.csv:1:1: the column mapping (--columns) names pwp=Pressure: no such header",
        ),
        (
            "bad_columns_field",
            &["--columns", "foo=X"],
            "--columns: `foo`: unknown field",
        ),
        (
            "bad_units_override",
            &["--fem-units", "length=furlong"],
            "--fem-units: unknown unit `furlong`",
        ),
        (
            "bad_kernel",
            &["--kernel", "epanechnikov"],
            "--kernel epanechnikov",
        ),
        (
            "negative_h",
            &["--h=-1"],
            "--h -1: the smoothing length must be a positive",
        ),
        (
            "stress_fem_without_stress",
            &["--stress", "fem"],
            "stress source `fem`: the FEM files have no total stress columns",
        ),
    ];
    let cases: Vec<(&str, String, &[&str], &str)> = bad_files
        .into_iter()
        .map(|(name, text, expected)| (name, text, &[][..], expected))
        .chain(
            bad_options
                .into_iter()
                .map(|(name, extra, expected)| (name, good_text.clone(), extra, expected)),
        )
        .collect();
    assert!(cases.len() >= 15);
    for (name, text, extra, expected) in cases {
        let dir = tmp.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        let fem = dir.join("seep.csv");
        if name == "utf16" {
            std::fs::write(&fem, [0xFF, 0xFE, b'X', 0, b',', 0]).unwrap();
        } else {
            std::fs::write(&fem, &text).unwrap();
        }
        let out = dir.join("out");
        let (code, stderr) = run_map(&gom, &fem, &out, extra);
        assert_eq!(code, 2, "{name}: {stderr}");
        assert!(
            stderr.contains(expected),
            "{name}: expected `{expected}` in:\n{stderr}"
        );
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
        assert!(!out.exists(), "{name}: an output folder was left behind");
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(leftovers.len(), 1, "{name}: {leftovers:?}");
    }
}

#[test]
fn conflicting_joins_are_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let (gom, _) = write_block(tmp.path());
    let a = tmp.path().join("a.csv");
    let b = tmp.path().join("b.csv");
    std::fs::write(&a, "Node,X,Y,PWP\n1,0,0,1\n2,1,0,2\n3,0,1,3\n").unwrap();
    let out = tmp.path().join("o");
    let join = || run_map(&gom, &a, &out, &["--fem", b.to_str().unwrap()]);
    std::fs::write(&b, "Node,X,Y,PWP\n1,0,0,1\n2,1,0,5\n3,0,1,3\n").unwrap();
    let (code, stderr) = join();
    assert_eq!(code, 2);
    assert_contains(&stderr, &["pwp of node 2 is -5 but -2"]);
    std::fs::write(&b, "Node,X,Y,PWP\n1,0,0,1\n2,1,0,2\n4,0,1,3\n").unwrap();
    let (code, stderr) = join();
    assert_eq!(code, 2);
    assert_contains(&stderr, &["node 3 of"]);
    assert!(!tmp.path().join("o").exists());
}

#[test]
fn real_geostudio_node_csv_with_mesh_ply() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("rd");
    let dir = fixture("geostudio-gsz-internal/rapid-drawdown");
    let node = dir.join("1-initial-steady-state_001_node.csv");
    let ply = dir.join("1-initial-steady-state_Mesh.ply");
    let gom = fixture("anura3d-rapid-drawdown/rapid_drawdown.GOM");
    // The fixities its README states: 57 nodes fixed in x and y on the
    // downward-facing sides, one on rollers (the toe block's end).
    let (model, _) = a3d_init::formats::gom::GomDocument::read(&gom)
        .unwrap()
        .model()
        .unwrap();
    let fixed = |f: [bool; 2]| {
        model
            .solid_fixity
            .iter()
            .filter(|x| [x[0], x[1]] == f)
            .count()
    };
    assert_eq!((fixed([true, true]), fixed([true, false])), (57, 1));
    // The embankment stands on its fixed base (#38: the base at y = 0 was
    // free, and no state at rest existed): `auto` solves for equilibrium
    // under the steady-state pore pressures and finds it.
    let mesh_args = ["--fem-mesh", ply.to_str().unwrap(), "--generate-cps"];
    let (code, stderr) = run_map(&gom, &node, &out, &mesh_args);
    assert_eq!(code, 0, "{stderr}");
    assert_contains(
        &stderr,
        &["stress: equilibrium", "equilibrium: IN EQUILIBRIUM"],
    );
    // And the runner keeps the state it was given at rest (the state as
    // intended: Anura3D's MAPF reader would first move τxy into σ'zz).
    let (code, text) = run(&[
        "verify",
        "--mpm",
        out.join("rapid_drawdown.GOM").to_str().unwrap(),
        "--state",
        out.join("mps.csv").to_str().unwrap(),
        "--out",
        tmp.path().join("v").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{text}");
    assert_contains(&text, &["verdict    IN EQUILIBRIUM"]);
    let (points, states) = mps_table::read_states(&out.join("mps.csv")).unwrap();
    assert_eq!(points.len(), 992 * 3);
    // GeoStudio: −38.8 .. 78.5 kPa (positive below the water table). Anura3D: flipped.
    let (lo, hi) = states
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
            (a.min(s.pwp), b.max(s.pwp))
        });
    assert!((-78.5 - 1e-9..-70.0).contains(&lo), "min pwp {lo}");
    assert!(hi > 30.0 && hi < 38.8 + 1e-9, "max pwp {hi}");
    // The most compressive pwp lies below the strongest suction.
    let most = points
        .iter()
        .zip(&states)
        .min_by(|a, b| a.1.pwp.total_cmp(&b.1.pwp))
        .unwrap();
    let least = points
        .iter()
        .zip(&states)
        .max_by(|a, b| a.1.pwp.total_cmp(&b.1.pwp))
        .unwrap();
    assert!(
        most.0.position[1] < least.0.position[1] - 5.0,
        "{:?} vs {:?}",
        most.0.position,
        least.0.position
    );
    // Without the mesh the node.csv has no coordinates: a clear error.
    let (code, stderr) = run_map(&gom, &node, &tmp.path().join("x"), &["--generate-cps"]);
    assert_eq!(code, 2);
    assert_contains(
        &stderr,
        &["no X and Y columns; give the GeoStudio mesh (Mesh.ply)"],
    );
}

#[test]
fn malformed_ply_files_are_positioned_errors() {
    use a3d_init::formats::ply::parse_ply_nodes;
    let good = std::fs::read(fixture(
        "geostudio-gsz-internal/rapid-drawdown/1-initial-steady-state_Mesh.ply",
    ))
    .unwrap();
    assert_eq!(
        parse_ply_nodes(Path::new("m.ply"), &good).unwrap().len(),
        553
    );
    let header_end = good.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let text = String::from_utf8_lossy(&good[..header_end]).into_owned();
    let with_header = |h: &str| [h.as_bytes(), &good[header_end..]].concat();
    for (name, bytes, expected) in [
        (
            "bad_magic",
            [b"plx".as_slice(), &good[3..]].concat(),
            "m.ply:1:1: not a PLY file",
        ),
        (
            "ascii_format",
            with_header(&text.replace("binary_little_endian", "ascii")),
            "m.ply:2:8: unsupported PLY format `ascii`",
        ),
        (
            "no_node_element",
            with_header(&text.replace("element node", "element knot")),
            "m.ply:1:1: the PLY has no `node` element",
        ),
        (
            "float_coordinates",
            with_header(&text.replace("property double x", "property float x")),
            "m.ply:7:1: the PLY `node` element must be `double x, y, z`: property 1 is `property float x`",
        ),
        (
            "truncated",
            good[..header_end + 4 + 24 * 100].to_vec(),
            "truncated PLY: 553 nodes need 13272 bytes",
        ),
        (
            "no_end_header",
            good[..50].to_vec(),
            "m.ply:1:1: not a PLY file: no `end_header`",
        ),
    ] {
        let err = parse_ply_nodes(Path::new("m.ply"), &bytes)
            .unwrap_err()
            .to_string();
        assert!(err.contains(expected), "{name}: {err}");
    }
}

/// #17: the binary `mps.vtu` and `fem.vtu` read back to the values of `mps.csv`
/// and the FEM table, bit for bit; MAPF and mps.csv are the same for 1 and 2 threads.
#[test]
fn binary_vtu_agrees_with_the_tables_and_outputs_do_not_depend_on_threads() {
    let tmp = tempfile::tempdir().unwrap();
    let (gom, fem) = write_block(tmp.path());
    let mut outputs = Vec::new();
    for threads in ["1", "2"] {
        let out = tmp.path().join(format!("out{threads}"));
        let output = std::process::Command::new(env!("CARGO_BIN_EXE_a3d-init"))
            .args(["map", "--fem", fem.to_str().unwrap(), "--mpm"])
            .arg(&gom)
            .arg("--out")
            .arg(&out)
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        outputs.push(out);
    }
    for name in ["block.MAPF", "mps.csv", "mps.vtu", "fem.vtu"] {
        let a = std::fs::read(outputs[0].join(name)).unwrap();
        let b = std::fs::read(outputs[1].join(name)).unwrap();
        assert!(a == b, "{name} differs between 1 and 2 threads");
    }
    let out = &outputs[0];
    let (points, states) = mps_table::read_states(&out.join("mps.csv")).unwrap();
    let vtu = a3d_init::formats::vtu::read(&out.join("mps.vtu")).unwrap();
    assert_eq!(vtu.points.len(), points.len());
    let array = |name: &str| {
        &vtu.arrays
            .iter()
            .find(|a| a.name == name)
            .unwrap_or_else(|| panic!("no {name}"))
            .values
    };
    for (i, (p, s)) in points.iter().zip(&states).enumerate() {
        assert_eq!(vtu.points[i], p.position);
        assert_eq!(array("pwp")[i], s.pwp);
        assert_eq!(array("total_stress")[9 * i + 4], s.total[1]);
        assert_eq!(array("volume")[i], p.volume);
    }
    let fem_vtu = a3d_init::formats::vtu::read(&out.join("fem.vtu")).unwrap();
    assert_eq!(fem_vtu.points.len(), 41 * 21);
    assert_eq!(fem_vtu.arrays[0].name, "pwp");
}
