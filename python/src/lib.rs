//! `a3d_init._native`: the Python extension behind the `a3d_init` package.
//! Every function here is one call of the Rust library's pipeline
//! (`a3d_init::pipeline`, `a3d_init::kernel`): never the CLI, never a shell.
//! Arguments arrive already checked by the Python layer (`a3d_init/__init__.py`),
//! which also turns the JSON reports into dicts; the checks are repeated here
//! where a wrong shape would otherwise reach the library. Long work runs with
//! the Python thread detached (the GIL released).

use std::path::PathBuf;

use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use a3d_init::formats::fem_csv::{self, CsvOptions};

use a3d_init::formats::fem::SignConvention;
use a3d_init::formats::fem_vtu::{self, StressRule, VtuOptions};
use a3d_init::formats::material_map::{MaterialMap, MaterialMapError};
use a3d_init::kernel::KernelKind;
use a3d_init::kernel::loo::Norm;
use a3d_init::kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy};
use a3d_init::pipeline::check::VerifyOptions;
use a3d_init::pipeline::check::start::StateSource;
use a3d_init::pipeline::fem::FemOptions;
use a3d_init::pipeline::io::output::Destination;
use a3d_init::pipeline::map::job::MapJob;
use a3d_init::pipeline::map::{EquilibriumOptions, MapConfig, SmoothingLength, UnknownName};
use a3d_init::pipeline::setting::{Setting, spell_settings};
use a3d_init::pipeline::stability::fos::{FosMethod, FosOptions};
use a3d_init::pipeline::{self, ErrorKind, PipelineError};
use a3d_init::slope::Method;

/// The Python spelling of each setting the library's messages name: the
/// keyword argument.
fn keyword(setting: Setting) -> &'static str {
    match setting {
        Setting::Columns => "columns=",
        Setting::FemUnits => "fem_units=",
        Setting::FemSign => "fem_sign=",
        Setting::FemMesh => "fem_mesh=",
        Setting::Analysis => "analysis=",
        Setting::GeneratedCps => "generate_cps=True",
        Setting::Replace => "force=True",
        Setting::SmoothingLength => "h=",
        Setting::Outside => "outside=",
        Setting::StressSource => "stress=",
        Setting::MixedState => "mixed_state=",
    }
}

/// An exception of the package's hierarchy (`a3d_init/_errors.py`: option
/// errors are `ValueError`s, file errors `OSError`s), by the library's kind,
/// its message with the keyword of each setting it names.
fn raise(kind: &str, message: &str) -> PyErr {
    let message = spell_settings(message, keyword);
    Python::attach(|py| {
        let made = py
            .import("a3d_init._errors")
            .and_then(|errors| errors.getattr("BY_KIND"))
            .and_then(|by_kind| by_kind.get_item(kind))
            .and_then(|class| class.call1((message.clone(),)));
        match made {
            Ok(exception) => PyErr::from_value(exception),
            Err(e) => e,
        }
    })
}

/// The library's error as the exception of its kind.
fn py_err(e: PipelineError) -> PyErr {
    let kind = match e.kind() {
        ErrorKind::InputFile => "input_file",
        ErrorKind::OptionValue => "option_value",
        ErrorKind::Model => "model",
        ErrorKind::Numerical => "numerical",
        ErrorKind::Output => "output",
        _ => "other",
    };
    raise(kind, &e.to_string())
}

/// An internal failure (`A3dInitError`).
fn internal(message: impl Into<String>) -> PyErr {
    raise("other", &message.into())
}

/// An argument whose value cannot be used (`OptionValueError`, a `ValueError`).
fn option_err(message: impl Into<String>) -> PyErr {
    py_err(PipelineError::Option(message.into()))
}

fn json<T: serde::Serialize>(value: &T) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| internal(e.to_string()))
}

fn kernel_kind(name: &str) -> PyResult<KernelKind> {
    KernelKind::parse(name, 2).ok_or_else(|| {
        option_err(format!(
            "kernel: expected 'cubic', 'gaussian' or 'wendland', got {name:?}"
        ))
    })
}

