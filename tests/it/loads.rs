//! GOM loads (#27): solid tractions and liquid pressures on nodes and on
//! material points, scaled by the CPS multipliers, against closed forms and
//! against the real Anura3D kernel run on the same project.

use crate::common;
use common::anura3d_kernel_or_skip;
use common::kernel_run::{run_in_place, vtk_scalars, vtk_vectors};

use a3d_init::model::MpState;
use a3d_init::mpm::{RunSettings, Simulation};
use a3d_init::pipeline::Project;
use a3d_init::pipeline::check::runner;

/// `test-1001` (a 0.1 m wide column of 20 TRI3 elements with 3 MPs each
/// under two empty ones; a −20 kPa vertical traction on the side between
/// them) run as MPM-MP with a stiffer soil (E = 10 MPa, so that strains
/// stay small), its load block named `block`, and `material` in place of
/// its dry material when given.
fn column_project(block: &str, material: Option<&str>, extra: &str) -> (String, String) {
    let dir = common::fixture("anura3d/test-1001");
    let gom = std::fs::read_to_string(dir.join("test-1001.GOM")).unwrap();
    let cps = std::fs::read_to_string(dir.join("test-1001.CPS_001")).unwrap();
    let mut gom = gom
        .replace("$$START_LOAD_ON_NODES_SOLID\n", &format!("{block}\n"))
        .replace("$$YOUNG_MODULUS\n100\n", "$$YOUNG_MODULUS\n10000\n");
    if let Some(m) = material {
        let start = gom.find("$$MATERIAL_TYPE").unwrap();
        let end = gom.find("$$K0_VALUE_SOLID").unwrap();
        gom.replace_range(start..end, m);
    }
    gom = gom.replace(
        "$$NUMBER_OF_MATERIALS",
        &format!("{extra}$$NUMBER_OF_MATERIALS"),
    );
    let cps = cps
        .replace("$$COMPUTATION_METHOD\nFEM", "$$COMPUTATION_METHOD\nMPM-MP")
        .replace("$$LIQUID_PRESSURE\noff", "$$LIQUID_PRESSURE\nstep");
    (gom, cps)
}

const COUPLED: &str = "$$MATERIAL_TYPE\nsaturated_material_coupled\n$$POROSITY_SOLID\n0.3\n\
$$DENSITY_SOLID\n2600\n$$DENSITY_LIQUID\n1000\n$$INTRINSIC_PERMEABILITY_LIQUID\n1e-8\n\
$$BULK_MODULUS_LIQUID\n100000\n$$DYNAMIC_VISCOSITY_LIQUID\n1e-6\n";

/// Writes the project as `slope.*` into `dir` and loads it.
fn write_project(dir: &std::path::Path, gom: &str, cps: &str) -> Project {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("slope.GOM"), gom).unwrap();
    std::fs::write(dir.join("slope.CPS_001"), cps).unwrap();
    Project::load(&dir.join("slope.GOM")).unwrap()
}

/// Runs the project with the CPS's damping and gravity for `time` s from
/// rest; the MPs' displacements and
/// pore pressures.
fn run_ours(
    project: &Project,
    time: f64,
    dt: Option<f64>,
) -> (Vec<[f64; 3]>, Vec<f64>, Vec<String>) {
    let states = vec![
        MpState {
            pwp: 0.0,
            total: [0.0; 6],
            saturation: 1.0,
        };
        project.points.len()
    ];
    let base = runner::with_cps(RunSettings::dynamic(time), project.cps.as_ref(), None);
    let (mut settings, _) = runner::with_project(base, project).unwrap();
    // test-1001's `$$GRAVITY_LOAD off` switches gravity off in both codes.
    let mut sim = Simulation::new(&project.model, &project.points, &states, &settings).unwrap();
    if let Some(dt) = dt {
        // The same Δt as the kernel's: scale the Courant number.
        settings.courant *= dt / sim.time_step();
        sim = Simulation::new(&project.model, &project.points, &states, &settings).unwrap();
    }
    while sim.time() < time - 0.5 * sim.time_step() {
        sim.step();
    }
    (sim.displacements(), sim.pore_pressures(), sim.notes())
}

/// The CPS with `$$TIME_PER_LOADSTEP` `time`, local damping `alpha` and no
/// quasi-static stop.
fn timed(cps: &str, time: f64, alpha: f64) -> String {
    let edited = common::kernel_run::edit_cps(cps, time);
    edited.replace(
        "$$HOMOGENEOUS_LOCAL_DAMPING\n0 0.0",
        &format!("$$HOMOGENEOUS_LOCAL_DAMPING\n1 {alpha}"),
    )
}

