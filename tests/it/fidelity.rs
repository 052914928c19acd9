//! Anura3D fidelity (#13): `verify` judges the files Anura3D reads (GOM, CPS,
//! MAPF) and writes the state Anura3D will hold; FEM/UL-FEM models get one MP
//! per element; MPM-MIXED elements carry their mean state; dry materials carry
//! no pore water; material properties are read by name and refused where the
//! kernel would refuse them. The real kernel, where built, is the oracle
//! (`anura3d_kernel_holds_what_verify_says`).

use crate::common;
use common::*;

use std::path::{Path, PathBuf};
use std::process::Command;

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::formats::{mapf, mps_table};
use a3d_testkit::generate::{self, MaterialSpec};

fn saturated_spec() -> MaterialSpec {
    soil_spec(0.3 / 0.7, 2e4, 1e-10)
}

/// A 4 m × 10 m saturated block (TRI3, 3 MPs per element) with a CPS using
/// `method`, and a hydrostatic FEM table (water table at the top).
fn block_project(dir: &Path, method: &str, mps: u32) -> (PathBuf, PathBuf) {
    let mesh = generate::structured_tri_mesh(0.0, 0.0, 4.0, 10.0, 4, 10);
    let model = generate::single_material_model(mesh, &saturated_spec(), mps);
    let project = dir.join("model");
    std::fs::create_dir_all(&project).unwrap();
    std::fs::write(project.join("block.GOM"), model_to_text(&model, "2023")).unwrap();
    std::fs::write(
        project.join("block.CPS_001"),
        format!(
            "### Anura3D_2023 ###\n$$COMPUTATION_METHOD\n{method}\n$$GRAVITY_ACCELERATION\n9.81\n$$HOMOGENEOUS_LOCAL_DAMPING\n1 0.75\n$$END\n"
        ),
    )
    .unwrap();
    let fem = dir.join("seep.csv");
    std::fs::write(&fem, hydrostatic_grid_csv("X,Y,PWP", 8, 20, 9.81, 10.0)).unwrap();
    (project, fem)
}

fn map(project: &Path, fem: &Path, out: &Path, extra: &[&str]) -> String {
    let (code, text) = run_map(project, fem, out, extra);
    assert_eq!(code, 0, "{text}");
    text
}

/// [`block_project`] (MPM-MP, 3 MPs per element) mapped into `out/` of a new
/// temporary folder: (the folder, `out`).
fn mapped_mpm_block() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let (project, fem) = block_project(tmp.path(), "MPM-MP", 3);
    let out = tmp.path().join("out");
    map(&project, &fem, &out, &[]);
    (tmp, out)
}

#[test]
fn verify_judges_the_mapf_not_mps_csv() {
    let (_tmp, out) = mapped_mpm_block();
    let text = verify_ok(&out);
    assert_contains(&text, &["mps.csv agrees with what Anura3D reads"]);
    // start.csv holds what Anura3D will hold: here the mapped state itself.
    let (_, start) = mps_table::read_states(&out.join("verify/start.csv")).unwrap();
    let (_, mapped) = mps_table::read_states(&out.join("mps.csv")).unwrap();
    for (a, b) in start.iter().zip(&mapped) {
        assert!((a.pwp - b.pwp).abs() < 1e-12 && (a.total[1] - b.total[1]).abs() < 1e-9);
    }
    // A rerun replaces verify/ without --force.
    verify_ok(&out);

    // Lower every MAPF stress by 20 %, leave mps.csv untouched: not in equilibrium.
    let path = out.join("block.MAPF");
    let table = mapf::read(&path).unwrap();
    let mut text_out = table.headers.join(" ") + "\n";
    for row in &table.rows {
        let cells: Vec<String> = row
            .iter()
            .zip(&table.headers)
            .map(|(v, h)| {
                if h.starts_with("Sig") {
                    format!("{}", v * 0.8)
                } else {
                    format!("{v}")
                }
            })
            .collect();
        text_out.push_str(&(cells.join(" ") + "\n"));
    }
    std::fs::write(&path, text_out).unwrap();
    let (code, text) = run(&["verify", out.to_str().unwrap()]);
    assert_eq!(code, 1, "{text}");
    assert_contains(&text, &["NOT IN EQUILIBRIUM"]);
    assert_contains(&text, &["mps.csv and the MAPF disagree on 240 of 240 MPs"]);
    assert_contains(&text, &["out of balance"]);
}

