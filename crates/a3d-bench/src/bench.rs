//! `a3d-bench`: speed figures of the hot paths on generated data, printed
//! as numbers (no timing assertions anywhere in the tests). For whole-process
//! figures such as peak memory, time the command with `/usr/bin/time -v`.

use std::path::Path;
use std::time::Instant;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{BenchArgs, SearchArg};

use a3d_init::formats::gom::GomDocument;
use a3d_init::formats::gom::write::model_to_text;
use a3d_init::kernel::KernelKind;
use a3d_init::kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy};
use a3d_testkit::generate::{self, MaterialSpec};

/// `bench map`: kernel mapping throughput on uniform random clouds.
pub fn map(args: &BenchArgs) -> anyhow::Result<()> {
    let threads = rayon::current_num_threads();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let dim = args.dim.clamp(2, 3);
    let mut cloud = |n: usize| -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| {
                [
                    rng.random_range(0.0..1.0),
                    rng.random_range(0.0..1.0),
                    if dim == 3 {
                        rng.random_range(0.0..1.0)
                    } else {
                        0.0
                    },
                ]
            })
            .collect()
    };
    let nodes = cloud(args.nodes);
    let points = cloud(args.points);
    let values: Vec<f64> = nodes.iter().map(|p| p[0] + 2.0 * p[1]).collect();
    // Support radius 2h holding `neighbours` nodes on average.
    let support = if dim == 3 {
        (args.neighbours / (args.nodes as f64 * 4.0 / 3.0 * std::f64::consts::PI)).cbrt()
    } else {
        (args.neighbours / (args.nodes as f64 * std::f64::consts::PI)).sqrt()
    };
    let h = support / 2.0;
    let cloud = NodeCloud {
        positions: &nodes,
        dim,
        values: &values,
        n_fields: 1,
        group: None,
        node_volume: 1.0 / args.nodes as f64,
    };
    let settings = MapSettings {
        kernel: KernelKind::Cubic,
        h,
        min_shepard: 0.0,
        outside: OutsidePolicy::Nearest,
    };
    let mut best = f64::INFINITY;
    let mut mean_neighbours = 0.0;
    for _ in 0..args.repeat.max(1) {
        let t = Instant::now();
        let search = match args.search {
            SearchArg::Grid => mapper::Search::Grid,
            SearchArg::GridPortable => mapper::Search::GridPortable,
            SearchArg::Kdtree => mapper::Search::KdTree,
        };
        let r = mapper::map_points_with(&cloud, &points, None, &settings, search, true)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        best = best.min(t.elapsed().as_secs_f64());
        mean_neighbours =
            r.n_neighbours.iter().map(|&n| n as f64).sum::<f64>() / points.len() as f64;
    }
    say!(
        "map {dim}D ({:?}): {} nodes → {} points, cubic, h = {h:.5}, {mean_neighbours:.1} neighbours/query, {threads} thread(s): {:.3} s (index build included) = {:.3e} queries/s ({:.3e} per thread)",
        args.search,
        args.nodes,
        args.points,
        best,
        args.points as f64 / best,
        args.points as f64 / best / threads as f64
    );
    // The weights alone, as the map computes them from its squared distances:
    // the floor the exact square root and d/h set (the divider), per neighbour.
    let simd = match args.search {
        SearchArg::Grid => a3d_init::kernel::simd::Avx512::detect(),
        _ => None,
    };
    let d2: Vec<f64> = (0..4096)
        .map(|_| (support * rng.random_range(0.0f64..1.0).powf(1.0 / dim as f64)).powi(2))
        .collect();
    let mut w = Vec::with_capacity(d2.len());
    let reps = 5000;
    let mut weights = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        for _ in 0..reps {
            KernelKind::Cubic.weights_squared(std::hint::black_box(&d2), h, simd, &mut w);
            std::hint::black_box(&w);
        }
        weights = weights.min(t.elapsed().as_secs_f64() / (reps * d2.len()) as f64);
    }
    say!(
        "  the cubic weights alone ({}): {:.2} ns per neighbour, {:.0} % of the map's time at {mean_neighbours:.1} neighbours per query",
        if simd.is_some() {
            "AVX-512"
        } else {
            "portable"
        },
        weights * 1e9,
        100.0 * weights * mean_neighbours * args.points as f64 / (best * threads as f64)
    );
    Ok(())
}