/// The largest vertical displacement magnitude.
fn largest(u: &[[f64; 3]]) -> f64 {
    u.iter().map(|v| v[1].abs()).fold(0.0, f64::max)
}

/// What the coupled comparisons read: per MP, displacements and pore
/// pressures, here and in the kernel.
struct Coupled {
    ours: Vec<[f64; 3]>,
    p_ours: Vec<f64>,
    theirs: Vec<[f64; 3]>,
    p_theirs: Vec<f64>,
}

/// Runs the project in `dir` for `time` s undamped in the kernel, then here
/// at the kernel's Δt: its two-phase critical step (Mieremet's, read from
/// `slope.OUT`) is not this runner's, and the comparison runs both with the
/// same Δt.
fn both_at_the_kernels_step(
    kernel: &std::path::Path,
    dir: &std::path::Path,
    project: &Project,
    time: f64,
) -> Coupled {
    let vtk = run_in_place(kernel, dir);
    let out = String::from_utf8_lossy(&std::fs::read(dir.join("slope.OUT")).unwrap()).into_owned();
    let dt: f64 = out
        .lines()
        .find_map(|l| l.trim().strip_prefix("TimeIncrement:"))
        .and_then(|v| v.trim().parse().ok())
        .expect("the kernel's TimeIncrement in slope.OUT");
    let (ours, p_ours, notes) = run_ours(project, time, Some(dt));
    assert!(notes.is_empty(), "{notes:?}");
    Coupled {
        ours,
        p_ours,
        theirs: vtk_vectors(&vtk, "displacement_solid"),
        p_theirs: vtk_scalars(
            &vtk.with_file_name("slope_MPScalar_001.vtk"),
            "pressure_liquid",
        ),
    }
}

/// Runs the project `gom`/`cps` for `time` s at local damping `alpha` in
/// both codes (in `dir`); the project and the largest vertical
/// displacement here and in the kernel.
fn both_settle(
    kernel: &std::path::Path,
    dir: &std::path::Path,
    (gom, cps): (&str, &str),
    time: f64,
    alpha: f64,
) -> (Project, f64, f64) {
    let project = write_project(dir, gom, &timed(cps, time, alpha));
    let (ours, _, notes) = run_ours(&project, time, None);
    assert!(notes.is_empty(), "{notes:?}");
    let theirs = vtk_vectors(&run_in_place(kernel, dir), "displacement_solid");
    let (a, b) = (largest(&ours), largest(&theirs));
    assert!(b > 1e-4, "the load moved nothing in the kernel");
    (project, a, b)
}

#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn solid_loads_on_nodes_and_on_mps_move_the_column_as_the_kernel_does() {
    let Some(kernel) = anura3d_kernel_or_skip("solid_loads_on_nodes_and_on_mps") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    // M = E(1 − ν)/((1 + ν)(1 − 2ν)) with E = 1e4 kPa, ν = 0.2; q = 20 kPa
    // over H = 1 m: the static settlement of the top q·H/M.
    let static_top = 20.0 * 1.0 / (1e4 * 0.8 / (1.2 * 0.6));
    for block in [
        "$$START_LOAD_ON_NODES_SOLID",
        "$$START_LOAD_ON_MATERIAL_POINTS_SOLID",
    ] {
        let (gom, cps) = column_project(block, None, "");
        for (time, alpha) in [(0.01, 0.0), (0.5, 0.75)] {
            let dir = tmp.path().join(format!("{}-{alpha}", &block[15..]));
            let (project, a, b) = both_settle(&kernel, &dir, (&gom, &cps), time, alpha);
            eprintln!(
                "{block}, {time} s, α = {alpha}: largest settlement {a:.5e} m (kernel {b:.5e} m, static {static_top:.5e} m)"
            );
            assert!((a - b).abs() < 0.02 * b, "{block}: {a:e} m against {b:e} m");
            if alpha > 0.0 && block.contains("NODES") {
                // At rest under a nodal load the top MP (at height y above
                // the fixed base) has settled q·y/M.
                let y = project
                    .points
                    .iter()
                    .map(|p| p.position[1])
                    .fold(0.0, f64::max);
                let exact = static_top * y;
                eprintln!("  closed form at the top MP (y = {y:.4} m): {exact:.5e} m");
                assert!(
                    (a - exact).abs() < 0.005 * exact,
                    "{a:e} m against q·y/M = {exact:e} m"
                );
            }
        }
    }
}