#[test]
fn verify_names_mps_anura3d_holds_as_nan() {
    let (_tmp, out) = mapped_mpm_block();
    // Keep only the first 30 rows: the other MPs have no row within 2h.
    let path = out.join("block.MAPF");
    let text = std::fs::read_to_string(&path).unwrap();
    let kept: Vec<&str> = text.lines().take(31).collect();
    std::fs::write(&path, kept.join("\n") + "\n").unwrap();
    let (code, text) = run(&["verify", out.to_str().unwrap()]);
    assert_eq!(code, 1, "{text}");
    assert_contains(&text, &["210 MPs will hold NaN in Anura3D"]);
    let start = std::fs::read_to_string(out.join("verify/start.csv")).unwrap();
    assert_eq!(start.lines().filter(|l| l.ends_with(",nan")).count(), 210);
}

#[test]
fn fem_method_places_one_point_per_element_even_with_zero_counts() {
    let tmp = tempfile::tempdir().unwrap();
    // GOM counts of 0 in every element: accepted in FEM mode.
    let (project, fem) = block_project(tmp.path(), "UL-FEM", 3);
    let gom = project.join("block.GOM");
    let text = std::fs::read_to_string(&gom).unwrap();
    let (head, tail) = text
        .split_once("$$START_NUMBER_OF_MATERIAL_POINTS\n")
        .unwrap();
    let rest = tail.split_once("$$FINISH").unwrap().1;
    let zeros = "0 0\n".repeat(80);
    std::fs::write(
        &gom,
        format!("{head}$$START_NUMBER_OF_MATERIAL_POINTS\n{zeros}$$FINISH{rest}"),
    )
    .unwrap();
    let out = tmp.path().join("out");
    map(&project, &fem, &out, &[]);
    let (points, _) = mps_table::read_states(&out.join("mps.csv")).unwrap();
    assert_eq!(points.len(), 80);
    let model = a3d_init::pipeline::Project::load(&project).unwrap();
    for p in &points {
        let c = model.model.mesh.corner_coords(p.element as usize);
        let mean = [
            (c[0][0] + c[1][0] + c[2][0]) / 3.0,
            (c[0][1] + c[1][1] + c[2][1]) / 3.0,
        ];
        assert!((p.position[0] - mean[0]).abs() < 1e-12 && (p.position[1] - mean[1]).abs() < 1e-12);
    }
    assert_eq!(mapf::read(&out.join("block.MAPF")).unwrap().rows.len(), 80);
    let (code, text) = run(&["verify", out.to_str().unwrap()]);
    assert!(code == 0 || code == 1, "{text}");
    assert!(!text.contains("NaN"), "{text}");
}

