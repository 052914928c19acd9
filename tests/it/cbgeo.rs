//! CB-Geo mpm as a second target (#41): `map --mpm mpm.json` on real CB-Geo
//! models, checked by CB-Geo itself. Both codes (cb-geo/mpm develop and the
//! two-phase fork geomechanics/mpm) are built by `.ci/run` from
//! `../shared/cbgeo-mpm/`; each written project is run for a step and every
//! particle's stresses (and pore pressure) read back from its HDF5 output
//! must equal what `map` says, its placement must equal a3d-init's, and its
//! log must hold no warning but the known harmless ones (both codes ignore a
//! wrong key form or row count with exit status 0 and a warning).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{fixture, run_map, run_ok};

/// The CB-Geo builds and the read-back script.
struct CbGeo {
    develop: PathBuf,
    fork: PathBuf,
    python: PathBuf,
    readback: PathBuf,
}

/// The CB-Geo oracle for the test `name`, or `None` after saying that it
/// skips: CI sets `A3D_INIT_REQUIRE_CBGEO`, and there a missing build fails.
#[allow(clippy::print_stderr)] // the skip must be visible in the test output
fn cbgeo_or_skip(name: &str) -> Option<CbGeo> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let build = std::env::var_os("CBGEO_BUILD")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/cbgeo"));
    let found = CbGeo {
        develop: build.join("build-cbgeo/mpm"),
        fork: build.join("build-fork/mpm"),
        python: build.join("venv/bin/python"),
        readback: root.join("../shared/cbgeo-mpm/readback.py"),
    };
    let ok = [&found.develop, &found.fork, &found.python, &found.readback]
        .iter()
        .all(|p| p.is_file());
    if !ok {
        assert!(
            std::env::var_os("A3D_INIT_REQUIRE_CBGEO").is_none(),
            "A3D_INIT_REQUIRE_CBGEO is set but CB-Geo is not built under {} (or $CBGEO_BUILD)",
            build.display()
        );
        eprintln!("SKIPPED {name}: no CB-Geo build (run .ci/run, which builds both branches)");
        return None;
    }
    Some(found)
}

/// The warnings both codes log on every run, whatever the input: optional
/// keys they did not find. Any other warning, and any error, fails.
const HARMLESS: [&str; 29] = [
    "Particle pore pressures are undefined; Particle pore pressure JSON data not found",
    "Particle entity sets are undefined",
    "Material sets are not specified",
    "No particle surface traction is defined",
    "No concentrated nodal force is defined",
    "No math functions are defined",
    "Math functions are undefined",
    "No VTK variables were specified",
    "No VTK statevariable were specified",
    "Euler angles are undefined",
    "Friction conditions are undefined",
    "Adhesion conditions are undefined",
    "Acceleration constraints are undefined",
    "Displacement constraints are undefined",
    "Nodal pressure constraints are undefined",
    "Absorbing conditions are undefined",
    "Cell entity sets are undefined",
    "Particle cells are undefined",
    "Particle volumes are undefined",
    "Particle sets are undefined",
    "Particle velocity constraints are undefined",
    "Material sets are undefined",
    "Rotation forces are undefined",
    "Concentrated nodal forces are undefined",
    "Stress update method is not specified",
    "Damping is not specified",
    "Check duplicates not specified",
    "Nodal velocity constraints are undefined",
    "Particle surface tractions are undefined",
];

/// Runs `mpm` on the project in `dir` (its `mpm.json`, shortened to `steps`
/// steps with output every `every`); returns its log. A non-zero exit, an
/// `[error]` or an unknown `[warning]` line fails.
fn run_cbgeo(
    mpm: &Path,
    dir: &Path,
    steps: u32,
    every: u32,
    edit: impl Fn(String) -> String,
) -> String {
    let json = dir.join("mpm.json");
    let text = std::fs::read_to_string(&json).unwrap();
    let text = set_number(&set_number(&text, "nsteps", steps), "output_steps", every);
    std::fs::write(&json, edit(text)).unwrap();
    let out = Command::new(mpm)
        .arg("-f")
        .arg(format!("{}/", dir.display()))
        .args(["-i", "mpm.json"])
        .output()
        .expect("CB-Geo runs");
    let log =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{}: {log}", mpm.display());
    let bad: Vec<&str> = log
        .lines()
        .filter(|l| {
            l.contains("[error]")
                || l.contains("[critical]")
                || (l.contains("[warning]") && !HARMLESS.iter().any(|h| l.contains(h)))
        })
        .collect();
    assert!(
        bad.is_empty(),
        "{} logged:\n{}",
        mpm.display(),
        bad.join("\n")
    );
    log
}