/// `bench loo`: the leave-one-out objective and a full calibration.
pub fn loo(args: &BenchArgs) -> anyhow::Result<()> {
    let threads = rayon::current_num_threads();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let nodes: Vec<[f64; 3]> = (0..args.nodes)
        .map(|_| {
            [
                rng.random_range(0.0..100.0),
                rng.random_range(0.0..100.0),
                0.0,
            ]
        })
        .collect();
    let values: Vec<f64> = nodes.iter().map(|p| 9.81 * (100.0 - p[1])).collect();
    let l = mapper::median_spacing(&nodes, 2);
    let t = Instant::now();
    let obj =
        a3d_init::kernel::loo::LooObjective::new(&nodes, 2, &values, 1, KernelKind::Cubic, 2.5 * l)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
    let build = t.elapsed().as_secs_f64();
    let mut best = f64::INFINITY;
    for _ in 0..args.repeat.max(1) {
        let t = Instant::now();
        std::hint::black_box(obj.evaluate(l, a3d_init::kernel::loo::Norm::L1));
        best = best.min(t.elapsed().as_secs_f64());
    }
    let t = Instant::now();
    let c = a3d_init::calibrate::calibrate(
        |h| obj.evaluate(h, a3d_init::kernel::loo::Norm::L1),
        0.3 * l,
        2.5 * l,
        &Default::default(),
    );
    let full = t.elapsed().as_secs_f64() + build;
    say!(
        "loo: {} nodes, {threads} thread(s): neighbour lists {:.3} s, one objective {:.2} ms, full calibration {:.3} s ({} evaluations, h/l = {:.3})",
        args.nodes,
        build,
        best * 1e3,
        full,
        c.evaluations,
        c.h / l
    );
    Ok(())
}

/// `bench csv`: FEM CSV reading throughput.
pub fn csv(args: &BenchArgs) -> anyhow::Result<()> {
    let threads = rayon::current_num_threads();
    let text = generated_fem_csv(args.nodes, 3);
    let mb = text.len() as f64 / 1e6;
    let options = a3d_init::formats::fem_csv::CsvOptions::default();
    let mut best = f64::INFINITY;
    for _ in 0..args.repeat.max(1) {
        let t = Instant::now();
        let (nodes, _) = a3d_init::formats::fem_csv::parse_csv(
            Path::new("bench.csv"),
            text.as_bytes(),
            &options,
        )?;
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(nodes);
    }
    say!(
        "csv: {} rows × 10 columns, {mb:.1} MB, {threads} thread(s): {best:.3} s = {:.0} MB/s",
        args.nodes,
        mb / best
    );
    Ok(())
}

/// `bench gom`: GOM parsing throughput.
pub fn gom(args: &BenchArgs) -> anyhow::Result<()> {
    let threads = rayon::current_num_threads();
    let nx = ((args.elements as f64 / 2.0).sqrt().round() as usize).max(1);
    let ny = (args.elements / (2 * nx)).max(1);
    let mesh = generate::structured_tri_mesh(0.0, 0.0, nx as f64, ny as f64, nx, ny);
    let spec = MaterialSpec::dry_soil("soil");
    let text = model_to_text(&generate::single_material_model(mesh, &spec, 3), "2023");
    let mb = text.len() as f64 / 1e6;
    let mut best = f64::INFINITY;
    for _ in 0..args.repeat.max(1) {
        let copy = text.clone();
        let t = Instant::now();
        let doc = GomDocument::parse(Path::new("bench.GOM"), copy)?;
        let (model, _) = doc.model()?;
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(model);
    }
    say!(
        "gom: {} elements, {mb:.1} MB, {threads} thread(s): {best:.3} s = {:.0} MB/s (lossless document + typed view)",
        2 * nx * ny,
        mb / best
    );
    Ok(())
}

