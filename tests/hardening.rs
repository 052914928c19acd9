//! Issue #15, one test per class, through the real binary: an output never
//! deletes or overwrites an input; `--force` replaces a folder whole; failed
//! runs leave nothing behind; non-regular files, oversized counts, zip bombs,
//! inconsistent counts, data after the end marker, non-finite values and garbage
//! options end as exit 2 with a positioned message, never a panic or a hang.
//! Every run is killed after 30 s, so a hang fails instead of blocking CI.
//! At the foot, the input defects of #24 and #30, one test per bug.

mod common;
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
            !name.starts_with(".a3d-init"),
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
    let source = a3d_init::pipeline::start::StateSource::Table {
        model: gom.clone(),
        state: state.clone(),
    };
    let e = a3d_init::pipeline::fos::fos(
        &source,
        &Default::default(),
        a3d_init::pipeline::output::Destination::new(Some(&state_dir), true),
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
    std::fs::create_dir(&out).unwrap();
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
    let mut csv = String::from("X,Y,Z,PWP\n");
    for l in &lines[start..start + 207] {
        let v: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
        csv.push_str(&format!("{},{},{},{}\n", v[0], v[1], v[2], -10.0 * v[2]));
    }
    let fem = tmp.path().join("fem.csv");
    std::fs::write(&fem, csv).unwrap();
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
