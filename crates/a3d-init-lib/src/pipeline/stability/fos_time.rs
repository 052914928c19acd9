//! `fos-time` as a library call: the factor of safety over a time series
//! of FEM pore-pressure fields on one Anura3D model, by limit equilibrium
//! (seconds for the whole curve), and the first time it falls to 1.
//!
//! At each saved time the FEM nodes' pore pressure is interpolated with the
//! kernel onto the section's raster ([`crate::pipeline::stability::slope::raster_field`]; the
//! saturation from each material's retention curve, the unit weights from
//! it), and the critical surface searched. Where the curve first crosses 1
//! between two saved times t₀ and t₁, the time is bisected: the pore
//! pressure at t is interpolated linearly in time node by node,
//! (1 − w)·p(t₀) + w·p(t₁) with w = (t − t₀)/(t₁ − t₀) (the two saved fields
//! must share their nodes). At that time only, strength reduction runs on the
//! MPs (the field mapped with geostatic stress), with its runtime reported.
//!
//! Inputs: every saved step of a GeoStudio `.gsz` analysis (each with its
//! time), or node tables with their times. Writes `fos_time.json`,
//! `fos_vs_time.csv`, `fos_vs_time.svg` and, where the curve reaches 1,
//! `fos_crossing.svg` (the critical surface at that time over the pore
//! pressure).

use std::path::{Path, PathBuf};
use std::time::Instant;

use plotters::style::RGBColor;

use crate::formats::fem::StepChoice;
use crate::formats::fem_csv::CsvOptions;
use crate::formats::fem_vtu::{VtuOptions, pvd};
use crate::formats::gsz::{self};
use crate::model::Quantity;
use crate::mpm::fos::strength_reduction;
use crate::pipeline::PipelineError;
use crate::pipeline::Project;
use crate::pipeline::check::runner;
use crate::pipeline::fem::{FemOptions, LoadedFem};
use crate::pipeline::io::output::{Destination, OutputDir, ReadLog};
use crate::pipeline::io::plot::{self, Series};
use crate::pipeline::map::{MapConfig, Outside, StressSource};
use crate::pipeline::stability::slope::{self as le, LeOptions, LeReport, Section};
use crate::slope::series::first_crossing;

/// Where the time series comes from.
#[derive(Clone, Debug)]
pub enum SeriesInput {
    /// Every saved step of one analysis of a `.gsz` project.
    Gsz {
        path: PathBuf,
        analysis: Option<String>,
        csv: CsvOptions,
    },
    /// Every output of a `.pvd` time series (OpenGeoSys, ParaView), each
    /// at its `timestep`.
    Pvd { path: PathBuf, vtu: VtuOptions },
    /// Node tables (or `.vtu` results), each with its time (s).
    Tables {
        files: Vec<(f64, PathBuf)>,
        csv: CsvOptions,
        mesh: Option<PathBuf>,
        vtu: VtuOptions,
    },
}

/// How `fos-time` runs.
#[derive(Clone, Debug)]
pub struct FosTimeOptions {
    pub le: LeOptions,
    /// Width of the final time bracket (s); `None`: 1 % of the narrowest
    /// saved interval.
    pub bisect_tolerance: Option<f64>,
    /// Run strength reduction at the first time with FS ≤ 1.
    pub srm: bool,
    /// Strength-reduction settings (damping, tolerance, window).
    pub srm_damping: Option<f64>,
}

impl Default for FosTimeOptions {
    fn default() -> Self {
        FosTimeOptions {
            le: LeOptions {
                // A curve of many times: fewer trial circles per time.
                search: crate::slope::SearchSettings {
                    trials: 2000,
                    ..Default::default()
                },
                ..LeOptions::default()
            },
            bisect_tolerance: None,
            srm: true,
            srm_damping: None,
        }
    }
}

impl FosTimeOptions {
    /// Refuses a bracket width that is not a positive number of seconds and
    /// a damping outside [0, 1).
    pub fn check(&self) -> Result<(), PipelineError> {
        if let Some(t) = self.bisect_tolerance
            && !(t.is_finite() && t > 0.0)
        {
            return Err(PipelineError::Option(format!(
                "bisection tolerance {t}: expected a positive number of seconds"
            )));
        }
        crate::pipeline::check::runner::check_damping(self.srm_damping)
    }
}

