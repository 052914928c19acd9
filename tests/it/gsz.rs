//! GeoStudio `.gsz` projects read directly: the shipped sample end to end, a
//! hand-made archive in imperial units, and corrupted archives (exit code 2).

use crate::common;
use common::*;

use std::io::Write;
use std::path::Path;
use std::process::Command;

use a3d_init::formats::fem::StepChoice;
use a3d_init::formats::fem_csv::CsvOptions;
use a3d_init::formats::gsz::{read_project, read_step};
use a3d_init::model::Quantity;
use a3d_testkit::generate;

fn ply_bytes(nodes: &[[f64; 3]], header_override: Option<&str>) -> Vec<u8> {
    let header = header_override.map(str::to_string).unwrap_or_else(|| {
        format!("ply\nformat binary_little_endian 1.0\nelement version 1\nproperty ushort major\nproperty ushort minor\nelement node {}\nproperty double x\nproperty double y\nproperty double z\nend_header\n", nodes.len())
    });
    let mut b = header.into_bytes();
    b.extend_from_slice(&[1, 0, 0, 0]);
    for p in nodes {
        for v in p {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b
}

/// A one-analysis project: `files` are (name in the archive, bytes).
fn make_gsz(path: &Path, unit_system: &str, files: &[(&str, Vec<u8>)]) {
    let file = std::fs::File::create(path).unwrap();
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default();
    let xml = format!(
        "<?xml version=\"1.0\"?><GSIData><EngCoords UnitSystem=\"{unit_system}\" /><Analyses Len=\"1\"><Analysis><ID>1</ID><Name>SEEP/W Drawdown</Name><Kind>SEEP/W</Kind><Method>SteadyState</Method></Analysis></Analyses></GSIData>"
    );
    zip.start_file("project.xml", options).unwrap();
    zip.write_all(xml.as_bytes()).unwrap();
    for (name, bytes) in files {
        zip.start_file(*name, options).unwrap();
        zip.write_all(bytes).unwrap();
    }
    zip.finish().unwrap();
}

#[test]
fn shipped_sample_reads_step_010_like_the_extracted_csv() {
    let gsz = fixture("geostudio-gsz-internal/1d-unsaturated-column/1D_unsaturated_column.gsz");
    let project = read_project(&gsz).unwrap();
    assert_eq!(project.analyses.len(), 1);
    let a = &project.analyses[0];
    assert_eq!(
        (
            a.name.as_str(),
            a.kind.as_str(),
            a.method.as_str(),
            a.folder.as_str()
        ),
        ("SEEP/W Analysis", "SEEP/W", "Transient", "SEEP&3W Analysis")
    );
    assert_eq!(a.steps.len(), 51);
    assert_eq!(a.steps[5].time, Some(12960.0));
    let (nodes, _, note) =
        read_step(&gsz, None, &StepChoice::Number(10), &CsvOptions::default()).unwrap();
    assert_contains(&note, &["step 010 at t = 12960 s"]);
    assert_eq!(nodes.len(), 306);
    let extracted = std::fs::read_to_string(fixture(
        "geostudio-gsz-internal/1d-unsaturated-column/seepw-analysis_010_node.csv",
    ))
    .unwrap();
    let pwp = nodes.field(Quantity::Pwp).unwrap();
    for (line, got) in extracted.lines().skip(1).zip(pwp) {
        let v: f64 = line.split(',').nth(1).unwrap().trim().parse().unwrap();
        assert_eq!(*got, -v, "GeoStudio sign flipped into Anura3D's");
    }
    let (by_time, _, _) = read_step(
        &gsz,
        Some("1"),
        &StepChoice::Time(12960.0),
        &CsvOptions::default(),
    )
    .unwrap();
    assert_eq!(by_time.field(Quantity::Pwp), nodes.field(Quantity::Pwp));
}

#[test]
fn shipped_sample_maps_end_to_end() {
    let tmp = tempfile::tempdir().unwrap();
    let gsz = fixture("geostudio-gsz-internal/1d-unsaturated-column/1D_unsaturated_column.gsz");
    let (nodes, _, _) = read_step(&gsz, None, &StepChoice::Last, &CsvOptions::default()).unwrap();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &nodes.positions {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
    let mesh = generate::structured_tri_mesh(lo[0], lo[1], w, h, 2, 20);
    let gom = tmp.path().join("column.GOM");
    write_gom(&gom, mesh, &soil_spec(0.5, 1e4, 1e-11));
    let out = tmp.path().join("out");
    let (code, stderr) = run_map(
        &gom,
        &gsz,
        &out,
        &["--step", "10", "--outside", "nearest", "--generate-cps"],
    );
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["fem_nodes"], 306);
    assert_eq!(report["material_points"], 2 * 20 * 2 * 3);
    let (code, stdout) = {
        let o = Command::new(env!("CARGO_BIN_EXE_a3d-init"))
            .args(["inspect", gsz.to_str().unwrap()])
            .output()
            .unwrap();
        (
            o.status.code().unwrap(),
            String::from_utf8_lossy(&o.stdout).into_owned(),
        )
    };
    assert_eq!(code, 0);
    assert_contains(
        &stdout,
        &[
            "analysis   1 `SEEP/W Analysis`: SEEP/W Transient",
            "306 nodes (2D), fields: pwp",
        ],
    );
}

#[test]
fn imperial_project_is_converted() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("imperial.gsz");
    let nodes = [
        [0.0, 0.0, 0.0],
        [10.0, 0.0, 0.0],
        [0.0, 10.0, 0.0],
        [10.0, 10.0, 0.0],
    ];
    make_gsz(
        &path,
        "Imperial",
        &[
            ("SEEP&3W Drawdown/Mesh.ply", ply_bytes(&nodes, None)),
            (
                "SEEP&3W Drawdown/001/node.csv",
                b"Node,PoreWaterPressure\r\n1,624\r\n2,624\r\n3,0\r\n4,0\r\n".to_vec(),
            ),
        ],
    );
    let (fem, report, note) = read_step(
        &path,
        Some("SEEP/W Drawdown"),
        &StepChoice::Last,
        &CsvOptions::default(),
    )
    .unwrap();
    assert_contains(&note, &["Imperial (ft, psf; converted to m and kPa)"]);
    assert!(
        (fem.positions[1][0] - 3.048).abs() < 1e-12 && (fem.positions[2][1] - 3.048).abs() < 1e-12
    );
    let pwp = fem.field(Quantity::Pwp).unwrap();
    assert!(
        (pwp[0] + 624.0 * 0.047880258980335).abs() < 1e-9,
        "{}",
        pwp[0]
    );
    assert_eq!(report.columns[1].unit.as_deref(), Some("psf"));
}

#[test]
fn corrupted_archives_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let gom = fixture("anura3d-mini/TwoMat.GOM");
    let nodes = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [2.0, 1.0, 0.0],
    ];
    let csv = b"Node,PoreWaterPressure\n1,1\n2,1\n3,0\n4,0\n".to_vec();
    type Files = Vec<(&'static str, Vec<u8>)>;
    let cases: Vec<(&str, Files, &str)> = vec![
        (
            "missing_ply",
            vec![("SEEP&3W Drawdown/001/node.csv", csv.clone())],
            "the archive has no `SEEP&3W Drawdown/Mesh.ply`",
        ),
        (
            "bad_ply_header",
            vec![
                (
                    "SEEP&3W Drawdown/Mesh.ply",
                    ply_bytes(
                        &nodes,
                        Some("ply\nformat ascii 1.0\nelement node 4\nend_header\n"),
                    ),
                ),
                ("SEEP&3W Drawdown/001/node.csv", csv.clone()),
            ],
            "unsupported PLY format `ascii`",
        ),
        (
            // A table may list a subset of the mesh (#14), but not a node outside it.
            "node_outside_mesh",
            vec![
                ("SEEP&3W Drawdown/Mesh.ply", ply_bytes(&nodes[..3], None)),
                ("SEEP&3W Drawdown/001/node.csv", csv.clone()),
            ],
            "001/node.csv:5:1: node 4 is not in the mesh: SEEP&3W Drawdown/Mesh.ply has 3 nodes",
        ),
        (
            "no_results",
            vec![("SEEP&3W Drawdown/Mesh.ply", ply_bytes(&nodes, None))],
            "has no saved results",
        ),
    ];
    for (name, files, expected) in cases {
        let path = tmp.path().join(format!("{name}.gsz"));
        make_gsz(&path, "Metric", &files);
        let out = tmp.path().join(format!("{name}-out"));
        let (code, stderr) = run_map(&gom, &path, &out, &[]);
        assert_eq!(code, 2, "{name}: {stderr}");
        assert!(
            stderr.contains(expected),
            "{name}: expected `{expected}` in {stderr}"
        );
        assert!(!out.exists());
    }
    // A truncated zip.
    let good = tmp.path().join("good.gsz");
    make_gsz(
        &good,
        "Metric",
        &[
            ("SEEP&3W Drawdown/Mesh.ply", ply_bytes(&nodes, None)),
            ("SEEP&3W Drawdown/001/node.csv", csv),
        ],
    );
    let bytes = std::fs::read(&good).unwrap();
    let truncated = tmp.path().join("truncated.gsz");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let (code, stderr) = run_map(&gom, &truncated, &tmp.path().join("t-out"), &[]);
    assert_eq!(code, 2, "{stderr}");
    assert_contains(&stderr, &["not a readable .gsz (zip) archive"]);
}

/// #24: `--step time=NaN` (or `inf`, `1e400`) mapped step 0 at t = 0 with exit
/// 0; a non-finite time is refused by the option parser and by `read_step`.
#[test]
fn step_time_nan_or_infinite_is_refused() {
    for text in [
        "time=NaN",
        "time=nan",
        "time=inf",
        "time=-inf",
        "time=1e400",
    ] {
        let e = text.parse::<StepChoice>().unwrap_err();
        assert!(e.contains("finite number of seconds"), "{text}: {e}");
    }
    assert_eq!("time=12960".parse(), Ok(StepChoice::Time(12960.0)));
    let gsz = fixture("geostudio-gsz-internal/1d-unsaturated-column/1D_unsaturated_column.gsz");
    for t in [f64::NAN, f64::INFINITY] {
        let e = read_step(&gsz, None, &StepChoice::Time(t), &CsvOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("finite number of seconds"), "{e}");
    }
    for step in ["time=NaN", "time=1e400"] {
        let (code, text) =
            common::run(&["inspect", "--fem", gsz.to_str().unwrap(), "--step", step]);
        assert_eq!(code, 2, "{step}: {text}");
        assert_contains(&text, &["--step", step, "finite number of seconds"]);
    }
}