#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn liquid_pressures_on_nodes_and_on_mps_load_the_water_as_the_kernel_does() {
    let Some(kernel) = anura3d_kernel_or_skip("liquid_pressures_on_nodes_and_on_mps") else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    // The same column, coupled (n = 0.3, K_w = 1e5 kPa, k = 0.1 m/s, so that
    // the drag relaxes slower than a time step and the kernel's explicit drag
    // and this runner's implicit one agree): a
    // −20 kPa liquid pressure on the side above it instead of the traction,
    // on nodes (along the normal out of the soil: it compresses the water)
    // and on MPs (along the normal as the side's node order gives it, here
    // pointing into the soil: it pulls).
    for block in [
        "$$START_LOAD_ON_NODES_LIQUID",
        "$$START_LOAD_ON_MATERIAL_POINTS_LIQUID",
    ] {
        let (gom, cps) = column_project(block, Some(COUPLED), "");
        // A liquid load is its first value at each node.
        let gom = gom.replace(
            "4 3            0          -20            0          -20",
            "4 3 -20 -20 -20 -20",
        );
        let time = 0.004;
        let dir = tmp.path().join(&block[15..]);
        let project = write_project(&dir, &gom, &timed(&cps, time, 0.0));
        let Coupled {
            ours,
            p_ours,
            theirs,
            p_theirs,
        } = both_at_the_kernels_step(&kernel, &dir, &project, time);
        let (a, b) = (largest(&ours), largest(&theirs));
        let pa = p_ours.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let pb = p_theirs.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let signed = |p: &[f64]| p.iter().sum::<f64>() / p.len() as f64;
        eprintln!(
            "{block}: largest displacement {a:.4e} m (kernel {b:.4e} m), largest |p| {pa:.4} kPa (kernel {pb:.4} kPa), mean p {:.4} kPa (kernel {:.4} kPa)",
            signed(&p_ours),
            signed(&p_theirs)
        );
        assert!(pb > 1.0, "the load moved no water in the kernel");
        assert!((a - b).abs() < 0.02 * b, "{block}: {a:e} m against {b:e} m");
        assert!(
            (pa - pb).abs() < 0.02 * pb,
            "{block}: |p| {pa} against {pb} kPa"
        );
        assert!(
            (signed(&p_ours) - signed(&p_theirs)).abs() < 0.02 * pb,
            "{block}: mean p apart"
        );
    }
}

/// A bad load block or multiplier is an error at its line and column, as
/// every GOM and CPS value is.
#[test]
fn bad_load_blocks_and_multipliers_are_errors_at_their_place() {
    use a3d_init::formats::cps::CpsDocument;
    use a3d_init::formats::gom::GomDocument;
    let (gom, cps) = column_project("$$START_LOAD_ON_NODES_SOLID", None, "");
    let side = "4 3            0          -20            0          -20";
    let line = gom.lines().position(|l| l == side).unwrap() + 1;
    let path = std::path::Path::new("column.GOM");
    for (bad, column, words) in [
        ("4 99 0 -20 0 -20", 3, "node id 99 is out of range 1..=24"),
        ("4 3 0 -20 0", 12, "expected 6 numbers per side"),
        (
            "4 3 0 -2x 0 -20",
            7,
            "expected a node id or a load value, found `-2x`",
        ),
    ] {
        let text = gom.replacen(side, bad, 1);
        let err = GomDocument::parse(path, text).unwrap().model().unwrap_err();
        let message = err.to_string();
        assert!(
            message.contains(&format!("column.GOM:{line}:{column}:")) && message.contains(words),
            "{bad}: {message}"
        );
    }
    let text = gom.replacen(
        &format!("SOLID\n1\n{side}"),
        &format!("SOLID\n2\n{side}"),
        1,
    );
    let message = GomDocument::parse(path, text)
        .unwrap()
        .model()
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("expects 2 loaded sides, found 1"),
        "{message}"
    );

    let cps_path = std::path::Path::new("column.CPS_001");
    let line = cps.lines().position(|l| l == "$$SOLID_TRACTION").unwrap() + 2;
    for (bad, column, words) in [
        (
            "ramp 0.0 1.0",
            1,
            "load type `ramp` must be `linear`, `step` or `off`",
        ),
        ("step 0.0 x", 10, "expected the final multiplier, found `x`"),
    ] {
        let text = cps.replacen(
            "$$SOLID_TRACTION\nstep  0.0  1.0",
            &format!("$$SOLID_TRACTION\n{bad}"),
            1,
        );
        let message = CpsDocument::parse(cps_path, text).unwrap_err().to_string();
        assert!(
            message.contains(&format!("column.CPS_001:{line}:{column}:"))
                && message.contains(words),
            "{bad}: {message}"
        );
    }
}

