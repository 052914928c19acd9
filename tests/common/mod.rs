//! Helpers shared by the integration tests: fixture paths and the real binary.
//! Each test file includes this module with `mod common;`; not every file uses
//! every helper.
#![allow(dead_code)]

pub mod column;
pub mod malformed;
pub mod random;

use std::path::{Path, PathBuf};
use std::process::Command;

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::model::Mesh;
use a3d_init::model::generate::{self, MaterialSpec};

/// `fixtures/<rel>` of this repository.
pub fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(rel)
}

/// The `a3d-init` binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_a3d-init"))
}

/// Runs the binary: (exit code, stdout, stderr).
pub fn run_split(args: &[&str]) -> (i32, String, String) {
    let out = bin().args(args).output().expect("the binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs the binary: (exit code, stdout followed by stderr).
pub fn run(args: &[&str]) -> (i32, String) {
    let (code, stdout, stderr) = run_split(args);
    (code, stdout + &stderr)
}

/// Runs the binary and checks that it exits 0: stdout followed by stderr.
#[track_caller]
pub fn run_ok(args: &[&str]) -> String {
    let (code, text) = run(args);
    assert_eq!(code, 0, "{text}");
    text
}

/// `a3d-init verify <out>`, which must exit 0: stdout followed by stderr.
#[track_caller]
pub fn verify_ok(out: &Path) -> String {
    run_ok(&["verify", out.to_str().unwrap()])
}

/// `a3d-init map --mpm <mpm> --fem <fem> --out <out> <extra…>`: (exit code,
/// stdout, stderr).
pub fn run_map_split(mpm: &Path, fem: &Path, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let mut args = vec![
        "map",
        "--mpm",
        mpm.to_str().unwrap(),
        "--fem",
        fem.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    run_split(&args)
}

/// [`run_map_split`] with stdout followed by stderr.
pub fn run_map(mpm: &Path, fem: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let (code, stdout, stderr) = run_map_split(mpm, fem, out, extra);
    (code, stdout + &stderr)
}

/// An elastic, saturated soil without Mohr–Coulomb or retention: "soil",
/// n = 0.4, ρs = 2650, ρw = 1000 kg/m³, ν = 0.3.
pub fn soil_spec(k0: f64, young_modulus: f64, permeability: f64) -> MaterialSpec {
    MaterialSpec {
        name: "soil".into(),
        porosity: 0.4,
        density_solid: 2650.0,
        density_liquid: Some(1000.0),
        k0,
        young_modulus,
        poisson_ratio: 0.3,
        mohr_coulomb: None,
        retention: None,
        permeability,
    }
}

/// The GOM text (header `version`) of `mesh` in one material `spec`, 3 MPs per
/// element.
pub fn gom_text(mesh: Mesh, spec: &MaterialSpec, version: &str) -> String {
    model_to_text(&generate::single_material_model(mesh, spec, 3), version)
}

/// Writes [`gom_text`] (header 2023) to `path`.
pub fn write_gom(path: &Path, mesh: Mesh, spec: &MaterialSpec) {
    std::fs::write(path, gom_text(mesh, spec, "2023")).unwrap();
}

/// A FEM CSV (`header`, then x, y, pwp) of hydrostatic pwp `gamma_w·(top − y)`
/// at the nodes of a 0.5 m grid, `nx + 1` by `ny + 1` from the origin.
pub fn hydrostatic_grid_csv(header: &str, nx: usize, ny: usize, gamma_w: f64, top: f64) -> String {
    let mut csv = format!("{header}\n");
    for j in 0..=ny {
        for i in 0..=nx {
            let (x, y) = (i as f64 * 0.5, j as f64 * 0.5);
            csv.push_str(&format!("{x},{y},{}\n", gamma_w * (top - y)));
        }
    }
    csv
}

/// Asserts that `text` contains every one of `parts`, showing `text` otherwise.
#[track_caller]
pub fn assert_contains(text: &str, parts: &[&str]) {
    for part in parts {
        assert!(text.contains(part), "expected `{part}` in:\n{text}");
    }
}

/// Runs the binary with stdin closed, killing it after `limit`: (exit code,
/// stderr followed by stdout), or `None` if it had to be killed.
pub fn run_within(args: &[&std::ffi::OsStr], limit: std::time::Duration) -> Option<(i32, String)> {
    use std::process::Stdio;
    let mut child = bin()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let out = child.wait_with_output().unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&out.stdout)
    );
    Some((out.status.code().unwrap_or(-1), text))
}

/// The FEM table of the mini two-material model (`fixtures/anura3d-mini`): a
/// 0.25 m grid over 2 × 1 m with hydrostatic pwp and a region column (clay left
/// of x = 1, sand from there).
pub fn mini_regions_csv() -> String {
    let mut csv = String::from("X (m),Y (m),PWP (kPa),Material\n");
    for j in 0..5 {
        for i in 0..9 {
            let (x, y) = (i as f64 * 0.25, j as f64 * 0.25);
            let region = if x < 1.0 { "clay" } else { "sand" };
            csv.push_str(&format!("{x},{y},{},{region}\n", 9.81 * (1.0 - y)));
        }
    }
    csv
}