/// A GeoStudio-style 3D node table: `n` random nodes in a 100 m cube with a
/// hydrostatic pwp and random stresses (seeded).
pub fn generated_fem_csv(n: usize, seed: u64) -> String {
    use std::fmt::Write as _;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut s = String::with_capacity(n * 190);
    s.push_str("X (m),Y (m),Z (m),Pore-Water Pressure (kPa),XTotalStress,YTotalStress,ZTotalStress,XYShearStress,YZShearStress,XZShearStress\n");
    for _ in 0..n {
        let x: f64 = rng.random_range(0.0..100.0);
        let y: f64 = rng.random_range(0.0..100.0);
        let z: f64 = rng.random_range(0.0..100.0);
        let _ = write!(s, "{x},{y},{z},{}", 9.81 * (100.0 - y));
        for k in 0..6 {
            let v: f64 = if k < 3 {
                rng.random_range(0.0..1000.0)
            } else {
                rng.random_range(-50.0..50.0)
            };
            let _ = write!(s, ",{v}");
        }
        s.push('\n');
    }
    s
}

/// `bench e2e`: generates the case, runs `map` as the command does, prints the
/// phases.
pub fn e2e(args: &BenchArgs) -> anyhow::Result<()> {
    use a3d_init::pipeline::fem::FemOptions;
    use a3d_init::pipeline::io::output::{OutputDir, ReadLog};
    use a3d_init::pipeline::map::job::{self, MapJob};
    use a3d_init::pipeline::map::{MapConfig, Outside, SmoothingLength};
    let threads = rayon::current_num_threads();
    let (dir, _removed_at_the_end) = crate::work_dir(args.dir.as_deref())?;
    let t = Instant::now();
    // The generated case, kept in `case/` for later runs, is published whole
    // through the output guard, as `map`'s folder is.
    let case = dir.join("case");
    let gom = case.join("e2e.GOM");
    let fem = case.join("e2e-fem.csv");
    // Kuhn cubes: 6 TETs each, 4 MPs per TET.
    let n_side = ((args.points as f64 / 24.0).cbrt().round() as usize).max(1);
    if !gom.exists() || !fem.exists() {
        let mesh = generate::structured_tet_mesh(100.0, 0.0, 100.0, 100.0, n_side, n_side, n_side);
        let spec = MaterialSpec::dry_soil("soil");
        let text = model_to_text(&generate::single_material_model(mesh, &spec, 4), "2023");
        let nothing_read = ReadLog::start();
        let out = OutputDir::create(&case, true, &nothing_read, "bench")?;
        out.write("e2e.GOM", |w| w.write_all(text.as_bytes()))?;
        let table = generated_fem_csv(args.nodes, 3);
        out.write("e2e-fem.csv", |w| w.write_all(table.as_bytes()))?;
        out.commit()?;
    }
    let generate_s = t.elapsed().as_secs_f64();
    // Support 2h holding `neighbours` nodes on average in the 100 m cube.
    let support =
        (args.neighbours / (args.nodes as f64 * 4.0 / 3.0 * std::f64::consts::PI)).cbrt() * 100.0;
    let job = MapJob {
        model: gom.clone(),
        fem: FemOptions::files(vec![fem.clone()]),
        config: MapConfig {
            kernel: KernelKind::Cubic,
            h: SmoothingLength::Metres(support / 2.0),
            outside: Outside::Nearest,
            ..MapConfig::default()
        },
        generate_cps: true,
        fem_vtu: args.fem_vtu,
    };
    let reads = ReadLog::start();
    let t = Instant::now();
    let mapped = job::compute(&job)?;
    let compute_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let out = OutputDir::create(&dir.join("out"), true, &reads, "bench")?;
    let written =
        a3d_init::pipeline::map::write::write_project(&mapped, &out.staging(), args.fem_vtu)?;
    let write_s = t.elapsed().as_secs_f64();
    // The commit: every file and the folder synced to disk, the rename, the
    // parent synced (what durability costs).
    let t = Instant::now();
    let target = out.commit()?;
    let publish_s = t.elapsed().as_secs_f64();
    let report = serde_json::to_value(&mapped.report)?;
    let mps = report["material_points"].as_u64().unwrap_or(0);
    drop(mapped);
    say!(
        "e2e: {} FEM nodes → {mps} MPs, h = {:.4} m, {threads} thread(s) (case generated in {generate_s:.2} s, not counted)",
        args.nodes,
        support / 2.0
    );
    if let Some(phases) = report["timings_ms"].as_array() {
        for p in phases {
            say!(
                "  {:<28} {:>8.3} s",
                p[0].as_str().unwrap_or("?"),
                p[1].as_f64().unwrap_or(0.0) / 1e3
            );
        }
    }
    let mut bytes = 0u64;
    for name in &written {
        bytes += std::fs::metadata(target.join(name)).map_or(0, |m| m.len());
    }
    say!(
        "  {:<28} {compute_s:>8.3} s",
        "compute (with untimed steps)"
    );
    say!(
        "  {:<28} {write_s:>8.3} s ({:.0} MB: {})",
        "write outputs",
        bytes as f64 / 1e6,
        written.join(", ")
    );
    say!("  {:<28} {publish_s:>8.3} s", "sync to disk and publish");
    say!(
        "  {:<28} {:>8.3} s",
        "total",
        compute_s + write_s + publish_s
    );
    say_peak_rss();
    if let Some(python) = &args.peer {
        let total = compute_s + write_s + publish_s;
        peer(python, &fem, &target.join("mps.csv"), support / 2.0, total)?;
    }
    Ok(())
}