/// One point of the curve.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CurvePoint {
    pub time: f64,
    pub factor: f64,
    /// `saved` (a FEM output) or `bisected` (interpolated in time).
    pub kind: &'static str,
    pub force_factor: Option<f64>,
    pub moment_factor: Option<f64>,
    pub lambda: Option<f64>,
}

/// Strength reduction at the crossing.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SrmAtCrossing {
    pub time: f64,
    pub factor: f64,
    pub lower: Option<f64>,
    pub upper: Option<f64>,
    pub trials: usize,
    pub runtime_s: f64,
}

/// Where the curve first reaches 1.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CrossingReport {
    pub time: f64,
    pub time_h: f64,
    pub factor: f64,
    /// The last time with FS > 1 and the first with FS ≤ 1.
    pub bracket: (f64, f64),
    pub analysis: LeReport,
}

/// What `fos-time` found.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FosTimeReport {
    pub method: &'static str,
    /// Saved and bisected points, by time.
    pub curve: Vec<CurvePoint>,
    pub crossing: Option<CrossingReport>,
    /// How the pore pressure between two saved times is taken.
    pub interpolation: String,
    pub bisect_tolerance: f64,
    /// Limit equilibrium for the whole curve, bisection included (s).
    pub limit_equilibrium_runtime_s: f64,
    pub strength_reduction: Option<SrmAtCrossing>,
    pub notes: Vec<String>,
}

impl FosTimeReport {
    /// (time, factor) at each saved time, in time order: one per output of
    /// the series.
    pub fn saved(&self) -> Vec<(f64, f64)> {
        self.curve
            .iter()
            .filter(|p| p.kind == "saved")
            .map(|p| (p.time, p.factor))
            .collect()
    }

    /// The index in the series of the first saved time with FS ≤ 1: the
    /// output `map --step failure` maps.
    pub fn first_failing_output(&self) -> Option<usize> {
        self.saved().iter().position(|&(_, f)| f <= 1.0)
    }
}

/// The series the input names: (time, FEM nodes), times ascending.
pub fn load_series(input: &SeriesInput) -> Result<Vec<(f64, LoadedFem)>, PipelineError> {
    let mut series = Vec::new();
    match input {
        SeriesInput::Gsz {
            path,
            analysis,
            csv,
        } => {
            let project = gsz::read_project(path)?;
            let chosen = match analysis {
                None if project.analyses.len() == 1 => &project.analyses[0],
                None => {
                    return Err(PipelineError::Option(format!(
                        "{}: {} analyses; make the analysis choice by name or index",
                        path.display(),
                        project.analyses.len()
                    )));
                }
                Some(key) => project
                    .analyses
                    .iter()
                    .find(|a| &a.name == key || key.parse::<usize>().ok() == Some(a.index))
                    .ok_or_else(|| {
                        PipelineError::Option(format!("{}: no analysis `{key}`", path.display()))
                    })?,
            };
            for step in &chosen.steps {
                let Some(time) = step.time else {
                    return Err(PipelineError::Input(format!(
                        "{}: step {} of `{}` has no time; FS(t) needs the time of every saved step",
                        path.display(),
                        step.folder,
                        chosen.name
                    )));
                };
                let options = FemOptions {
                    paths: vec![path.clone()],
                    csv: csv.clone(),
                    mesh: None,
                    analysis: Some(chosen.index.to_string()),
                    step: StepChoice::Number(step.number),
                    vtu: VtuOptions::default(),
                };
                series.push((time, crate::pipeline::fem::load(&options)?));
            }
        }
        SeriesInput::Pvd { path, vtu } => {
            for output in pvd::read(path)?.outputs {
                let options = FemOptions {
                    vtu: vtu.clone(),
                    ..FemOptions::files(vec![output.file])
                };
                series.push((output.time, crate::pipeline::fem::load(&options)?));
            }
        }
        SeriesInput::Tables {
            files,
            csv,
            mesh,
            vtu,
        } => {
            for (time, path) in files {
                let options = FemOptions {
                    paths: vec![path.clone()],
                    csv: csv.clone(),
                    mesh: mesh.clone(),
                    analysis: None,
                    step: StepChoice::Last,
                    vtu: vtu.clone(),
                };
                series.push((*time, crate::pipeline::fem::load(&options)?));
            }
        }
    }
    if series.len() < 2 {
        return Err(PipelineError::Input(format!(
            "a time series needs at least two saved times, got {}",
            series.len()
        )));
    }
    if series.iter().any(|(t, _)| !t.is_finite()) {
        return Err(PipelineError::Option(
            "every time must be a finite number".into(),
        ));
    }
    series.sort_by(|a, b| a.0.total_cmp(&b.0));
    if series.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err(PipelineError::Option(
            "two saved fields have the same time".into(),
        ));
    }
    Ok(series)
}

