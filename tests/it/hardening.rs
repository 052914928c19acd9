//! Issue #15, one test per class, through the real binary: an output never
//! deletes or overwrites an input; `--force` replaces a folder whole; failed
//! runs leave nothing behind; non-regular files, oversized counts, zip bombs,
//! inconsistent counts, data after the end marker, non-finite values and garbage
//! options end as exit 2 with a positioned message, never a panic or a hang.
//! Every run is killed after 30 s, so a hang fails instead of blocking CI.
//! At the foot, the input defects of #24 and #30, one test per bug.

use crate::common;
use common::{Watchdog, assert_contains, fixture, mini_regions_csv, run_map, run_watched};

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs the binary under the hang watchdog: (exit code, stderr + stdout).
fn run(args: &[&dyn AsRef<std::ffi::OsStr>]) -> (i32, String) {
    let os: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_ref()).collect();
    let (code, text) = run_watched(&os, Watchdog::default()).unwrap_or_else(|e| panic!("{e}"));
    assert!(!text.contains("panicked"), "{text}");
    assert!(!text.contains("internal error"), "{text}");
    (code, text)
}

/// `map --fem FEM --mpm GOM --out OUT`, then `extra`, through [`run`].
fn map(fem: &Path, gom: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> =
        vec![&"map", &"--fem", &fem, &"--mpm", &gom, &"--out", &out];
    args.extend(extra.iter().map(|a| a as &dyn AsRef<std::ffi::OsStr>));
    run(&args)
}

/// `verify --mpm GOM --state STATE --out OUT`, then `extra`, through [`run`].
fn verify_state(gom: &Path, state: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![
        &"verify", &"--mpm", &gom, &"--state", &state, &"--out", &out,
    ];
    args.extend(extra.iter().map(|a| a as &dyn AsRef<std::ffi::OsStr>));
    run(&args)
}

/// `calibrate INPUTS --out OUT --force` where OUT is the folder of an input:
/// refused (exit 2) with a message naming that input.
fn calibrate_refused(inputs: &[&dyn AsRef<std::ffi::OsStr>], out: &Path, input: &str) {
    let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"calibrate"];
    args.extend_from_slice(inputs);
    args.extend([&"--out" as &dyn AsRef<std::ffi::OsStr>, &out, &"--force"]);
    let (code, text) = run(&args);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains(input), "{text}");
}

/// A temporary folder holding the mini two-material model with a FEM table
/// that has a region column, in `model/` and `fem/`: (folder, GOM, FEM table).
fn mini_project() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let model = tmp.path().join("model");
    let fem = tmp.path().join("fem");
    std::fs::create_dir_all(&model).unwrap();
    std::fs::create_dir_all(&fem).unwrap();
    for f in ["TwoMat.GOM", "TwoMat.CPS_001"] {
        std::fs::copy(fixture("anura3d-mini").join(f), model.join(f)).unwrap();
    }
    std::fs::write(fem.join("fem.csv"), mini_regions_csv()).unwrap();
    (tmp, model.join("TwoMat.GOM"), fem.join("fem.csv"))
}

/// Every file under `dir` with its bytes.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap_or_default()));
            }
        }
    }
    out.sort();
    out
}

fn no_staging_left(dir: &Path) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            !name.starts_with(".a3d-init") || name == a3d_init::pipeline::io::output::MARKER,
            "{name} left in {}",
            dir.display()
        );
    }
}

#[test]
fn force_never_deletes_or_overwrites_an_input() {
    let (tmp, gom, fem) = mini_project();
    let cps = gom.with_extension("CPS_001");
    let fem_dir = fem.parent().unwrap().to_path_buf();
    let model_dir = gom.parent().unwrap().to_path_buf();
    let before = snapshot(tmp.path());
    // map --out = the folder of the FEM table, of the model, or the model file itself.
    for out in [&fem_dir, &model_dir, &gom, &tmp.path().to_path_buf()] {
        let (code, text) = map(&fem, &gom, out, &["--force"]);
        assert_eq!(code, 2, "{text}");
        assert!(text.contains("refusing to write"), "{text}");
        assert!(
            text.contains(&out.display().to_string()),
            "names the output: {text}"
        );
    }
    // A symlink to the FEM folder is the FEM folder.
    let link = tmp.path().join("link");
    std::os::unix::fs::symlink(&fem_dir, &link).unwrap();
    let (code, text) = map(&fem, &gom, &link, &["--force"]);
    assert_eq!(code, 2, "{text}");
    std::fs::remove_file(&link).unwrap();
    // inspect --mps = the GOM, the CPS, or a hard link to the GOM.
    let hard = tmp.path().join("hard.GOM");
    std::fs::hard_link(&gom, &hard).unwrap();
    for target in [&gom, &cps, &hard] {
        let (code, text) = run(&[&"inspect", &model_dir, &"--mps", target, &"--force"]);
        assert_eq!(code, 2, "{text}");
        assert!(text.contains("is the input"), "{text}");
    }
    std::fs::remove_file(&hard).unwrap();
    // calibrate --out = the folder of the --check table.
    let check_dir = tmp.path().join("check");
    std::fs::create_dir(&check_dir).unwrap();
    let check = check_dir.join("check.csv");
    std::fs::copy(&fem, &check).unwrap();
    calibrate_refused(
        &[&"--fem", &fem, &"--check", &check],
        &check_dir,
        "check.csv",
    );
    std::fs::remove_dir_all(&check_dir).unwrap();
    assert_eq!(snapshot(tmp.path()), before, "no input changed");
    no_staging_left(tmp.path());
}

#[test]
fn verify_run_and_fos_out_may_not_hold_the_state_and_fem_mesh_is_an_input() {
    let (tmp, gom, fem) = mini_project();
    let mapped = tmp.path().join("mapped");
    let (code, text) = map(&fem, &gom, &mapped, &[]);
    assert_eq!(code, 0, "{text}");
    let state_dir = tmp.path().join("state");
    std::fs::create_dir(&state_dir).unwrap();
    let state = state_dir.join("mps.csv");
    std::fs::copy(mapped.join("mps.csv"), &state).unwrap();
    let before = std::fs::read(&state).unwrap();
    let (code, text) = verify_state(&gom, &state, &state_dir, &["--force", "--max-steps", "10"]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("holds the input"), "{text}");
    assert_eq!(std::fs::read(&state).unwrap(), before);
    // Regression (#24): `fos --mpm model --state run1/state.csv --out run1
    // --force` exited 0 and deleted the state table, because `fos` listed
    // only the model among its inputs. Every file a command reads now guards
    // its output, for every command that takes a state table.
    for command in ["fos", "run"] {
        let (code, text) = run(&[
            &command, &"--mpm", &gom, &"--state", &state, &"--out", &state_dir, &"--force",
        ]);
        assert_eq!(code, 2, "{command}: {text}");
        assert!(text.contains("holds the input"), "{command}: {text}");
        assert_eq!(std::fs::read(&state).unwrap(), before, "{command}");
    }
    // The same through the library, without the CLI.
    let source = a3d_init::pipeline::check::start::StateSource::Table {
        model: gom.clone(),
        state: state.clone(),
    };
    let e = a3d_init::pipeline::stability::fos::fos(
        &source,
        &Default::default(),
        a3d_init::pipeline::io::output::Destination::new(Some(&state_dir), true),
    )
    .unwrap_err();
    assert_eq!(e.kind(), a3d_init::pipeline::ErrorKind::Output, "{e}");
    assert_eq!(std::fs::read(&state).unwrap(), before);
    // --fem-mesh: the folder of Mesh.ply is an input folder too.
    let rd = fixture("geostudio-gsz-internal/rapid-drawdown");
    let mesh_dir = tmp.path().join("mesh");
    std::fs::create_dir(&mesh_dir).unwrap();
    let mesh = mesh_dir.join("Mesh.ply");
    std::fs::copy(rd.join("1-initial-steady-state_Mesh.ply"), &mesh).unwrap();
    let node = rd.join("1-initial-steady-state_001_node.csv");
    calibrate_refused(
        &[&"--fem", &node, &"--fem-mesh", &mesh],
        &mesh_dir,
        "Mesh.ply",
    );
    assert!(mesh.exists());
}