#[test]
fn mixed_elements_carry_their_mean_state() {
    let tmp = tempfile::tempdir().unwrap();
    let (project, fem) = block_project(tmp.path(), "MPM-MIXED", 6);
    let mean = tmp.path().join("mean");
    map(&project, &fem, &mean, &[]);
    let per_mp = tmp.path().join("per-mp");
    let text = map(&project, &fem, &per_mp, &["--mixed-state", "per-mp"]);
    assert_contains(&text, &["MPM-MP"]);
    let (points, a) = mps_table::read_states(&mean.join("mps.csv")).unwrap();
    let (_, b) = mps_table::read_states(&per_mp.join("mps.csv")).unwrap();
    for e in 0..80u32 {
        let idx: Vec<usize> = (0..points.len())
            .filter(|&i| points[i].element == e)
            .collect();
        let vol: f64 = idx.iter().map(|&i| points[i].volume).sum();
        let expect: f64 = idx
            .iter()
            .map(|&i| points[i].volume * b[i].pwp)
            .sum::<f64>()
            / vol;
        for &i in &idx {
            assert!((a[i].pwp - expect).abs() < 1e-9, "element {e}");
            assert_eq!(a[i].total, a[idx[0]].total);
        }
        assert!(idx.iter().any(|&i| b[i].pwp != b[idx[0]].pwp));
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(mean.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["mixed_state"], "Mean");
    assert_eq!(report["computation_method"], "MpmMixed");
    // verify models the collapse to the first MP: the per-MP folder reports the spread.
    let (_, text) = run(&["verify", per_mp.to_str().unwrap()]);
    assert_contains(&text, &["MPM-MIXED: the first step gives every MP"]);
}

/// The §1.7 two-material model with a third, undrained material block written
/// in the newer order (`$$BULK_MODULUS_LIQUID` before `$$K0_VALUE_SOLID`).
fn undrained_gom(k0: &str) -> String {
    let mut text = std::fs::read_to_string(fixture("anura3d-mini/TwoMat.GOM")).unwrap();
    for (old, new) in [
        (
            "$$MATERIAL_TYPE\ndry_material\n$$POROSITY_SOLID\n0.35\n$$DENSITY_SOLID\n2650\n$$K0_VALUE_SOLID\n0.5\n",
            format!(
                "$$MATERIAL_TYPE\nsaturated_material_undrained_effective\n$$POROSITY_SOLID\n0.35\n$$DENSITY_SOLID\n2650\n$$DENSITY_LIQUID\n1000\n$$BULK_MODULUS_LIQUID\n2.2e6\n$$K0_VALUE_SOLID\n{k0}\n"
            ),
        ),
        (
            "$$POISSON_RATIO\n0.25\n",
            "$$POISSON_RATIO\n0.25\n$$POISSON_RATIO_UNDRAINED\n0.495\n".to_string(),
        ),
    ] {
        assert!(text.contains(old), "{old}");
        text = text.replacen(old, &new, 1);
    }
    text
}

#[test]
fn undrained_material_in_the_newer_order_is_read_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let gom = tmp.path().join("TwoMat.GOM");
    std::fs::write(&gom, undrained_gom("0.6")).unwrap();
    let doc = a3d_init::formats::gom::GomDocument::read(&gom).unwrap();
    let (model, info) = doc.model().unwrap();
    let m = &model.materials[1];
    assert_eq!(m.k0, Some(0.6));
    assert_eq!(m.density_liquid, Some(1000.0));
    assert_eq!(m.poisson_ratio, Some(0.25));
    assert!(
        info.warnings
            .iter()
            .any(|w| w.contains("read by the names")),
        "{:?}",
        info.warnings
    );
    // A K0 the kernel refuses is an error with its line.
    std::fs::write(&gom, undrained_gom("2.2e6")).unwrap();
    let (code, text) = run(&["inspect", gom.to_str().unwrap()]);
    assert_eq!(code, 2, "{text}");
    assert_contains(
        &text,
        &["TwoMat.GOM:", "K0_VALUE_SOLID = 2200000 must lie in [0, 1]"],
    );
}

#[test]
fn kernel_refused_values_are_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(fixture("anura3d-mini/TwoMat.GOM")).unwrap();
    for (from, to, what) in [
        (
            "$$POROSITY_SOLID\n0.4\n",
            "$$POROSITY_SOLID\n1.4\n",
            "POROSITY_SOLID",
        ),
        (
            "$$DENSITY_SOLID\n2650\n",
            "$$DENSITY_SOLID\n-1\n",
            "DENSITY_SOLID",
        ),
        (
            "$$K0_VALUE_SOLID\n0.5\n",
            "$$K0_VALUE_SOLID\n-0.1\n",
            "K0_VALUE_SOLID",
        ),
    ] {
        let gom = tmp.path().join("TwoMat.GOM");
        std::fs::write(&gom, base.replacen(from, to, 1)).unwrap();
        let (code, text) = run(&["inspect", gom.to_str().unwrap()]);
        assert_eq!(code, 2, "{what}: {text}");
        assert!(
            text.contains(what) && text.contains("TwoMat.GOM:"),
            "{text}"
        );
    }
}