/// The pore pressures and materials of one saved field, nodes outside the
/// section left out.
struct Field {
    positions: Vec<[f64; 3]>,
    pwp: Vec<f64>,
    material: Vec<u32>,
}

fn field(section: &Section, fem: &LoadedFem, time: f64) -> Result<Field, PipelineError> {
    let pwp = fem.nodes.field(Quantity::Pwp).ok_or_else(|| {
        PipelineError::Input(format!(
            "the FEM field at t = {time} s has no pore pressure"
        ))
    })?;
    let mut f = Field {
        positions: Vec::new(),
        pwp: Vec::new(),
        material: Vec::new(),
    };
    for (p, &v) in fem.nodes.positions.iter().zip(pwp) {
        let region = section
            .domain
            .region_at(p[0], p[1])
            .or_else(|| section.domain.region_at(p[0], p[1] - 1e-9));
        if let Some(k) = region {
            f.positions.push(*p);
            f.pwp.push(v);
            f.material
                .push(section.domain.regions()[k].material as u32 + 1);
        }
    }
    if f.positions.is_empty() {
        return Err(PipelineError::Input(format!(
            "no FEM node of the field at t = {time} s lies inside the model's section"
        )));
    }
    Ok(f)
}

fn factor_of(
    project: &Project,
    section: &Section,
    f: &Field,
    options: &LeOptions,
) -> Result<LeReport, PipelineError> {
    let values = le::PointValues {
        positions: &f.positions,
        pwp: &f.pwp,
        saturation: None,
        material: &f.material,
        source: "FEM nodes",
    };
    let (raster, note) = le::raster_field(section, &project.model, &values, options.h)?;
    let weighted = le::weights_from_field(&project.model, section, &raster)?;
    le::analyse(&weighted, &raster, note, options)
}

fn point(time: f64, kind: &'static str, r: &LeReport) -> CurvePoint {
    CurvePoint {
        time,
        factor: r.factor,
        kind,
        force_factor: r.force_factor,
        moment_factor: r.moment_factor,
        lambda: r.lambda,
    }
}

/// The section of `project` with every element saturated (the unit weights
/// then follow each field's pore pressures).
fn series_section(project: &Project) -> Result<Section, PipelineError> {
    let gravity = project.gravity();
    le::build_section(
        &project.model,
        gravity,
        &vec![1.0; project.model.mesh.n_elements()],
    )
}

/// The limit-equilibrium factor of one FEM field on `project`, as one point
/// of [`fos_over_time`] computes it (writes nothing).
pub fn factor_of_field(
    project: &Project,
    fem: &LoadedFem,
    options: &LeOptions,
) -> Result<LeReport, PipelineError> {
    let section = series_section(project)?;
    let f = field(&section, fem, 0.0)?;
    factor_of(project, &section, &f, options)
}