/// The scipy peer (`benches/peer/scipy_map.py`: cKDTree on all threads, the
/// same cubic Shepard mapping, nothing written) on the same case, run by
/// `python` (with numpy and scipy): its read and compute times, and `ours`
/// (this map's total, s) against its compute alone.
fn peer(python: &Path, fem: &Path, mps: &Path, h: f64, ours: f64) -> anyhow::Result<()> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../benches/peer/scipy_map.py");
    let output = std::process::Command::new(python)
        .arg(&script)
        .arg(fem)
        .arg(mps)
        .arg(h.to_string())
        .stdin(std::process::Stdio::null())
        .output()?;
    let text = String::from_utf8_lossy(&output.stdout);
    // "read R s, compute C s, N MPs, M nodes"
    let seconds = |key: &str| {
        text.split(", ").find_map(|part| {
            part.trim()
                .strip_prefix(key)?
                .strip_suffix(" s")?
                .parse::<f64>()
                .ok()
        })
    };
    let (Some(read), Some(compute)) = (seconds("read "), seconds("compute ")) else {
        let stderr = String::from_utf8_lossy(&output.stderr);
        anyhow::bail!(
            "the scipy peer ({}) printed no times: {}",
            script.display(),
            stderr.lines().rev().take(3).collect::<Vec<_>>().join(" | ")
        );
    };
    say!(
        "  scipy peer                    read {read:.3} s, compute {compute:.3} s: this map's total is {:.1}× faster than the peer's compute alone",
        compute / ours
    );
    Ok(())
}

/// Prints the process's peak resident memory (Linux), if known.
fn say_peak_rss() {
    if let Ok(status) = std::fs::read_to_string("/proc/self/status")
        && let Some(line) = status.lines().find(|l| l.starts_with("VmHWM"))
    {
        say!("  peak RSS {}", line.trim_start_matches("VmHWM:").trim());
    }
}

