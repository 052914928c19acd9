//! Every command is a library call (#24): `map`, `verify`, `run`, `fos`,
//! `diff`, `inspect` and `calibrate` driven through `a3d_init::pipeline`
//! alone, without the CLI, and their results equal to what the binary writes
//! for the same inputs.

use crate::common;

use std::path::Path;

use a3d_init::kernel::KernelKind;
use a3d_init::kernel::loo::Norm;
use a3d_init::pipeline::calibrate::CalibrateOptions;
use a3d_init::pipeline::check::VerifyOptions;
use a3d_init::pipeline::check::runout::RunOptions;
use a3d_init::pipeline::check::start::StateSource;
use a3d_init::pipeline::diff::DiffOptions;
use a3d_init::pipeline::fem::FemOptions;
use a3d_init::pipeline::io::output::Destination;
use a3d_init::pipeline::map::MapConfig;
use a3d_init::pipeline::map::job::{self, MapJob};
use a3d_init::pipeline::stability::fos::FosOptions;
use a3d_init::pipeline::{self, ErrorKind};
use common::{fixture, mini_regions_csv, run_ok};

fn mini_job(dir: &Path) -> MapJob {
    let fem = dir.join("fem.csv");
    std::fs::write(&fem, mini_regions_csv()).unwrap();
    MapJob {
        model: fixture("anura3d-mini"),
        fem: FemOptions::files(vec![fem]),
        config: MapConfig::default(),
        generate_cps: false,
        fem_vtu: false,
    }
}

#[test]
fn map_verify_run_fos_diff_inspect_and_calibrate_run_without_the_cli() {
    let tmp = tempfile::tempdir().unwrap();
    let job = mini_job(tmp.path());

    // map, twice: the second into an existing folder needs force.
    let out = tmp.path().join("out");
    let (mapped, written) = job::map(&job, Destination::new(Some(&out), false)).unwrap();
    assert_eq!(written.folder, out);
    assert!(
        written.files.iter().any(|f| f == "TwoMat.MAPF"),
        "{:?}",
        written.files
    );
    assert_eq!(mapped.states.len(), mapped.project.points.len());
    let e = job::map(&job, Destination::new(Some(&out), false))
        .err()
        .unwrap();
    assert_eq!(e.kind(), ErrorKind::Output);
    assert!(matches!(e, pipeline::PipelineError::Exists(_)));

    // The binary writes the same files for the same inputs.
    let cli_out = tmp.path().join("cli-out");
    run_ok(&[
        "map",
        "--fem",
        job.fem.paths[0].to_str().unwrap(),
        "--mpm",
        job.model.to_str().unwrap(),
        "--out",
        cli_out.to_str().unwrap(),
    ]);
    for f in &written.files {
        if f != "report.json" {
            assert_eq!(
                std::fs::read(out.join(f)).unwrap(),
                std::fs::read(cli_out.join(f)).unwrap(),
                "{f}"
            );
        }
    }

    // diff: the two folders agree.
    let report = pipeline::diff::diff(&out, &cli_out, &DiffOptions::default()).unwrap();
    assert!(report.equal, "{:?}", report.files);
    assert!(report.files.iter().any(|f| f.kind == "mapf"));

    // verify, from the folder: the state Anura3D will hold.
    let source = StateSource::Folder(out.clone());
    let (outcome, verify_dir) =
        pipeline::check::verify(&source, &VerifyOptions::default(), Destination::default())
            .unwrap();
    assert_eq!(verify_dir, out.join("verify"));
    let check = outcome.anura3d.as_ref().unwrap();
    let table = check.mps_csv.as_ref().unwrap();
    assert_eq!(
        (table.compared, table.unmatched_rows, table.missing),
        (12, 0, 0)
    );
    assert!(outcome.run.is_some());
    for f in pipeline::check::file_names(&outcome) {
        assert!(verify_dir.join(f).is_file(), "{f}");
    }

    // run, a short run-out.
    let run = pipeline::check::runout::run(
        &source,
        &RunOptions {
            time: 0.05,
            snapshots: vec![0.02],
            damping: None,
            drained: false,
        },
        Destination::default(),
    )
    .unwrap();
    assert_eq!(run.snapshots.len(), 1);
    assert!(run.folder.join("run.json").is_file());
    let e = pipeline::check::runout::run(
        &source,
        &RunOptions {
            time: f64::NAN,
            snapshots: vec![],
            damping: None,
            drained: false,
        },
        Destination::new(None, true),
    )
    .err()
    .unwrap();
    assert_eq!(e.kind(), ErrorKind::OptionValue, "{e}");

    // fos (strength reduction: the mini model's ground is level, so limit
    // equilibrium has no slip surface to try, and says so), on the same
    // start verify judged.
    let e = pipeline::stability::fos::fos(
        &source,
        &FosOptions::default(),
        Destination::new(None, true),
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("no trial circle"), "{e}");
    let (fos, fos_dir) =
        pipeline::stability::fos::fos(&source, &FosOptions::srm(), Destination::new(None, true))
            .unwrap();
    assert!(fos.factor.is_finite() && fos.factor > 0.0, "{}", fos.factor);
    assert_eq!(fos.n_points, mapped.states.len());
    assert!(fos_dir.join("fos.json").is_file());

    // inspect: the project, and the FEM.
    let summary = pipeline::inspect::project(&job.model, None, false).unwrap();
    assert_eq!(summary.material_points, mapped.project.points.len());
    assert_eq!(summary.materials.len(), 2);
    let fem = pipeline::inspect::fem(&job.fem).unwrap();
    assert_eq!(fem.reports.len(), 1);
    assert!(fem.fields.iter().any(|f| f.name == "pwp"));

    // calibrate, with a check against the same table.
    let (calibrated, cal_dir) = pipeline::calibrate::calibrate(
        &CalibrateOptions {
            fem: job.fem.clone(),
            field: "pwp".into(),
            kernel: KernelKind::Cubic,
            seed: 1,
            norm: Norm::L1,
            check: Some(job.fem.paths[0].clone()),
        },
        &tmp.path().join("cal"),
        false,
    )
    .unwrap();
    assert!(calibrated.outcome.h > 0.0);
    assert!(calibrated.check.as_ref().unwrap().r2 > 0.99);
    for f in calibrated.file_names() {
        assert!(cal_dir.join(f).is_file(), "{f}");
    }
}

