//! The pipeline as a library (#16): load, map and write without the CLI, and
//! check the MAPF that comes out; the map's stages called one by one, and the
//! material defaults the report names (#24).

use std::path::Path;

use a3d_init::formats::fem::StepChoice;
use a3d_init::formats::fem_csv::CsvOptions;
use a3d_init::formats::mapf;
use a3d_init::pipeline::Project;
use a3d_init::pipeline::fem::{self, FemOptions};
use a3d_init::pipeline::map::write;
use a3d_init::pipeline::map::{self, MapConfig, StressSource};

#[test]
fn library_map_writes_the_mapf_of_the_sample_slope() {
    let (project, fem) = sample_slope();
    let n_points = project.points.len();
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

fn sample_slope() -> (Project, fem::LoadedFem) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let project = Project::load(&root.join("anura3d/K0_phreaticSurf_Geom")).unwrap();
    let fem = fem::load(&FemOptions {
        paths: vec![root.join("geostudio-csv/k0-slope-hydrostatic.csv")],
        csv: CsvOptions::default(),
        mesh: None,
        analysis: None,
        step: StepChoice::Last,
        vtu: Default::default(),
    })
    .unwrap();
    (project, fem)
}

/// The stages of `map` called one by one, as a library caller would (#24),
/// give the states `map` gives, bit for bit.
#[test]
fn map_stages_run_alone_give_what_map_gives() {
    use a3d_init::kernel::Kernel;
    use map::{inputs, interpolate, mixed, place, plausibility, smoothing, stress};
    let config = MapConfig {
        stress: StressSource::Geostatic,
        ..MapConfig::default()
    };
    let (project, mut fem) = sample_slope();
    inputs::check_fem(&project, &fem).unwrap();
    let source = inputs::stress_source(config.stress, &project, &fem)
        .unwrap()
        .source;
    assert_eq!(source, StressSource::Geostatic);
    let chosen = smoothing::choose_h(&fem.nodes, config.kernel, &config.h, source).unwrap();
    let support = config.kernel.support() * chosen.h;
    let placement = place::place(&project, &fem, None, source, config.outside, support).unwrap();
    // The FEM fields are not needed afterwards: freed once copied.
    let settings = config.settings(chosen.h);
    let (l, keep) = (chosen.spacing, interpolate::KeepNodes::Positions);
    let cloud = interpolate::prepare(&mut fem.nodes, &placement, source, settings, l, keep);
    let mut result =
        interpolate::interpolate(&cloud, &placement, &project.points, &fem.paths).unwrap();
    assert_eq!(interpolate::null_points(&result), 0);
    let values = std::mem::take(&mut result.values);
    let mut states = stress::derive_stress(&project, source, &cloud.quantities, values).states;
    let notes =
        stress::geostatic_stress(&project, &project.mp_positions(), &cloud, &mut states).unwrap();
    assert!(notes[0].contains("overburden"));
    stress::zero_skipped(&mut states, &result.status);
    let collapse = mixed::collapse_mixed(&project, config.mixed_state, &mut states);
    assert_eq!(collapse.applied, Some(map::MixedState::Mean));
    plausibility::check_finite(&states).unwrap();

    let (project, fem) = sample_slope();
    let mapped = map::map(project, fem, &config).unwrap();
    assert_eq!(states, mapped.states);
}

/// A material without ν or K0 in the GOM: the value assumed is named in the
/// report, its notes and its `assumed_defaults` (#24).
#[test]
fn map_report_names_the_material_defaults_it_assumes() {
    let (mut project, fem) = sample_slope();
    let config = MapConfig {
        stress: StressSource::Geostatic,
        ..MapConfig::default()
    };
    let with_k0 = map::map(project, fem, &config).unwrap();
    assert!(with_k0.report.assumed_defaults.is_empty());
    let json = serde_json::to_string(&with_k0.report).unwrap();
    assert!(!json.contains("assumed_defaults"));

    (project, _) = sample_slope();
    project.model.materials[0].k0 = None;
    let (_, fem) = sample_slope();
    let without = map::map(project, fem, &config).unwrap();
    let [assumed] = &without.report.assumed_defaults[..] else {
        panic!("{:?}", without.report.assumed_defaults)
    };
    assert_eq!(assumed.parameter, a3d_init::state::defaults::Parameter::K0);
    assert_eq!((assumed.material, assumed.value), (1, 0.5));
    assert!(without.report.notes.iter().any(|n| n.contains(
        "material 1 `Sand` has no $$K0_VALUE_SOLID: K0 = 0.5 assumed for its geostatic horizontal stress"
    )));
    // K0 = 0.5 is the fixture's own value: the same states.
    assert_eq!(without.states, with_k0.states);
    let json = serde_json::to_value(&without.report).unwrap();
    assert_eq!(json["assumed_defaults"][0]["parameter"], "k0");
}

/// `auto` on the sample slope (pore pressures only, ground not flat) is the
/// equilibrium solve, and the stages run alone give what `map` gives: the
/// pore state collapsed as MPM-MIXED will hold it, then the solve (#25).
#[test]
fn auto_on_a_slope_is_the_equilibrium_stage() {
    use a3d_init::kernel::Kernel;
    use map::{equilibrium, inputs, interpolate, mixed, place, smoothing, stress};
    let config = MapConfig::default();
    let (project, mut fem) = sample_slope();
    let resolved = inputs::stress_source(config.stress, &project, &fem).unwrap();
    assert_eq!(resolved.source, StressSource::Equilibrium);
    assert!(
        resolved.because.contains("not flat"),
        "{}",
        resolved.because
    );
    let source = resolved.source;
    let chosen = smoothing::choose_h(&fem.nodes, config.kernel, &config.h, source).unwrap();
    let support = config.kernel.support() * chosen.h;
    let placement = place::place(&project, &fem, None, source, config.outside, support).unwrap();
    let cloud = interpolate::prepare(
        &mut fem.nodes,
        &placement,
        source,
        config.settings(chosen.h),
        chosen.spacing,
        interpolate::KeepNodes::Nothing,
    );
    let quantities = cloud.quantities.clone();
    let mut result =
        interpolate::interpolate_taking(cloud, &placement, &project.points, &fem.paths).unwrap();
    let values = std::mem::take(&mut result.values);
    let mut states = stress::derive_stress(&project, source, &quantities, values).states;
    stress::zero_skipped(&mut states, &result.status);
    let report = equilibrium::equilibrium_stress(
        &project,
        &mut states,
        config.mixed_state,
        &config.equilibrium,
        resolved.because,
    )
    .unwrap();
    assert!(report.outcome.equilibrium, "{:?}", report.outcome);
    mixed::collapse_mixed(&project, config.mixed_state, &mut states);

    let (project, fem) = sample_slope();
    let mapped = map::map(project, fem, &config).unwrap();
    assert_eq!(states, mapped.states);
    assert_eq!(mapped.report.stress_source, "equilibrium");
}