/// `text` with the JSON number member `key` set to `value` (first match).
fn set_number(text: &str, key: &str, value: u32) -> String {
    let at = text
        .find(&format!("\"{key}\""))
        .unwrap_or_else(|| panic!("no {key}"));
    let colon = at + text[at..].find(':').unwrap() + 1;
    let end = colon + text[colon..].find([',', '\n', '}']).unwrap();
    format!("{} {value}{}", &text[..colon], &text[end..])
}

/// One particle as CB-Geo's HDF5 output holds it.
#[derive(Debug)]
struct Particle {
    xyz: [f64; 3],
    stress: [f64; 6],
    pore_pressure: Option<f64>,
}

/// Every particle of output step `step`, in CB-Geo's order.
fn read_back(cb: &CbGeo, dir: &Path, step: u32) -> Vec<Particle> {
    let out = Command::new(&cb.python)
        .arg(&cb.readback)
        .arg(dir)
        .args(["--step", &step.to_string()])
        .output()
        .expect("readback.py runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name);
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |name: &str| f[col(name).unwrap()].parse::<f64>().unwrap();
            Particle {
                xyz: [num("coord_x"), num("coord_y"), num("coord_z")],
                stress: [
                    "stress_xx",
                    "stress_yy",
                    "stress_zz",
                    "tau_xy",
                    "tau_yz",
                    "tau_xz",
                ]
                .map(num),
                pore_pressure: col("pore_pressure").map(|_| num("pore_pressure")),
            }
        })
        .collect()
}

/// What `map` says of each MP in mps.csv: position, pwp and total stress (kPa).
fn mps(dir: &Path) -> Vec<([f64; 3], f64, [f64; 6])> {
    let text = std::fs::read_to_string(dir.join("mps.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |name: &str| f[col(name)].parse::<f64>().unwrap();
            (
                [num("x"), num("y"), num("z")],
                num("pwp"),
                ["sxx", "syy", "szz", "sxy", "syz", "sxz"].map(num),
            )
        })
        .collect()
}

/// Checks that CB-Geo holds what `map` said: the same particles at the same
/// places (1e-12 m), each stress within 1e-9 of the range (the total for
/// single phase, σ + p·I for two-phase) and each pore pressure.
fn assert_holds(dir: &Path, got: &[Particle], two_phase: bool) {
    let want = mps(dir);
    assert_eq!(got.len(), want.len(), "particle count");
    let range = want
        .iter()
        .flat_map(|w| w.2.iter().chain([&w.1]))
        .fold(0.0f64, |m, v| m.max(v.abs()))
        * 1000.0;
    for (i, (g, (xyz, pwp, total))) in got.iter().zip(&want).enumerate() {
        for k in 0..3 {
            assert!(
                (g.xyz[k] - xyz[k]).abs() <= 1e-12,
                "particle {i}: CB-Geo at {:?}, map at {xyz:?}",
                g.xyz
            );
        }
        for (k, (&got, &s)) in g.stress.iter().zip(total).enumerate() {
            let s = if two_phase && k < 3 { s - pwp } else { s };
            assert!(
                (got - s * 1000.0).abs() <= 1e-9 * range,
                "particle {i} stress {k}: CB-Geo {got}, map {}",
                s * 1000.0
            );
        }
        if two_phase {
            let p = g
                .pore_pressure
                .expect("a two-phase particle has a pore pressure");
            assert!(
                (p + pwp * 1000.0).abs() <= 1e-9 * range,
                "particle {i} p: CB-Geo {p}, map {}",
                -pwp * 1000.0
            );
        }
    }
}

/// How far CB-Geo's particles moved between two outputs of one run.
struct Drift {
    /// The largest displacement along x, y and z (m).
    moved: [f64; 3],
    /// The largest change of a stress component (Pa).
    changed: f64,
    /// The largest |σyy| at the start (Pa), the scale of `changed`.
    range: f64,
}