/// FS(t) over `series` on `project` (writes nothing).
pub fn fos_over_time(
    project: &Project,
    series: &[(f64, LoadedFem)],
    options: &FosTimeOptions,
) -> Result<FosTimeReport, PipelineError> {
    let started = Instant::now();
    options.check()?;
    let section = series_section(project)?;
    let fields: Vec<Field> = series
        .iter()
        .map(|(t, fem)| field(&section, fem, *t))
        .collect::<Result<_, _>>()?;
    let mut curve = Vec::new();
    let mut saved = Vec::new();
    let mut reports = Vec::new();
    // Each time's search also starts from the best of the critical surfaces
    // of the times before: where the pore pressures only worsen, the factor
    // cannot rise by the search missing a surface it found before.
    let mut le = options.le.clone();
    for ((t, _), f) in series.iter().zip(&fields) {
        let r = factor_of(project, &section, f, &le)?;
        le.search.starts.push(r.critical_surface.clone());
        curve.push(point(*t, "saved", &r));
        saved.push((*t, r.factor));
        reports.push(r);
    }
    let narrowest = series
        .windows(2)
        .map(|w| w[1].0 - w[0].0)
        .fold(f64::INFINITY, f64::min);
    let tolerance = options.bisect_tolerance.unwrap_or(0.01 * narrowest);
    let mut notes: Vec<String> = series
        .iter()
        .zip(&reports)
        .find_map(|((t, _), r)| {
            r.warnings
                .first()
                .map(|w| format!("from t = {t} s on, {w}"))
        })
        .into_iter()
        .collect();
    let mut at_crossing: Option<(LeReport, Field)> = None;
    let crossing = {
        let k = saved.iter().position(|&(_, f)| f <= 1.0);
        let interpolable = |k: usize| k > 0 && fields[k - 1].positions == fields[k].positions;
        match k {
            Some(k) if k > 0 && !interpolable(k) => {
                notes.push(format!(
                    "the fields at t = {} s and {} s do not share their nodes: the crossing is not bisected",
                    series[k - 1].0, series[k].0
                ));
                None
            }
            _ => {
                let mut bisected: Vec<(CurvePoint, LeReport, Field)> = Vec::new();
                let c = first_crossing(&saved, tolerance, |t| {
                    let k = k.unwrap_or(0);
                    let (t0, t1) = (series[k - 1].0, series[k].0);
                    let w = (t - t0) / (t1 - t0);
                    let (a, b) = (&fields[k - 1], &fields[k]);
                    let f = Field {
                        positions: a.positions.clone(),
                        pwp: a
                            .pwp
                            .iter()
                            .zip(&b.pwp)
                            .map(|(p, q)| (1.0 - w) * p + w * q)
                            .collect(),
                        material: a.material.clone(),
                    };
                    // The critical surfaces of the saved times and of the
                    // bisection so far as starts too.
                    let mut le = options.le.clone();
                    le.search.starts = reports
                        .iter()
                        .chain(bisected.iter().map(|b| &b.1))
                        .map(|r| r.critical_surface.clone())
                        .collect();
                    let r = factor_of(project, &section, &f, &le)?;
                    bisected.push((point(t, "bisected", &r), r, f));
                    Ok::<f64, PipelineError>(bisected.last().map_or(f64::NAN, |b| b.0.factor))
                })?;
                if let Some(c) = &c {
                    // The report and field at the crossing time.
                    let found = bisected.iter().find(|b| b.0.time == c.time);
                    let k = k.unwrap_or(0);
                    match found {
                        Some((_, r, f)) => {
                            let f = Field {
                                positions: f.positions.clone(),
                                pwp: f.pwp.clone(),
                                material: f.material.clone(),
                            };
                            at_crossing = Some((r.clone(), f));
                        }
                        None => {
                            let f = Field {
                                positions: fields[k].positions.clone(),
                                pwp: fields[k].pwp.clone(),
                                material: fields[k].material.clone(),
                            };
                            at_crossing = Some((reports[k].clone(), f));
                        }
                    }
                }
                curve.extend(bisected.into_iter().map(|b| b.0));
                c
            }
        }
    };
    curve.sort_by(|a, b| a.time.total_cmp(&b.time));
    let limit_equilibrium_runtime_s = started.elapsed().as_secs_f64();
    let crossing_report = match (crossing, &at_crossing) {
        (Some(c), Some((r, _))) => Some(CrossingReport {
            time: c.time,
            time_h: c.time / 3600.0,
            factor: c.factor,
            bracket: c.bracket,
            analysis: r.clone(),
        }),
        _ => None,
    };
    let strength_reduction = match (&crossing_report, &at_crossing) {
        (Some(c), Some((_, f))) if options.srm => {
            Some(srm_at(project, series, f, c.time, options)?)
        }
        _ => None,
    };
    Ok(FosTimeReport {
        method: options.le.method.name(),
        curve,
        crossing: crossing_report,
        interpolation: "pore pressure linear in time between the two saved fields, node by node"
            .into(),
        bisect_tolerance: tolerance,
        limit_equilibrium_runtime_s,
        strength_reduction,
        notes,
    })
}