/// Regression (#30): a few duplicated rows appended to mps.csv made `verify`
/// say "mps.csv and the MAPF disagree on 993 of 974 MPs (worst: )". Counts are
/// of MPs compared, never more than the model's; repeated rows are counted as
/// rows that match no MP; an empty worst list is not printed.
#[test]
fn regression_verify_counts_mps_compared_never_more_than_the_model() {
    let tmp = tempfile::tempdir().unwrap();
    let job = mini_job(tmp.path());
    let out = tmp.path().join("out");
    job::map(&job, Destination::new(Some(&out), false)).unwrap();
    let mps = out.join("mps.csv");
    let text = std::fs::read_to_string(&mps).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    let mut edited = text.clone();
    for row in &rows[1..4] {
        edited.push_str(row);
        edited.push('\n');
    }
    std::fs::write(&mps, edited).unwrap();
    let (outcome, _) = pipeline::check::verify(
        &StateSource::Folder(out.clone()),
        &VerifyOptions::default(),
        Destination::default(),
    )
    .unwrap();
    let table = outcome.anura3d.unwrap().mps_csv.unwrap();
    assert_eq!(table.rows, 15);
    assert_eq!(table.compared, 12);
    assert_eq!(table.unmatched_rows, 3);
    assert_eq!(table.missing, 0);
    assert!(table.differing <= table.compared);
    let (_, text) = common::run(&["verify", out.to_str().unwrap()]);
    assert!(
        text.contains("3 of the 15 rows of mps.csv match no MP"),
        "{text}"
    );
    assert!(!text.contains("(worst: )"), "{text}");
    assert!(
        text.contains("mps.csv agrees with what Anura3D reads from the MAPF (12 MPs compared)"),
        "{text}"
    );
}