#[test]
fn force_replaces_an_output_folder_whole_and_leaves_no_staging() {
    let (tmp, gom, fem) = mini_project();
    let out = tmp.path().join("out");
    // An earlier output, with a file a3d-init no longer writes.
    let (code, text) = map(&fem, &gom, &out, &[]);
    assert_eq!(code, 0, "{text}");
    std::fs::write(out.join("stale.txt"), "old run").unwrap();
    let (code, text) = map(&fem, &gom, &out, &["--force"]);
    assert_eq!(code, 0, "{text}");
    assert!(
        !out.join("stale.txt").exists(),
        "the old folder is gone whole"
    );
    assert!(out.join("report.json").exists());
    no_staging_left(tmp.path());
    // A failed run (bad --material-map) leaves the old output and nothing else.
    let (code, text) = map(&fem, &gom, &out, &["--force", "--material-map", "clay=9"]);
    assert_eq!(code, 2, "{text}");
    assert!(out.join("report.json").exists());
    no_staging_left(tmp.path());
    // A failed verify (a state that is not a number) leaves no staging folder.
    let mut state = std::fs::read_to_string(out.join("mps.csv")).unwrap();
    state = state.replacen(",1,", ",x,", 1);
    let bad = tmp.path().join("bad.csv");
    std::fs::write(&bad, state).unwrap();
    let (code, _) = verify_state(&gom, &bad, &tmp.path().join("v"), &[]);
    assert_eq!(code, 2);
    no_staging_left(tmp.path());
}

#[test]
fn non_regular_files_are_refused_at_once() {
    let (tmp, gom, fem) = mini_project();
    let fifo = tmp.path().join("fifo.csv");
    let status = Command::new("mkfifo").arg(&fifo).status();
    let mut specials: Vec<PathBuf> = vec![PathBuf::from("/dev/zero"), tmp.path().to_path_buf()];
    if status.is_ok_and(|s| s.success()) {
        specials.push(fifo.clone());
    }
    for special in &specials {
        let (code, text) = map(special, &gom, &tmp.path().join("o"), &[]);
        assert_eq!(code, 2, "{}: {text}", special.display());
        let (code, text) = run(&[
            &"calibrate",
            &"--fem",
            &fem,
            &"--fem-mesh",
            special,
            &"--out",
            &tmp.path().join("o"),
        ]);
        assert_eq!(code, 2, "{}: {text}", special.display());
        let (code, text) = run(&[&"inspect", &"--fem", special]);
        assert_eq!(code, 2, "{}: {text}", special.display());
        if !special.is_dir() {
            let (code, text) = run(&[&"diff", special, special]);
            assert_eq!(code, 2, "{}: {text}", special.display());
        }
    }
    let (code, text) = run(&[&"inspect", &"/dev/zero"]);
    assert_eq!(code, 2, "{text}");
}

fn ply_with_header(header_nodes: &str, nodes: usize) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement version 1\nproperty ushort major\nproperty ushort minor\nelement node {header_nodes}\nproperty double x\nproperty double y\nproperty double z\nelement element 4611686018427387904\nproperty list uchar int id\nend_header\n"
    )
    .into_bytes();
    b.extend_from_slice(&[1, 0, 0, 0]);
    for k in 0..nodes {
        for v in [k as f64, 0.0, 0.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
    }
    b
}

#[test]
fn huge_declared_counts_are_errors_not_panics() {
    use a3d_init::formats::ply;
    let base = std::fs::read_to_string(fixture("anura3d-mini/TwoMat.GOM")).unwrap();
    let p = Path::new("Mesh.ply");
    for (declared, actual) in [
        ("4611686018427387904", 3),
        ("18446744073709551615", 3),
        ("4", 3),
    ] {
        let e = ply::parse_ply_nodes(p, &ply_with_header(declared, actual))
            .unwrap_err()
            .to_string();
        assert!(e.contains("PLY"), "{declared}: {e}");
    }
    // Huge element counts after the nodes: refused before any loop.
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("Mesh.ply");
    std::fs::write(&file, ply_with_header("3", 3)).unwrap();
    let e = ply::read_ply_mesh(&file).unwrap_err().to_string();
    assert!(e.contains("truncated PLY"), "{e}");
    // A material count of 10^18 (found by hand: a capacity-overflow panic).
    let dir = tmp.path().join("materials");
    std::fs::create_dir(&dir).unwrap();
    let gom = dir.join("TwoMat.GOM");
    std::fs::write(
        &gom,
        base.replacen(
            "$$NUMBER_OF_MATERIALS\n2\n",
            "$$NUMBER_OF_MATERIALS\n999999999999999999\n",
            1,
        ),
    )
    .unwrap();
    let (code, text) = run(&[&"inspect", &gom]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("TwoMat.GOM:"), "{text}");
    // GOM counters of 2^62 or 10^18.
    for counters in [
        "4611686018427387904 6",
        "4 999999999999999999",
        "999999999999999999 999999999999999999",
    ] {
        let dir = tmp.path().join(counters.replace(' ', "_"));
        std::fs::create_dir(&dir).unwrap();
        let gom = dir.join("TwoMat.GOM");
        std::fs::write(&gom, base.replacen("4 6\n", &format!("{counters}\n"), 1)).unwrap();
        let (code, text) = run(&[&"inspect", &gom]);
        assert_eq!(code, 2, "{text}");
        assert!(text.contains("TwoMat.GOM:"), "{text}");
    }
}

#[test]
fn a_zip_bomb_entry_is_refused_before_it_fills_memory() {
    let tmp = tempfile::tempdir().unwrap();
    let gsz = tmp.path().join("bomb.gsz");
    let file = std::fs::File::create(&gsz).unwrap();
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default();
    zip.start_file("project.xml", options).unwrap();
    zip.write_all(b"<GSIData><Analyses><Analysis><Name>A</Name></Analysis></Analyses></GSIData>")
        .unwrap();
    zip.start_file("A/001/node.csv", options).unwrap();
    let zeros = vec![b'0'; 1 << 20];
    for _ in 0..40 {
        zip.write_all(&zeros).unwrap();
    }
    zip.start_file("A/Mesh.ply", options).unwrap();
    zip.write_all(b"ply\n").unwrap();
    zip.finish().unwrap();
    assert!(std::fs::metadata(&gsz).unwrap().len() < 1 << 20);
    let (code, text) = run(&[&"inspect", &"--fem", &gsz]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("zip bomb"), "{text}");
}

/// The GOM's inconsistent counts, trailing data and overflowing numbers are
/// cases of `common::malformed`, read through the library and the binary.
#[test]
fn non_finite_values_and_data_after_the_end_of_a_cps_are_positioned() {
    let tmp = tempfile::tempdir().unwrap();
    let gom = std::fs::read_to_string(fixture("anura3d-mini/TwoMat.GOM")).unwrap();
    let cps = std::fs::read_to_string(fixture("anura3d-mini/TwoMat.CPS_001")).unwrap();
    let cases = [
        (
            "cps_nan",
            cps.replacen("9.81\n", "NaN\n", 1),
            "TwoMat.CPS_001:9:1: $$GRAVITY_ACCELERATION: `NaN` is not a finite number",
        ),
        (
            "cps_inf_damping",
            cps.replacen("1 0.75\n", "1 -Infinity\n", 1),
            "TwoMat.CPS_001:21:3:",
        ),
        (
            "cps_after_end",
            format!("{cps}junk\n"),
            "TwoMat.CPS_001:34:1: data after `$$END`",
        ),
    ];
    for (name, c, expected) in cases {
        let dir = tmp.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(dir.join("TwoMat.GOM"), &gom).unwrap();
        std::fs::write(dir.join("TwoMat.CPS_001"), c).unwrap();
        let (code, text) = run(&[&"inspect", &dir]);
        assert_eq!(code, 2, "{name}: {text}");
        assert!(
            text.contains(expected),
            "{name}: expected `{expected}` in {text}"
        );
    }
}

#[test]
fn garbage_material_map_and_bad_states_are_exit_2() {
    let (tmp, gom, fem) = mini_project();
    for (spec, expected) in [
        ("snad=1", "no region `snad`"),
        ("clay=1,clay=2", "mapped twice"),
        ("=1", "both sides"),
        ("clay", "expected region=material"),
        (",", "no region=material pair"),
        ("clay=\u{1}", "no GOM material"),
    ] {
        let (code, text) = map(&fem, &gom, &tmp.path().join("o"), &["--material-map", spec]);
        assert_eq!(code, 2, "{spec}: {text}");
        assert!(text.contains(expected), "{spec}: {text}");
    }
    let out = tmp.path().join("mapped");
    let (code, text) = map(&fem, &gom, &out, &[]);
    assert_eq!(code, 0, "{text}");
    let good = std::fs::read_to_string(out.join("mps.csv")).unwrap();
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    let mut fields: Vec<String> = lines[2].split(',').map(String::from).collect();
    fields[8] = "NaN".into();
    lines[2] = fields.join(",");
    let column = fields[..8]
        .iter()
        .map(|f| f.chars().count() + 1)
        .sum::<usize>()
        + 1;
    let bad = tmp.path().join("bad.csv");
    std::fs::write(&bad, lines.join("\n")).unwrap();
    let (code, text) = verify_state(&gom, &bad, &tmp.path().join("v"), &[]);
    assert_eq!(code, 2, "{text}");
    assert!(
        text.contains(&format!(
            "bad.csv:3:{column}: field 9: expected a finite number, found `NaN`"
        )),
        "{text}"
    );
}