impl Drift {
    fn between(start: &[Particle], end: &[Particle]) -> Drift {
        let mut d = Drift {
            moved: [0.0; 3],
            changed: 0.0,
            range: 0.0,
        };
        for (a, b) in start.iter().zip(end) {
            for k in 0..3 {
                d.moved[k] = d.moved[k].max((a.xyz[k] - b.xyz[k]).abs());
            }
            for k in 0..6 {
                d.changed = d.changed.max((a.stress[k] - b.stress[k]).abs());
            }
            d.range = d.range.max(a.stress[1].abs());
        }
        d
    }
}

/// Maps the column fixture (a gauss generator, single phase) into `out`.
fn map_column(out: &Path, json: &Path) {
    let (code, text) = run_map(
        json,
        &fixture("cbgeo/column/hydrostatic.csv"),
        out,
        &["--stress", "geostatic"],
    );
    assert_eq!(code, 0, "{text}");
}

#[test]
fn develop_holds_the_mapped_column_and_places_its_gauss_particles_as_a3d_init_does() {
    let Some(cb) = cbgeo_or_skip("develop_holds_the_mapped_column") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("column");
    map_column(&out, &fixture("cbgeo/column/mpm.json"));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["cbgeo"]["branch"], "Develop");
    run_cbgeo(&cb.develop, &out, 1, 1, |t| t);
    let got = read_back(&cb, &out, 0);
    assert_eq!(got.len(), 160);
    assert_holds(&out, &got, false);
}

#[test]
fn the_fork_holds_a_two_phase_state_with_its_pore_pressures() {
    let Some(cb) = cbgeo_or_skip("the_fork_holds_a_two_phase_state") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("consolidation");
    let (code, text) = run_map(
        &fixture("cbgeo/consolidation/mpm.json"),
        &fixture("cbgeo/consolidation/fem-state.csv"),
        &out,
        &["--stress", "fem"],
    );
    assert_eq!(code, 0, "{text}");
    // The benchmark's soil needs this key in today's fork (../shared/cbgeo-mpm/README.md).
    run_cbgeo(&cb.fork, &out, 1, 1, |t| {
        t.replacen(
            "\"porosity\": 0.3,",
            "\"porosity\": 0.3, \"intrinsic_permeability\": false,",
            1,
        )
    });
    let got = read_back(&cb, &out, 0);
    assert_eq!(got.len(), 600);
    assert_holds(&out, &got, true);
}

#[test]
fn each_branch_gets_its_own_key_form_and_the_other_form_is_caught() {
    let Some(cb) = cbgeo_or_skip("each_branch_gets_its_own_key_form") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    // The column with the fork's object form: a3d-init keeps the fork's form.
    let model = tmp.path().join("model");
    std::fs::create_dir(&model).unwrap();
    for f in ["mesh.txt", "entity_sets.json"] {
        std::fs::copy(fixture("cbgeo/column").join(f), model.join(f)).unwrap();
    }
    let json = std::fs::read_to_string(fixture("cbgeo/column/mpm.json")).unwrap().replacen(
        "\"node_type\": \"N2D\",",
        "\"node_type\": \"N2D\",\n\t\t\"particles_stresses\": {\"type\": \"isotropic\", \"values\": [0, 0, 0, 0, 0, 0]},",
        1,
    );
    std::fs::write(model.join("mpm.json"), json).unwrap();
    let out = tmp.path().join("fork");
    map_column(&out, &model.join("mpm.json"));
    let written = std::fs::read_to_string(out.join("mpm.json")).unwrap();
    assert!(
        written.contains(
            "\"particles_stresses\": {\"type\": \"file\", \"location\": \"particles-stresses.txt\"}"
        ),
        "{written}"
    );
    let again = tmp.path().join("fork-run");
    copy_dir(&out, &again);
    run_cbgeo(&cb.fork, &again, 1, 1, |t| t);
    assert_holds(&out, &read_back(&cb, &again, 0), false);
    // The same project in develop: the object form is not develop's, and the
    // log says so (the stresses stay zero, the exit status is 0).
    let wrong = tmp.path().join("develop-run");
    copy_dir(&out, &wrong);
    let caught = std::panic::catch_unwind(|| run_cbgeo(&cb.develop, &wrong, 1, 1, |t| t));
    let message = caught
        .expect_err("develop read the fork's key form without a warning")
        .downcast::<String>()
        .unwrap();
    assert!(message.contains("stresses"), "{message}");
}

