//! `a3d-bench kernel`: the explicit runner against the real Anura3D kernel
//! (`--anura3d`, built by `shared/anura3d-kernel/build.sh`), both as whole
//! processes on one thread, on the same GOM and CPS for the same simulated
//! time:
//!
//! - `demo`: the demo's slope (`fixtures/slope`, 5040 MPs, two-phase
//!   coupled) mapped as the demo maps it (its one-step `map` command), 0.2 s
//!   undamped;
//! - `tet`: a 100 m box of Kuhn cubes (tetrahedral_old, about `--points`
//!   MPs, box fixities, Mohr–Coulomb) from zero stress, 4 s of gravity at
//!   local damping 0.75. The kernel starts from its own zero state
//!   (`$$MP_STRESS_INITIALIZATION_FROMFILE 0`, no MAPF): its MAPF reader is
//!   O(N_MP × N_rows), hours at 10⁵ MPs.
//!
//! Each code takes its own time step, so the figure per core is
//! particle-steps per second (MPs × steps / wall); the time to the same
//! simulated time is printed too. Our runner is the `a3d-init` binary next
//! to this one (`--a3d-init` to name another) with `RAYON_NUM_THREADS=1`;
//! the kernel's steps are the last row of its `<project>_001.ENG`. Printed,
//! never asserted.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{Context, bail};

use crate::{BenchArgs, KernelCase};
use a3d_init::formats::cps::CpsDocument;
use a3d_init::formats::gom::write::model_to_text;
use a3d_init::pipeline::io::output::{OutputDir, ReadLog};
use a3d_testkit::generate::{self, MaterialSpec};

/// One model the two codes run.
struct Case {
    name: &'static str,
    /// The folder `map` wrote (its CPS edited for the run).
    folder: PathBuf,
    time: f64,
    damping: f64,
    /// Whether the kernel reads the MAPF.
    mapf: bool,
}

/// What one code did on one case.
struct Timed {
    walls: Vec<f64>,
    steps: usize,
    points: usize,
}

impl Timed {
    fn min(&self) -> f64 {
        self.walls.iter().copied().fold(f64::INFINITY, f64::min)
    }

    fn median(&self) -> f64 {
        let mut w = self.walls.clone();
        w.sort_by(f64::total_cmp);
        let n = w.len();
        if n % 2 == 1 {
            w[n / 2]
        } else {
            0.5 * (w[n / 2 - 1] + w[n / 2])
        }
    }

    /// Particle-steps per second at the median wall time.
    fn rate(&self) -> f64 {
        (self.points * self.steps) as f64 / self.median()
    }
}

pub fn kernel(args: &BenchArgs) -> anyhow::Result<()> {
    let Some(anura3d) = args.anura3d.as_deref() else {
        bail!(
            "give the Anura3D kernel with --anura3d PATH (shared/anura3d-kernel/README.md builds it in a minute)"
        );
    };
    let anura3d = std::fs::canonicalize(anura3d)
        .with_context(|| format!("the kernel {}", anura3d.display()))?;
    let ours = match &args.a3d_init {
        Some(p) => p.clone(),
        None => std::env::current_exe()?.with_file_name("a3d-init"),
    };
    if !ours.is_file() {
        bail!(
            "no a3d-init binary at {} (cargo build --release -p a3d-init, or --a3d-init PATH)",
            ours.display()
        );
    }
    let (dir, _removed_at_the_end) = crate::work_dir(args.dir.as_deref())?;
    let repeat = args.repeat.max(1);
    let kernel_repeat = args.kernel_repeat.max(1);
    say!(
        "kernel: the runner ({}) against the Anura3D kernel ({}), one thread each, whole processes; {repeat} run(s) of ours, {kernel_repeat} of the kernel",
        ours.display(),
        anura3d.display()
    );
    let cases = match args.case {
        KernelCase::Demo => vec![demo_case(&ours, &dir)?],
        KernelCase::Tet => vec![tet_case(&ours, &dir, args.points)?],
        KernelCase::Both => vec![demo_case(&ours, &dir)?, tet_case(&ours, &dir, args.points)?],
    };
    for case in &cases {
        let mine = run_ours(&ours, case, &dir, repeat)?;
        let theirs = run_kernel(&anura3d, case, &dir, kernel_repeat)?;
        say!(
            "  {}: {} MPs, {} s simulated",
            case.name,
            mine.points,
            case.time
        );
        for (who, t) in [("a3d-init run", &mine), ("Anura3D kernel", &theirs)] {
            say!(
                "    {who:<15} {:>6} steps (Δt {:.2e} s)  wall min {:>7.2} s, median {:>7.2} s  {:.3e} particle-steps/s",
                t.steps,
                case.time / t.steps as f64,
                t.min(),
                t.median(),
                t.rate()
            );
        }
        say!(
            "    ratio           {:.2}× per particle-step, {:.2}× in time to {} s",
            mine.rate() / theirs.rate(),
            theirs.median() / mine.median(),
            case.time
        );
    }
    Ok(())
}