fn outside_policy(name: &str) -> PyResult<OutsidePolicy> {
    match name {
        "error" => Ok(OutsidePolicy::Error),
        "nearest" => Ok(OutsidePolicy::Nearest),
        "skip" => Ok(OutsidePolicy::Skip),
        _ => Err(option_err(format!(
            "outside: expected 'error', 'nearest' or 'skip', got {name:?}"
        ))),
    }
}

/// The FEM reading options, as `--fem …` and its companions give them.
#[allow(clippy::too_many_arguments)]
fn fem_options(
    fem: Vec<PathBuf>,
    columns: Option<Vec<(String, String)>>,
    fem_units: (Option<String>, Option<String>),
    fem_sign: Option<&str>,
    fem_mesh: Option<PathBuf>,
    analysis: Option<String>,
    step: &str,
) -> PyResult<FemOptions> {
    // `columns` names table headers, or VTU arrays by role when every file is a .vtu/.pvd.
    let all_vtu = fem.iter().all(|p| fem_vtu::is_vtk_path(p));
    let (columns, arrays) = match columns {
        Some(pairs) if all_vtu => (
            Vec::new(),
            fem_vtu::arrays_from_pairs(&pairs).map_err(|e| option_err(format!("columns: {e}")))?,
        ),
        Some(pairs) => (
            fem_csv::columns_from_pairs(&pairs).map_err(|e| option_err(format!("columns: {e}")))?,
            Vec::new(),
        ),
        None => (Vec::new(), Vec::new()),
    };
    let units = fem_csv::units_from(fem_units.0.as_deref(), fem_units.1.as_deref())
        .map_err(|e| option_err(format!("fem_units: {e}")))?;
    // None: GeoStudio's for tables and .gsz, OpenGeoSys's for .vtu/.pvd.
    let sign = match fem_sign {
        None => None,
        Some("geostudio") => Some(SignConvention::GeoStudio),
        Some("tension-positive" | "tension_positive") => Some(SignConvention::TensionPositive),
        Some("ogs") => Some(SignConvention::Ogs),
        Some(other) => {
            return Err(option_err(format!(
                "fem_sign: expected 'geostudio', 'tension-positive' or 'ogs', got {other:?}"
            )));
        }
    };
    Ok(FemOptions {
        paths: fem,
        csv: CsvOptions {
            columns,
            units: units.clone(),
            sign: sign.unwrap_or(SignConvention::GeoStudio),
        },
        vtu: VtuOptions {
            arrays,
            units,
            sign,
            stress: StressRule::Auto,
        },
        mesh: fem_mesh,
        analysis,
        step: step.parse().map_err(|e| option_err(format!("step {e}")))?,
    })
}

/// (n, 3) positions from an (n, dim) float64 array, dim 2 or 3.
fn positions(name: &str, a: &PyReadonlyArray2<'_, f64>) -> PyResult<(Vec<[f64; 3]>, usize)> {
    let shape = a.shape();
    let dim = shape[1];
    if dim != 2 && dim != 3 {
        return Err(option_err(format!(
            "{name}: expected shape (n, 2) or (n, 3), got {shape:?}"
        )));
    }
    let view = a.as_array();
    let mut out = Vec::with_capacity(shape[0]);
    for row in view.rows() {
        let mut p = [0.0; 3];
        for (k, v) in row.iter().enumerate() {
            p[k] = *v;
        }
        out.push(p);
    }
    Ok((out, dim))
}

/// A contiguous row-major copy-free view, or a copy when the array is strided.
fn row_major(a: &PyReadonlyArray2<'_, f64>) -> Vec<f64> {
    match a.as_slice() {
        Ok(s) => s.to_vec(),
        Err(_) => a.as_array().iter().copied().collect(),
    }
}