#[test]
fn the_mapped_column_stays_at_rest_in_develop_and_an_unstressed_one_does_not() {
    let Some(cb) = cbgeo_or_skip("the_mapped_column_stays_at_rest") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("column");
    map_column(&out, &fixture("cbgeo/column/mpm.json"));
    let zero = tmp.path().join("unstressed");
    copy_dir(&out, &zero);
    // 0.1 s (1000 steps of 1e-4 s) under gravity.
    run_cbgeo(&cb.develop, &out, 1001, 1000, |t| t);
    let (start, end) = (read_back(&cb, &out, 0), read_back(&cb, &out, 1000));
    let d = Drift::between(&start, &end);
    assert!(
        d.moved[1] < 1e-9,
        "the mapped column moved {:?} m in 0.1 s",
        d.moved
    );
    assert!(
        d.changed < 1e-6 * d.range,
        "its stresses changed by {} Pa of {}",
        d.changed,
        d.range
    );
    // The control: without the stresses, the same column sinks under gravity.
    let n = 160;
    let zeros = format!("{n}\n{}", "0\t0\t0\t0\t0\t0\n".repeat(n));
    std::fs::write(zero.join("particles-stresses.txt"), zeros).unwrap();
    run_cbgeo(&cb.develop, &zero, 1001, 1000, |t| t);
    let (a, b) = (read_back(&cb, &zero, 0), read_back(&cb, &zero, 1000));
    let sank = Drift::between(&a, &b).moved[1];
    assert!(
        sank > 1e-3,
        "an unstressed column moved only {sank} m: the check could not fail"
    );
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
}

#[test]
fn a_mapped_project_maps_again_to_the_same_bytes() {
    // Nothing changes between two maps: the run file (whose keys already name
    // the files written), the mesh and every copied file come back identical.
    let tmp = tempfile::tempdir().unwrap();
    let first = tmp.path().join("first");
    let (code, text) = run_map(
        &fixture("cbgeo/consolidation/mpm.json"),
        &fixture("cbgeo/consolidation/fem-state.csv"),
        &first,
        &["--stress", "fem"],
    );
    assert_eq!(code, 0, "{text}");
    let second = tmp.path().join("second");
    let (code, text) = run_map(
        &first.join("mpm.json"),
        &fixture("cbgeo/consolidation/fem-state.csv"),
        &second,
        &["--stress", "fem"],
    );
    assert_eq!(code, 0, "{text}");
    for f in [
        "mpm.json",
        "mesh.txt",
        "entity_sets.json",
        "particle.txt",
        "pore-pressure-constraint.txt",
        "particles-stresses.txt",
        "particles-pore-pressures.txt",
    ] {
        assert!(
            std::fs::read(first.join(f)).unwrap() == std::fs::read(second.join(f)).unwrap(),
            "{f} differs:\n{}\n----\n{}",
            std::fs::read_to_string(first.join(f)).unwrap(),
            std::fs::read_to_string(second.join(f)).unwrap()
        );
    }
    // The model's own files are copied byte for byte, and the run file
    // differs from the input only in the two initial-state members.
    for f in [
        "mesh.txt",
        "entity_sets.json",
        "particle.txt",
        "pore-pressure-constraint.txt",
    ] {
        assert_eq!(
            std::fs::read(fixture("cbgeo/consolidation").join(f)).unwrap(),
            std::fs::read(first.join(f)).unwrap(),
            "{f}"
        );
    }
    let input = std::fs::read_to_string(fixture("cbgeo/consolidation/mpm.json")).unwrap();
    let output = std::fs::read_to_string(first.join("mpm.json")).unwrap();
    let old =
        "{\n\t\t\t\"type\": \"file\",\n\t\t\t\"location\": \"particle-pore-pressure.txt\"\n\t\t}";
    let new = "{\"type\": \"file\", \"location\": \"particles-pore-pressures.txt\"}";
    let added = ",\n\t\t\"particles_stresses\": {\"type\": \"file\", \"location\": \"particles-stresses.txt\"}";
    let expected = input.replacen(old, new, 1).replacen(
        "\t\t\t]\n\t\t}\n\t},\n\t\"particles\"",
        &format!("\t\t\t]\n\t\t}}{added}\n\t}},\n\t\"particles\""),
        1,
    );
    assert_eq!(output, expected);
}