/// The demo's slope, mapped by the demo's one-step `map` command.
fn demo_case(ours: &Path, dir: &Path) -> anyhow::Result<Case> {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/slope");
    let folder = dir.join("demo-map");
    let pvd = fixtures.join("ogs/results/rain.pvd");
    let fem = pvd.to_string_lossy().into_owned();
    let model = fixtures.to_string_lossy().into_owned();
    let out = folder.to_string_lossy().into_owned();
    // The demo's one-step command; no equilibrium is found on this state
    // (exit 1, the folder written).
    run_quiet(
        Command::new(ours).args([
            "map",
            "--fem",
            &fem,
            "--step",
            "failure",
            "--mpm",
            &model,
            "--h",
            "auto",
            "--stress",
            "equilibrium",
            "--material-map",
            "mat0=silty_sand",
            "--out",
            &out,
            "--force",
        ]),
        "the demo's map",
        &[0, 1],
    )?;
    edit_cps(&folder, "slope", 0.2, 0.0, true)?;
    Ok(Case {
        name: "demo slope, two-phase, undamped",
        folder,
        time: 0.2,
        damping: 0.0,
        mapf: true,
    })
}

/// The 3D tetrahedral box, mapped from zero stress.
fn tet_case(ours: &Path, dir: &Path, points: usize) -> anyhow::Result<Case> {
    let case = dir.join("tet-case");
    let gom = case.join("box.GOM");
    let fem = case.join("box-fem.csv");
    // Kuhn cubes: 6 TETs each, 4 MPs per TET.
    let n_side = ((points as f64 / 24.0).cbrt().round() as usize).max(1);
    let mesh = generate::structured_tet_mesh(100.0, 0.0, 100.0, 100.0, n_side, n_side, n_side);
    let spec = MaterialSpec::dry_soil("soil");
    let text = model_to_text(&generate::single_material_model(mesh, &spec, 4), "2023");
    let nothing_read = ReadLog::start();
    let out = OutputDir::create(&case, true, &nothing_read, "bench")?;
    out.write("box.GOM", |w| std::io::Write::write_all(w, text.as_bytes()))?;
    let table = crate::bench::generated_fem_csv(1000, 3);
    out.write("box-fem.csv", |w| {
        std::io::Write::write_all(w, table.as_bytes())
    })?;
    out.commit()?;
    let folder = dir.join("tet-map");
    let (gom, fem, out) = (
        gom.to_string_lossy().into_owned(),
        fem.to_string_lossy().into_owned(),
        folder.to_string_lossy().into_owned(),
    );
    run_quiet(
        Command::new(ours).args([
            "map",
            "--fem",
            &fem,
            "--mpm",
            &gom,
            "--generate-cps",
            "--stress",
            "zero",
            "--h",
            "20",
            "--outside",
            "nearest",
            "--out",
            &out,
            "--force",
        ]),
        "the box's map",
        &[0],
    )?;
    edit_cps(&folder, "box", 4.0, 0.75, false)?;
    Ok(Case {
        name: "3D tetrahedral box, Mohr–Coulomb, from zero stress, damping 0.75",
        folder,
        time: 4.0,
        damping: 0.75,
        mapf: false,
    })
}

/// Sets the run in `<folder>/<project>.CPS_001`: one dynamic load step of
/// `time` s, local damping `damping`, the MAPF read or not.
fn edit_cps(
    folder: &Path,
    project: &str,
    time: f64,
    damping: f64,
    mapf: bool,
) -> anyhow::Result<()> {
    let path = folder.join(format!("{project}.CPS_001"));
    let mut cps = CpsDocument::read(&path)?;
    let time = time.to_string();
    let damping = if damping > 0.0 {
        format!("1 {damping}")
    } else {
        "0 0.0".into()
    };
    cps.set("$$NUMBER_OF_LOADSTEPS", &["1"]);
    cps.set("$$TIME_PER_LOADSTEP", &[&time]);
    cps.set("$$QUASISTATIC_CONVERGENCE", &["0"]);
    cps.set("$$HOMOGENEOUS_LOCAL_DAMPING", &[&damping]);
    cps.set(
        "$$MP_STRESS_INITIALIZATION_FROMFILE",
        &[if mapf { "1" } else { "0" }],
    );
    std::fs::write(&path, cps.to_text())?;
    Ok(())
}