#[test]
fn dry_materials_carry_no_pore_water() {
    // 3D column, dry material, water table below the column: the FEM gives
    // suction everywhere; nothing of it may reach the MAPF.
    let tmp = tempfile::tempdir().unwrap();
    let mesh = generate::structured_tet_mesh(1.0, 0.0, 4.0, 1.0, 1, 4, 1);
    let mut spec = MaterialSpec::dry_soil("dry");
    spec.k0 = 0.5;
    let model = generate::single_material_model(mesh, &spec, 4);
    let project = tmp.path().join("col");
    std::fs::create_dir_all(&project).unwrap();
    std::fs::write(project.join("col.GOM"), model_to_text(&model, "2023")).unwrap();
    let mut csv = String::from("X,Y,Z,PWP\n");
    for i in 0..=2 {
        for j in 0..=8 {
            for k in 0..=2 {
                let (x, y, z) = (i as f64 * 0.5, j as f64 * 0.5, k as f64 * 0.5);
                csv.push_str(&format!("{x},{y},{z},{}\n", -9.81 * (y + 2.0)));
            }
        }
    }
    let fem = tmp.path().join("seep.csv");
    std::fs::write(&fem, csv).unwrap();
    let out = tmp.path().join("out");
    map(&project, &fem, &out, &["--generate-cps"]);
    let (_, states) = mps_table::read_states(&out.join("mps.csv")).unwrap();
    for s in &states {
        assert_eq!(s.pwp, 0.0);
        assert_eq!(s.effective(), s.total);
        assert!(
            s.total[0] <= 0.0 && s.total[2] <= 0.0,
            "no tension: {:?}",
            s.total
        );
    }
    let table = mapf::read(&out.join("col.MAPF")).unwrap();
    let c = table.column("Pwp[kPa]").unwrap();
    assert!(table.rows.iter().all(|r| r[c] == 0.0));
    let report = std::fs::read_to_string(out.join("report.json")).unwrap();
    assert_contains(&report, &["FEM pore pressure dropped", "`dry`"]);
    let (_, text) = run(&["verify", out.to_str().unwrap()]);
    let (_, start) = mps_table::read_states(&out.join("verify/start.csv")).unwrap();
    assert!(start.iter().all(|s| s.pwp == 0.0), "{text}");
}

#[test]
fn demo_prints_only_measured_words() {
    let (out, text) = demo_no_fos();
    assert!(!text.contains("FS ≈ 1"), "{text}");
    assert_contains(text, &["σ'zz := τxy"]);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert!(
        report["calibration"].is_object(),
        "the demo's calibration is reported"
    );
    assert!(
        report["smoothing_length_rule"]
            .as_str()
            .unwrap()
            .starts_with("calibrated")
    );
}

/// Runs the kernel on `out` and compares its initial-state dump with verify/start.csv.
fn compare_with_kernel(kernel: &Path, out: &Path, work: &Path) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/anura3d-kernel/run.sh");
    let status = Command::new("bash")
        .arg(&script)
        .arg(kernel)
        .arg(out)
        .arg(work)
        .output()
        .unwrap();
    let dump = std::fs::read_dir(work)
        .unwrap()
        .filter_map(Result::ok)
        .map(|e| e.path())
        .find(|p| p.to_string_lossy().ends_with(".ORACLE_MP0.csv"))
        .unwrap_or_else(|| {
            panic!(
                "no kernel dump: {}",
                String::from_utf8_lossy(&status.stdout)
            )
        });
    let read = |p: &Path| -> Vec<std::collections::HashMap<String, f64>> {
        let mut r = csv::Reader::from_path(p).unwrap();
        let headers = r.headers().unwrap().clone();
        r.records()
            .map(|rec| {
                let rec = rec.unwrap();
                headers
                    .iter()
                    .zip(rec.iter())
                    .filter_map(|(h, v)| v.trim().parse::<f64>().ok().map(|v| (h.to_string(), v)))
                    .collect()
            })
            .collect()
    };
    let ours = read(&out.join("verify/start.csv"));
    let theirs = read(&dump);
    assert_eq!(ours.len(), theirs.len(), "MP count");
    let three = ours.iter().any(|r| r["z"] != 0.0);
    let mut pairs = vec![
        ("x", "x"),
        ("y", "y"),
        ("volume", "volume"),
        ("pwp", "pwp"),
        ("saturation", "sr"),
        ("esxx", "se1"),
        ("esyy", "se2"),
        ("eszz", "se3"),
        ("esxy", "se4"),
    ];
    if three {
        pairs.extend([("z", "z"), ("esyz", "se5"), ("esxz", "se6")]);
    }
    for (a, b) in pairs {
        let range = ours
            .iter()
            .zip(&theirs)
            .map(|(o, t)| o[a].abs().max(t[b].abs()))
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        for (i, (o, t)) in ours.iter().zip(&theirs).enumerate() {
            let (u, v) = (o[a], t[b]);
            let same = (u.is_nan() && v.is_nan()) || (u - v).abs() <= 1e-9 * range.max(1e-300);
            assert!(
                same,
                "{}: MP {} {a}: verify {u} vs Anura3D {v}",
                out.display(),
                i + 1
            );
        }
    }
}

