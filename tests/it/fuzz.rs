//! Bounded, seeded fuzzing of every reader (#15): GOM (through the typed model
//! and MP placement), CPS, MAPF, FEM CSV, PLY, `.gsz`, mps.csv, CB-Geo's files,
//! FEM VTU in each encoding, `.pvd` series and the MP VTU (#38). Each case is
//! a fixture with one to three structure-aware mutations: truncation, bit flips,
//! duplicated, deleted, swapped or inserted lines, extreme numbers (0, −1, 2⁶²,
//! 10¹⁸, 1e308, NaN, …) anywhere or as the count after a `$$KEYWORD`, numbers
//! nudged by one (wrong counts), and data after the end marker. A reader
//! may accept or refuse a case; it may not panic.
//!
//! CI runs `A3D_FUZZ_CASES` cases per reader (default 400, about 10 s
//! in the debug test profile on two cores). For a release run raise it, e.g.
//! `A3D_FUZZ_CASES=20000 A3D_FUZZ_SEED=7 cargo test --release --test it fuzz::`.
//! A failing case is written to `target/fuzz-failures/` and its reader, seed and
//! case number are printed; every crash found becomes a named test in
//! `tests/it/hardening.rs`.

use crate::common;
use common::{Watchdog, fixture, mini_regions_csv, run_watched};

use std::io::Write;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use a3d_init::formats::cps::CpsDocument;
use a3d_init::formats::fem_csv::{self, CsvOptions};
use a3d_init::formats::gom::GomDocument;
use a3d_init::formats::mps_table::{self, MpDiagnostics};
use a3d_init::formats::{gsz, mapf, ply};
use a3d_init::model::MpState;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn cases() -> usize {
    env_u64("A3D_FUZZ_CASES", 400) as usize
}

fn seed() -> u64 {
    env_u64("A3D_FUZZ_SEED", 15)
}

const EXTREMES: [&str; 16] = [
    "0",
    "-1",
    "1",
    "4611686018427387904",
    "999999999999999999",
    "4294967296",
    "4294967297",
    "1e308",
    "-1e308",
    "1e400",
    "NaN",
    "inf",
    "-0",
    "1e-320",
    "2147483648",
    "",
];