#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn face_loads_in_3d_move_the_column_as_the_kernel_does() {
    let Some(kernel) = anura3d_kernel_or_skip("face_loads_in_3d") else {
        return;
    };
    // test-1005_3D: 60 tetrahedral_old elements with 4 MPs each under six
    // empty ones, a −20 kPa vertical traction on the MPs next to the two
    // faces between them; stiffened as above, run as MPM-MP, and the same
    // load put on the faces' nodes.
    let dir = common::fixture("anura3d/test-1005_3D");
    let gom = std::fs::read_to_string(dir.join("test-1005_3D.GOM"))
        .unwrap()
        .replace("$$YOUNG_MODULUS\n100\n", "$$YOUNG_MODULUS\n10000\n");
    let cps = std::fs::read_to_string(dir.join("test-1005_3D.CPS_001")).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    for block in [
        "$$START_LOAD_ON_MATERIAL_POINTS_SOLID",
        "$$START_LOAD_ON_NODES_SOLID",
    ] {
        let gom = gom.replace(
            "$$START_LOAD_ON_MATERIAL_POINTS_SOLID\n",
            &format!("{block}\n"),
        );
        for (time, alpha) in [(0.01, 0.0), (0.5, 0.75)] {
            let dir = tmp.path().join(format!("{}-{alpha}", &block[15..]));
            let (_, a, b) = both_settle(&kernel, &dir, (&gom, &cps), time, alpha);
            eprintln!(
                "3D {block}, {time} s, α = {alpha}: largest settlement {a:.5e} m (kernel {b:.5e} m)"
            );
            assert!((a - b).abs() < 0.02 * b, "{block}: {a:e} m against {b:e} m");
        }
    }
}

#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn a_water_level_from_a_file_loads_the_column_as_the_kernel_does() {
    let Some(kernel) = anura3d_kernel_or_skip("a_water_level_from_a_file") else {
        return;
    };
    // The coupled column of the liquid test with its traction switched off:
    // `$$HYDRAULIC_HEAD file` with the head rising from 1.2 m to 1.6 m over
    // 0.004 s in slope.HHBF, over an area holding the column's top side
    // (y = 1 m, under the two empty elements): a water pressure
    // −γw·(h − 1) on the water and on the mixture there.
    let (gom, cps) = column_project(
        "$$START_LOAD_ON_NODES_SOLID",
        Some(COUPLED),
        "$$BOUNDARY_HYDRAULIC_HEAD_AREA\n-1 1\n0.95 1.05\n",
    );
    // γw is the liquid's density × g × the gravity multiplier: gravity on.
    let cps = cps
        .replace("$$SOLID_TRACTION\nstep", "$$SOLID_TRACTION\noff")
        .replace(
            "$$GRAVITY_LOAD\noff  0.0  1.0",
            "$$GRAVITY_LOAD\nstep  1.0  1.0",
        )
        .replace("$$END", "$$HYDRAULIC_HEAD\nfile 0.0\n$$END");
    let time = 0.004;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("slope.HHBF"), "0.0 1.2\n0.004 1.6\n1.0 1.6\n").unwrap();
    let project = write_project(dir, &gom, &timed(&cps, time, 0.0));
    let Coupled {
        ours,
        p_ours,
        theirs,
        p_theirs,
    } = both_at_the_kernels_step(&kernel, dir, &project, time);
    let (a, b) = (largest(&ours), largest(&theirs));
    let mean = |p: &[f64]| p.iter().sum::<f64>() / p.len() as f64;
    let (pa, pb) = (mean(&p_ours), mean(&p_theirs));
    eprintln!(
        "water level: largest displacement {a:.4e} m (kernel {b:.4e} m), mean p {pa:.4} kPa (kernel {pb:.4} kPa)"
    );
    assert!(
        b > 1e-6 && pb.abs() > 0.1,
        "the water level moved nothing in the kernel"
    );
    assert!((a - b).abs() < 0.02 * b, "{a:e} m against {b:e} m");
    assert!(
        (pa - pb).abs() < 0.02 * pb.abs(),
        "mean p {pa} against {pb} kPa"
    );
}

