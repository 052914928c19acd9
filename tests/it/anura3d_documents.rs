//! GOM and CPS documents against the 11 real Anura3D samples in
//! `fixtures/anura3d/`: byte-identical round trips, typed views, edits that touch
//! one block only, and malformed inputs that must give `path:line:col` errors.

use crate::common;
use common::{malformed, soil_spec};

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

fn gom_error(text: &str) -> String {
    let path = Path::new("TwoMat.GOM");
    match GomDocument::parse(path, text.to_string()).and_then(|d| d.model().map(|_| ())) {
        Ok(()) => "no error".to_string(),
        Err(e) => e.to_string(),
    }
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
    let cases = malformed::gom_cases();
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
    use a3d_testkit::generate;
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