/// `bench equilibrium`: a dry Mohr–Coulomb slope (φ′ = 30°, c′ = 5 kPa; 100 m
/// wide, crest 40 m high, toe 25 m, the face over the middle 30 m: 27°) of
/// about `--points` MPs, solved as `map --stress equilibrium` solves it.
pub fn equilibrium(args: &BenchArgs) -> anyhow::Result<()> {
    use a3d_init::mpm::equilibrium::{self, EquilibriumSettings};
    use a3d_init::mpm::{Elasticity, ReturnMap, SolidModel};
    let threads = rayon::current_num_threads();
    let t = Instant::now();
    let (width, height) = (100.0, 40.0);
    let mut mesh = if args.dim == 2 {
        // Two TRI3 per cell, 3 MPs each, cells 2:1.
        let ny = ((args.points as f64 / 12.0).sqrt().round() as usize).max(1);
        generate::structured_tri_mesh(0.0, 0.0, width, height, 2 * ny, ny)
    } else {
        // Six tetrahedra per cell, 4 MPs each, cells 2:1:1.
        let ny = ((args.points as f64 / 48.0).cbrt().round() as usize).max(1);
        generate::structured_tet_mesh(width, 0.0, height, width / 2.0, 2 * ny, ny, ny)
    };
    generate::slope_profile(&mut mesh, height, height, 25.0, 35.0, 65.0);
    let spec = MaterialSpec {
        mohr_coulomb: Some((30.0, 5.0, 0.0)),
        ..MaterialSpec::dry_soil("soil")
    };
    let mps = if args.dim == 2 { 3 } else { 4 };
    let model = generate::single_material_model(mesh, &spec, mps);
    let points = a3d_init::place::place_material_points_for(
        &model,
        a3d_init::model::ComputationMethod::MpmMp,
    )
    .map_err(|e| anyhow::anyhow!("placing the MPs: {} errors", e.0.len()))?;
    let states = vec![
        a3d_init::model::MpState {
            saturation: 1.0,
            ..Default::default()
        };
        points.len()
    ];
    let m = &model.materials[0];
    let k0 = m.k0.unwrap_or(0.5);
    let elasticity = Elasticity::from_young_poisson(spec.young_modulus, k0 / (1.0 + k0))
        .ok_or_else(|| anyhow::anyhow!("invalid elasticity"))?;
    let gom = SolidModel::from_material(m)?;
    let laws = vec![Some(SolidModel {
        elasticity,
        plasticity: gom
            .plasticity
            .map(|r| ReturnMap::new(r.criterion, elasticity)),
    })];
    let generate_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let out = equilibrium::solve(
        &model,
        &points,
        &states,
        &laws,
        &EquilibriumSettings::default(),
    )?;
    let total_s = t.elapsed().as_secs_f64();
    say!(
        "equilibrium: {}D, {} elements, {} MPs, {} unknowns, {threads} thread(s) (model generated in {generate_s:.2} s, not counted)",
        args.dim,
        model.mesh.n_elements(),
        points.len(),
        out.unknowns
    );
    say!("  {:<28} {:>8.3} s", "assemble K", out.assembly_s);
    say!(
        "  {:<28} {:>8.3} s ({} entries in K, {} in L)",
        "factorise K (Cholesky)",
        out.factorisation_s,
        out.stiffness_entries,
        out.factor_entries
    );
    say!("  {:<28} {:>8.3} s", "elastic solve", out.elastic_solve_s);
    say!(
        "  {:<28} {:>8.3} s ({} iterations, {} load steps, {} MPs yielding)",
        "plastic iterations",
        out.plastic_s,
        out.plastic_iterations,
        out.load_steps,
        out.yielding_points
    );
    say!(
        "  {:<28} {:>8.3} s (residual ratio {:.2e}; elastic {:.2e}; {})",
        "total solve",
        total_s,
        out.residual_ratio,
        out.elastic_residual_ratio,
        if out.equilibrium {
            "in equilibrium"
        } else {
            "NO EQUILIBRIUM"
        }
    );
    say_peak_rss();
    Ok(())
}
