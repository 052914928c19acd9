//! FS(t) by limit equilibrium over a time series of FEM fields (#31), on the
//! shipped slope: a synthetic series whose pore pressures rise monotonically
//! (a perched water table rising over the clay, suction falling) gives a
//! factor of safety that falls monotonically (within 0.01), crosses 1, and is
//! bisected in time to the tolerance asked; the files are written.

use crate::common;
use common::*;

use std::path::{Path, PathBuf};

use a3d_init::formats::fem_csv::CsvOptions;
use a3d_init::pipeline::io::output::Destination;
use a3d_init::pipeline::stability::fos_time::{self, FosTimeOptions, SeriesInput};
use a3d_testkit::generate;

/// Node tables at `n` times over 2 h, the table rising from 0 to 1.8 times
/// the stand-in's and the suction cap falling from 6 to 1.5 kPa
/// ([`generate::rising_table_series`]).
fn series(dir: &Path, n: usize) -> Vec<(f64, PathBuf)> {
    let text = std::fs::read_to_string(fixture("slope/sand-nodes.csv")).unwrap();
    generate::rising_table_series(&text, n)
        .unwrap()
        .into_iter()
        .enumerate()
        .map(|(k, (time, table))| {
            let path = dir.join(format!("t{k:02}.csv"));
            std::fs::write(&path, table).unwrap();
            (time, path)
        })
        .collect()
}