#[test]
fn calibrate_on_overflowing_fields_is_an_error_not_a_hang() {
    let tmp = tempfile::tempdir().unwrap();
    let mut csv = String::from("X (m),Y (m),PWP (kPa)\n");
    for j in 0..15 {
        for i in 0..15 {
            let v = if (i + j) % 3 == 0 { 1e308 } else { -1e308 };
            csv.push_str(&format!("{},{},{v}\n", i as f64 * 0.5, j as f64 * 0.5));
        }
    }
    let fem = tmp.path().join("huge.csv");
    std::fs::write(&fem, csv).unwrap();
    for norm in ["l1", "l2", "relative"] {
        let (code, text) = run(&[
            &"calibrate",
            &"--fem",
            &fem,
            &"--norm",
            &norm,
            &"--out",
            &tmp.path().join("c"),
        ]);
        assert_eq!(code, 2, "{norm}: {text}");
        assert!(text.contains("calibration:"), "{text}");
    }
    assert!(!tmp.path().join("c").exists());
}

/// Found by CLI fuzzing: `$$GRAVITY_ACCELERATION 0` made `verify` panic while
/// plotting an infinite residual ratio (attempt to add with overflow).
#[test]
fn verify_with_zero_gravity_plots_without_panicking() {
    let (tmp, gom, fem) = mini_project();
    let cps = gom.with_extension("CPS_001");
    let text = std::fs::read_to_string(&cps).unwrap();
    std::fs::write(&cps, text.replacen("9.81\n", "0\n", 1)).unwrap();
    let out = tmp.path().join("mapped");
    let (code, text) = map(&fem, &gom, &out, &[]);
    assert_eq!(code, 0, "{text}");
    let (code, text) = run(&[&"verify", &out, &"--max-steps", &"100"]);
    assert!(matches!(code, 0..=2), "{text}");
    no_staging_left(&out);
}

/// A smoothing length wider than the whole FEM would make every MP average
/// every node at O(MPs × nodes) cost (a 60k-MP model ran past 60 s): refused.
#[test]
fn a_smoothing_length_wider_than_the_fem_is_refused() {
    k0_map_refused(
        &fixture("geostudio-csv/k0-slope-hydrostatic.csv"),
        &["--h", "1000"],
        &[
            "smoothing length h = 1000 m",
            "more than twice the FEM's extent",
        ],
    );
}

/// `map` of the K0 slope sample with `fem` and `extra` is refused (exit 2)
/// saying each of `expected`, and leaves no output folder.
#[track_caller]
fn k0_map_refused(fem: &Path, extra: &[&str], expected: &[&str]) {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let (code, text) = run_map(&fixture("anura3d/K0_phreaticSurf_Geom"), fem, &out, extra);
    assert_eq!(code, 2, "{extra:?}: {text}");
    assert_contains(&text, expected);
    assert!(!text.contains("panicked"), "{text}");
    assert!(!out.exists());
}

// ---- Input defects (#24, #30) ----

/// #24: `calibrate --field all` on a table with only X and Y panicked in the
/// leave-one-out code (index out of bounds); `map` on it must stay a clear error.
#[test]
fn calibrate_field_all_on_a_table_without_fields_is_exit_2_not_a_panic() {
    let tmp = tempfile::tempdir().unwrap();
    let fem = tmp.path().join("xy.csv");
    std::fs::write(&fem, "X,Y\n0,0\n1,0\n0,1\n1,1\n2,2\n").unwrap();
    let out = tmp.path().join("c");
    for field in ["all", "pwp"] {
        let (code, text) = run(&[
            &"calibrate",
            &"--fem",
            &fem,
            &"--field",
            &field,
            &"--out",
            &out,
        ]);
        assert_eq!(code, 2, "{field}: {text}");
        assert_contains(&text, &["xy.csv", "no field to calibrate on"]);
        assert!(!out.exists());
    }
    k0_map_refused(
        &fem,
        &["--h", "auto"],
        &["xy.csv", "no pore-water pressure or total stress columns"],
    );
}

/// #24: a `node.csv` row with an empty `Node` cell took its row number as id,
/// so with `--fem-mesh` its pore pressure landed on another mesh node.
#[test]
fn empty_node_id_with_fem_mesh_is_exit_2_at_its_cell() {
    let tmp = tempfile::tempdir().unwrap();
    let rd = fixture("geostudio-gsz-internal/rapid-drawdown");
    let text = std::fs::read_to_string(rd.join("1-initial-steady-state_001_node.csv")).unwrap();
    let node = tmp.path().join("node.csv");
    std::fs::write(&node, text.replacen("\r\n4,", "\r\n,", 1)).unwrap();
    let mesh = rd.join("1-initial-steady-state_Mesh.ply");
    let out = tmp.path().join("out");
    let (code, text) = map(
        &node,
        &fixture("anura3d-rapid-drawdown/rapid_drawdown.GOM"),
        &out,
        &["--fem-mesh", mesh.to_str().unwrap(), "--generate-cps"],
    );
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["node.csv:5:1: empty node id in `Node`"]);
    assert!(!out.exists());
}

/// #24: a PLY whose header declares more nodes than the data holds (`element
/// node 554` over 553 rows) was read when only nodes were needed: node 554
/// took its numbers from the element block. Every declared count is checked
/// against the data, in every read path (`--fem-mesh`, the mesh of a `.gsz`).
#[test]
fn ply_node_count_larger_than_the_data_is_refused() {
    use a3d_init::formats::ply;
    let rd = fixture("geostudio-gsz-internal/rapid-drawdown");
    let good = std::fs::read(rd.join("1-initial-steady-state_Mesh.ply")).unwrap();
    let header_end = good.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = String::from_utf8_lossy(&good[..header_end]).into_owned();
    let with_header = |from: &str, to: &str| {
        [header.replacen(from, to, 1).as_bytes(), &good[header_end..]].concat()
    };
    let p = Path::new("Mesh.ply");
    assert_eq!(ply::parse_ply_nodes(p, &good).unwrap().len(), 553);
    for (name, bytes, expected) in [
        (
            "554 nodes",
            with_header("element node 553", "element node 554"),
            "truncated PLY",
        ),
        (
            "552 nodes",
            with_header("element node 553", "element node 552"),
            "Mesh.ply: byte ",
        ),
        (
            "682 elements",
            with_header("element element 681", "element element 682"),
            "truncated PLY",
        ),
        (
            "trailing bytes",
            [&good[..], &[0u8; 7]].concat(),
            "7 bytes after the last element `node_pair`",
        ),
    ] {
        // Nodes only (what --fem-mesh and a .gsz read); nodes and elements.
        let e = ply::parse_ply_nodes(p, &bytes).unwrap_err().to_string();
        assert!(
            e.starts_with("Mesh.ply: byte ") && e.contains(expected),
            "{name}: {e}"
        );
        let e = ply::parse_ply_mesh(p, &bytes).unwrap_err().to_string();
        assert!(e.starts_with("Mesh.ply: byte "), "{name}: {e}");
    }
    // Through the binary: `--fem-mesh`, and the mesh inside a `.gsz`.
    let tmp = tempfile::tempdir().unwrap();
    let bad = with_header("element node 553", "element node 554");
    let mesh = tmp.path().join("Mesh.ply");
    std::fs::write(&mesh, &bad).unwrap();
    let node = rd.join("1-initial-steady-state_001_node.csv");
    let (code, text) = run(&[&"inspect", &"--fem", &node, &"--fem-mesh", &mesh]);
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["Mesh.ply: byte ", "truncated PLY"]);
    let gsz = tmp.path().join("p.gsz");
    let mut zip = zip::ZipWriter::new(std::fs::File::create(&gsz).unwrap());
    let options = zip::write::SimpleFileOptions::default();
    zip.start_file("project.xml", options).unwrap();
    zip.write_all(b"<GSIData><Analyses><Analysis><Name>A</Name></Analysis></Analyses></GSIData>")
        .unwrap();
    zip.start_file("A/001/node.csv", options).unwrap();
    zip.write_all(&std::fs::read(&node).unwrap()).unwrap();
    zip.start_file("A/Mesh.ply", options).unwrap();
    zip.write_all(&bad).unwrap();
    zip.finish().unwrap();
    let (code, text) = run(&[&"inspect", &"--fem", &gsz]);
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["A/Mesh.ply: byte ", "truncated PLY"]);
}