/// `a3d-init run` on the case, `repeat` times.
fn run_ours(ours: &Path, case: &Case, dir: &Path, repeat: usize) -> anyhow::Result<Timed> {
    let out = dir.join("run-ours");
    let (time, damping) = (case.time.to_string(), case.damping.to_string());
    let mut walls = Vec::new();
    for _ in 0..repeat {
        let started = Instant::now();
        run_quiet(
            Command::new(ours)
                .env("RAYON_NUM_THREADS", "1")
                .arg("run")
                .arg(&case.folder)
                .args(["--time", &time, "--damping", &damping])
                .args(["--snapshots", &time, "--out"])
                .arg(&out)
                .arg("--force"),
            "a3d-init run",
            &[0],
        )?;
        walls.push(started.elapsed().as_secs_f64());
    }
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("run.json"))?)?;
    let count = |key: &str| {
        report[key]
            .as_u64()
            .map(|v| v as usize)
            .with_context(|| format!("run.json has no `{key}`"))
    };
    Ok(Timed {
        walls,
        steps: count("steps")?,
        points: count("n_points")?,
    })
}

/// The kernel on a fresh copy of the case's GOM, CPS (and MAPF), `repeat`
/// times.
fn run_kernel(bin: &Path, case: &Case, dir: &Path, repeat: usize) -> anyhow::Result<Timed> {
    let cps = std::fs::read_dir(&case.folder)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "CPS_001"))
        .context("the map folder has no CPS")?;
    let project = cps
        .file_stem()
        .and_then(|s| s.to_str())
        .context("the CPS's name")?
        .to_string();
    let run = dir.join("run-kernel");
    let mut walls = Vec::new();
    let mut steps = 0;
    for _ in 0..repeat {
        if run.exists() {
            std::fs::remove_dir_all(&run)?;
        }
        std::fs::create_dir_all(&run)?;
        let mut names = vec![format!("{project}.GOM"), format!("{project}.CPS_001")];
        if case.mapf {
            names.push(format!("{project}.MAPF"));
        }
        for name in &names {
            std::fs::copy(case.folder.join(name), run.join(name))
                .with_context(|| format!("copying {name}"))?;
        }
        let started = Instant::now();
        let output = Command::new(bin)
            .arg(&project)
            .current_dir(&run)
            .stdin(Stdio::null())
            .output()
            .context("starting the kernel")?;
        walls.push(started.elapsed().as_secs_f64());
        let log = String::from_utf8_lossy(&output.stdout);
        if !log.contains("Calculation finished") {
            bail!(
                "the kernel did not finish in {} (its last lines: {})",
                run.display(),
                log.lines().rev().take(5).collect::<Vec<_>>().join(" | ")
            );
        }
        steps = last_step(&run.join(format!("{project}_001.ENG")))?;
    }
    let points = kernel_points(&run.join(format!("{project}_001.INF")))?;
    Ok(Timed {
        walls,
        steps,
        points,
    })
}

/// The time step number of the last row of the kernel's energy file
/// (columns: load step, time step, …).
fn last_step(eng: &Path) -> anyhow::Result<usize> {
    let text = std::fs::read_to_string(eng).with_context(|| eng.display().to_string())?;
    text.lines()
        .filter_map(|l| l.split_whitespace().nth(1)?.parse::<usize>().ok())
        .max()
        .with_context(|| format!("no time steps in {}", eng.display()))
}

/// The kernel's `Number of material points` in its `<project>_001.INF`.
fn kernel_points(inf: &Path) -> anyhow::Result<usize> {
    let text = std::fs::read_to_string(inf).with_context(|| inf.display().to_string())?;
    text.lines()
        .find(|l| l.starts_with("Number of material points"))
        .and_then(|l| l.split_whitespace().last()?.parse().ok())
        .with_context(|| format!("no material point count in {}", inf.display()))
}

/// Runs `command` with its output captured; an exit code outside `ok` is an
/// error that shows the output's end.
fn run_quiet(command: &mut Command, what: &str, ok: &[i32]) -> anyhow::Result<()> {
    let output = command
        .stdin(Stdio::null())
        .output()
        .with_context(|| format!("starting {what}"))?;
    let code = output.status.code().unwrap_or(-1);
    if !ok.contains(&code) {
        let text = String::from_utf8_lossy(&output.stderr).into_owned()
            + &String::from_utf8_lossy(&output.stdout);
        let tail: Vec<&str> = text.lines().rev().take(6).collect();
        bail!("{what} exited with {code}: {}", tail.join(" | "));
    }
    Ok(())
}
