//! Real projects as users have them (#14): one test per class of real file, on
//! our own fixtures in `fixtures/real-projects/` (see its README), through the
//! real binary. GiD folders, node tables listing a subset of the mesh, misnamed
//! project files, FEM files that do not reach the model, implausible pore
//! pressures, and the small CLI fixes (`inspect --fem` extent, unreadable `.gsz`,
//! `diff` with a missing path).

use crate::common;
use common::*;

use std::io::Write;
use std::path::{Path, PathBuf};

use a3d_testkit::generate;

fn real(rel: &str) -> PathBuf {
    fixture("real-projects").join(rel)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The fixture GOMs: a 10 × 5 m saturated block (1 m TRI3 cells, 3 MPs each)
/// at `origin`, with header `version`.
fn block_gom(version: &str, origin: (f64, f64)) -> String {
    let mesh = generate::structured_tri_mesh(origin.0, origin.1, 10.0, 5.0, 10, 5);
    gom_text(mesh, &soil_spec(0.5, 1e4, 1e-10), version)
}

/// `a3d-init inspect <path>`, which must exit 0: its stdout.
#[track_caller]
fn inspect_ok(path: &Path) -> String {
    let (code, stdout, stderr) = run_split(&["inspect", s(path)]);
    assert_eq!(code, 0, "{stderr}");
    stdout
}

/// (fixture path, version, origin) of every generated GOM.
const GOMS: &[(&str, &str, (f64, f64))] = &[
    ("Block.gid/Block-2.dat", "2024", (0.0, 0.0)),
    ("Stage.gid/Stage-2.dat", "2025", (0.0, 0.0)),
    ("misnamed/X.GOM.GOM_stage0", "2025", (0.0, 0.0)),
    ("bare/Bare.GOM", "2024", (0.0, 0.0)),
    ("offset/Site.GOM", "2023", (1000.0, 200.0)),
];

/// The committed GOMs are what the generator writes (`A3D_BLESS=1` rewrites them).
#[test]
fn fixture_goms_are_the_generator_output() {
    for (rel, version, origin) in GOMS {
        let text = block_gom(version, *origin);
        let path = real(rel);
        if std::env::var_os("A3D_BLESS").is_some() {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &text).unwrap();
        }
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            text,
            "{rel}: run with A3D_BLESS=1"
        );
    }
}

fn lines(text: &str) -> Vec<&str> {
    text.split_inclusive('\n').collect()
}

/// Class 1: a GiD project folder. `-1.dat` is the CPS; the output holds the
/// model's own CPS with only the two switches changed, under its own header and
/// the names Anura3D looks for.
#[test]
fn gid_project_folder_maps_with_its_own_cps() {
    let tmp = tempfile::tempdir().unwrap();
    let gid = real("Block.gid");
    let stdout = inspect_ok(&gid);
    assert_contains(&stdout, &["Block-1.dat"]);
    assert_contains(
        &stdout,
        &["names      map writes Block.GOM, Block.CPS_001 (CPS header 2024"],
    );
    assert!(
        stdout.contains("CPS Anura3D_2024") || stdout.contains("CPS 2024"),
        "{stdout}"
    );
    let out = tmp.path().join("out");
    let (code, _, stderr) = run_map_split(&gid, &real("hydrostatic.csv"), &out, &[]);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("defaults are used"), "{stderr}");
    let mut files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert!(files.contains(&"Block.GOM".to_string()), "{files:?}");
    assert!(files.contains(&"Block.CPS_001".to_string()), "{files:?}");
    assert!(files.contains(&"Block.MAPF".to_string()), "{files:?}");
    assert!(!files.iter().any(|f| f.ends_with(".dat")), "{files:?}");
    assert_eq!(
        std::fs::read(out.join("Block.GOM")).unwrap(),
        std::fs::read(gid.join("Block-2.dat")).unwrap()
    );
    let own = std::fs::read_to_string(gid.join("Block-1.dat")).unwrap();
    let written = std::fs::read_to_string(out.join("Block.CPS_001")).unwrap();
    assert!(written.starts_with("### Anura3D_2024 ###\r\n"));
    let (a, b) = (lines(&own), lines(&written));
    assert_eq!(a.len(), b.len());
    let changed: Vec<(&str, &str)> = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x != y)
        .map(|(x, y)| (*x, *y))
        .collect();
    assert_eq!(changed, vec![("1\r\n", "0\r\n"), ("0\r\n", "1\r\n")]);
    // The changed lines are the values of the two switches.
    let k0 = a
        .iter()
        .position(|l| l.starts_with("$$K0_PROCEDURE"))
        .unwrap();
    assert_eq!(b[k0 + 1], "0\r\n");
    let mapf = a
        .iter()
        .position(|l| l.starts_with("$$MP_STRESS_INITIALIZATION_FROMFILE"))
        .unwrap();
    assert_eq!(b[mapf + 1], "1\r\n");
}