#[test]
fn fs_over_time_of_a_rising_water_table_is_monotone_and_crosses_one() {
    let tmp = tempfile::tempdir().unwrap();
    let files = series(tmp.path(), 40);
    let input = SeriesInput::Tables {
        files,
        csv: CsvOptions::default(),
        mesh: None,
        vtu: Default::default(),
    };
    let options = FosTimeOptions {
        srm: false,
        bisect_tolerance: Some(5.0),
        ..FosTimeOptions::default()
    };
    let out = tmp.path().join("fos_time");
    let (report, dir) = fos_time::fos_time(
        &fixture("slope"),
        &input,
        &options,
        Destination::new(Some(&out), false),
    )
    .unwrap();
    let saved: Vec<(f64, f64)> = report
        .curve
        .iter()
        .filter(|p| p.kind == "saved")
        .map(|p| (p.time, p.factor))
        .collect();
    assert_eq!(saved.len(), 40);
    // Monotone within 0.01, over the whole curve (bisected points included).
    for w in report.curve.windows(2) {
        assert!(
            w[1].factor <= w[0].factor + 0.01,
            "FS rises from {:.4} at {} s to {:.4} at {} s",
            w[0].factor,
            w[0].time,
            w[1].factor,
            w[1].time
        );
    }
    assert!(saved[0].1 > 1.2, "{saved:?}");
    // The table stops at the ground: no water stands above it.
    assert!(
        report.notes.iter().all(|n| !n.contains("ponding")),
        "{:?}",
        report.notes
    );
    let c = report.crossing.as_ref().expect("the curve crosses 1");
    assert!(c.factor <= 1.0 && c.bracket.1 - c.bracket.0 <= 5.0, "{c:?}");
    // The saved factor just before the crossing is above 1, the one after at
    // or below 1.
    let k = saved.iter().position(|s| s.1 <= 1.0).unwrap();
    assert!(saved[k - 1].0 <= c.bracket.0 && c.time <= saved[k].0);
    for f in fos_time::file_names(&report) {
        assert!(dir.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(dir.join("fos_vs_time.csv")).unwrap();
    assert_eq!(csv.lines().count(), report.curve.len() + 1);
}

/// A `.gsz` series is every saved step of its analysis, in time order, each
/// with its time (the shipped SEEP/W column: 51 steps, 0 to 129,600 s).
#[test]
fn a_gsz_series_is_every_saved_step_with_its_time() {
    let input = SeriesInput::Gsz {
        path: fixture("geostudio-gsz-internal/1d-unsaturated-column/1D_unsaturated_column.gsz"),
        analysis: None,
        csv: CsvOptions::default(),
    };
    let series = fos_time::load_series(&input).unwrap();
    assert_eq!(series.len(), 51);
    assert_eq!(series[0].0, 0.0);
    assert_eq!(series[50].0, 129_600.0);
    assert!(series.windows(2).all(|w| w[1].0 > w[0].0));
    assert!(series.iter().all(|(_, f)| f.nodes.len() == 306));
}

/// The shipped OpenGeoSys rain series (#26) read as a `.pvd`: every output
/// at its time, limit equilibrium on each, and the first FS ≤ 1 bisected
/// between two saved outputs.
#[test]
fn fs_over_time_of_the_shipped_ogs_rain_crosses_one_between_two_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let input = SeriesInput::Pvd {
        path: fixture("slope/ogs/results/rain.pvd"),
        vtu: Default::default(),
    };
    let options = FosTimeOptions {
        srm: false,
        bisect_tolerance: Some(5.0),
        ..FosTimeOptions::default()
    };
    let (report, _) = fos_time::fos_time(
        &fixture("slope"),
        &input,
        &options,
        Destination::new(Some(&tmp.path().join("fos_time")), false),
    )
    .unwrap();
    let saved: Vec<(f64, f64)> = report
        .curve
        .iter()
        .filter(|p| p.kind == "saved")
        .map(|p| (p.time, p.factor))
        .collect();
    let outputs = a3d_init::formats::fem_vtu::pvd::read(&fixture("slope/ogs/results/rain.pvd"))
        .unwrap()
        .outputs;
    assert_eq!(saved.len(), outputs.len());
    assert!(saved.iter().zip(&outputs).all(|(s, o)| s.0 == o.time));
    // Dry sand at the start stands; the saturated slope at the end does not.
    assert!(saved[0].1 > 1.2, "FS at t = 0: {}", saved[0].1);
    assert!(saved.last().unwrap().1 < 1.0);
    let crossing = report.crossing.as_ref().expect("FS falls to 1");
    let before = saved.iter().rev().find(|s| s.0 < crossing.time).unwrap();
    let after = saved.iter().find(|s| s.0 >= crossing.time).unwrap();
    assert!(before.1 > 1.0 && after.1 <= 1.0, "{before:?} {after:?}");
    assert!(crossing.time - before.0 > 0.0 && after.0 - crossing.time >= 0.0);
}

/// The factor at the shipped OGS output of 1.29 h does not depend on the
/// number of trial circles (#39): the circles are refined in (entry, exit,
/// half-angle), and the non-circular refinement starts from a fixed grid of
/// translational surfaces as well as from the circles, so 2,000, 5,000 and
/// 20,000 circles end within 0.002.
#[test]
fn the_factor_at_the_129_h_output_does_not_depend_on_the_trial_count() {
    let project = a3d_init::pipeline::Project::load(&fixture("slope")).unwrap();
    let series = fos_time::load_series(&SeriesInput::Pvd {
        path: fixture("slope/ogs/results/rain.pvd"),
        vtu: Default::default(),
    })
    .unwrap();
    let fem = &series.iter().find(|s| s.0 == 4644.0).unwrap().1;
    let docs = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/slope.md"),
    )
    .unwrap();
    let factors: Vec<f64> = [(2000, "2,000"), (5000, "5,000"), (20000, "20,000")]
        .iter()
        .map(|&(trials, label)| {
            let mut le = a3d_init::pipeline::stability::slope::LeOptions::default();
            le.search.trials = trials;
            let report = fos_time::factor_of_field(&project, fem, &le).unwrap();
            // docs/slope.md's table quotes the factor and the best circle.
            let quoted = format!(
                "| {:.4} ({:.4}) |",
                report.factor, report.analysis.circular.factor
            );
            let row = docs
                .lines()
                .find(|l| l.starts_with(&format!("| {label} |")))
                .unwrap_or_default();
            assert!(
                row.ends_with(&quoted),
                "docs/slope.md's {label} row should end `{quoted}`: {row}"
            );
            report.factor
        })
        .collect();
    let (lo, hi) = factors
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &f| {
            (a.min(f), b.max(f))
        });
    assert!(hi - lo <= 0.002, "{factors:?}");
    // A slope at its failure time: below the best circle's 1.02.
    assert!(hi < 1.0, "{factors:?}");
    // Where the search has not converged yet (t = 0, no slab along the
    // clay), docs/slope.md quotes the spread as measured.
    let first = &series[0].1;
    let (mut at_zero, mut circles) = (Vec::new(), Vec::new());
    for trials in [2000, 5000, 20000] {
        let mut le = a3d_init::pipeline::stability::slope::LeOptions::default();
        le.search.trials = trials;
        let report = fos_time::factor_of_field(&project, first, &le).unwrap();
        at_zero.push(format!("{:.4}", report.factor));
        circles.push(format!("{:.3}", report.analysis.circular.factor));
    }
    let flat = docs.split_whitespace().collect::<Vec<_>>().join(" ");
    let quoted = format!(
        "is {}, {} and {} for 2,000, 5,000 and 20,000 circles",
        at_zero[0], at_zero[1], at_zero[2]
    );
    assert!(
        flat.contains(&quoted),
        "docs/slope.md should say `{quoted}`"
    );
    let quoted = format!("differ ({})", circles.join(", "));
    assert!(
        flat.contains(&quoted),
        "docs/slope.md should say `{quoted}`"
    );
}