/// #24: two mesh nodes at one point in a `Mesh.ply` (two pore pressures at
/// one place) were accepted, while the same data as an X, Y table was
/// refused. Both are refused, naming both lines.
#[test]
fn coincident_mesh_nodes_are_refused_like_coincident_table_rows() {
    let rd = fixture("geostudio-gsz-internal/rapid-drawdown");
    let good = std::fs::read(rd.join("1-initial-steady-state_Mesh.ply")).unwrap();
    let header_end = good.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // Node 11 moved onto node 10 (the version element takes 4 bytes).
    let node = |k: usize| header_end + 4 + 24 * (k - 1);
    let mut bad = good.clone();
    bad.copy_within(node(10)..node(10) + 24, node(11));
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("Mesh.ply");
    std::fs::write(&mesh, &bad).unwrap();
    let csv = rd.join("1-initial-steady-state_001_node.csv");
    let (code, text) = run(&[&"inspect", &"--fem", &csv, &"--fem-mesh", &mesh]);
    assert_eq!(code, 2, "{text}");
    assert_contains(
        &text,
        &[
            "1-initial-steady-state_001_node.csv:12:1: duplicate node: mesh node 11 of ",
            "Mesh.ply is at the same point as mesh node 10 (",
            "1-initial-steady-state_001_node.csv:11)",
        ],
    );
    // The same nodes as an X, Y table: the check and its message of before.
    let nodes = a3d_init::formats::ply::parse_ply_nodes(&mesh, &bad).unwrap();
    let mut table = String::from("X,Y,PWP\n");
    for p in &nodes {
        table.push_str(&format!("{},{},1\n", p[0], p[1]));
    }
    let xy = tmp.path().join("xy.csv");
    std::fs::write(&xy, table).unwrap();
    let (code, text) = run(&[&"inspect", &"--fem", &xy]);
    assert_eq!(code, 2, "{text}");
    assert_contains(
        &text,
        &["xy.csv:12:1: duplicate node: same coordinates as line 11"],
    );
}

/// #24: `$$GRAVITY_VECTOR 1.0 0.0` (or `0.0 0.0`) was accepted: `map` computed
/// geostatic stress for −y gravity and `verify` ran with −y gravity. Every
/// command that reads the CPS for gravity refuses it at its line and column.
#[test]
fn gravity_vector_not_along_minus_y_is_refused_by_every_command() {
    let (tmp, gom, fem) = mini_project();
    let out = tmp.path().join("mapped");
    let (code, text) = map(&fem, &gom, &out, &["--stress", "geostatic"]);
    assert_eq!(code, 0, "{text}");
    let cps = gom.with_extension("CPS_001");
    let good = std::fs::read_to_string(&cps).unwrap();
    let mapped_cps = out.join("TwoMat.CPS_001");
    let mapped = std::fs::read_to_string(&mapped_cps).unwrap();
    for (vector, column) in [("1.0 0.0", 1), ("0.0 0.0", 5), ("0.0 -9.81", 5)] {
        let line = |text: &str| text.lines().position(|l| l == "$$GRAVITY_VECTOR").unwrap() + 2;
        let at = format!("TwoMat.CPS_001:{}:{column}: $$GRAVITY_VECTOR", line(&good));
        std::fs::write(&cps, good.replacen("0.0 -1.0\n", &format!("{vector}\n"), 1)).unwrap();
        let (code, text) = map(&fem, &gom, &tmp.path().join("o"), &[]);
        assert_eq!(code, 2, "{vector}: {text}");
        assert_contains(&text, &[&at]);
        assert!(!tmp.path().join("o").exists());
        let (code, text) = run(&[&"inspect", &gom]);
        assert_eq!(code, 2, "{vector}: {text}");
        assert_contains(&text, &[&at]);
        // A mapped folder whose CPS was edited afterwards.
        let at = format!(
            "TwoMat.CPS_001:{}:{column}: $$GRAVITY_VECTOR",
            line(&mapped)
        );
        std::fs::write(
            &mapped_cps,
            mapped.replacen("0.0 -1.0\n", &format!("{vector}\n"), 1),
        )
        .unwrap();
        for command in ["verify", "run", "fos"] {
            let (code, text) = run(&[&command, &out, &"--out", &tmp.path().join("v")]);
            assert_eq!(code, 2, "{command} {vector}: {text}");
            assert_contains(&text, &[&at]);
        }
        let (code, text) = verify_state(&gom, &out.join("mps.csv"), &tmp.path().join("v"), &[]);
        assert_eq!(code, 2, "{vector}: {text}");
        assert_contains(&text, &["$$GRAVITY_VECTOR: component"]);
    }
    assert!(!tmp.path().join("v").exists());
}

/// #24: `--h 1e-300` (far below the node spacing) overflowed the neighbour
/// grid's cell count and aborted on a 3 GB allocation; it is refused like an
/// h wider than the FEM, whatever `--outside` says.
#[test]
fn h_far_below_the_node_spacing_is_refused() {
    for extra in [
        &["--h", "1e-300"][..],
        &["--h", "0.0001", "--outside", "nearest"],
    ] {
        k0_map_refused(
            &fixture("geostudio-csv/k0-slope-hydrostatic.csv"),
            extra,
            &[
                &format!("smoothing length h = {} m: the kernel support", extra[1]),
                "below a thousandth of the node spacing l = 0.5000 m",
            ],
        );
    }
}

/// #30: one mesh node at x = 1e308 in a PLY aborted `map` on a 6 GB
/// allocation (the neighbour grid sized by the extent). A node that far from
/// the others cannot be meant: refused at its row, naming the coordinate, in
/// a `node.csv` joined to a mesh and in a table with X and Y alike.
#[test]
fn a_mesh_node_at_1e308_is_refused_not_a_6_gb_allocation() {
    let rd = fixture("geostudio-gsz-internal/rapid-drawdown");
    let mut ply = std::fs::read(rd.join("1-initial-steady-state_Mesh.ply")).unwrap();
    let header_end = ply.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let x10 = header_end + 4 + 24 * 9;
    ply[x10..x10 + 8].copy_from_slice(&1e308f64.to_le_bytes());
    let tmp = tempfile::tempdir().unwrap();
    let mesh = tmp.path().join("Mesh.ply");
    std::fs::write(&mesh, &ply).unwrap();
    let out = tmp.path().join("out");
    let (code, text) = map(
        &rd.join("1-initial-steady-state_001_node.csv"),
        &fixture("anura3d-rapid-drawdown/rapid_drawdown.GOM"),
        &out,
        &["--fem-mesh", mesh.to_str().unwrap(), "--generate-cps"],
    );
    assert_eq!(code, 2, "{text}");
    assert_contains(
        &text,
        &[
            "1-initial-steady-state_001_node.csv:11:1: mesh node 10 of ",
            "Mesh.ply: x = 1e308 lies more than 10^6 times the spread of the nodes",
        ],
    );
    assert!(!out.exists());
    let csv = std::fs::read_to_string(fixture("geostudio-csv/k0-slope-hydrostatic.csv")).unwrap();
    let lines = csv.lines().count();
    let fem = tmp.path().join("far.csv");
    std::fs::write(&fem, format!("{csv}9999,1e308,0.0,5.0\n")).unwrap();
    let (code, text) = map(&fem, &fixture("anura3d/K0_phreaticSurf_Geom"), &out, &[]);
    assert_eq!(code, 2, "{text}");
    assert_contains(
        &text,
        &[&format!("far.csv:{}:1: x = 1e308 lies", lines + 1)],
    );
}

/// `<dir>/fem.csv`: the 207 nodes of `test-1005_3D` with the pore pressure
/// `pwp(z)`.
fn test_1005_nodes_csv(dir: &Path, pwp: impl Fn(f64) -> f64) -> PathBuf {
    let gom = std::fs::read_to_string(fixture("anura3d/test-1005_3D/test-1005_3D.GOM")).unwrap();
    let lines: Vec<&str> = gom.lines().collect();
    let start = lines.iter().position(|l| *l == "$$STARTNODES").unwrap() + 1;
    let mut csv = String::from("X,Y,Z,PWP\n");
    for l in &lines[start..start + 207] {
        let v: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
        csv.push_str(&format!("{},{},{},{}\n", v[0], v[1], v[2], pwp(v[2])));
    }
    let fem = dir.join("fem.csv");
    std::fs::write(&fem, csv).unwrap();
    fem
}