/// Class 1, 2025: staged names, and the OPD that GiD writes into `name.A3D/`.
#[test]
fn gid_project_folder_2025_uses_staged_names() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let (code, _, stderr) = run_map_split(
        &real("Stage.gid/Stage-2.dat"),
        &real("hydrostatic.csv"),
        &out,
        &[],
    );
    assert_eq!(code, 0, "{stderr}");
    for f in [
        "Stage.GOM_stage0",
        "Stage.CPS_001",
        "Stage.OPD_stage0",
        "Stage.MAPF",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    assert_eq!(
        std::fs::read(out.join("Stage.OPD_stage0")).unwrap(),
        std::fs::read(real("Stage.A3D/Stage.OPD_stage0")).unwrap()
    );
    let cps = std::fs::read_to_string(out.join("Stage.CPS_001")).unwrap();
    assert!(cps.starts_with("### Anura3D_2025 ###\r\n$$STAGE\r\n0\r\n"));
}

/// Class 1, no CPS at all: `map` refuses unless `--generate-cps`, which writes a
/// complete CPS under the model's own header.
#[test]
fn no_cps_refuses_map_unless_a_cps_is_generated() {
    let tmp = tempfile::tempdir().unwrap();
    let gom = real("bare/Bare.GOM");
    let fem = real("hydrostatic.csv");
    let out = tmp.path().join("out");
    let (code, _, stderr) =
        run_split(&["map", "--mpm", s(&gom), "--fem", s(&fem), "--out", s(&out)]);
    assert_eq!(code, 2, "{stderr}");
    assert_contains(&stderr, &["Bare.GOM: no CPS"]);
    assert_contains(&stderr, &["--generate-cps"]);
    assert!(!out.exists());
    let (code, _, stderr) = run_map_split(&gom, &fem, &out, &["--generate-cps"]);
    assert_eq!(code, 0, "{stderr}");
    let cps = std::fs::read_to_string(out.join("Bare.CPS_001")).unwrap();
    assert!(cps.starts_with("### Anura3D_2024 ###\n"), "{cps}");
    let keywords: Vec<&str> = cps.lines().filter(|l| l.starts_with("$$")).collect();
    assert_eq!(
        keywords,
        a3d_init::formats::cps_template::keywords("2024")
            .into_iter()
            .chain(["$$END"])
            .collect::<Vec<_>>()
    );
    assert!(keywords.len() > 100, "{}", keywords.len());
    assert!(cps.contains("$$K0_PROCEDURE\n0\n"));
    assert!(cps.contains("$$MP_STRESS_INITIALIZATION_FROMFILE\n1\n"));
    assert!(out.join("Bare.GOM").exists());
}