/// Kernel interpolation on arrays alone (paper Eq. 1). Returns the values at
/// the points (m, k), the Shepard ratio (m) and the neighbour counts (m).
#[pyfunction]
#[pyo3(signature = (nodes, values, points, h, kernel="cubic", node_regions=None, point_regions=None, node_volume=None, outside="nearest", min_shepard=0.0))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn interpolate<'py>(
    py: Python<'py>,
    nodes: PyReadonlyArray2<'py, f64>,
    values: PyReadonlyArray2<'py, f64>,
    points: PyReadonlyArray2<'py, f64>,
    h: f64,
    kernel: &str,
    node_regions: Option<PyReadonlyArray1<'py, u32>>,
    point_regions: Option<PyReadonlyArray1<'py, u32>>,
    node_volume: Option<f64>,
    outside: &str,
    min_shepard: f64,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<u32>>,
)> {
    let (node_xyz, dim) = positions("nodes", &nodes)?;
    let (point_xyz, point_dim) = positions("points", &points)?;
    if point_dim != dim {
        return Err(option_err(format!(
            "points: {point_dim} columns, but nodes have {dim}"
        )));
    }
    let n_fields = values.shape()[1];
    if values.shape()[0] != node_xyz.len() {
        return Err(option_err(format!(
            "values: {} rows, but nodes has {}",
            values.shape()[0],
            node_xyz.len()
        )));
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(option_err(format!(
            "h: expected a positive number of metres, got {h}"
        )));
    }
    let kernel = kernel_kind(kernel)?.for_dim(dim);
    let outside = outside_policy(outside)?;
    let groups = |name: &str,
                  a: &Option<PyReadonlyArray1<'py, u32>>,
                  n: usize|
     -> PyResult<Option<Vec<u32>>> {
        let Some(a) = a else { return Ok(None) };
        if a.len() != n {
            return Err(option_err(format!(
                "{name}: {} entries, expected {n}",
                a.len()
            )));
        }
        Ok(Some(a.as_array().to_vec()))
    };
    let node_group = groups("node_regions", &node_regions, node_xyz.len())?;
    let point_group = groups("point_regions", &point_regions, point_xyz.len())?;
    if node_group.is_some() != point_group.is_some() {
        return Err(option_err(
            "node_regions and point_regions: give both or neither",
        ));
    }
    let values = row_major(&values);
    let result = py.detach(|| {
        let node_volume =
            node_volume.unwrap_or_else(|| mapper::median_spacing(&node_xyz, dim).powi(dim as i32));
        let cloud = NodeCloud {
            positions: &node_xyz,
            dim,
            values: &values,
            n_fields,
            group: node_group.as_deref(),
            node_volume,
        };
        let settings = MapSettings {
            kernel,
            h,
            min_shepard,
            outside,
        };
        mapper::map_points(&cloud, &point_xyz, point_group.as_deref(), &settings)
    });
    let result = result.map_err(|e| py_err(PipelineError::Numerical(e.to_string())))?;
    let m = point_xyz.len();
    let mapped = Array2::from_shape_vec((m, n_fields), result.values)
        .map_err(|e| internal(e.to_string()))?;
    Ok((
        mapped.into_pyarray(py),
        result.shepard.into_pyarray(py),
        result.n_neighbours.into_pyarray(py),
    ))
}

