//! The pipeline as a library (#16): load, map and write without the CLI, and
//! check the MAPF that comes out.

use std::path::Path;

use a3d_init::formats::fem_csv::CsvOptions;
use a3d_init::formats::gsz::StepChoice;
use a3d_init::formats::mapf;
use a3d_init::pipeline::fem::{self, FemOptions};
use a3d_init::pipeline::map::{self, MapConfig, StressSource};
use a3d_init::pipeline::{Project, write};

#[test]
fn library_map_writes_the_mapf_of_the_sample_slope() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let project = Project::load(&root.join("anura3d/K0_phreaticSurf_Geom")).unwrap();
    let n_points = project.points.len();
    let fem = fem::load(&FemOptions {
        paths: vec![root.join("geostudio-csv/k0-slope-hydrostatic.csv")],
        csv: CsvOptions::default(),
        mesh: None,
        analysis: None,
        step: StepChoice::Last,
    })
    .unwrap();
    let config = MapConfig {
        stress: StressSource::Geostatic,
        ..MapConfig::default()
    };
    let mapped = map::map(project, fem, &config).unwrap();
    assert_eq!(mapped.states.len(), n_points);
    let tmp = tempfile::tempdir().unwrap();
    let written = write::write_project(&mapped, tmp.path(), false).unwrap();
    assert!(written.contains(&"K0_phreaticSurf_Geom.MAPF".to_string()));
    let table = mapf::read(&tmp.path().join("K0_phreaticSurf_Geom.MAPF")).unwrap();
    assert_eq!(table.rows.len(), n_points);
    let (x, pwp, sig_y) = (
        table.column("X[m]").unwrap(),
        table.column("Pwp[kPa]").unwrap(),
        table.column("SigY[kPa]").unwrap(),
    );
    for (row, (p, s)) in table
        .rows
        .iter()
        .zip(mapped.project.points.iter().zip(&mapped.states))
    {
        assert_eq!(row[x], p.position[0]);
        assert_eq!(row[pwp], s.pwp);
        assert_eq!(row[sig_y], s.total[1]);
        assert!(s.total[1] <= 0.0, "geostatic σyy is compressive");
    }
    // The notes promised in the report reach it (one notes list, #16).
    assert!(mapped.report.notes.iter().any(|n| n.contains("overburden")));
}