#[test]
fn anura3d_kernel_holds_what_verify_says() {
    let Some(kernel) = anura3d_kernel_or_skip("anura3d_kernel_holds_what_verify_says") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    // 2D MPM-MP, MIXED, UL-FEM blocks; the MIXED one with per-MP values too.
    for (method, extra) in [
        ("MPM-MP", &[][..]),
        ("MPM-MIXED", &["--mixed-state", "per-mp"][..]),
        ("UL-FEM", &[][..]),
    ] {
        let dir = tmp.path().join(method);
        let (project, fem) = block_project(&dir, method, 6);
        let out = dir.join("out");
        map(&project, &fem, &out, extra);
        run(&["verify", out.to_str().unwrap()]);
        compare_with_kernel(&kernel, &out, &dir.join("run"));
    }
    // Shipped samples: 2D axisymmetric (MPM-MP) and 3D tetrahedral_old (MPM-MP),
    // from an analytic FEM table over their extent.
    for (sample, three) in [
        ("CC_AXI_MC_2Phase_K0_MPM-MP", false),
        ("test-1005_3D", true),
    ] {
        let dir = tmp.path().join(sample);
        std::fs::create_dir_all(&dir).unwrap();
        let fem = dir.join("fem.csv");
        let mut csv = String::from(if three {
            "X,Y,Z,PWP,SXX,SYY,SZZ,SXY,SYZ,SXZ\n"
        } else {
            "X,Y,PWP,SXX,SYY,SXY\n"
        });
        for i in 0..=12 {
            for j in 0..=12 {
                for k in 0..=if three { 12 } else { 0 } {
                    let (x, y, z) = (
                        -0.1 + 0.1 * i as f64,
                        -0.1 + 0.1 * j as f64,
                        -0.1 + 0.1 * k as f64,
                    );
                    let (p, sv) = (9.81 * (0.7 - y), 19.0 * (1.0 - y) + x);
                    csv.push_str(&if three {
                        format!(
                            "{x},{y},{z},{p},{},{sv},{},{},{},{}\n",
                            0.5 * sv,
                            0.4 * sv,
                            0.1 * x,
                            0.2 * z,
                            0.3 * y
                        )
                    } else {
                        format!("{x},{y},{p},{},{sv},{}\n", 0.5 * sv, 0.1 * x - 0.2 * y)
                    });
                }
            }
        }
        std::fs::write(&fem, csv).unwrap();
        let out = dir.join("out");
        map(
            &fixture(&format!("anura3d/{sample}")),
            &fem,
            &out,
            &["--outside", "nearest"],
        );
        run(&["verify", out.to_str().unwrap()]);
        compare_with_kernel(&kernel, &out, &dir.join("run"));
    }
    // The demo slope (unsaturated sand over a dry base) and a foreign MAPF
    // written at the FEM nodes (Anura3D's own interpolation, with NaN MPs).
    let (demo, _) = demo_no_fos();
    compare_with_kernel(&kernel, demo, &tmp.path().join("run-demo"));
    let nodal = tmp.path().join("nodal");
    std::fs::create_dir_all(&nodal).unwrap();
    for f in ["slope.GOM", "slope.CPS_001"] {
        std::fs::copy(demo.join(f), nodal.join(f)).unwrap();
    }
    let nodes = std::fs::read_to_string(fixture("slope/sand-nodes.csv")).unwrap();
    let mut mapf_text =
        String::from("X[m] Y[m] Pwp[kPa] SigX[kPa] SigY[kPa] SigXY[kPa] SmoothLength[m]\n");
    for line in nodes.lines().skip(1).step_by(3) {
        let f: Vec<f64> = line
            .split(',')
            .filter_map(|v| v.trim().parse().ok())
            .collect();
        let (x, y, p) = (f[1], f[2], f[3]);
        mapf_text.push_str(&format!(
            "{x} {y} {} {} {} 0.1 0.06\n",
            -p,
            -5.0 - y,
            -10.0 - 2.0 * y
        ));
    }
    std::fs::write(nodal.join("slope.MAPF"), mapf_text).unwrap();
    run(&["verify", nodal.to_str().unwrap()]);
    compare_with_kernel(&kernel, &nodal, &tmp.path().join("run-nodal"));
}