/// h by leave-one-out cross-validation (paper Eq. 4) on arrays alone:
/// (h, outcome as JSON).
#[pyfunction]
#[pyo3(signature = (nodes, values, kernel="cubic", seed=1, norm="l1", fields=None))]
fn calibrate<'py>(
    py: Python<'py>,
    nodes: PyReadonlyArray2<'py, f64>,
    values: PyReadonlyArray2<'py, f64>,
    kernel: &str,
    seed: u64,
    norm: &str,
    fields: Option<Vec<String>>,
) -> PyResult<(f64, String)> {
    let (xyz, dim) = positions("nodes", &nodes)?;
    if values.shape()[0] != xyz.len() {
        return Err(option_err(format!(
            "values: {} rows, but nodes has {}",
            values.shape()[0],
            xyz.len()
        )));
    }
    let n_fields = values.shape()[1];
    let names = fields.unwrap_or_else(|| (0..n_fields).map(|k| format!("field{k}")).collect());
    if names.len() != n_fields {
        return Err(option_err(format!(
            "fields: {} names for {n_fields} columns of values",
            names.len()
        )));
    }
    let norm = match norm {
        "l1" => Norm::L1,
        "l2" => Norm::L2,
        "relative" => Norm::Relative,
        _ => {
            return Err(option_err(format!(
                "norm: expected 'l1', 'l2' or 'relative', got {norm:?}"
            )));
        }
    };
    let kernel = kernel_kind(kernel)?.for_dim(dim);
    let values = row_major(&values);
    let outcome = py
        .detach(|| {
            pipeline::calibrate::calibrate_values(&xyz, dim, &values, &names, kernel, seed, norm)
        })
        .map_err(py_err)?;
    Ok((outcome.h, json(&outcome)?))
}

/// Reads FEM node files as `map` does: (positions (n, 3), dim, ids, regions,
/// fields {name: values}, read reports as JSON, notes).
#[pyfunction]
#[pyo3(signature = (fem, columns=None, fem_units=(None, None), fem_sign=None, fem_mesh=None, analysis=None, step="last"))]
#[allow(clippy::too_many_arguments)]
fn read_fem<'py>(
    py: Python<'py>,
    fem: Vec<PathBuf>,
    columns: Option<Vec<(String, String)>>,
    fem_units: (Option<String>, Option<String>),
    fem_sign: Option<&str>,
    fem_mesh: Option<PathBuf>,
    analysis: Option<String>,
    step: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let options = fem_options(fem, columns, fem_units, fem_sign, fem_mesh, analysis, step)?;
    let loaded = py
        .detach(|| pipeline::fem::load(&options))
        .map_err(py_err)?;
    let nodes = loaded.nodes;
    let out = PyDict::new(py);
    let n = nodes.len();
    let flat: Vec<f64> = nodes.positions.iter().flatten().copied().collect();
    let xyz = Array2::from_shape_vec((n, 3), flat).map_err(|e| internal(e.to_string()))?;
    out.set_item("positions", xyz.into_pyarray(py))?;
    out.set_item("dim", nodes.dim)?;
    out.set_item("ids", nodes.ids.into_pyarray(py))?;
    out.set_item("regions", nodes.region)?;
    let fields = PyDict::new(py);
    for (q, v) in nodes.fields {
        fields.set_item(q.name(), v.into_pyarray(py))?;
    }
    out.set_item("fields", fields)?;
    out.set_item("reports", json(&loaded.reports)?)?;
    out.set_item("notes", loaded.notes)?;
    Ok(out)
}

/// The project at `model` and its predicted MPs: (summary as JSON, MP columns).
#[pyfunction]
fn inspect<'py>(py: Python<'py>, model: PathBuf) -> PyResult<(String, Bound<'py, PyDict>)> {
    let project = py
        .detach(|| pipeline::Project::load(&model))
        .map_err(py_err)?;
    let summary = pipeline::inspect::ProjectSummary::of(&project);
    let points = &project.points;
    let columns = PyDict::new(py);
    columns.set_item("id", column_of(py, points, |p| p.id))?;
    // 1-based element ids, as in every file.
    columns.set_item("element", column_of(py, points, |p| p.element + 1))?;
    columns.set_item("material", column_of(py, points, |p| p.material))?;
    columns.set_item("x", column_of(py, points, |p| p.position[0]))?;
    columns.set_item("y", column_of(py, points, |p| p.position[1]))?;
    columns.set_item("z", column_of(py, points, |p| p.position[2]))?;
    columns.set_item("volume", column_of(py, points, |p| p.volume))?;
    Ok((json(&summary)?, columns))
}

/// One numpy column from a field of each item.
fn column_of<'py, T, U: numpy::Element>(
    py: Python<'py>,
    items: &[T],
    f: impl Fn(&T) -> U,
) -> Bound<'py, numpy::PyArray1<U>> {
    items.iter().map(f).collect::<Vec<U>>().into_pyarray(py)
}