/// Byte ranges of the numeric tokens of `text`.
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        if text[i].is_ascii_digit() {
            let start = if i > 0 && text[i - 1] == b'-' {
                i - 1
            } else {
                i
            };
            while i < text.len()
                && (text[i].is_ascii_alphanumeric() || matches!(text[i], b'.' | b'+' | b'-'))
            {
                i += 1;
            }
            out.push((start, i));
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of the lines of `text` (including the line ending).
fn lines(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &b) in text.iter().enumerate() {
        if b == b'\n' {
            out.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < text.len() {
        out.push((start, text.len()));
    }
    out
}

/// One to three structure-aware mutations of `input`.
fn mutate(rng: &mut ChaCha8Rng, input: &[u8], end_marker: Option<&str>) -> Vec<u8> {
    let mut b = input.to_vec();
    let n_ops = rng.random_range(1..=3);
    for _ in 0..n_ops {
        if b.is_empty() {
            b.extend_from_slice(b"0\n");
        }
        let ls = lines(&b);
        match rng.random_range(0..11) {
            0 => {
                let at = rng.random_range(0..b.len());
                b.truncate(at);
            }
            1 => {
                let at = rng.random_range(0..b.len());
                b[at] ^= 1 << rng.random_range(0..8);
            }
            2 => {
                let (s, e) = ls[rng.random_range(0..ls.len())];
                let line = b[s..e].to_vec();
                b.splice(e..e, line);
            }
            3 => {
                let (s, e) = ls[rng.random_range(0..ls.len())];
                b.drain(s..e);
            }
            4 | 5 => {
                let nums = numbers(&b);
                if nums.is_empty() {
                    continue;
                }
                let (s, e) = nums[rng.random_range(0..nums.len())];
                let replacement = if rng.random_range(0..2) == 0 {
                    EXTREMES[rng.random_range(0..EXTREMES.len())].to_string()
                } else {
                    // A count or value nudged by one.
                    let text = String::from_utf8_lossy(&b[s..e]).into_owned();
                    match text.parse::<i64>() {
                        Ok(v) => (v + if rng.random_range(0..2) == 0 { 1 } else { -1 }).to_string(),
                        Err(_) => "0".to_string(),
                    }
                };
                b.splice(s..e, replacement.into_bytes());
            }
            6 => {
                if ls.len() < 2 {
                    continue;
                }
                let i = rng.random_range(0..ls.len() - 1);
                let (s1, e1) = ls[i];
                let (s2, e2) = ls[i + 1];
                let mut swapped = b[s2..e2].to_vec();
                if !swapped.ends_with(b"\n") {
                    swapped.push(b'\n');
                }
                swapped.extend_from_slice(&b[s1..e1]);
                b.splice(s1..e2, swapped);
            }
            7 => {
                let (s, _) = ls[rng.random_range(0..ls.len())];
                let garbage: &[u8] = match rng.random_range(0..5) {
                    0 => b"$$STARTNODES\n",
                    1 => b"\x00\xff\xfe garbage\n",
                    2 => b"1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25\n",
                    3 => b"\n\n\n",
                    _ => b"$$FINISH\n",
                };
                b.splice(s..s, garbage.iter().copied());
            }
            8 => {
                if let Some(marker) = end_marker {
                    b.extend_from_slice(format!("{marker}\nafter the end\n").as_bytes());
                } else {
                    b.extend_from_slice(b"trailing,data\n");
                }
            }
            9 => {
                // A count: the first token of a line right after a `$$KEYWORD` line.
                let after_keyword: Vec<(usize, usize)> = ls
                    .windows(2)
                    .filter(|w| b[w[0].0..w[0].1].starts_with(b"$$"))
                    .map(|w| w[1])
                    .collect();
                if after_keyword.is_empty() {
                    continue;
                }
                let (s, e) = after_keyword[rng.random_range(0..after_keyword.len())];
                let end = b[s..e]
                    .iter()
                    .position(|c| matches!(c, b' ' | b'\t' | b',' | b'\r' | b'\n'))
                    .map_or(e, |k| s + k);
                let replacement = EXTREMES[rng.random_range(0..EXTREMES.len())];
                b.splice(s..end, replacement.bytes());
            }
            _ => {
                // Cut the file at a line boundary (a clean truncation).
                let (s, _) = ls[rng.random_range(0..ls.len())];
                b.truncate(s);
            }
        }
    }
    b
}

/// What one fuzz case came to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Case {
    /// The reader took the mutated input.
    Read,
    /// The reader refused it with an error.
    Refused,
    /// The case never reached the reader (for example, not UTF-8 text for a
    /// reader of text): it tests nothing.
    Skipped,
}

impl<T, E> From<Result<T, E>> for Case {
    fn from(r: Result<T, E>) -> Case {
        if r.is_ok() { Case::Read } else { Case::Refused }
    }
}

/// Runs `read` on `cases()` mutations of `base`; returns the failures: every
/// panic, and too many skipped cases (more than half: the fuzzer would then
/// test little while passing). The tally is part of every failure message.
fn fuzz(
    reader: &str,
    base: &[u8],
    end_marker: Option<&str>,
    read: impl Fn(&Path, &[u8]) -> Case,
) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    let mut rng = ChaCha8Rng::seed_from_u64(seed() ^ hash(reader));
    let (mut read_n, mut refused_n, mut skipped_n) = (0usize, 0usize, 0usize);
    for case in 0..cases() {
        let bytes = mutate(&mut rng, base, end_marker);
        let path = dir.path().join(format!("case-{case}"));
        let outcome = catch_unwind(AssertUnwindSafe(|| read(&path, &bytes)));
        match outcome {
            Ok(Case::Read) => read_n += 1,
            Ok(Case::Refused) => refused_n += 1,
            Ok(Case::Skipped) => skipped_n += 1,
            Err(_) => {}
        }
        if outcome.is_err() {
            let keep = Path::new(env!("CARGO_TARGET_TMPDIR"))
                .join("..")
                .join("fuzz-failures");
            let _ = std::fs::create_dir_all(&keep);
            let file = keep.join(format!("{reader}-seed{}-case{case}.bin", seed()));
            let _ = std::fs::write(&file, &bytes);
            failures.push(format!(
                "{reader}: seed {} case {case} panicked; input kept in {}",
                seed(),
                file.display()
            ));
        }
    }
    let tally = format!(
        "{reader}: {} cases: {read_n} read, {refused_n} refused, {skipped_n} skipped, {} panicked",
        cases(),
        failures.len()
    );
    if 2 * skipped_n > cases() {
        failures.push(format!("{tally}: more than half the cases were skipped"));
    }
    if read_n == 0 || refused_n == 0 {
        failures.push(format!(
            "{tally}: the mutations must give both accepted and refused inputs"
        ));
    }
    for f in &mut failures {
        if !f.starts_with(&tally) {
            *f = format!("{f} ({tally})");
        }
    }
    failures
}