#[test]
fn bad_cbgeo_inputs_are_refused_with_their_place_and_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("model");
    std::fs::create_dir(&model).unwrap();
    for f in ["mesh.txt", "entity_sets.json", "mpm.json"] {
        std::fs::copy(fixture("cbgeo/column").join(f), model.join(f)).unwrap();
    }
    let fem = fixture("cbgeo/column/hydrostatic.csv");
    let json = model.join("mpm.json");
    let cases: [(&str, &str, String, &str); 4] = [
        (
            "mpm.json",
            "\"cell_type\": \"ED2Q4\"",
            "\"cell_type\": \"ED2Q9\"".into(),
            "mpm.json:6:16: cell type `ED2Q9`",
        ),
        (
            "mpm.json",
            "\"material_id\": 0",
            "\"material_id\": 7".into(),
            "mpm.json:35:20: \"material_id\" 7",
        ),
        (
            "mpm.json",
            "\"dt\": 0.0001,",
            "\"dt\": 0.0001,,".into(),
            "mpm.json:58:16: not valid JSON",
        ),
        (
            "mesh.txt",
            "0\t1\t4\t3\n",
            "0\t1\t4\t99\n".into(),
            "mesh.txt:66:7: cell 0: `99`",
        ),
    ];
    for (file, from, to, want) in cases {
        let path = model.join(file);
        let good = std::fs::read_to_string(&path).unwrap();
        assert!(good.contains(from), "{file} holds {from}");
        std::fs::write(&path, good.replacen(from, &to, 1)).unwrap();
        let out = tmp.path().join("out");
        let (code, text) = run_map(&json, &fem, &out, &[]);
        assert_eq!(code, 2, "{text}");
        assert!(text.contains(want), "wanted `{want}` in: {text}");
        assert!(!out.exists(), "no partial output");
        std::fs::write(&path, good).unwrap();
    }
    // The untouched model still maps.
    run_ok(&[
        "map",
        "--mpm",
        json.to_str().unwrap(),
        "--fem",
        fem.to_str().unwrap(),
        "--out",
        tmp.path().join("ok").to_str().unwrap(),
    ]);
}