/// The generated CPS holds every keyword of the sample CPS files, among them the
/// kernel-written `K0_phreaticSurf_File.CPS_002`.
#[test]
fn generated_cps_covers_the_sample_cps_files() {
    use a3d_init::formats::cps::CpsDocument;
    use a3d_init::formats::cps_template::generate_cps;
    let mut checked = 0;
    for dir in std::fs::read_dir(fixture("anura3d")).unwrap() {
        let dir = dir.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        for f in std::fs::read_dir(&dir).unwrap() {
            let f = f.unwrap().path();
            if !f.to_string_lossy().contains(".CPS_") {
                continue;
            }
            let sample = CpsDocument::read(&f).unwrap();
            let generated = generate_cps(sample.version(), 2, 1);
            let generated = CpsDocument::parse(Path::new("g.CPS_001"), generated).unwrap();
            for block in sample.document().blocks() {
                let k = &block.keyword;
                if k.starts_with("$$") && k != "$$END" {
                    assert!(
                        generated.get(k).is_some(),
                        "{}: {k} is not in the generated CPS",
                        f.display()
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 300, "{checked}");
}

/// Class 3: `X.GOM.GOM_stage0` beside `X.CPS_001` is project X.
#[test]
fn misnamed_project_file_is_reported_and_the_obvious_project_used() {
    let tmp = tempfile::tempdir().unwrap();
    let gom = real("misnamed/X.GOM.GOM_stage0");
    let stdout = inspect_ok(&gom);
    assert!(stdout.starts_with("project    X\n"), "{stdout}");
    assert_contains(&stdout, &["X.CPS_001"]);
    assert_contains(
        &stdout,
        &[
            "Anura3D will look for X.GOM_stage0",
            "the run would fail with the files as named",
        ],
    );
    // The folder finds the same project.
    let (code, stdout, _) = run_split(&["inspect", s(&real("misnamed"))]);
    assert_eq!(code, 0);
    assert!(stdout.starts_with("project    X\n"), "{stdout}");
    let out = tmp.path().join("out");
    let (code, _, stderr) = run_map_split(&gom, &real("hydrostatic.csv"), &out, &[]);
    assert_eq!(code, 0, "{stderr}");
    assert_contains(&stderr, &["will look for X.GOM_stage0"]);
    for f in ["X.GOM_stage0", "X.CPS_001", "X.OPD_stage0", "X.MAPF"] {
        assert!(out.join(f).exists(), "{f} missing");
    }
}

fn rd_mesh() -> PathBuf {
    fixture("geostudio-gsz-internal/rapid-drawdown/1-initial-steady-state_Mesh.ply")
}

/// A one-analysis `.gsz` holding `node` as step 001 and the rapid-drawdown mesh.
fn make_gsz(path: &Path, node: &[u8], mesh: &[u8]) {
    let file = std::fs::File::create(path).unwrap();
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default();
    let xml = "<?xml version=\"1.0\"?><GSIData><EngCoords UnitSystem=\"Metric\" /><Analyses Len=\"1\"><Analysis><ID>1</ID><Name>SEEP/W Region</Name><Kind>SEEP/W</Kind><Method>SteadyState</Method></Analysis></Analyses></GSIData>";
    for (name, bytes) in [
        ("project.xml", xml.as_bytes()),
        ("SEEP&3W Region/001/node.csv", node),
        ("SEEP&3W Region/Mesh.ply", mesh),
    ] {
        zip.start_file(name, options).unwrap();
        zip.write_all(bytes).unwrap();
    }
    zip.finish().unwrap();
}

/// Class 2: GeoStudio node tables that list a subset of the mesh.
#[test]
fn node_table_listing_a_subset_of_the_mesh_is_joined_by_id() {
    let tmp = tempfile::tempdir().unwrap();
    let node = real("subset/node.csv");
    let mesh = rd_mesh();
    let (code, stdout, stderr) = run_split(&["inspect", "--fem", s(&node), "--fem-mesh", s(&mesh)]);
    assert_eq!(code, 0, "{stderr}");
    assert_contains(&stdout, &["nodes      492 (2D)"]);
    assert_contains(&stdout, &["lists 492 of the 553 mesh nodes"]);
    let cal = tmp.path().join("cal");
    let (code, _, stderr) = run_split(&[
        "calibrate",
        "--fem",
        s(&node),
        "--fem-mesh",
        s(&mesh),
        "--out",
        s(&cal),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let out = tmp.path().join("out");
    let gom = fixture("anura3d-rapid-drawdown/rapid_drawdown.GOM");
    let (code, _, stderr) = run_map_split(
        &gom,
        &node,
        &out,
        &[
            "--fem-mesh",
            s(&mesh),
            "--generate-cps",
            "--outside",
            "nearest",
            "--stress",
            "geostatic",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let report = std::fs::read_to_string(out.join("report.json")).unwrap();
    assert!(report.contains("lists 492 of the 553 mesh nodes"));
    // The same table inside a .gsz.
    let gsz = tmp.path().join("region.gsz");
    make_gsz(
        &gsz,
        &std::fs::read(&node).unwrap(),
        &std::fs::read(&mesh).unwrap(),
    );
    let stdout = inspect_ok(&gsz);
    assert_contains(&stdout, &["492 nodes (2D)"]);
    let out2 = tmp.path().join("out2");
    let (code, _, stderr) = run_map_split(
        &gom,
        &gsz,
        &out2,
        &[
            "--generate-cps",
            "--outside",
            "nearest",
            "--stress",
            "geostatic",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    // Informational notes are not warnings.
    assert!(
        !stderr
            .lines()
            .any(|l| l.contains("warning: ") && l.contains("unit system")),
        "{stderr}"
    );
    // Ids outside the mesh and duplicates are refused at their line.
    for (file, message) in [
        (
            "subset/node-id-outside-mesh.csv",
            "node-id-outside-mesh.csv:12:1: node 554 is not in the mesh",
        ),
        (
            "subset/node-duplicate-id.csv",
            "node-duplicate-id.csv:12:1: duplicate node id 4 (also on line 5)",
        ),
    ] {
        let (code, _, stderr) =
            run_split(&["inspect", "--fem", s(&real(file)), "--fem-mesh", s(&mesh)]);
        assert_eq!(code, 2, "{stderr}");
        assert!(stderr.contains(message), "{stderr}");
        let bad = tmp.path().join("bad.gsz");
        make_gsz(
            &bad,
            &std::fs::read(real(file)).unwrap(),
            &std::fs::read(&mesh).unwrap(),
        );
        let (code, _, stderr) = run_split(&["inspect", s(&bad)]);
        assert_eq!(code, 2, "{stderr}");
        let (code, _, stderr) =
            run_map_split(&gom, &bad, &tmp.path().join("never"), &["--generate-cps"]);
        assert_eq!(code, 2, "{stderr}");
        assert_contains(&stderr, &["node.csv:12:1: "]);
    }
}

/// Class 4: a FEM file that does not reach the model: the file, both extents and
/// the unit factor are named; with the unit given, the same file maps.
#[test]
fn fem_in_feet_is_named_with_both_extents_and_the_factor() {
    let tmp = tempfile::tempdir().unwrap();
    let gom = real("offset/Site.GOM");
    let fem = real("site-ft.csv");
    let (code, _, stderr) = run_map_split(&gom, &fem, &tmp.path().join("a"), &[]);
    assert_eq!(code, 2, "{stderr}");
    for part in [
        "site-ft.csv: the FEM nodes do not reach the model",
        "FEM nodes: x 3280.840 .. 3313.648, y 656.168 .. 672.572 m",
        "model mesh: x 1000.000 .. 1010.000, y 200.000 .. 205.000 m",
        "the FEM looks 3.28× larger than the model: is it in ft? give the FEM units (--fem-units) length=ft",
    ] {
        assert!(stderr.contains(part), "{part}: {stderr}");
    }
    let (code, _, stderr) = run_map_split(
        &gom,
        &fem,
        &tmp.path().join("b"),
        &["--fem-units", "length=ft"],
    );
    assert_eq!(code, 0, "{stderr}");
    let (code, _, stderr) = run_split(&[
        "calibrate",
        "--fem",
        s(&fem),
        "--fem-units",
        "length=ft",
        "--out",
        s(&tmp.path().join("cal")),
    ]);
    assert_eq!(code, 0, "{stderr}");
}

/// Class 4, partly covered: the mapper's refusal also names the file and both extents.
#[test]
fn fem_covering_part_of_the_model_names_file_and_extents() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(real("site-m.csv")).unwrap();
    let part: String = text
        .lines()
        .filter(|l| {
            l.starts_with('X') || l.split(',').next().unwrap().parse::<f64>().unwrap() <= 1007.0
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let fem = tmp.path().join("part.csv");
    std::fs::write(&fem, part).unwrap();
    let (code, _, stderr) =
        run_map_split(&real("offset/Site.GOM"), &fem, &tmp.path().join("out"), &[]);
    assert_eq!(code, 2, "{stderr}");
    assert_contains(&stderr, &["part.csv: "]);
    assert_contains(&stderr, &["have no FEM node inside the kernel support"]);
    assert_contains(
        &stderr,
        &[
            "FEM nodes: x 1000.000 .. 1007.000, y 200.000 .. 205.000 m; model mesh: x 1000.000 .. 1010.000",
        ],
    );
}

/// Class 5: plausibility warnings (psf read as kPa, a flipped sign), none on the
/// valid file; each warning names its path once.
#[test]
fn implausible_pore_pressures_are_warned_not_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let gid = real("Block.gid");
    let map = |fem: &str, out: &str| run_map_split(&gid, &real(fem), &tmp.path().join(out), &[]);
    let (code, _, stderr) = map("hydrostatic.csv", "ok");
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    let (code, _, stderr) = map("hydrostatic-psf.csv", "psf");
    assert_eq!(code, 0, "{stderr}");
    assert_contains(
        &stderr,
        &["exceeds 1.5× the total vertical stress", "Worst: MP "],
    );
    let (code, _, stderr) = map("hydrostatic-flipped.csv", "flipped");
    assert_eq!(code, 0, "{stderr}");
    assert_contains(&stderr, &["above the model's top"]);
    for line in stderr.lines().filter(|l| l.contains("warning")) {
        for path in [real("hydrostatic-flipped.csv"), gid.clone()] {
            assert!(line.matches(s(&path)).count() <= 1, "{line}");
        }
    }
}

#[test]
fn inspect_fem_prints_the_coordinate_range() {
    let (code, stdout, stderr) = run_split(&["inspect", "--fem", s(&real("site-m.csv"))]);
    assert_eq!(code, 0, "{stderr}");
    assert_contains(
        &stdout,
        &["extent     x 1000.000 .. 1010.000, y 200.000 .. 205.000 m"],
    );
}

#[test]
fn inspect_on_an_unreadable_gsz_exits_2() {
    let tmp = tempfile::tempdir().unwrap();
    let mesh = std::fs::read(rd_mesh()).unwrap();
    let node = std::fs::read(real("subset/node.csv")).unwrap();
    let gsz = tmp.path().join("truncated.gsz");
    // The header and 10 of the 553 nodes.
    let header_end = mesh.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    make_gsz(&gsz, &node, &mesh[..header_end + 4 + 240]);
    let (code, stdout, stderr) = run_split(&["inspect", s(&gsz)]);
    assert_eq!(code, 2, "{stdout}\n{stderr}");
    assert_contains(&stdout, &["unreadable"]);
    assert_contains(&stderr, &["truncated PLY"]);
    let (code, _, _) = run_split(&["inspect", "--json", s(&gsz)]);
    assert_eq!(code, 2);
}

#[test]
fn diff_with_a_missing_path_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("nope");
    for args in [
        [s(&real("Block.gid")), s(&missing)],
        [s(&missing), s(&real("hydrostatic.csv"))],
    ] {
        let (code, _, stderr) = run_split(&["diff", args[0], args[1]]);
        assert_eq!(code, 2, "{stderr}");
        assert!(
            stderr.contains(&format!("{}: no such file or folder", missing.display())),
            "{stderr}"
        );
    }
}
