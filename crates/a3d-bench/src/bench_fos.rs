//! `a3d-bench fos`: the speed figures of limit equilibrium on the shipped slope
//! (`fixtures/slope`, run from the repository root, or `--dir` naming the
//! model folder): its Morgenstern–Price factor with the default search (about
//! 5,000 trial circles, then the non-circular refinement) on the stand-in
//! pore pressures, and FS(t) by limit equilibrium over 40 generated node
//! tables of a table rising to the ground, bisected where it crosses 1.
//! Printed, never asserted.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;

use crate::BenchArgs;
use a3d_init::formats::fem_csv::CsvOptions;
use a3d_init::pipeline::Project;
use a3d_init::pipeline::fem::{self, FemOptions};
use a3d_init::pipeline::stability::fos_time::{self, FosTimeOptions, SeriesInput};
use a3d_init::pipeline::stability::slope::LeOptions;
use a3d_testkit::generate;

/// [`generate::rising_table_series`] written as node tables into `dir`.
fn series(nodes_csv: &Path, dir: &Path, n: usize) -> anyhow::Result<Vec<(f64, PathBuf)>> {
    let text = std::fs::read_to_string(nodes_csv)
        .with_context(|| format!("{}: cannot read", nodes_csv.display()))?;
    let tables = generate::rising_table_series(&text, n)
        .map_err(|e| anyhow::anyhow!("{}: {e}", nodes_csv.display()))?;
    tables
        .into_iter()
        .enumerate()
        .map(|(k, (time, table))| {
            let path = dir.join(format!("t{k:02}.csv"));
            std::fs::write(&path, table)?;
            Ok((time, path))
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