/// `map`: reads, maps and writes the project. Returns (report as JSON, the
/// folder written, the files written, the mapped state's columns).
#[pyfunction]
#[pyo3(signature = (fem, model, out=None, force=false, h=None, calibrate_h=false, kernel="cubic", seed=1, stress="auto", outside="error", min_shepard=0.02, material_map=None, mixed_state="mean", generate_cps=false, fem_vtu=false, columns=None, fem_units=(None, None), fem_sign=None, fem_mesh=None, analysis=None, step="last", k0_consistent=true))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn map<'py>(
    py: Python<'py>,
    fem: Vec<PathBuf>,
    model: PathBuf,
    out: Option<PathBuf>,
    force: bool,
    h: Option<f64>,
    calibrate_h: bool,
    kernel: &str,
    seed: u64,
    stress: &str,
    outside: &str,
    min_shepard: f64,
    material_map: Option<Vec<(String, String)>>,
    mixed_state: &str,
    generate_cps: bool,
    fem_vtu: bool,
    columns: Option<Vec<(String, String)>>,
    fem_units: (Option<String>, Option<String>),
    fem_sign: Option<&str>,
    fem_mesh: Option<PathBuf>,
    analysis: Option<String>,
    step: &str,
    k0_consistent: bool,
) -> PyResult<(String, PathBuf, Vec<String>, Bound<'py, PyDict>)> {
    let h = match (h, calibrate_h) {
        (_, true) => SmoothingLength::Calibrate { seed },
        (None, false) => SmoothingLength::SpacingRule,
        (Some(v), false) if v > 0.0 && v.is_finite() => SmoothingLength::Metres(v),
        (Some(v), false) => {
            return Err(option_err(format!(
                "h: expected a positive number of metres, 'auto' or None, got {v:?}"
            )));
        }
    };
    let parse = |what: &str, e: &dyn std::fmt::Display| option_err(format!("{what}: {e}"));
    let config = MapConfig {
        kernel: kernel_kind(kernel)?,
        h,
        outside: outside
            .parse()
            .map_err(|e: UnknownName| parse("outside", &e))?,
        min_shepard,
        stress: stress
            .parse()
            .map_err(|e: UnknownName| parse("stress", &e))?,
        material_map: material_map
            .map(|pairs| MaterialMap::from_pairs(&pairs))
            .transpose()
            .map_err(|e: MaterialMapError| parse("material_map", &e))?,
        mixed_state: mixed_state
            .parse()
            .map_err(|e: UnknownName| parse("mixed_state", &e))?,
        equilibrium: EquilibriumOptions {
            k0_consistent,
            ..EquilibriumOptions::default()
        },
        keep_fem_fields: true,
        ..MapConfig::default()
    };
    let job = MapJob {
        model,
        fem: fem_options(fem, columns, fem_units, fem_sign, fem_mesh, analysis, step)?,
        config,
        generate_cps,
        fem_vtu,
    };
    let (mapped, written) = py
        .detach(|| pipeline::map::job::map(&job, Destination::new(out.as_deref(), force)))
        .map_err(py_err)?;
    let states = &mapped.states;
    let state = PyDict::new(py);
    let n = states.len();
    let tensor = |f: &dyn Fn(&a3d_init::model::MpState) -> [f64; 6]| -> PyResult<Array2<f64>> {
        let flat: Vec<f64> = states.iter().flat_map(f).collect();
        Array2::from_shape_vec((n, 6), flat).map_err(|e| internal(e.to_string()))
    };
    state.set_item("pwp", column_of(py, states, |s| s.pwp))?;
    state.set_item("total_stress", tensor(&|s| s.total)?.into_pyarray(py))?;
    state.set_item(
        "effective_stress",
        tensor(&|s| s.effective())?.into_pyarray(py),
    )?;
    state.set_item("saturation", column_of(py, states, |s| s.saturation))?;
    let diagnostics = &mapped.diagnostics;
    state.set_item("neighbours", column_of(py, diagnostics, |d| d.neighbours))?;
    state.set_item(
        "shepard",
        column_of(py, diagnostics, |d| d.shepard.unwrap_or(f64::NAN)),
    )?;
    Ok((json(&mapped.report)?, written.folder, written.files, state))
}

