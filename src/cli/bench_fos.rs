//! `a3d-init bench fos`: the speed figures of #31 on the shipped slope
//! (`fixtures/slope`, run from the repository root, or `--dir` naming the
//! model folder): its Morgenstern–Price factor with the default search (about
//! 5,000 trial circles, then the non-circular refinement) on the stand-in
//! pore pressures, and FS(t) by limit equilibrium over 40 generated node
//! tables of a table rising to the ground, bisected where it crosses 1.
//! Printed, never asserted.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;

use super::bench::BenchArgs;
use crate::formats::fem_csv::CsvOptions;
use crate::pipeline::Project;
use crate::pipeline::fem::{self, FemOptions};
use crate::pipeline::fos_time::{self, FosTimeOptions, SeriesInput};
use crate::pipeline::slope::LeOptions;

const GAMMA_W: f64 = 9.81;

/// The fixture's clay surface (fixtures/slope/README.md).
fn clay_top(x: f64) -> f64 {
    let slope = 32f64.to_radians().tan();
    let x_toe = 0.5 + 2.9 / slope;
    if x <= 0.5 {
        2.9
    } else if x >= x_toe {
        0.0
    } else {
        2.9 - slope * (x - 0.5)
    }
}

/// Node tables at `n` times over 2 h: a perched table over the clay rising to
/// 1.8 times its shape, at most at the ground; suction capped at 6 → 1.5 kPa.
fn series(nodes_csv: &Path, dir: &Path, n: usize) -> anyhow::Result<Vec<(f64, PathBuf)>> {
    let text = std::fs::read_to_string(nodes_csv)
        .with_context(|| format!("{}: cannot read", nodes_csv.display()))?;
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default().to_string();
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate() {
        let r: Vec<&str> = line.split(',').collect();
        let num = |i: usize| -> anyhow::Result<f64> {
            r.get(i)
                .and_then(|v| v.trim().parse().ok())
                .with_context(|| format!("{}:{}: expected x and y", nodes_csv.display(), k + 2))
        };
        let rest = r
            .get(4..)
            .with_context(|| format!("{}:{}: expected 5 columns", nodes_csv.display(), k + 2))?;
        rows.push((r[0].to_string(), num(1)?, num(2)?, rest.join(",")));
    }
    let mut tops: Vec<(f64, f64)> = Vec::new();
    for &(_, x, y, _) in &rows {
        match tops.iter_mut().find(|t| (t.0 - x).abs() < 1e-9) {
            Some(t) => t.1 = t.1.max(y),
            None => tops.push((x, y)),
        }
    }
    let top = |x: f64| {
        tops.iter()
            .find(|t| (t.0 - x).abs() < 1e-9)
            .map_or(x, |t| t.1)
    };
    (0..n)
        .map(|k| {
            let s = k as f64 / (n - 1) as f64;
            let (rise, cap) = (1.8 * s, 6.0 - 4.5 * (1.25 * s).min(1.0));
            let mut out = header.clone();
            for (id, x, y, rest) in &rows {
                let t = ((x - 0.5) / 5.5).clamp(0.0, 1.0);
                let table = (clay_top(*x) + rise * (0.05 + 0.45 * t * t)).min(top(*x));
                let pwp = if *y <= table {
                    GAMMA_W * (table - y)
                } else {
                    -(GAMMA_W * (y - table)).min(cap)
                };
                out.push_str(&format!("\n{id},{x},{y},{pwp},{rest}"));
            }
            let path = dir.join(format!("t{k:02}.csv"));
            std::fs::write(&path, out)?;
            Ok((2.0 * 3600.0 * s, path))
        })
        .collect()
}

pub fn fos(args: &BenchArgs) -> anyhow::Result<()> {
    let model = args
        .dir
        .clone()
        .unwrap_or_else(|| PathBuf::from("fixtures/slope"));
    let project = Project::load(&model)?;
    let repeat = args.repeat.max(1);
    let threads = rayon::current_num_threads();

    // One factor: the stand-in field, the default (`fos`) search.
    let fem = fem::load(&FemOptions::files(vec![model.join("sand-nodes.csv")]))?;
    let le = LeOptions::default();
    let mut best = f64::INFINITY;
    let mut report = None;
    for _ in 0..repeat {
        let started = Instant::now();
        let r = fos_time::factor_of_field(&project, &fem, &le)?;
        best = best.min(started.elapsed().as_secs_f64());
        report = Some(r);
    }
    let (factor, generated, refined) = report.map_or((f64::NAN, 0, 0), |r| {
        let s = &r.analysis.search;
        (
            r.factor,
            s.counts.generated,
            s.polyline_refinement.as_ref().map_or(0, |p| p.evaluations),
        )
    });
    say!(
        "bench fos: shipped slope, {} with {generated} trial circles and {refined} non-circular refinements: FS = {factor:.4} in {best:.3} s (best of {repeat}, {threads} threads)",
        le.method.name()
    );

    // FS(t) over 40 tables.
    let tmp = tempfile::tempdir()?;
    let files = series(&model.join("sand-nodes.csv"), tmp.path(), 40)?;
    let input = SeriesInput::Tables {
        files,
        csv: CsvOptions::default(),
        mesh: None,
        vtu: Default::default(),
    };
    let started = Instant::now();
    let loaded = fos_time::load_series(&input)?;
    let read = started.elapsed().as_secs_f64();
    let options = FosTimeOptions {
        srm: false,
        ..FosTimeOptions::default()
    };
    let started = Instant::now();
    let r = fos_time::fos_over_time(&project, &loaded, &options)?;
    let curve = started.elapsed().as_secs_f64();
    say!(
        "bench fos: FS(t) over 40 node tables ({} trial circles a time), {} bisected points: {curve:.2} s (+ {read:.2} s reading); first FS ≤ 1 at {}",
        options.le.search.trials,
        r.curve.iter().filter(|p| p.kind == "bisected").count(),
        r.crossing
            .as_ref()
            .map_or("none".into(), |c| format!("t = {:.1} s", c.time))
    );
    Ok(())
}
