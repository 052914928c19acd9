//! Helpers shared by the integration tests: fixture paths and the real binary.
//! Each test file includes this module with `mod common;`; not every file uses
//! every helper.
#![allow(dead_code)]

pub mod column;
pub mod kernel_run;
pub mod malformed;
pub mod random;

use std::path::{Path, PathBuf};
use std::process::Command;

use a3d_init::formats::gom::write::model_to_text;
use a3d_init::model::Mesh;
use a3d_testkit::generate::{self, MaterialSpec};

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

/// One `a3d-init demo --no-fos` run for the tests that read its output (a
/// minute of the test build's time each, four times over before): its
/// folder, which no test writes into, and what it printed (stdout, then
/// stderr). It runs on first use, in `CARGO_TARGET_TMPDIR`, in a folder named
/// after this process; folders that earlier test processes left are removed.
pub fn demo_no_fos() -> &'static (PathBuf, String) {
    static DEMO: std::sync::OnceLock<(PathBuf, String)> = std::sync::OnceLock::new();
    DEMO.get_or_init(|| {
        let root = Path::new(env!("CARGO_TARGET_TMPDIR"));
        let prefix = "demo-no-fos-";
        // Where /proc tells which processes live, a folder whose process has
        // ended is removed; a running one's is left alone.
        let proc = Path::new("/proc/self").exists();
        for entry in std::fs::read_dir(root).into_iter().flatten().flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if let Some(pid) = name.strip_prefix(prefix)
                && proc
                && !Path::new("/proc").join(pid).exists()
            {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
        let out = root.join(format!("{prefix}{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let text = run_ok(&["demo", "--no-fos", "--out", out.to_str().unwrap()]);
        (out, text)
    })
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

/// CPU seconds (user + system) a process has used so far, from
/// `/proc/<pid>/stat`; `None` where there is no such file (not Linux, or the
/// process is gone).
fn cpu_seconds(pid: u32) -> Option<f64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name, which is in parentheses and may hold spaces.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// A hang watchdog for the binary: it is killed when it has used no CPU time
/// for `idle` (blocked: on a FIFO, a lock, stdin), or after `wall` in all
/// (a runaway loop). A slow or loaded machine still advances the CPU time, so
/// slowness alone never trips the first limit; the second is generous.
#[derive(Clone, Copy, Debug)]
pub struct Watchdog {
    pub idle: std::time::Duration,
    pub wall: std::time::Duration,
}

impl Default for Watchdog {
    fn default() -> Self {
        Watchdog {
            idle: std::time::Duration::from_secs(60),
            wall: std::time::Duration::from_secs(20 * 60),
        }
    }
}

/// Runs the binary with stdin closed under the [`Watchdog`]: (exit code,
/// stderr followed by stdout), or `Err` saying why it was killed.
pub fn run_watched(args: &[&std::ffi::OsStr], dog: Watchdog) -> Result<(i32, String), String> {
    use std::process::Stdio;
    use std::time::{Duration, Instant};
    let mut child = bin()
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Drain the pipes on threads, so a chatty child never blocks on a full pipe.
    let mut stdout = child.stdout.take().unwrap();
    let mut stderr = child.stderr.take().unwrap();
    let out_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = std::io::Read::read_to_end(&mut stdout, &mut v);
        v
    });
    let err_reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = std::io::Read::read_to_end(&mut stderr, &mut v);
        v
    });
    let start = Instant::now();
    let (mut last_cpu, mut last_progress) = (-1.0f64, Instant::now());
    let killed = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Ok(status);
        }
        let cpu = cpu_seconds(child.id()).unwrap_or(last_cpu);
        if cpu > last_cpu {
            (last_cpu, last_progress) = (cpu, Instant::now());
        }
        let why = if last_progress.elapsed() > dog.idle {
            Some(format!("used no CPU time for {:?} (blocked)", dog.idle))
        } else if start.elapsed() > dog.wall {
            Some(format!("still running after {:?}", dog.wall))
        } else {
            None
        };
        if let Some(why) = why {
            let _ = child.kill();
            let _ = child.wait();
            break Err(why);
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let (out, err) = (out_reader.join().unwrap(), err_reader.join().unwrap());
    let status = killed.map_err(|why| format!("a3d-init {args:?} hung: {why}"))?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&err),
        String::from_utf8_lossy(&out)
    );
    Ok((status.code().unwrap_or(-1), text))
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