/// The source a folder or a model with a state table names.
fn source(
    folder: Option<PathBuf>,
    model: Option<PathBuf>,
    state: Option<PathBuf>,
) -> PyResult<StateSource> {
    match (folder, model, state) {
        (Some(dir), None, None) => Ok(StateSource::Folder(dir)),
        (None, Some(model), Some(state)) => Ok(StateSource::Table { model, state }),
        _ => Err(option_err(
            "give a folder written by map, or model= and state= (an mps.csv)",
        )),
    }
}

/// `verify`: (outcome as JSON, folder written).
#[pyfunction]
#[pyo3(signature = (folder=None, model=None, state=None, max_steps=20000, damping=None, out=None, force=false, drained=false))]
#[allow(clippy::too_many_arguments)]
fn verify(
    py: Python<'_>,
    folder: Option<PathBuf>,
    model: Option<PathBuf>,
    state: Option<PathBuf>,
    max_steps: usize,
    damping: Option<f64>,
    out: Option<PathBuf>,
    force: bool,
    drained: bool,
) -> PyResult<(String, PathBuf)> {
    let source = source(folder, model, state)?;
    let options = VerifyOptions {
        max_steps,
        damping,
        drained,
    };
    let (outcome, written) = py
        .detach(|| {
            pipeline::check::verify(&source, &options, Destination::new(out.as_deref(), force))
        })
        .map_err(py_err)?;
    Ok((json(&outcome)?, written))
}

/// The factor-of-safety method by its command-line name.
fn fos_method(name: &str) -> PyResult<FosMethod> {
    if name == "srm" {
        return Ok(FosMethod::Srm);
    }
    Method::ALL
        .into_iter()
        .find(|m| m.name() == name)
        .map(FosMethod::Le)
        .ok_or_else(|| {
            let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
            option_err(format!(
                "method: expected one of {} or 'srm', got {name:?}",
                names.join(", ")
            ))
        })
}

/// `fos` (limit equilibrium by `method`, or strength reduction with
/// `method="srm"`, on the state Anura3D will hold): (fos.json as JSON, folder
/// written).
#[pyfunction]
#[pyo3(signature = (folder=None, model=None, state=None, method="srm", damping=None, tolerance=0.01, window=None, zero_pwp=false, out=None, force=false, drained=true))]
#[allow(clippy::too_many_arguments)]
fn fos(
    py: Python<'_>,
    folder: Option<PathBuf>,
    model: Option<PathBuf>,
    state: Option<PathBuf>,
    method: &str,
    damping: Option<f64>,
    tolerance: f64,
    window: Option<f64>,
    zero_pwp: bool,
    out: Option<PathBuf>,
    force: bool,
    drained: bool,
) -> PyResult<(String, PathBuf)> {
    let source = source(folder, model, state)?;
    let options = FosOptions {
        method: fos_method(method)?,
        damping,
        tolerance,
        window,
        zero_pwp,
        drained,
        ..FosOptions::default()
    };
    let (analysis, written) = py
        .detach(|| {
            pipeline::stability::fos::fos(
                &source,
                &options,
                Destination::new(out.as_deref(), force),
            )
        })
        .map_err(py_err)?;
    let report = pipeline::stability::fos::json(&analysis).map_err(py_err)?;
    Ok((json(&report)?, written))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(interpolate, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(read_fem, m)?)?;
    m.add_function(wrap_pyfunction!(inspect, m)?)?;
    m.add_function(wrap_pyfunction!(map, m)?)?;
    m.add_function(wrap_pyfunction!(verify, m)?)?;
    m.add_function(wrap_pyfunction!(fos, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