/// #30: z = 1e308 on one node of a 3D GOM made `map` panic with "capacity
/// overflow" (the geostatic stress's vertical index sized by the extent;
/// bounded now whatever the mesh, see `state::geostatic`). A node that far
/// from the others cannot be meant: the GOM reader refuses it at its
/// coordinate, whatever `--outside` says.
#[test]
fn a_3d_gom_node_at_z_1e308_is_refused_not_a_capacity_overflow() {
    let tmp = tempfile::tempdir().unwrap();
    let src = fixture("anura3d/test-1005_3D");
    let dir = tmp.path().join("model");
    std::fs::create_dir(&dir).unwrap();
    let gom = std::fs::read_to_string(src.join("test-1005_3D.GOM")).unwrap();
    let lines: Vec<&str> = gom.lines().collect();
    let start = lines.iter().position(|l| *l == "$$STARTNODES").unwrap() + 1;
    let fem = test_1005_nodes_csv(tmp.path(), |z| -10.0 * z);
    // Node 9, (0, 0, 0), a corner of the first elements.
    assert_eq!(
        lines[start + 8].split_whitespace().collect::<Vec<_>>(),
        ["0", "0", "0"]
    );
    let far = gom.replacen(
        lines[start + 8],
        "           0            0        1e308",
        1,
    );
    std::fs::write(dir.join("test-1005_3D.GOM"), far).unwrap();
    std::fs::copy(
        src.join("test-1005_3D.CPS_001"),
        dir.join("test-1005_3D.CPS_001"),
    )
    .unwrap();
    let out = tmp.path().join("out");
    for extra in [&[][..], &["--outside", "nearest"]] {
        let (code, text) = map(&fem, &dir, &out, extra);
        assert_eq!(code, 2, "{text}");
        assert_contains(
            &text,
            &["test-1005_3D.GOM:19:34: node 9: z = 1e308 lies more than 10^6 times the spread"],
        );
        assert!(!out.exists());
    }
}

// ---- #38: the readers and commands added since #30, against crafted input ----

/// The crafted files of #38 stay under this address-space limit (1 GiB):
/// the binary runs under `prlimit --as`, so an allocation on a declared size
/// aborts (exit 134) instead of passing unseen. Without `prlimit` it runs
/// unlimited.
const MEMORY_LIMIT: u64 = 1 << 30;

/// A run of the binary is killed after this long (a hang guard, not a speed
/// target: every command here answers at once).
const KILL_AFTER_S: u32 = 120;

/// Whether `tool --version` runs here.
fn have(tool: &str) -> bool {
    use std::process::Stdio;
    Command::new(tool)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// [`run`] with the address space capped at [`MEMORY_LIMIT`] (`prlimit`)
/// and killed after [`KILL_AFTER_S`] (`timeout`): (exit code, stderr +
/// stdout).
fn run_capped(args: &[&dyn AsRef<std::ffi::OsStr>]) -> (i32, String) {
    run_capped_at(MEMORY_LIMIT, args)
}

/// [`run_capped`] with an address-space limit of `limit` bytes.
fn run_capped_at(limit: u64, args: &[&dyn AsRef<std::ffi::OsStr>]) -> (i32, String) {
    use std::process::Stdio;
    let bin = env!("CARGO_BIN_EXE_a3d-init");
    let mut wrappers: Vec<String> = Vec::new();
    if have("timeout") {
        wrappers.extend([
            "timeout".into(),
            "-s".into(),
            "KILL".into(),
            KILL_AFTER_S.to_string(),
        ]);
    }
    if have("prlimit") {
        wrappers.extend(["prlimit".into(), format!("--as={limit}"), "--".into()]);
    }
    let mut command = match wrappers.split_first() {
        Some((first, rest)) => {
            let mut c = Command::new(first);
            c.args(rest).arg(bin);
            c
        }
        None => Command::new(bin),
    };
    let os: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_ref()).collect();
    command.args(&os);
    let started = std::time::Instant::now();
    let out = command
        .stdin(Stdio::null())
        .output()
        .expect("the binary runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(
        started.elapsed() < std::time::Duration::from_secs(KILL_AFTER_S.into()),
        "{os:?} ran {:?} and was killed",
        started.elapsed()
    );
    assert!(!text.contains("panicked"), "{text}");
    assert!(!text.contains("memory allocation"), "{text}");
    (out.status.code().unwrap_or(-1), text)
}

/// A small ASCII VTU of two triangles on four points (the unit square) with
/// a `pressure` array; `edit` rewrites its text before it is written.
fn crafted_vtu(dir: &Path, name: &str, edit: impl FnOnce(String) -> String) -> PathBuf {
    let text = r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64" compressor="vtkZLibDataCompressor">
<UnstructuredGrid>
<Piece NumberOfPoints="4" NumberOfCells="2">
<PointData>
<DataArray type="Float64" Name="pressure" format="ascii">0 0 0 0</DataArray>
</PointData>
<Points>
<DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0 1 0 0 1 1 0 0 1 0</DataArray>
</Points>
<Cells>
<DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 0 2 3</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">3 6</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">5 5</DataArray>
</Cells>
</Piece>
</UnstructuredGrid>
</VTKFile>
"#;
    let path = dir.join(name);
    std::fs::write(&path, edit(text.to_string())).unwrap();
    path
}

/// Base64 of a zlib block header (UInt64): one block of `bytes`, and a
/// compressed size of 10, followed by a few bytes that are no zlib stream.
fn lying_zlib_header(bytes: u64) -> String {
    use base64::Engine as _;
    let mut header = Vec::new();
    for v in [1u64, bytes, bytes, 10] {
        header.extend(v.to_le_bytes());
    }
    header.extend([0x78, 0x9c, 1, 2, 3, 4, 5, 6, 7, 8]);
    base64::engine::general_purpose::STANDARD.encode(header)
}

/// `map --fem VTU` onto the mini model, capped: (exit code, text); the output
/// folder must not exist afterwards.
fn map_vtu_capped(tmp: &Path, vtu: &Path) -> (i32, String) {
    let gom = fixture("anura3d-mini/TwoMat.GOM");
    let out = tmp.join("out");
    let result = run_capped(&[&"map", &"--fem", &vtu, &"--mpm", &gom, &"--out", &out]);
    assert!(!out.exists(), "{}", result.1);
    result
}

/// #38 (1): a 600-byte VTU declaring 10¹² points, its zlib header claiming
/// 24 TB, aborted with "memory allocation of 24000000000000 bytes failed";
/// so did a connectivity sized by a last offset of 10¹². Nothing is
/// allocated on a declared size: the file's decode budget refuses both.
#[test]
fn regression_38_a_600_byte_vtu_declaring_1e12_points_is_refused_not_an_abort() {
    let tmp = tempfile::tempdir().unwrap();
    let points = crafted_vtu(tmp.path(), "points.vtu", |t| {
        t.replace("NumberOfPoints=\"4\"", "NumberOfPoints=\"1000000000000\"")
            .replace(
                "NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 1 1 0 0 1 0<",
                &format!(
                    "NumberOfComponents=\"3\" format=\"binary\">{}<",
                    lying_zlib_header(24_000_000_000_000)
                ),
            )
    });
    assert!(std::fs::metadata(&points).unwrap().len() < 1000);
    let (code, text) = map_vtu_capped(tmp.path(), &points);
    assert_eq!(code, 2, "{text}");
    assert_contains(
        &text,
        &[
            "points.vtu:9:1: the points: 3000000000000 values take",
            "a compression bomb",
        ],
    );
    let connectivity = crafted_vtu(tmp.path(), "cells.vtu", |t| {
        t.replace(">3 6<", ">3 1000000000000<").replace(
            "Name=\"connectivity\" format=\"ascii\">0 1 2 0 2 3<",
            &format!(
                "Name=\"connectivity\" format=\"binary\">{}<",
                lying_zlib_header(8_000_000_000_000)
            ),
        )
    });
    let (code, text) = map_vtu_capped(tmp.path(), &connectivity);
    assert_eq!(code, 2, "{text}");
    assert_contains(
        &text,
        &["cells.vtu:12:1: array `connectivity`: 1000000000000 values take"],
    );
}