/// `map` carries the water level's file into the folder it writes, and a
/// missing one stops `verify` with exit code 2, naming it.
#[test]
fn the_head_file_travels_with_map_and_a_missing_one_is_an_error() {
    let (gom, cps) = column_project(
        "$$START_LOAD_ON_NODES_SOLID",
        Some(COUPLED),
        "$$BOUNDARY_HYDRAULIC_HEAD_AREA\n-1 1\n0.95 1.05\n",
    );
    let cps = cps.replace("$$END", "$$HYDRAULIC_HEAD\nfile 0.0\n$$END");
    let tmp = tempfile::tempdir().unwrap();
    let input = tmp.path().join("in");
    write_project(&input, &gom, &cps);
    std::fs::write(input.join("slope.HHBF"), "0 1.2\n1 1.6\n").unwrap();
    let fem = tmp.path().join("fem.csv");
    std::fs::write(
        &fem,
        common::hydrostatic_grid_csv("x,y,pwp", 1, 3, 9.81, 1.0),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let (code, text) = common::run_map(&input.join("slope.GOM"), &fem, &out, &[]);
    assert_eq!(code, 0, "{text}");
    assert_eq!(
        std::fs::read(out.join("slope.HHBF")).unwrap(),
        b"0 1.2\n1 1.6\n".to_vec()
    );
    std::fs::write(out.join("slope.HHBF"), "0 1.2\n0 1.6\n").unwrap();
    let (code, text) = common::run(&["verify", out.to_str().unwrap()]);
    assert_eq!(code, 2, "{text}");
    common::assert_contains(&text, &["slope.HHBF:2:1:", "times must increase"]);
    std::fs::remove_file(out.join("slope.HHBF")).unwrap();
    let (code, text) = common::run(&["verify", out.to_str().unwrap()]);
    assert_eq!(code, 2, "{text}");
    common::assert_contains(&text, &["slope.HHBF"]);
}

#[test]
#[allow(clippy::print_stderr)] // the measured values belong in the test output
fn gravity_follows_the_cps_multiplier_as_in_the_kernel() {
    let Some(kernel) = anura3d_kernel_or_skip("gravity_follows_the_cps_multiplier") else {
        return;
    };
    // The dry column without its traction: under `$$GRAVITY_LOAD linear 0 1`
    // (gravity ramped over the load step) for 0.05 s undamped, where a
    // ramp and a step part by far; under `step 1 1` damped to rest, where a
    // column of height H fixed at its base has settled
    // u(y) = γ·(H·y − y²/2)/M at height y.
    let (gom, cps) = column_project("$$START_LOAD_ON_NODES_SOLID", None, "");
    let cps = cps.replace("$$SOLID_TRACTION\nstep", "$$SOLID_TRACTION\noff");
    let tmp = tempfile::tempdir().unwrap();
    let gamma = (1.0 - 0.3) * 2.6 * 9.81;
    let modulus = 1e4 * 0.8 / (1.2 * 0.6);
    for (multiplier, time, alpha) in [
        ("linear  0.0  1.0", 0.05, 0.0),
        ("step  1.0  1.0", 0.5, 0.75),
    ] {
        let cps = cps.replace(
            "$$GRAVITY_LOAD\noff  0.0  1.0",
            &format!("$$GRAVITY_LOAD\n{multiplier}"),
        );
        let dir = tmp
            .path()
            .join(multiplier.split_whitespace().next().unwrap());
        let (project, a, b) = both_settle(&kernel, &dir, (&gom, &cps), time, alpha);
        eprintln!(
            "gravity {multiplier}, {time} s, α = {alpha}: top settlement {a:.5e} m (kernel {b:.5e} m)"
        );
        assert!(
            (a - b).abs() < 0.02 * b,
            "{multiplier}: {a:e} m against {b:e} m"
        );
        if alpha > 0.0 {
            let y = project
                .points
                .iter()
                .map(|p| p.position[1])
                .fold(0.0, f64::max);
            let exact = gamma * (1.0 * y - y * y / 2.0) / modulus;
            eprintln!("  closed form at rest: {exact:.5e} m");
            assert!(
                (a - exact).abs() < 0.01 * exact,
                "{a:e} m against {exact:e} m"
            );
        }
    }
}