/// `map --step failure` on a series that never fails says so and exits 2,
/// writing nothing; a single table or a reader given `failure` is refused
/// with the reason (#39).
#[test]
fn step_failure_without_a_failing_output_is_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    // The first three outputs of the shipped rain: FS ≥ 1.3.
    let results = fixture("slope/ogs/results");
    let mut pvd = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
    );
    for t in [0, 180, 360] {
        let name = format!("rain_t_{t}.vtu");
        std::fs::copy(results.join(&name), tmp.path().join(&name)).unwrap();
        pvd.push_str(&format!(
            "<DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{name}\"/>\n"
        ));
    }
    pvd.push_str("</Collection>\n</VTKFile>\n");
    let series = tmp.path().join("dry.pvd");
    std::fs::write(&series, pvd).unwrap();
    let out = tmp.path().join("out");
    let model = fixture("slope");
    let run = |fem: &std::path::Path, extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_a3d-init"))
            .args(["map", "--fem", fem.to_str().unwrap(), "--step", "failure"])
            .args([
                "--mpm",
                model.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .args(["--material-map", "mat0=silty_sand"])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&series, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no saved step fails") && err.contains("dry.pvd"),
        "{err}"
    );
    assert!(!out.exists(), "nothing is written");
    let o = run(&fixture("slope/sand-nodes.csv"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("needs one time series"), "{err}");
    let o = run(&series, &["--failure-method", "srm"]);
    assert_eq!(o.status.code(), Some(2));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_a3d-init"))
        .args([
            "inspect",
            "--fem",
            series.to_str().unwrap(),
            "--step",
            "failure",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("`map` finds it against the model"), "{err}");
    assert!(!out.exists());
}

/// The OGS README's *What OGS computes* table quotes the mean saturation
/// and the pressure range of the shipped results at seven times (OGS's sign,
/// kPa): the files say so (#39).
#[test]
fn the_ogs_readme_quotes_the_shipped_pressure_ranges() {
    use a3d_init::model::Quantity;
    let series = fos_time::load_series(&SeriesInput::Pvd {
        path: fixture("slope/ogs/results/rain.pvd"),
        vtu: Default::default(),
    })
    .unwrap();
    let readme = std::fs::read_to_string(fixture("slope/ogs/README.md")).unwrap();
    let kpa = |v: f64| {
        let s = format!("{:.2}", v.abs());
        if v < 0.0 && s != "0.00" {
            format!("−{s}")
        } else {
            s
        }
    };
    for (hours, label) in [
        (0.0, "0"),
        (0.5, "0.5"),
        (1.0, "1.0"),
        (1.2, "1.2"),
        (1.3, "1.3"),
        (1.5, "1.5"),
        (2.0, "2.0"),
    ] {
        let fem = &series
            .iter()
            .find(|s| (s.0 - hours * 3600.0).abs() < 1.0)
            .unwrap_or_else(|| panic!("no output at {hours} h"))
            .1;
        // Loaded in Anura3D's sign (compression negative): OGS's p is −that.
        let p = fem.nodes.field(Quantity::Pwp).unwrap();
        let (lo, hi) = p
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(-v), b.max(-v))
            });
        // Mean S over the nodes, S from p by the README's retention curve
        // (van Genuchten, p_b = 1/α = 1/0.51 kPa, n = 2.73, S 0.1 .. 1).
        let n = 2.73;
        let m = 1.0 - 1.0 / n;
        let saturation = |p_ogs: f64| {
            if p_ogs >= 0.0 {
                1.0
            } else {
                0.1 + 0.9 * (1.0 + (-p_ogs * 0.51).powf(n)).powf(-m)
            }
        };
        let mean_s = p.iter().map(|&v| saturation(-v)).sum::<f64>() / p.len() as f64;
        let range = if kpa(lo) == kpa(hi) {
            format!("| {} everywhere |", kpa(lo))
        } else {
            format!("| {} .. {} |", kpa(lo), kpa(hi))
        };
        let row = readme
            .lines()
            .find(|l| l.starts_with(&format!("| {label} |")))
            .unwrap_or_default();
        let mean = format!("| {label} | {mean_s:.2} |");
        assert!(
            row.starts_with(&mean),
            "the OGS README's {label} h row should start `{mean}`: {row}"
        );
        assert!(
            row.contains(&range),
            "the OGS README's {label} h row should hold `{range}`: {row}"
        );
    }
}