/// #38 (2): a zlib bomb. Coordinates of zeros in 1.5 MB blocks compress
/// about a thousand times: a 0.4 MB file inflated to 400 MB of points (and
/// as many again as f64), past a 512 MiB limit (the issue's 1.4 MB file
/// reached 2.1 GB). The file's decode budget (32× its size, at least 32 MiB)
/// refuses it before anything is inflated.
#[test]
fn regression_38_a_zlib_bomb_in_a_vtu_is_refused_before_it_inflates() {
    let tmp = tempfile::tempdir().unwrap();
    const BLOCK: usize = 24 << 16; // 2¹⁶ points of 3 Float64
    const BLOCKS: usize = 256;
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    z.write_all(&vec![0u8; BLOCK]).unwrap();
    let compressed = z.finish().unwrap();
    let mut data = Vec::new();
    for v in [BLOCKS as u64, BLOCK as u64, BLOCK as u64] {
        data.extend(v.to_le_bytes());
    }
    for _ in 0..BLOCKS {
        data.extend((compressed.len() as u64).to_le_bytes());
    }
    for _ in 0..BLOCKS {
        data.extend(&compressed);
    }
    let n_points = BLOCKS * BLOCK / 24;
    let head = crafted_vtu(tmp.path(), "head.xml", |t| {
        t.replace(
            "NumberOfPoints=\"4\"",
            &format!("NumberOfPoints=\"{n_points}\""),
        )
        .replace(
            "NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 1 1 0 0 1 0</DataArray>",
            "NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>",
        )
        .replace("</VTKFile>\n", "<AppendedData encoding=\"raw\">\n_")
    });
    let mut bytes = std::fs::read(&head).unwrap();
    bytes.extend(&data);
    bytes.extend(b"\n</AppendedData>\n</VTKFile>\n");
    let bomb = tmp.path().join("bomb.vtu");
    std::fs::write(&bomb, &bytes).unwrap();
    assert!(bytes.len() < 1 << 20, "{} bytes", bytes.len());
    let gom = fixture("anura3d-mini/TwoMat.GOM");
    let out = tmp.path().join("out");
    let (code, text) = run_capped_at(
        512 << 20,
        &[&"map", &"--fem", &bomb, &"--mpm", &gom, &"--out", &out],
    );
    assert!(!out.exists());
    assert_eq!(code, 2, "{text}");
    assert_contains(
        &text,
        &[
            "bomb.vtu:9:1: the points: 50331648 values take 402653184 bytes decoded, past the",
            "a compression bomb",
        ],
    );
    // `inspect` reads no values, and says what the file holds.
    let (code, text) = run_capped(&[&"inspect", &bomb]);
    assert!(matches!(code, 0 | 2), "{text}");
}

/// The mini model mapped into `<tmp>/mapped`: (folder, GOM, FEM, mapped).
fn mini_mapped() -> (tempfile::TempDir, PathBuf, PathBuf, PathBuf) {
    let (tmp, gom, fem) = mini_project();
    let out = tmp.path().join("mapped");
    let (code, text) = map(&fem, &gom, &out, &[]);
    assert_eq!(code, 0, "{text}");
    (tmp, gom, fem, out)
}

/// `run MAPPED --time TIME --snapshots SNAPSHOTS --out OUT`, capped.
fn run_snapshots(mapped: &Path, time: &str, snapshots: &str, out: &Path) -> (i32, String) {
    run_capped(&[
        &"run",
        &mapped,
        &"--time",
        &time,
        &"--snapshots",
        &snapshots,
        &"--out",
        &out,
    ])
}

/// #38 (3): `run --snapshots` with 15,000 entries grew to 3.7 GB (every
/// snapshot kept until the end), equal times included. Each snapshot is now
/// written as it is taken; a time given twice and more than 1000 times are
/// refused.
#[test]
fn regression_38_snapshot_lists_are_capped_and_a_repeated_time_refused() {
    let (tmp, _, _, mapped) = mini_mapped();
    let out = tmp.path().join("run");
    let equal = vec!["0.01"; 15_000].join(",");
    let distinct: Vec<String> = (1..=15_000).map(|k| k.to_string()).collect();
    for list in [equal, distinct.join(",")] {
        let (code, text) = run_snapshots(&mapped, "0.05", &list, &out);
        assert_eq!(code, 2, "{text}");
        assert_contains(&text, &["15000 snapshot times: a run writes at most 1000"]);
    }
    let (code, text) = run_snapshots(&mapped, "0.05", "0.01,0.02,0.01", &out);
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["snapshot time 0.01 is given twice"]);
    assert!(!out.exists());
}

/// #38 (4): a VTU with many arrays parsed in quadratic time (each tag's line
/// counted from the start of the file): 20,000 arrays took 10.8 s and 100,000
/// (7 MB) did not finish. Positions come from one index of line starts now.
#[test]
fn regression_38_a_vtu_with_100000_arrays_is_read_in_linear_time() {
    let tmp = tempfile::tempdir().unwrap();
    let vtu = crafted_vtu(tmp.path(), "many.vtu", |t| {
        let mut arrays = String::new();
        for k in 0..100_000 {
            arrays.push_str(&format!(
                "<DataArray type=\"Float64\" Name=\"a{k}\" format=\"ascii\">0 0 0 0</DataArray>\n"
            ));
        }
        t.replace("</PointData>", &format!("{arrays}</PointData>"))
    });
    assert!(std::fs::metadata(&vtu).unwrap().len() > 7_000_000);
    // The watchdog's wall limit is a hang guard (the old reader ran for
    // hours), not a speed target.
    let dog = Watchdog {
        idle: std::time::Duration::from_secs(60),
        wall: std::time::Duration::from_secs(120),
    };
    let (code, text) =
        run_watched(&["inspect".as_ref(), vtu.as_os_str()], dog).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(code, 0, "{text}");
    assert_contains(&text, &["a99999"]);
    let out = tmp.path().join("out");
    let gom = fixture("anura3d-mini/TwoMat.GOM");
    let (code, text) = run_watched(
        &[
            "map".as_ref(),
            "--fem".as_ref(),
            vtu.as_os_str(),
            "--mpm".as_ref(),
            gom.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ],
        dog,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(matches!(code, 0 | 2), "{text}");
}

/// #38 (5): `--out DIR --force` replaced any folder, one a3d-init never
/// wrote (`Documents/` with `paper.docx`) too. `--force` replaces only an
/// empty folder or one holding a3d-init's marker; and no output may hold a
/// file of a `.pvd` series, read or not.
#[test]
fn regression_38_force_never_replaces_a_folder_a3d_init_did_not_write() {
    let (tmp, gom, fem) = mini_project();
    let documents = tmp.path().join("Documents");
    std::fs::create_dir(&documents).unwrap();
    std::fs::write(documents.join("paper.docx"), "years of work").unwrap();
    for command in [&["map"][..], &["calibrate"]] {
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&command[0], &"--fem", &fem];
        if command[0] == "map" {
            args.extend([&"--mpm" as &dyn AsRef<std::ffi::OsStr>, &gom]);
        }
        args.extend([
            &"--out" as &dyn AsRef<std::ffi::OsStr>,
            &documents,
            &"--force",
        ]);
        let (code, text) = run(&args);
        assert_eq!(code, 2, "{command:?}: {text}");
        assert_contains(
            &text,
            &[
                "refusing to replace",
                "Documents: it is not empty and a3d-init did not write it",
            ],
        );
    }
    assert_eq!(
        std::fs::read_to_string(documents.join("paper.docx")).unwrap(),
        "years of work"
    );
    // An empty folder and a3d-init's own output are replaced.
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let (code, text) = map(&fem, &gom, &empty, &["--force"]);
    assert_eq!(code, 0, "{text}");
    let (code, text) = map(&fem, &gom, &empty, &["--force"]);
    assert_eq!(code, 0, "{text}");
    assert!(empty.join(a3d_init::pipeline::io::output::MARKER).is_file());
    // A series: step 0 beside the .pvd, step 1 inside an earlier output.
    // Mapping step 0 reads step 1 nowhere, but may not replace its folder.
    let vtu = crafted_vtu(tmp.path(), "run_0.vtu", |t| t);
    std::fs::copy(&vtu, empty.join("run_1.vtu")).unwrap();
    let pvd = tmp.path().join("run.pvd");
    std::fs::write(
        &pvd,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n\
         <DataSet timestep=\"0\" file=\"run_0.vtu\"/>\n<DataSet timestep=\"1\" file=\"empty/run_1.vtu\"/>\n\
         </Collection>\n</VTKFile>\n",
    )
    .unwrap();
    let (code, text) = map(&pvd, &gom, &empty, &["--step", "0", "--force"]);
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["holds the input", "run_1.vtu"]);
    assert!(empty.join("run_1.vtu").is_file());
}

