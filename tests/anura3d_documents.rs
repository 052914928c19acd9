//! GOM and CPS documents against the 11 real Anura3D samples in
//! `fixtures/anura3d/`: byte-identical round trips, typed views, edits that touch
//! one block only, and malformed inputs that must give `path:line:col` errors.

mod common;
use common::soil_spec;

use std::path::{Path, PathBuf};

use a3d_init::formats::cps::CpsDocument;
use a3d_init::formats::gom::GomDocument;
use a3d_init::model::{Dimension, ElementType};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

/// Every sample file with its kind ("GOM" or "CPS"; OPD files share the CPS layout).
fn sample_files() -> Vec<(PathBuf, &'static str)> {
    let mut out = Vec::new();
    for dir in std::fs::read_dir(fixtures().join("anura3d")).unwrap() {
        let dir = dir.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        for file in std::fs::read_dir(&dir).unwrap() {
            let path = file.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            if name.contains(".GOM") || name.ends_with("-2.dat") {
                out.push((path, "GOM"));
            } else if name.contains(".CPS_") || name.contains(".OPD_") {
                out.push((path, "CPS"));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn every_sample_round_trips_byte_for_byte() {
    let files = sample_files();
    assert_eq!(
        files.iter().filter(|(_, k)| *k == "GOM").count(),
        12,
        "GOM files (incl. -2.dat and stage1)"
    );
    assert!(files.iter().filter(|(_, k)| *k == "CPS").count() >= 12);
    for (path, kind) in files {
        let original = std::fs::read(&path).unwrap();
        let written = match kind {
            "GOM" => GomDocument::read(&path).unwrap().to_text(),
            _ if path.to_string_lossy().contains(".OPD_") => {
                CpsDocument::read_opd(&path).unwrap().to_text()
            }
            _ => CpsDocument::read(&path).unwrap().to_text(),
        };
        assert!(
            written.as_bytes() == original.as_slice(),
            "{} did not round-trip",
            path.display()
        );
    }
}

#[test]
fn every_sample_gom_has_a_typed_view() {
    for (path, kind) in sample_files() {
        if kind != "GOM" {
            continue;
        }
        let doc = GomDocument::read(&path).unwrap();
        let (model, info) = doc.model().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            model.element_material.len(),
            model.mesh.n_elements(),
            "{}",
            path.display()
        );
        assert_eq!(info.element_lines.len(), model.mesh.n_elements());
        assert!(!model.materials.is_empty());
    }
}

#[test]
fn typed_view_of_k0_phreatic_slope() {
    let path = fixtures().join("anura3d/K0_phreaticSurf_Geom/K0_phreaticSurf_Geom.GOM");
    let (model, _) = GomDocument::read(&path).unwrap().model().unwrap();
    assert_eq!(model.mesh.dimension, Dimension::PlaneStrain);
    assert_eq!(model.mesh.element_type, ElementType::Tri3);
    assert_eq!((model.mesh.n_elements(), model.mesh.n_nodes()), (822, 456));
    let sand = &model.materials[0];
    assert_eq!(sand.name, "Sand");
    assert_eq!(sand.material_type, "unsaturated_material_2phase_suction");
    assert_eq!(sand.porosity, Some(0.4));
    assert_eq!(sand.density_solid, Some(2650.0));
    assert_eq!(sand.density_liquid, Some(1000.0));
    assert_eq!(sand.k0, Some(0.5));
    assert_eq!(sand.young_modulus, Some(50000.0));
    assert_eq!(sand.poisson_ratio, Some(0.3));
    assert_eq!(
        sand.retention,
        Some(a3d_init::model::RetentionCurve::Linear { av: 4e-4 })
    );
    assert_eq!(
        model.element_material.iter().filter(|&&m| m > 0).count(),
        331
    );
}

#[test]
fn typed_view_of_two_material_column_collapse() {
    let path = fixtures().join("anura3d/ColumCollapse/ColumCollapse.GOM_stage0");
    let (model, info) = GomDocument::read(&path).unwrap().model().unwrap();
    assert_eq!(info.version, "2025");
    let column = &model.materials[0];
    assert_eq!(
        (column.name.as_str(), column.model.as_deref()),
        ("Column", Some("mohr_coulomb"))
    );
    assert_eq!(
        (
            column.friction_angle,
            column.cohesion,
            column.dilatancy_angle,
            column.tensile_strength
        ),
        (Some(30.0), Some(0.0), Some(0.0), Some(0.0))
    );
    assert_eq!(model.materials[1].name, "Base");
    assert!(model.solid_fixity.iter().any(|f| f[0] && f[1]));
}

#[test]
fn tetrahedral_old_reads_ten_ids_per_element() {
    let path = fixtures().join("anura3d/test-1005_3D/test-1005_3D.GOM");
    let (model, _) = GomDocument::read(&path).unwrap().model().unwrap();
    assert_eq!(model.mesh.element_type, ElementType::TetOld);
    assert_eq!(model.mesh.connectivity.len(), 66 * 10);
    // First element line: 189 181 185 199 184 182 188 193 190 192 (1-based ids).
    let first_ids: Vec<u32> = model.mesh.element_nodes(0).iter().map(|n| n + 1).collect();
    assert_eq!(
        first_ids,
        [189, 181, 185, 199, 184, 182, 188, 193, 190, 192]
    );
}

#[test]
fn editing_mp_counts_rewrites_only_that_block() {
    let path = fixtures().join("anura3d/ColumCollapse/ColumCollapse.GOM_stage0");
    let mut doc = GomDocument::read(&path).unwrap();
    let (model, _) = doc.model().unwrap();
    let counts: Vec<(u32, u32)> = model
        .mp_counts
        .iter()
        .map(|&(s, l)| if s > 0 { (6, l) } else { (0, l) })
        .collect();
    doc.set_mp_counts(&counts).unwrap();
    let original = std::fs::read_to_string(&path).unwrap();
    let edited = doc.to_text();
    let (a, b): (Vec<&str>, Vec<&str>) = (
        original.split("\r\n").collect(),
        edited.split("\r\n").collect(),
    );
    assert_eq!(a.len(), b.len());
    let changed: Vec<usize> = (0..a.len()).filter(|&i| a[i] != b[i]).collect();
    assert_eq!(
        changed.len(),
        800,
        "only the 800 active elements' MP lines change"
    );
    let block_start = a
        .iter()
        .position(|l| *l == "$$START_NUMBER_OF_MATERIAL_POINTS")
        .unwrap();
    assert!(
        changed
            .iter()
            .all(|&i| i > block_start && i <= block_start + 4600)
    );
    let reread = GomDocument::parse(&path, edited).unwrap();
    assert_eq!(reread.model().unwrap().0.mp_counts, counts);
}

#[test]
fn cps_set_switches_mapf_on_and_k0_off() {
    let path = fixtures().join("anura3d/K0_phreaticSurf_Geom/K0_phreaticSurf_Geom.CPS_001");
    let mut cps = CpsDocument::read(&path).unwrap();
    assert_eq!(cps.get("$$K0_PROCEDURE"), Some(vec!["1"]));
    cps.set("$$K0_PROCEDURE", &["0"]);
    cps.set("$$MP_STRESS_INITIALIZATION_FROMFILE", &["1"]);
    let text = cps.to_text();
    let reread = CpsDocument::parse(&path, text.clone()).unwrap();
    assert_eq!(reread.get("$$K0_PROCEDURE"), Some(vec!["0"]));
    assert_eq!(
        reread.get("$$MP_STRESS_INITIALIZATION_FROMFILE"),
        Some(vec!["1"])
    );
    let original = std::fs::read_to_string(&path).unwrap();
    let (a, b): (Vec<&str>, Vec<&str>) = (original.lines().collect(), text.lines().collect());
    assert_eq!(
        b.len(),
        a.len() + 2,
        "one keyword and one value line inserted"
    );
    let k0 = a
        .iter()
        .position(|l| l.eq_ignore_ascii_case("$$K0_PROCEDURE"))
        .unwrap();
    for i in 0..a.len() - 1 {
        if i != k0 + 1 {
            assert_eq!(a[i], b[i], "line {} changed", i + 1);
        }
    }
    assert_eq!(
        &b[a.len() - 1..],
        ["$$MP_STRESS_INITIALIZATION_FROMFILE", "1", "$$END"]
    );
}

#[test]
fn staged_cps_knows_its_stage() {
    let dir = fixtures().join("anura3d/ColumCollapse");
    let cps1 = CpsDocument::read(&dir.join("ColumCollapse.CPS_001")).unwrap();
    let cps2 = CpsDocument::read(&dir.join("ColumCollapse.CPS_002")).unwrap();
    assert!(cps1.is_staged());
    assert_eq!((cps1.stage(), cps2.stage()), (0, 1));
}

// ---------------------------------------------------------------------------
// Malformed inputs: each case mutates the TwoMat fixture and names the place.

fn two_mat() -> String {
    std::fs::read_to_string(fixtures().join("anura3d-mini/TwoMat.GOM")).unwrap()
}

/// Replaces the first occurrence of the whole line `from` with `to`.
fn replace_line(text: &str, from: &str, to: &str) -> String {
    let mut done = false;
    text.lines()
        .map(|l| {
            if !done && l == from {
                done = true;
                to.to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

fn gom_error(text: &str) -> String {
    let path = Path::new("TwoMat.GOM");
    match GomDocument::parse(path, text.to_string()).and_then(|d| d.model().map(|_| ())) {
        Ok(()) => "no error".to_string(),
        Err(e) => e.to_string(),
    }
}

pub fn malformed_gom_cases() -> Vec<(&'static str, String, &'static str)> {
    let base = two_mat();
    let lines: Vec<&str> = base.lines().collect();
    vec![
        ("empty_file", String::new(), "TwoMat.GOM:1:1: empty file"),
        ("truncated_in_nodes", lines[..14].join("\n"), "TwoMat.GOM:14:1: missing `$$FINISH`"),
        ("missing_finish", base.replace("$$FINISH\n", ""), "TwoMat.GOM:89:1: missing `$$FINISH`"),
        ("wrong_header", base.replacen("### Anura3D_2023 ###", "### Anura3D_2020 ###", 1), "TwoMat.GOM:1:1: expected a version header"),
        ("header_with_leading_blank", base.replacen("### Anura3D_2023 ###", " ### Anura3D_2023 ###", 1), "TwoMat.GOM:1:1: expected a version header"),
        ("counters_not_numbers", replace_line(&base, "4 6", "4 six"), "TwoMat.GOM:9:3: expected a count, found `six`"),
        ("counters_say_more_nodes", replace_line(&base, "4 6", "4 7"), "TwoMat.GOM:17:1: $$STARTNODES (line 10) expects 7 node lines ($$STARTCOUNTERS), found 6"),
        ("bad_number_in_node", replace_line(&base, "1.0 1.0", "1.0 1.O"), "TwoMat.GOM:15:5: expected a coordinate, found `1.O`"),
        ("node_with_one_coordinate", replace_line(&base, "2.0 1.0", "2.0"), "TwoMat.GOM:16:4: node 6 needs 2 coordinates"),
        ("node_id_out_of_range", replace_line(&base, "2 6 5", "2 9 5"), "TwoMat.GOM:21:3: element 4: node id 9 is out of range 1..=6"),
        ("node_id_zero", replace_line(&base, "1 2 5", "0 2 5"), "TwoMat.GOM:18:1: element 1: node id 0 is out of range 1..=6"),
        ("element_with_two_nodes", replace_line(&base, "1 5 4", "1 5"), "TwoMat.GOM:19:4: element 2 needs 3 node ids"),
        ("unsupported_element_type", replace_line(&base, "triangular_3-noded", "hexahedral_8-noded"), "TwoMat.GOM:5:1: element type `hexahedral_8-noded` is not supported"),
        ("unknown_element_type", replace_line(&base, "triangular_3-noded", "triangle"), "TwoMat.GOM:5:1: element type `triangle` is unknown"),
        ("dimension_mismatch", replace_line(&base, "2D-plane_strain", "3D-cartesian"), "TwoMat.GOM:5:1: element type triangular_3-noded is 2D but the model is 3D-cartesian"),
        ("unknown_dimension", replace_line(&base, "2D-plane_strain", "2D"), "TwoMat.GOM:3:1: unknown dimension `2D`"),
        ("missing_nodes_block", replace_line(&base, "$$STARTNODES", "$$STARTNODEZ"), "TwoMat.GOM:90:1: missing required block $$STARTNODES"),
        ("fixity_node_out_of_range", replace_line(&base, "6 1 0", "60 1 0"), "TwoMat.GOM:28:1: node id 60 is out of range 1..=6"),
        ("material_index_not_its_position", base.replacen("$$MATERIAL_INDEX\n2", "$$MATERIAL_INDEX\n3", 1), "TwoMat.GOM:58:1: material index 3 at position 2"),
        ("unknown_material_type", replace_line(&base, "dry_material", "wet_material"), "TwoMat.GOM:36:1: unknown material type `wet_material`"),
        ("bad_porosity", replace_line(&base, "0.4", "zero.four"), "TwoMat.GOM:38:1: expected a number for $$POROSITY_SOLID, found `zero.four`"),
        ("element_material_out_of_range", base.replacen("$$STARTELMMAT\n1\n1\n2\n2", "$$STARTELMMAT\n1\n1\n2\n3", 1), "TwoMat.GOM:79:1: element 4: material 3 does not exist (2 materials)"),
        ("mp_count_not_allowed", base.replacen("$$START_NUMBER_OF_MATERIAL_POINTS\n3 0", "$$START_NUMBER_OF_MATERIAL_POINTS\n4 0", 1), "TwoMat.GOM:86:1: element 1: 4 MPs per element is not allowed for triangular_3-noded"),
        ("mp_counts_short", base.replacen("3 0\n$$FINISH", "$$FINISH", 1), "TwoMat.GOM:89:1: $$START_NUMBER_OF_MATERIAL_POINTS (line 85) expects 4 MP count lines, found 3"),
    ]
    .into_iter()
    .collect()
}

/// An active element without MPs is legal in the GOM (FEM/UL-FEM ignore the
/// counts); for an MPM computation the placement refuses it at its count line.
#[test]
fn active_element_without_mps_is_refused_for_mpm_at_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(fixtures().join("anura3d-mini/TwoMat.GOM")).unwrap();
    let gom = dir.path().join("TwoMat.GOM");
    std::fs::write(
        &gom,
        base.replacen(
            "$$START_NUMBER_OF_MATERIAL_POINTS\n3 0",
            "$$START_NUMBER_OF_MATERIAL_POINTS\n0 0",
            1,
        ),
    )
    .unwrap();
    let err = a3d_init::pipeline::Project::load(&gom)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains(
            "TwoMat.GOM:86:1: element 1: active element (material 1) without material points"
        ),
        "{err}"
    );
}

#[test]
fn malformed_goms_give_positioned_errors() {
    let cases = malformed_gom_cases();
    assert!(cases.len() >= 15);
    for (name, text, expected) in cases {
        let got = gom_error(&text);
        assert!(
            got.starts_with(expected),
            "case {name}:\n  expected prefix: {expected}\n  got: {got}"
        );
    }
}

#[test]
fn malformed_cps_gives_positioned_errors() {
    let path = Path::new("TwoMat.CPS_001");
    let base = std::fs::read_to_string(fixtures().join("anura3d-mini/TwoMat.CPS_001")).unwrap();
    for (name, text, expected) in [
        (
            "missing_end",
            base.replace("$$END\n", ""),
            "TwoMat.CPS_001:32:1: missing `$$END`",
        ),
        (
            "wrong_header",
            base.replacen("2023", "23", 1),
            "TwoMat.CPS_001:1:1: expected a version header",
        ),
        ("empty", String::new(), "TwoMat.CPS_001:1:1: empty file"),
    ] {
        let got = CpsDocument::parse(path, text)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(
            got.starts_with(expected),
            "case {name}: expected {expected}, got {got}"
        );
    }
}

#[test]
fn generated_models_survive_write_then_read() {
    use a3d_init::formats::gom::write::model_to_text;
    use a3d_init::model::RetentionCurve;
    use a3d_init::model::generate;
    // A saturated Mohr–Coulomb sand with van Genuchten retention.
    let mut spec = soil_spec(0.4554, 2500.0, 2.087e-11);
    spec.name = "sand".into();
    (spec.porosity, spec.density_solid) = (0.58, 2718.0);
    spec.mohr_coulomb = Some((33.0, 0.0, 0.0));
    spec.retention = Some(RetentionCurve::VanGenuchten {
        s_min: 0.1,
        s_max: 1.0,
        p0: 1.0 / 0.51,
        lambda: 1.0 - 1.0 / 2.73,
    });
    for mesh in [
        generate::structured_tri_mesh(0.0, -1.0, 2.0, 3.0, 4, 5),
        generate::structured_tet_mesh(1.0, 0.0, 2.0, 1.0, 2, 3, 1),
    ] {
        let model = generate::single_material_model(mesh, &spec, 1);
        let text = model_to_text(&model, "2023");
        let (back, info) = GomDocument::parse(Path::new("gen.GOM"), text.clone())
            .unwrap()
            .model()
            .unwrap();
        assert!(info.warnings.is_empty(), "{:?}", info.warnings);
        assert_eq!(back, model);
        assert_eq!(
            GomDocument::parse(Path::new("gen.GOM"), text.clone())
                .unwrap()
                .to_text(),
            text
        );
    }
}