/// Strength reduction on the MPs with the field at the crossing mapped onto
/// them (geostatic total stress, the spacing rule for h).
fn srm_at(
    project: &Project,
    series: &[(f64, LoadedFem)],
    f: &Field,
    time: f64,
    options: &FosTimeOptions,
) -> Result<SrmAtCrossing, PipelineError> {
    let started = Instant::now();
    let template = &series[0].1;
    let mut nodes = template.nodes.clone();
    nodes.positions = f.positions.clone();
    nodes.ids = (1..=f.positions.len() as i64).collect();
    // Each node labelled with the material it lies in, as a FEM region.
    nodes.region = Some(
        f.material
            .iter()
            .map(|&m| project.model.materials[m as usize - 1].name.clone())
            .collect(),
    );
    nodes.fields = vec![(Quantity::Pwp, f.pwp.clone())];
    let fem = LoadedFem {
        nodes,
        reports: template.reports.clone(),
        paths: template.paths.clone(),
        sign: template.sign,
        notes: Vec::new(),
    };
    let again = Project::load(&project.files.dir)?;
    let config = MapConfig {
        stress: StressSource::Geostatic,
        outside: Outside::Nearest,
        ..MapConfig::default()
    };
    let mapped = crate::pipeline::map::map(again, fem, &config)?;
    // As `fos --method srm` runs it: the pore pressures held.
    let mut settings = crate::pipeline::stability::fos::FosOptions {
        damping: options.srm_damping,
        ..crate::pipeline::stability::fos::FosOptions::srm()
    }
    .settings(project.cps.as_ref());
    settings.run = runner::with_project(settings.run, &mapped.project)?.0;
    // A factor of safety is of the slope under its full weight.
    settings.run.loads.gravity = crate::model::loads::Multiplier::FULL;
    let report = strength_reduction(
        &mapped.project.model,
        &mapped.project.points,
        &mapped.states,
        &settings,
    )
    .map_err(|e| PipelineError::Numerical(e.to_string()))?;
    Ok(SrmAtCrossing {
        time,
        factor: report.factor,
        lower: report.lower,
        upper: report.upper,
        trials: report.iterations,
        runtime_s: started.elapsed().as_secs_f64(),
    })
}

/// The files [`fos_time`] writes.
pub fn file_names(report: &FosTimeReport) -> Vec<&'static str> {
    let mut v = vec!["fos_time.json", "fos_vs_time.csv", "fos_vs_time.svg"];
    if report.crossing.is_some() {
        v.push("fos_crossing.svg");
    }
    v
}

/// `fos-time`: the model (a GOM, CPS or folder), the series, the curve and
/// its files in `out`.
pub fn fos_time(
    model: &Path,
    input: &SeriesInput,
    options: &FosTimeOptions,
    to: Destination<'_>,
) -> Result<(FosTimeReport, PathBuf), PipelineError> {
    options.check()?;
    let reads = ReadLog::start();
    let project = Project::load(model)?;
    let series = load_series(input)?;
    let target = to.or(|| project.files.dir.join("fos_time"));
    let dir = OutputDir::create(&target, to.replace, &reads, "fos-time")?;
    let report = fos_over_time(&project, &series, options)?;
    write_outputs(&dir, &report, &series)?;
    Ok((report, dir.commit()?))
}