/// #38 (6): `run --time 1e300` ran until killed. A duration whose step count
/// passes 10⁷ at the model's time step is refused, naming the count.
#[test]
fn regression_38_a_run_time_no_one_can_mean_is_refused_with_its_step_count() {
    let (tmp, _, _, mapped) = mini_mapped();
    let out = tmp.path().join("run");
    for time in ["1e300", "1e9"] {
        let (code, text) = run_snapshots(&mapped, time, "", &out);
        assert_eq!(code, 2, "{text}");
        assert_contains(
            &text,
            &["would take", "steps, more than the 10000000 a run may take"],
        );
    }
    assert!(!out.exists());
}

/// #38 (7): snapshots were named `mps_t{:.2}`, so 0.001, 0.002 and 0.003 s
/// were one file and two snapshots were lost. Names carry as many decimals
/// as distinct times need.
#[test]
fn regression_38_every_snapshot_time_gets_its_own_file() {
    let (tmp, _, _, mapped) = mini_mapped();
    let out = tmp.path().join("run");
    let (code, text) = run_snapshots(&mapped, "0.004", "0.003,0.001,0.002", &out);
    assert_eq!(code, 0, "{text}");
    assert_contains(&text, &["3 snapshots"]);
    for name in ["mps_t0.001.vtu", "mps_t0.002.vtu", "mps_t0.003.vtu"] {
        assert!(out.join(name).is_file(), "{name}: {text}");
    }
    let names = a3d_init::pipeline::check::runout::snapshot_names(&[0.3, 0.8, 1.2, 2.0]);
    let names: Vec<&str> = names.iter().map(|(_, n)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "mps_t0.30.vtu",
            "mps_t0.80.vtu",
            "mps_t1.20.vtu",
            "mps_t2.00.vtu"
        ]
    );
}

/// #38 (8): `--bisect-tol NaN` and `--bisect-tol=-1` were taken, and the
/// bisection silently skipped; a damping outside [0, 1) was clamped.
#[test]
fn regression_38_bisect_tolerance_and_damping_outside_their_range_are_refused() {
    let (tmp, gom, fem) = mini_project();
    let out = tmp.path().join("ft");
    for bad in [
        "--bisect-tol=NaN",
        "--bisect-tol=-1",
        "--bisect-tol=0",
        "--damping=1.5",
    ] {
        let (code, text) = run(&[
            &"fos-time",
            &"--mpm",
            &gom,
            &"--fem",
            &fem,
            &"--fem",
            &fem,
            &"--times",
            &"0,3600",
            &bad,
            &"--out",
            &out,
        ]);
        assert_eq!(code, 2, "{bad}: {text}");
        let what = if bad.starts_with("--damping") {
            "local damping 1.5: expected a number in [0, 1)"
        } else {
            "expected a positive number of seconds"
        };
        assert_contains(&text, &[what]);
    }
    let (_mapped_tmp, _, _, mapped) = mini_mapped();
    for command in ["verify", "run", "fos"] {
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> =
            vec![&command, &mapped, &"--damping=-0.5", &"--out", &out];
        if command == "fos" {
            args.push(&"--method=srm");
        }
        let (code, text) = run(&args);
        assert_eq!(code, 2, "{command}: {text}");
        assert_contains(&text, &["local damping -0.5: expected a number in [0, 1)"]);
    }
    assert!(!out.exists());
}

/// #38 (9): `map` copied an HHBF whose times do not increase into its
/// ready-to-run project (exit 0), and left out a FIFO in its place; an
/// error on a 50 MB token echoed all of it. The HHBF is read as `verify`
/// reads it; tokens are cut in every message.
#[test]
fn regression_38_map_checks_the_hhbf_and_no_error_echoes_a_huge_token() {
    let (tmp, gom, fem) = mini_project();
    let hhbf = gom.with_extension("HHBF");
    let out = tmp.path().join("out");
    std::fs::write(&hhbf, "0 1.0\n0 2.0\n").unwrap();
    let (code, text) = map(&fem, &gom, &out, &[]);
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["TwoMat.HHBF:2:1: time 0 does not follow 0"]);
    assert!(!out.exists());
    // A good one travels with the project, byte for byte.
    std::fs::write(&hhbf, "0 1.0\n10 2.0\n").unwrap();
    let (code, text) = map(&fem, &gom, &out, &[]);
    assert_eq!(code, 0, "{text}");
    assert_eq!(
        std::fs::read(out.join("TwoMat.HHBF")).unwrap(),
        b"0 1.0\n10 2.0\n"
    );
    std::fs::remove_dir_all(&out).unwrap();
    // A FIFO in its place: an error at once, not a hang, nothing left out.
    std::fs::remove_file(&hhbf).unwrap();
    let made = Command::new("mkfifo").arg(&hhbf).status();
    if made.is_ok_and(|s| s.success()) {
        let (code, text) = map(&fem, &gom, &out, &[]);
        assert_eq!(code, 2, "{text}");
        assert_contains(&text, &["TwoMat.HHBF: not a regular file"]);
        assert!(!out.exists());
        std::fs::remove_file(&hhbf).unwrap();
    }
    // A 50 MB token in the HHBF and in the FEM table: a few dozen characters.
    let token = "9".repeat(50 << 20) + "x";
    std::fs::write(&hhbf, format!("0 1.0\n1 {token}\n")).unwrap();
    let (code, text) = run_capped(&[&"map", &"--fem", &fem, &"--mpm", &gom, &"--out", &out]);
    assert_eq!(code, 2, "{}", &text[..text.len().min(2000)]);
    assert!(text.len() < 2000, "{} bytes of error", text.len());
    assert_contains(&text, &["TwoMat.HHBF:2:3:", "9999…9999", "characters)"]);
    std::fs::remove_file(&hhbf).unwrap();
    let csv = tmp.path().join("token.csv");
    std::fs::write(&csv, format!("X,Y,PWP\n0,0,{token}\n1,0,0\n0,1,0\n")).unwrap();
    let (code, text) = run_capped(&[&"map", &"--fem", &csv, &"--mpm", &gom, &"--out", &out]);
    assert_eq!(code, 2, "{}", &text[..text.len().min(2000)]);
    assert!(text.len() < 2000, "{} bytes of error", text.len());
    assert!(!out.exists());
}

/// #38 (10): E = −2500 and a porosity of 1 passed `map` and `fos` (exit 0)
/// and reached Anura3D; only `verify` refused them. The GOM reader checks
/// every material once, at the model's load, for every command.
#[test]
fn regression_38_impossible_materials_are_refused_at_load_by_every_command() {
    let (tmp, gom, fem, mapped) = mini_mapped();
    let text = std::fs::read_to_string(&gom).unwrap();
    let line_of =
        |text: &str, keyword: &str| text.lines().position(|l| l.trim() == keyword).unwrap() + 2;
    for (keyword, bad, message) in [
        (
            "$$YOUNG_MODULUS",
            "-2500",
            "YOUNG_MODULUS = -2500 must be > 0",
        ),
        (
            "$$POROSITY_SOLID",
            "1",
            "POROSITY_SOLID = 1 must lie in [0, 1)",
        ),
        (
            "$$FRICTION_ANGLE",
            "95",
            "FRICTION_ANGLE = 95 must lie in [0°, 90°)",
        ),
    ] {
        let at = line_of(&text, keyword);
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        lines[at - 1] = bad.to_string();
        let edited = lines.join("\n") + "\n";
        let expected = format!("TwoMat.GOM:{at}:1: material 1 `clay`: {message}");
        std::fs::write(&gom, &edited).unwrap();
        let out = tmp.path().join("out");
        let (code, output) = map(&fem, &gom, &out, &[]);
        assert_eq!(code, 2, "{keyword}: {output}");
        assert_contains(&output, &[&expected]);
        std::fs::write(&gom, &text).unwrap();
        // The mapped folder's own GOM, for the commands that read a folder.
        let mapped_gom = mapped.join("TwoMat.GOM");
        let original = std::fs::read_to_string(&mapped_gom).unwrap();
        std::fs::write(&mapped_gom, &edited).unwrap();
        for command in ["verify", "run", "fos", "inspect"] {
            let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&command];
            if command == "inspect" {
                args.push(&mapped_gom);
            } else {
                args.extend([&mapped as &dyn AsRef<std::ffi::OsStr>, &"--out", &out]);
            }
            let (code, output) = run(&args);
            assert_eq!(code, 2, "{command} {keyword}: {output}");
            assert_contains(&output, &[message]);
        }
        std::fs::write(&mapped_gom, original).unwrap();
        assert!(!out.exists());
    }
}