/// Where the real Anura3D kernel (the oracle) is: `$ANURA3D_KERNEL`, else
/// `target/anura3d-kernel/Anura3D.out` (built by `.ci/run`).
pub fn anura3d_kernel() -> Option<PathBuf> {
    let path = std::env::var_os("ANURA3D_KERNEL")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("target/anura3d-kernel/Anura3D.out")
        });
    path.is_file().then_some(path)
}

/// The kernel for the test `name`, or `None` after saying that it skips: CI
/// sets `A3D_INIT_REQUIRE_KERNEL`, and there a missing kernel fails instead.
#[allow(clippy::print_stderr)] // the skip must be visible in the test output
pub fn anura3d_kernel_or_skip(name: &str) -> Option<PathBuf> {
    let kernel = anura3d_kernel();
    if kernel.is_none() {
        assert!(
            std::env::var_os("A3D_INIT_REQUIRE_KERNEL").is_none(),
            "A3D_INIT_REQUIRE_KERNEL is set but there is no Anura3D kernel at target/anura3d-kernel/Anura3D.out (or $ANURA3D_KERNEL)"
        );
        eprintln!(
            "SKIPPED {name}: no Anura3D kernel (set ANURA3D_KERNEL or run .ci/run, which builds it with gfortran)"
        );
    }
    kernel
}

/// The row of docs/slope-stability.md's *Four measures of one slope* table
/// that starts with `| <slope>`, checked against `fos.json` of a
/// `fos --method srm` run: limit equilibrium, its Davis variant, strength
/// reduction and the equilibrium solve's factor, as the table prints them
/// (3 decimals). A figure that drifts fails the caller (#39).
pub fn assert_four_measures_quoted(slope: &str, fos_json: &Path) {
    let docs = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/slope-stability.md"),
    )
    .unwrap();
    let row = docs
        .lines()
        .find(|l| l.starts_with(&format!("| {slope}")))
        .unwrap_or_else(|| panic!("docs/slope-stability.md has no row `| {slope}`"));
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    let fos: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fos_json).unwrap()).unwrap();
    let c = &fos["comparison"];
    let measured = [
        c["limit_equilibrium"].as_f64(),
        c["limit_equilibrium_davis"].as_f64(),
        fos["factor"].as_f64(),
        c["equilibrium_solve"]["holds"].as_f64(),
    ];
    for (k, (value, name)) in measured
        .iter()
        .zip([
            "limit equilibrium",
            "LE, Davis",
            "strength reduction",
            "equilibrium solve",
        ])
        .enumerate()
    {
        let value = value.unwrap_or_else(|| panic!("{name} missing from {}", fos_json.display()));
        assert_eq!(
            cells[k + 2],
            format!("{value:.3}"),
            "docs/slope-stability.md quotes {name} on `{slope}` as {}, the run gives {value}",
            cells[k + 2]
        );
    }
}

/// Runs `fos DIR --out OUT` with `extra` flags (it must exit 0): (what it
/// printed, its `fos.json`).
pub fn fos(dir: &Path, out: &Path, extra: &[&str]) -> (String, serde_json::Value) {
    let mut args = vec!["fos", dir.to_str().unwrap(), "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let text = run_ok(&args);
    let fos =
        serde_json::from_str(&std::fs::read_to_string(out.join("fos.json")).unwrap()).unwrap();
    (text, fos)
}