/// Writes `fos_time.json`, `fos_vs_time.csv`, `fos_vs_time.svg` and, with a
/// crossing, `fos_crossing.svg` into `dir`.
pub fn write_outputs(
    dir: &OutputDir,
    report: &FosTimeReport,
    series: &[(f64, LoadedFem)],
) -> Result<(), PipelineError> {
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| PipelineError::Output(format!("fos_time.json: {e}")))?;
    dir.write("fos_time.json", |w| w.write_all(json.as_bytes()))?;
    dir.write("fos_vs_time.csv", |w| {
        writeln!(
            w,
            "time_s,time_h,factor,kind,force_factor,moment_factor,lambda"
        )?;
        let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        for p in &report.curve {
            writeln!(
                w,
                "{},{},{},{},{},{},{}",
                p.time,
                p.time / 3600.0,
                p.factor,
                p.kind,
                opt(p.force_factor),
                opt(p.moment_factor),
                opt(p.lambda)
            )?;
        }
        Ok(())
    })?;
    curve_plot(&dir.path("fos_vs_time.svg"), report)?;
    if let Some(c) = &report.crossing {
        let field: Vec<(f64, f64, f64)> = crossing_field(series, c.time);
        le::write_surface_plot(
            &dir.path("fos_crossing.svg"),
            &format!(
                "First FS ≤ 1: t = {:.3} h, {} FS = {:.3}",
                c.time_h, c.analysis.method, c.factor
            ),
            &c.analysis,
            &field,
            &c.analysis.ground,
        )?;
    }
    Ok(())
}

/// The FEM nodes' pore pressure at `time`, interpolated between the saved
/// fields around it (for the plot).
fn crossing_field(series: &[(f64, LoadedFem)], time: f64) -> Vec<(f64, f64, f64)> {
    let k = series
        .partition_point(|(t, _)| *t < time)
        .min(series.len() - 1);
    let (t1, b) = (&series[k].0, &series[k].1);
    let (a_t, a) = if k > 0 {
        (series[k - 1].0, &series[k - 1].1)
    } else {
        (*t1, b)
    };
    let w = if *t1 > a_t {
        (time - a_t) / (t1 - a_t)
    } else {
        1.0
    };
    let (Some(pa), Some(pb)) = (a.nodes.field(Quantity::Pwp), b.nodes.field(Quantity::Pwp)) else {
        return Vec::new();
    };
    let same = a.nodes.positions == b.nodes.positions;
    b.nodes
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let v = if same {
                (1.0 - w) * pa[i] + w * pb[i]
            } else {
                pb[i]
            };
            (p[0], p[1], v)
        })
        .collect()
}

fn curve_plot(path: &Path, report: &FosTimeReport) -> Result<(), PipelineError> {
    let pts = |kind: &str| -> Vec<(f64, f64)> {
        report
            .curve
            .iter()
            .filter(|p| p.kind == kind)
            .map(|p| (p.time / 3600.0, p.factor))
            .collect()
    };
    let saved = pts("saved");
    let (t0, t1) = saved
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.0), b.max(p.0))
        });
    let mut series = vec![
        Series {
            label: "FS(t), saved outputs",
            points: saved.clone(),
            color: RGBColor(31, 119, 180),
            markers: false,
        },
        Series {
            label: "saved output",
            points: saved,
            color: RGBColor(31, 119, 180),
            markers: true,
        },
        Series {
            label: "bisected",
            points: pts("bisected"),
            color: RGBColor(255, 127, 14),
            markers: true,
        },
        Series {
            label: "FS = 1",
            points: vec![(t0, 1.0), (t1, 1.0)],
            color: RGBColor(120, 120, 120),
            markers: false,
        },
    ];
    if let Some(c) = &report.crossing {
        series.push(Series {
            label: "first FS ≤ 1",
            points: vec![(c.time_h, c.factor)],
            color: RGBColor(214, 39, 40),
            markers: true,
        });
    }
    plot::line_chart(
        path,
        &format!("Factor of safety over time ({})", report.method),
        "time (h)",
        "factor of safety (–)",
        &series,
        false,
    )
}