/// #38 (11): wrong messages. A VTK cell type 300 was "cell type 0" (cut to
/// a byte); a `types` array of Float64 5.7 was read as TRI3; four distinct
/// points, one at x = 1e308, were "two mesh nodes at the same place".
#[test]
fn regression_38_vtu_messages_say_what_is_wrong() {
    let tmp = tempfile::tempdir().unwrap();
    let types = "type=\"UInt8\" Name=\"types\" format=\"ascii\">5 5<";
    for (name, from, to, expected) in [
        (
            "t300.vtu",
            types,
            "type=\"Int32\" Name=\"types\" format=\"ascii\">5 300<",
            "1 cells: VTK cell type 300 is not read",
        ),
        (
            "t57.vtu",
            types,
            "type=\"Float64\" Name=\"types\" format=\"ascii\">5.7 5<",
            "cell 1: type 5.7 is not an integer",
        ),
        (
            "far.vtu",
            ">0 0 0 1 0 0 1 1 0 0 1 0<",
            ">0 0 0 1e308 0 0 1 1 0 0 1 0<",
            "x = 1e308 lies more than 10^6 times the spread",
        ),
    ] {
        let vtu = crafted_vtu(tmp.path(), name, |t| t.replace(from, to));
        let (code, text) = map_vtu_capped(tmp.path(), &vtu);
        assert_eq!(code, 2, "{name}: {text}");
        assert_contains(&text, &[expected]);
        assert!(!text.contains("at the same place"), "{text}");
    }
}

/// #38 (12): test-1005_3D's CPS switches gravity off at the start
/// (`$$GRAVITY_LOAD off 0.0 1.0`); `map` wrote a gravity stress into it with
/// no word, and the column sprang 13 cm out of balance in `verify`. `map`
/// warns, naming the CPS line, on screen and in the report.
#[test]
fn regression_38_map_warns_when_the_cps_starts_gravity_below_full() {
    let tmp = tempfile::tempdir().unwrap();
    let src = fixture("anura3d/test-1005_3D");
    let fem = test_1005_nodes_csv(tmp.path(), |_| 0.0);
    let cps = std::fs::read_to_string(src.join("test-1005_3D.CPS_001")).unwrap();
    let line = cps
        .lines()
        .position(|l| l.trim() == "$$GRAVITY_LOAD")
        .unwrap()
        + 1;
    let out = tmp.path().join("out");
    let (code, text) = map(&fem, &src, &out, &["--stress", "geostatic"]);
    assert_eq!(code, 0, "{text}");
    let place = format!("test-1005_3D.CPS_001:{line}: `$$GRAVITY_LOAD off");
    assert_contains(
        &text,
        &[
            "warning: the CPS's gravity starts at 0.000·g",
            &place,
            "starts it out of balance",
        ],
    );
    let report = std::fs::read_to_string(out.join("report.json")).unwrap();
    assert!(
        report.contains("the CPS's gravity starts at 0.000·g"),
        "{report}"
    );
    // The mini model's CPS holds full gravity: no such warning.
    let (tmp2, gom, fem) = mini_project();
    let (code, text) = map(&fem, &gom, &tmp2.path().join("o"), &[]);
    assert_eq!(code, 0, "{text}");
    assert!(!text.contains("gravity starts"), "{text}");
}

/// #38 (13): `run` and `verify` named materials by index alone, and called a
/// dry material "drained (pwp frozen)". Each is named as the GOM names it,
/// and a dry one is "dry".
#[test]
fn regression_38_run_names_each_material_and_says_dry() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("slope");
    let (code, text) = run_map(
        &fixture("slope"),
        &fixture("slope/sand-nodes.csv"),
        &out,
        &[],
    );
    assert_eq!(code, 0, "{text}");
    let (code, text) = run(&[&"run", &out, &"--time", &"0.001", &"--snapshots", &""]);
    assert_eq!(code, 0, "{text}");
    assert_contains(
        &text,
        &[
            "water      material 1 `silty_sand`: two-phase coupled (the water flows); material 2 `compacted_clay`: dry",
        ],
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run/run.json")).unwrap()).unwrap();
    assert_eq!(report["formulations"][1], serde_json::json!([2, "dry"]));
    assert_eq!(
        report["material_names"],
        serde_json::json!(["silty_sand", "compacted_clay"])
    );
}

/// Regression (#38), options that were silently dropped, found by fuzzing:
/// - `run --fos` and `run --max-steps` were listed by `run --help` and did
///   nothing (a run lasts `--time`): now clap refuses them;
/// - `inspect MODEL --fem FEM` ignored the model and any `--mps`, and
///   `inspect --fem FEM --mps OUT` wrote nothing with exit 0: now both are
///   refused, naming why, and nothing is written.
#[test]
fn regression_38_no_option_is_dropped_in_silence() {
    let tmp = tempfile::tempdir().unwrap();
    let slope = fixture("slope");
    let fem = fixture("slope/sand-nodes.csv");
    for extra in [["--fos"].as_slice(), &["--max-steps", "200"]] {
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"run", &slope];
        args.extend(extra.iter().map(|a| a as &dyn AsRef<std::ffi::OsStr>));
        let (code, text) = run(&args);
        assert_eq!(code, 2, "{text}");
        assert_contains(&text, &[&format!("unexpected argument '{}'", extra[0])]);
    }
    let out = tmp.path().join("mps.csv");
    let (code, text) = run(&[&"inspect", &slope, &"--fem", &fem, &"--mps", &out]);
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["or --fem FILE, not both"]);
    let (code, text) = run(&[&"inspect", &"--fem", &fem, &"--mps", &out]);
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["the MP table is predicted from an Anura3D model"]);
    let vtu = fixture("fem-vtu/hm2d_quad8_ascii.vtu");
    let (code, text) = run(&[&"inspect", &vtu, &"--mps", &out]);
    assert_eq!(code, 2, "{text}");
    assert_contains(&text, &["is not one"]);
    assert!(!out.exists());
    // The model alone still writes its table.
    let (code, text) = run(&[&"inspect", &slope, &"--mps", &out]);
    assert_eq!(code, 0, "{text}");
    assert!(out.is_file());
}

/// Regression (#38): `demo --out` naming a file, or a folder without
/// `--force`, was refused only after steps 1 to 4 (about half a minute):
/// fuzzing under a 20 s limit saw a hang. Now it is refused before the first
/// step, and nothing is written.
#[test]
fn regression_38_demo_checks_its_output_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("existing.txt");
    std::fs::write(&file, "mine").unwrap();
    let folder = tmp.path().join("folder");
    std::fs::create_dir(&folder).unwrap();
    std::fs::write(folder.join("paper.docx"), "mine").unwrap();
    for (out, force, says) in [
        (&file, false, "exists; pass --force"),
        (&file, true, "exists and is not a folder"),
        (&folder, false, "exists; pass --force"),
        (&folder, true, "a3d-init did not write it"),
    ] {
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"demo", &"--no-fos", &"--out", out];
        if force {
            args.push(&"--force");
        }
        let (code, text) = run(&args);
        assert_eq!(code, 2, "{text}");
        assert_contains(&text, &[says]);
        // Refused before step 1 printed its line.
        assert!(!text.contains("1 inspect"), "{text}");
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 1);
    assert_eq!(std::fs::read_dir(tmp.path()).unwrap().count(), 2);
}

/// Regression (#38): a symlink loop given as an input was reported with its
/// reason twice (`l1: Too many levels of symbolic links (os error 40): Too
/// many levels …`), and `diff` called it "no such file or folder".
#[test]
fn regression_38_a_symlink_loop_is_named_once_with_its_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let (l1, l2) = (tmp.path().join("l1"), tmp.path().join("l2"));
    std::os::unix::fs::symlink(&l2, &l1).unwrap();
    std::os::unix::fs::symlink(&l1, &l2).unwrap();
    let reason = "Too many levels of symbolic links";
    let out = tmp.path().join("out");
    for args in [
        vec![&"inspect" as &dyn AsRef<std::ffi::OsStr>, &l1],
        vec![&"inspect", &"--fem", &l1],
        vec![
            &"map",
            &"--fem",
            &l1,
            &"--mpm",
            &fixture("slope"),
            &"--out",
            &out,
        ],
        vec![&"diff", &l1, &l2],
    ] {
        let (code, text) = run(&args);
        assert_eq!(code, 2, "{text}");
        assert_eq!(text.matches(reason).count(), 1, "{text}");
        assert_contains(&text, &[&l1.display().to_string()]);
    }
}