fn hash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    })
}

fn check(failures: Vec<String>) {
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn read_gom(path: &Path, bytes: &[u8]) -> Case {
    let Ok(text) = String::from_utf8(bytes.to_vec()) else {
        return Case::Skipped;
    };
    let Ok(doc) = GomDocument::parse(path, text.clone()) else {
        return Case::Refused;
    };
    assert_eq!(doc.to_text(), text, "an untouched document round-trips");
    let Ok((model, _)) = doc.model() else {
        return Case::Refused;
    };
    a3d_init::place::place_material_points(&model).into()
}

#[test]
fn fuzz_gom() {
    let base = std::fs::read(fixture("anura3d-mini/TwoMat.GOM")).unwrap();
    check(fuzz("gom", &base, Some("$$FINISH"), read_gom));
}

#[test]
fn fuzz_cps() {
    let base = std::fs::read(fixture("anura3d-mini/TwoMat.CPS_001")).unwrap();
    check(fuzz("cps", &base, Some("$$END"), |path, bytes| {
        let Ok(text) = String::from_utf8(bytes.to_vec()) else {
            return Case::Skipped;
        };
        let Ok(cps) = CpsDocument::parse(path, text) else {
            return Case::Refused;
        };
        let _ = (cps.gravity(), cps.local_damping(), cps.stage());
        let _ = cps.computation_method();
        Case::Read
    }));
}

/// The placed MPs of the mini model with a made-up state, for the MAPF and
/// mps.csv bases.
fn mini_state() -> (Vec<a3d_init::model::MaterialPoint>, Vec<MpState>) {
    let gom = GomDocument::read(&fixture("anura3d-mini/TwoMat.GOM")).unwrap();
    let (model, _) = gom.model().unwrap();
    let points = a3d_init::place::place_material_points(&model).unwrap();
    let states = points
        .iter()
        .map(|p| MpState {
            pwp: -10.0 * (1.0 - p.position[1]),
            total: [-5.0, -20.0 * (1.0 - p.position[1]), -5.0, 0.5, 0.0, 0.0],
            saturation: 1.0,
        })
        .collect();
    (points, states)
}

#[test]
fn fuzz_mapf() {
    let (points, states) = mini_state();
    let mut base = Vec::new();
    mapf::write(&mut base, &points, &states, 2, 0.01).unwrap();
    check(fuzz("mapf", &base, None, |path, bytes| {
        std::fs::write(path, bytes).unwrap();
        mapf::read(path).into()
    }));
}

#[test]
fn fuzz_mps_csv() {
    let (points, states) = mini_state();
    let diagnostics = vec![
        MpDiagnostics {
            neighbours: 4,
            shepard: Some(1.0),
            status: "mapped",
        };
        points.len()
    ];
    let mut base = Vec::new();
    mps_table::write_states(&mut base, &points, &states, &diagnostics).unwrap();
    check(fuzz("mps", &base, None, |path, bytes| {
        std::fs::write(path, bytes).unwrap();
        let _ = mps_table::read_states(path);
        mps_table::read_states_for(path, &points).into()
    }));
}

#[test]
fn fuzz_fem_csv() {
    let base = std::fs::read(fixture("geostudio-csv/k0-slope-hydrostatic.csv")).unwrap();
    check(fuzz("csv", &base, None, |path, bytes| {
        fem_csv::parse_csv(path, bytes, &CsvOptions::default()).into()
    }));
}

/// Mutations of a binary PLY: its ASCII header as text, or bytes of the body.
#[test]
fn fuzz_ply() {
    let base = std::fs::read(fixture(
        "geostudio-gsz-internal/rapid-drawdown/1-initial-steady-state_Mesh.ply",
    ))
    .unwrap();
    check(fuzz("ply", &base, None, |path, bytes| {
        let _ = ply::parse_ply_nodes(path, bytes);
        std::fs::write(path, bytes).unwrap();
        ply::read_ply_mesh(path).into()
    }));
}

/// A small one-analysis archive around the rapid-drawdown node table and mesh.
fn make_gsz(path: &Path, xml: &[u8], csv: &[u8], mesh: &[u8]) {
    let file = std::fs::File::create(path).unwrap();
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default();
    for (name, bytes) in [
        ("project.xml", xml),
        ("Steady/001/node.csv", csv),
        ("Steady/Mesh.ply", mesh),
    ] {
        zip.start_file(name, options).unwrap();
        zip.write_all(bytes).unwrap();
    }
    zip.finish().unwrap();
}

const GSZ_XML: &[u8] = b"<?xml version=\"1.0\"?><GSIData><EngCoords UnitSystem=\"Metric\" /><Analyses Len=\"1\"><Analysis><ID>1</ID><Name>Steady</Name><Kind>SEEP/W</Kind><Method>SteadyState</Method><TimeStep ElapsedTime=\"1\" /></Analysis></Analyses></GSIData>";

#[test]
fn fuzz_gsz() {
    let dir = fixture("geostudio-gsz-internal/rapid-drawdown");
    let csv = std::fs::read(dir.join("1-initial-steady-state_001_node.csv")).unwrap();
    let mesh = std::fs::read(dir.join("1-initial-steady-state_Mesh.ply")).unwrap();
    let read = |path: &Path| -> Case {
        let _ = gsz::read_project(path);
        gsz::read_step(
            path,
            None,
            &a3d_init::formats::fem::StepChoice::Last,
            &CsvOptions::default(),
        )
        .into()
    };
    // The unmutated archive reads.
    let tmp = tempfile::tempdir().unwrap();
    let good = tmp.path().join("good.gsz");
    make_gsz(&good, GSZ_XML, &csv, &mesh);
    gsz::read_step(
        &good,
        None,
        &a3d_init::formats::fem::StepChoice::Last,
        &CsvOptions::default(),
    )
    .unwrap();
    let mut failures = Vec::new();
    failures.extend(fuzz("gsz-csv", &csv, None, |path, bytes| {
        make_gsz(path, GSZ_XML, bytes, &mesh);
        read(path)
    }));
    failures.extend(fuzz("gsz-mesh", &mesh, None, |path, bytes| {
        make_gsz(path, GSZ_XML, &csv, bytes);
        read(path)
    }));
    failures.extend(fuzz("gsz-xml", GSZ_XML, None, |path, bytes| {
        make_gsz(path, bytes, &csv, &mesh);
        read(path)
    }));
    let archive = std::fs::read(&good).unwrap();
    failures.extend(fuzz("gsz-bytes", &archive, None, |path, bytes| {
        std::fs::write(path, bytes).unwrap();
        read(path)
    }));
    check(failures);
}

/// Runs the binary under the hang watchdog: (exit code, stderr + stdout);
/// a hang is exit -9 with the watchdog's reason.
fn run_bin(args: &[&std::ffi::OsStr]) -> (i32, String) {
    run_watched(args, Watchdog::default()).unwrap_or_else(|e| (-9, e))
}

/// The whole pipeline through the real binary: `map` on a mutated GOM, CPS or
/// FEM table of the mini project, then `verify` and `calibrate` on what it wrote.
/// Each run ends with 0, 1 or 2 and no panic or hang, changes no input, and
/// leaves either a complete output folder or none (and no staging folder).
/// `A3D_FUZZ_CLI_CASES` cases (default 100).
#[test]
fn fuzz_cli_pipeline() {
    let n = env_u64("A3D_FUZZ_CLI_CASES", 100) as usize;
    let gom = std::fs::read(fixture("anura3d-mini/TwoMat.GOM")).unwrap();
    let cps = std::fs::read(fixture("anura3d-mini/TwoMat.CPS_001")).unwrap();
    let fem = mini_regions_csv().into_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(seed() ^ hash("cli"));
    let tmp = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for case in 0..n {
        let dir = tmp.path().join(format!("case-{case}"));
        let model = dir.join("model");
        std::fs::create_dir_all(&model).unwrap();
        let which = rng.random_range(0..3);
        let files = [
            (
                model.join("TwoMat.GOM"),
                if which == 0 {
                    mutate(&mut rng, &gom, Some("$$FINISH"))
                } else {
                    gom.clone()
                },
            ),
            (
                model.join("TwoMat.CPS_001"),
                if which == 1 {
                    mutate(&mut rng, &cps, Some("$$END"))
                } else {
                    cps.clone()
                },
            ),
            (
                dir.join("fem.csv"),
                if which == 2 {
                    mutate(&mut rng, &fem, None)
                } else {
                    fem.clone()
                },
            ),
        ];
        for (path, bytes) in &files {
            std::fs::write(path, bytes).unwrap();
        }
        let out = dir.join("out");
        let stress = ["auto", "geostatic", "zero"][rng.random_range(0..3)];
        let (code, text) = run_bin(&[
            "map".as_ref(),
            "--fem".as_ref(),
            files[2].0.as_os_str(),
            "--mpm".as_ref(),
            model.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
            "--stress".as_ref(),
            stress.as_ref(),
        ]);
        let mut problems = Vec::new();
        if !matches!(code, 0 | 2) || text.contains("panicked") || text.contains("internal error") {
            problems.push(format!("map exit {code}: {text}"));
        }
        if code == 0 && !out.join("report.json").exists() {
            problems.push("map succeeded without a complete output".into());
        }
        if code != 0 && out.exists() {
            problems.push("map failed but left an output".into());
        }
        if code == 0 {
            for args in [
                vec![
                    "verify".as_ref(),
                    out.as_os_str(),
                    "--max-steps".as_ref(),
                    "100".as_ref(),
                ],
                vec![
                    "calibrate".as_ref(),
                    "--fem".as_ref(),
                    files[2].0.as_os_str(),
                    "--out".as_ref(),
                    dir.join("cal").as_os_str(),
                ],
            ] {
                let (code, text) = run_bin(&args);
                if !matches!(code, 0..=2)
                    || text.contains("panicked")
                    || text.contains("internal error")
                {
                    problems.push(format!("{:?} exit {code}: {text}", args[0]));
                }
            }
        }
        for (path, bytes) in &files {
            if std::fs::read(path).unwrap() != *bytes {
                problems.push(format!("{} changed", path.display()));
            }
        }
        for d in [&dir, &model] {
            for entry in std::fs::read_dir(d).unwrap() {
                let name = entry.unwrap().file_name().to_string_lossy().into_owned();
                if name.starts_with(".a3d-init") {
                    problems.push(format!("{name} left behind"));
                }
            }
        }
        if !problems.is_empty() {
            failures.push(format!(
                "cli: seed {} case {case} (inputs kept in {}): {}",
                seed(),
                dir.display(),
                problems.join("; ")
            ));
        }
    }
    if !failures.is_empty() {
        let _ = tmp.keep();
    }
    check(failures);
}

/// A CB-Geo run file and its model, read and placed as `map --mpm mpm.json`
/// does, from the files written into `dir` beside `path`.
fn read_cbgeo(path: &Path) -> Case {
    match a3d_init::pipeline::cbgeo::load(path) {
        Ok(project) => {
            // What the writer edits: the run file with its keys set.
            let model = &project.cbgeo.as_ref().unwrap().model;
            let _ = a3d_init::formats::cbgeo::write::run_file(model, "s.txt", Some("p.txt"));
            Case::Read
        }
        Err(_) => Case::Refused,
    }
}

/// The column's files beside the cases, so that a run file finds its mesh.
fn cbgeo_column_beside(case: &Path) {
    let dir = case.parent().unwrap();
    for f in ["mesh.txt", "entity_sets.json"] {
        if !dir.join(f).exists() {
            std::fs::copy(fixture("cbgeo/column").join(f), dir.join(f)).unwrap();
        }
    }
}

#[test]
fn fuzz_cbgeo_run_file() {
    let base = std::fs::read(fixture("cbgeo/column/mpm.json")).unwrap();
    check(fuzz("cbgeo-json", &base, None, |path, bytes| {
        cbgeo_column_beside(path);
        std::fs::write(path, bytes).unwrap();
        read_cbgeo(path)
    }));
}

#[test]
fn fuzz_cbgeo_mesh_and_particles() {
    // The mesh of the column (gauss particles) and the consolidation's
    // particle file (file particles), each mutated under an intact run file.
    for (reader, base, model) in [
        ("cbgeo-mesh", "cbgeo/column/mesh.txt", "cbgeo/column"),
        (
            "cbgeo-particles",
            "cbgeo/consolidation/particle.txt",
            "cbgeo/consolidation",
        ),
    ] {
        let base_bytes = std::fs::read(fixture(base)).unwrap();
        let name = Path::new(base)
            .file_name()
            .unwrap()
            .to_str()
            .unwrap()
            .to_string();
        check(fuzz(reader, &base_bytes, None, |path, bytes| {
            let dir = path.with_extension("d");
            std::fs::create_dir_all(&dir).unwrap();
            for f in std::fs::read_dir(fixture(model)).unwrap() {
                let f = f.unwrap().path();
                std::fs::copy(&f, dir.join(f.file_name().unwrap())).unwrap();
            }
            std::fs::write(dir.join(&name), bytes).unwrap();
            let case = read_cbgeo(&dir.join("mpm.json"));
            std::fs::remove_dir_all(&dir).unwrap();
            case
        }));
    }
}

/// FEM results as VTK XML, in every encoding the reader takes: ASCII, inline
/// base64 with and without zlib, appended raw, float32 from meshio, VTK's LZ4
/// and LZMA blocks, and a 3D hexahedral mesh. Each is read as `map --fem` reads it and
/// described as `inspect` does.
#[test]
fn fuzz_fem_vtu() {
    use a3d_init::formats::fem_vtu::{self, VtuOptions};
    let mut failures = Vec::new();
    for name in [
        "hm2d_quad8_ascii.vtu",
        "hm2d_quad8_binary.vtu",
        "hm2d_quad8_raw.vtu",
        "hm2d_quad8_uncompressed.vtu",
        "hm2d_quad8_meshio_float32.vtu",
        "hm2d_quad8_meshio_lzma.vtu",
        "hm2d_quad8_vtk_lz4.vtu",
        "hm2d_quad8_vtk_lzma.vtu",
        "shear3d_hex8.vtu",
    ] {
        let base = std::fs::read(fixture("fem-vtu").join(name)).unwrap();
        // The unmutated file reads.
        let tmp = tempfile::tempdir().unwrap();
        let good = tmp.path().join(name);
        std::fs::write(&good, &base).unwrap();
        fem_vtu::read_vtu(&good, &VtuOptions::default()).unwrap();
        failures.extend(fuzz(&format!("vtu-{name}"), &base, None, |path, bytes| {
            let path = path.with_extension("vtu");
            std::fs::write(&path, bytes).unwrap();
            let _ = fem_vtu::describe(&path);
            fem_vtu::read_vtu(&path, &VtuOptions::default()).into()
        }));
    }
    check(failures);
}

/// A `.pvd` series over the fixture's steps, each step chosen by number,
/// time and `last`.
#[test]
fn fuzz_pvd() {
    use a3d_init::formats::fem::StepChoice;
    use a3d_init::formats::fem_vtu::{self, VtuOptions};
    let dir = fixture("fem-vtu");
    let base = std::fs::read(dir.join("hm2d_quad4_series.pvd")).unwrap();
    check(fuzz("pvd", &base, None, |path, bytes| {
        let beside = path.parent().unwrap();
        for t in ["0", "0.5", "1", "2", "5"] {
            let name = format!("hm2d_quad4_series_t_{t}.vtu");
            if !beside.join(&name).exists() {
                std::fs::copy(dir.join(&name), beside.join(&name)).unwrap();
            }
        }
        let path = path.with_extension("pvd");
        std::fs::write(&path, bytes).unwrap();
        let options = VtuOptions::default();
        let _ = fem_vtu::read(&path, &options, &StepChoice::Number(2));
        let _ = fem_vtu::read(&path, &options, &StepChoice::Time(0.5));
        fem_vtu::read(&path, &options, &StepChoice::Last).into()
    }));
}

/// The material point VTU that `map` writes (read back by tests and tools).
#[test]
fn fuzz_mp_vtu() {
    use a3d_init::formats::vtu;
    let (mps, states) = mini_state();
    let arrays = [
        vtu::ArrayFn::scalar("pwp", |i| states[i].pwp),
        vtu::ArrayFn {
            name: "total_stress".into(),
            components: 6,
            fill: Box::new(|i, out: &mut [f64]| out.copy_from_slice(&states[i].total)),
        },
    ];
    let mut base = Vec::new();
    vtu::write_points_with(&mut base, mps.len(), &|i| mps[i].position, &arrays).unwrap();
    vtu::parse(Path::new("mps.vtu"), &base).unwrap();
    check(fuzz("mp-vtu", &base, None, |path, bytes| {
        vtu::parse(path, bytes).into()
    }));
}