#[test]
fn inspect_and_diff_read_cbgeo_projects() {
    let model = fixture("cbgeo/consolidation/mpm.json");
    let text = run_ok(&["inspect", model.to_str().unwrap()]);
    crate::common::assert_contains(
        &text,
        &[
            "CB-Geo     geomechanics/mpm (the two-phase fork)",
            "generator  file ",
            "600 P2D2PHASE particles (ids 0..599), material ids [0, 1]",
            "two-phase  600 particles",
            "MPs        600",
            "saturated_material_coupled / linear_elasticity: 150 elements, 600 MPs",
        ],
    );
    let json: serde_json::Value = serde_json::from_str(&run_ok(&[
        "inspect",
        fixture("cbgeo/column/mpm.json").to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    assert_eq!(json["material_points"], 160);
    assert_eq!(json["cbgeo"]["branch"], "Develop");
    assert_eq!(json["cbgeo"]["cell_type"], "ED2Q4");

    // Two maps of one model with different h: the run files and the model's
    // files are equal, the particle stresses and pore pressures are not.
    let tmp = tempfile::tempdir().unwrap();
    let fem = fixture("cbgeo/consolidation/fem-state.csv");
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    for (out, h) in [(&a, "0.01"), (&b, "0.012")] {
        let (code, text) = run_map(&model, &fem, out, &["--stress", "fem", "--h", h]);
        assert_eq!(code, 0, "{text}");
    }
    let (code, text) = crate::common::run(&["diff", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert_eq!(code, 1, "{text}");
    crate::common::assert_contains(
        &text,
        &[
            "mpm.json (json): equal",
            "mesh.txt (cbgeo-file): equal",
            "particle.txt (cbgeo-file): equal",
            "particles-stresses.txt (cbgeo-stresses):",
            "particles-pore-pressures.txt (cbgeo-pore-pressures):",
        ],
    );
    assert!(text.contains("≠") && text.contains("syy:"), "{text}");
    let (code, text) = crate::common::run(&["diff", a.to_str().unwrap(), a.to_str().unwrap()]);
    assert_eq!(code, 0, "{text}");
    // A run file against the model's: the two initial-state members differ.
    let (code, text) = crate::common::run(&[
        "diff",
        a.join("mpm.json").to_str().unwrap(),
        model.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{text}");
    crate::common::assert_contains(
        &text,
        &[
            "mesh.particles_pore_pressures.location: \"particles-pore-pressures.txt\" → \"particle-pore-pressure.txt\"",
            "mesh.particles_stresses: only in the first",
        ],
    );
}

#[test]
fn develop_places_triangle_particles_as_a3d_init_does() {
    let Some(cb) = cbgeo_or_skip("develop_places_triangle_particles") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("column-t3");
    map_column(&out, &fixture("cbgeo/column-t3/mpm.json"));
    run_cbgeo(&cb.develop, &out, 1, 1, |t| t);
    let got = read_back(&cb, &out, 0);
    assert_eq!(got.len(), 240, "3 points in each of 80 triangles");
    assert_holds(&out, &got, false);
}

#[test]
fn verify_checks_what_cbgeo_will_hold_on_triangles_and_refuses_quadrilaterals_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("column-t3");
    map_column(&out, &fixture("cbgeo/column-t3/mpm.json"));
    let text = crate::common::verify_ok(&out);
    crate::common::assert_contains(&text, &["240 MPs on 80 elements", "IN EQUILIBRIUM"]);
    // What verify runs is what CB-Geo reads: without the stresses file's
    // values the same column is far from rest.
    let zero = tmp.path().join("zero");
    copy_dir(&out, &zero);
    std::fs::write(
        zero.join("particles-stresses.txt"),
        format!("240\n{}", "0\t0\t0\t0\t0\t0\n".repeat(240)),
    )
    .unwrap();
    let (_, text) = crate::common::run(&["verify", zero.to_str().unwrap()]);
    assert!(text.contains("NOT IN EQUILIBRIUM"), "{text}");
    // A stresses file CB-Geo would ignore (a row missing) is refused.
    let short = tmp.path().join("short");
    copy_dir(&out, &short);
    std::fs::write(
        short.join("particles-stresses.txt"),
        format!("240\n{}", "0\t0\t0\t0\t0\t0\n".repeat(239)),
    )
    .unwrap();
    let (code, text) = crate::common::run(&["verify", short.to_str().unwrap()]);
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains("declares 240 particles but has 239 stress lines"),
        "{text}"
    );
    // The runner has no quadrilaterals: a clear refusal, exit 2.
    let quads = tmp.path().join("column");
    map_column(&quads, &fixture("cbgeo/column/mpm.json"));
    let (code, text) = crate::common::run(&["verify", quads.to_str().unwrap()]);
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains("does not support 2D-plane_strain with quadrilateral_4-noded"),
        "{text}"
    );
}

#[test]
fn develop_holds_a_mapped_3d_hexahedral_column_at_rest() {
    let Some(cb) = cbgeo_or_skip("develop_holds_a_mapped_3d_hexahedral_column") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("column-3d");
    let (code, text) = run_map(
        &fixture("cbgeo/column-3d/mpm.json"),
        &fixture("cbgeo/column-3d/hydrostatic.csv"),
        &out,
        &["--stress", "geostatic"],
    );
    assert_eq!(code, 0, "{text}");
    // 0.02 s (200 steps of 1e-4 s) under gravity, rollers on all sides.
    run_cbgeo(&cb.develop, &out, 201, 200, |t| t);
    let start = read_back(&cb, &out, 0);
    assert_eq!(start.len(), 640, "8 points in each of 80 hexahedra");
    assert_holds(&out, &start, false);
    let end = read_back(&cb, &out, 200);
    let d = Drift::between(&start, &end);
    let moved = d.moved.into_iter().fold(0.0f64, f64::max);
    assert!(moved < 1e-9, "the mapped 3D column moved {:?} m", d.moved);
    assert!(
        d.changed < 1e-6 * d.range,
        "its stresses changed by {} Pa of {}",
        d.changed,
        d.range
    );
}

/// ACADS 1(a) written as a CB-Geo model: its Anura3D mesh as `mesh.txt`
/// (ED2T3), its MPs as a particle file, its Mohr–Coulomb soil as
/// `MohrCoulomb2D` with the bulk density (1 − n)·ρs (SI units).
fn acads_1a_as_cbgeo(dir: &Path) {
    let project = a3d_init::pipeline::Project::load(&fixture("acads-1a")).unwrap();
    let mesh = &project.model.mesh;
    let mut text = format!("{}\t{}\n", mesh.n_nodes(), mesh.n_elements());
    for p in &mesh.nodes {
        text += &format!("{}\t{}\n", p[0], p[1]);
    }
    for e in 0..mesh.n_elements() {
        let c = mesh.element_nodes(e);
        text += &format!("{}\t{}\t{}\n", c[0], c[1], c[2]);
    }
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("mesh.txt"), text).unwrap();
    let mut particles = format!("{}\n", project.points.len());
    for p in &project.points {
        particles += &format!("{}\t{}\n", p.position[0], p.position[1]);
    }
    std::fs::write(dir.join("particles.txt"), particles).unwrap();
    // The GOM's fixities as node sets: 0 fixed in x, 1 fixed in y.
    let fixed = |k: usize| -> Vec<usize> {
        let f = &project.model.solid_fixity;
        (0..f.len()).filter(|&n| f[n][k]).collect()
    };
    let sets =
        serde_json::json!({"node_sets": [{"id": 0, "set": fixed(0)}, {"id": 1, "set": fixed(1)}]});
    std::fs::write(dir.join("entity_sets.json"), sets.to_string()).unwrap();
    let m = &project.model.materials[0];
    let density = (1.0 - m.porosity.unwrap()) * m.density_solid.unwrap();
    let json = format!(
        r#"{{
	"title": "acads_1a",
	"mesh": {{
		"mesh": "mesh.txt",
		"entity_sets": "entity_sets.json",
		"cell_type": "ED2T3",
		"io_type": "Ascii2D",
		"node_type": "N2D",
		"boundary_conditions": {{
			"velocity_constraints": [
				{{"nset_id": 0, "dir": 0, "velocity": 0.0}},
				{{"nset_id": 1, "dir": 1, "velocity": 0.0}}
			]
		}}
	}},
	"particles": [
		{{
			"generator": {{
				"type": "file",
				"location": "particles.txt",
				"io_type": "Ascii2D",
				"particle_type": "P2D",
				"material_id": 0,
				"pset_id": 0
			}}
		}}
	],
	"materials": [
		{{
			"id": 0,
			"name": "acads_1a",
			"type": "MohrCoulomb2D",
			"density": {density},
			"youngs_modulus": {},
			"poisson_ratio": {},
			"friction": {},
			"dilation": 0.0,
			"cohesion": {},
			"tension_cutoff": 0.0
		}}
	],
	"external_loading_conditions": {{
		"gravity": [0.0, -9.81]
	}},
	"analysis": {{
		"type": "MPMExplicit2D",
		"dt": 0.0001,
		"nsteps": 10,
		"velocity_update": false,
		"uuid": "acads_1a"
	}},
	"post_processing": {{
		"path": "results/",
		"output_steps": 10
	}}
}}
"#,
        m.young_modulus.unwrap() * 1000.0,
        m.poisson_ratio.unwrap(),
        m.friction_angle.unwrap(),
        m.cohesion.unwrap() * 1000.0
    );
    std::fs::write(dir.join("mpm.json"), json).unwrap();
}

#[test]
fn fos_on_a_cbgeo_project_is_the_anura3d_models_factor() {
    // The same slope, section, unit weight and strength through either
    // target: limit equilibrium gives the same factor, near the referee's 1.00.
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("acads-1a-cbgeo");
    acads_1a_as_cbgeo(&model);
    let nodes = fixture("acads-1a/nodes.csv");
    let cbgeo = tmp.path().join("cbgeo");
    let (code, text) = run_map(&model.join("mpm.json"), &nodes, &cbgeo, &[]);
    assert_eq!(code, 0, "{text}");
    let anura3d = tmp.path().join("anura3d");
    let (code, text) = run_map(&fixture("acads-1a"), &nodes, &anura3d, &[]);
    assert_eq!(code, 0, "{text}");
    let factor = |dir: &Path, out: &str| {
        let (text, fos) = crate::common::fos(dir, &tmp.path().join(out), &[]);
        (
            fos["factor"].as_f64().unwrap_or_else(|| panic!("{text}")),
            text,
        )
    };
    let (f_cbgeo, text_cbgeo) = factor(&cbgeo, "fos-cbgeo");
    let (f_anura3d, _) = factor(&anura3d, "fos-anura3d");
    assert!(
        (f_cbgeo / f_anura3d - 1.0).abs() < 1e-9,
        "CB-Geo {f_cbgeo} against Anura3D {f_anura3d}: {text_cbgeo}"
    );
    assert!(
        (f_cbgeo - 1.0).abs() < 0.05,
        "{f_cbgeo} against the referee's 1.00"
    );
}
