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
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use a3d_init::formats::fem_csv::{self, CsvOptions, SignConvention};
use a3d_init::formats::fem_vtu::{self, StressRule, VtuOptions};
use a3d_init::formats::material_map::MaterialMapError;
use a3d_init::kernel::KernelKind;
use a3d_init::kernel::loo::Norm;
use a3d_init::kernel::mapper::{self, MapSettings, NodeCloud, OutsidePolicy};
use a3d_init::pipeline::check::VerifyOptions;
use a3d_init::pipeline::fem::FemOptions;
use a3d_init::pipeline::fos::{FosMethod, FosOptions};
use a3d_init::pipeline::map::{EquilibriumOptions, MapConfig, SmoothingLength, UnknownName};
use a3d_init::pipeline::mapping::MapJob;
use a3d_init::pipeline::output::Destination;
use a3d_init::pipeline::start::StateSource;
use a3d_init::pipeline::{self, ErrorKind, PipelineError};
use a3d_init::slope::Method;

create_exception!(
    _native,
    A3dInitError,
    PyException,
    "Any a3d-init error; `kind` says which."
);
create_exception!(
    _native,
    InputFileError,
    A3dInitError,
    "An input file is missing, unreadable or malformed (the message is positioned: path:line:col)."
);
create_exception!(
    _native,
    OptionValueError,
    A3dInitError,
    "An option's value cannot be used."
);
create_exception!(
    _native,
    ModelError,
    A3dInitError,
    "The model has something this step does not support."
);
create_exception!(
    _native,
    NumericalError,
    A3dInitError,
    "A numerical failure."
);
create_exception!(
    _native,
    OutputError,
    A3dInitError,
    "An output cannot or may not be written."
);

/// The library's error as the exception of its kind, with `kind` set.
fn py_err(e: PipelineError) -> PyErr {
    let message = e.to_string();
    let (err, kind) = match e.kind() {
        ErrorKind::InputFile => (InputFileError::new_err(message), "input_file"),
        ErrorKind::OptionValue => (OptionValueError::new_err(message), "option_value"),
        ErrorKind::Model => (ModelError::new_err(message), "model"),
        ErrorKind::Numerical => (NumericalError::new_err(message), "numerical"),
        ErrorKind::Output => (OutputError::new_err(message), "output"),
        _ => (A3dInitError::new_err(message), "other"),
    };
    Python::attach(|py| {
        let _ = err.value(py).setattr("kind", kind);
    });
    err
}

fn option_err(message: String) -> PyErr {
    py_err(PipelineError::Option(message))
}

fn json<T: serde::Serialize>(value: &T) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| A3dInitError::new_err(e.to_string()))
}

fn kernel_kind(name: &str) -> PyResult<KernelKind> {
    KernelKind::parse(name, 2).ok_or_else(|| {
        PyValueError::new_err(format!(
            "kernel: expected 'cubic', 'gaussian' or 'wendland', got {name:?}"
        ))
    })
}

fn outside_policy(name: &str) -> PyResult<OutsidePolicy> {
    match name {
        "error" => Ok(OutsidePolicy::Error),
        "nearest" => Ok(OutsidePolicy::Nearest),
        "skip" => Ok(OutsidePolicy::Skip),
        _ => Err(PyValueError::new_err(format!(
            "outside: expected 'error', 'nearest' or 'skip', got {name:?}"
        ))),
    }
}

/// The FEM reading options, as `--fem …` and its companions give them.
#[allow(clippy::too_many_arguments)]
fn fem_options(
    fem: Vec<PathBuf>,
    columns: Option<&str>,
    fem_units: Option<&str>,
    fem_sign: Option<&str>,
    fem_mesh: Option<PathBuf>,
    analysis: Option<String>,
    step: &str,
) -> PyResult<FemOptions> {
    // `columns` names table headers, or VTU arrays by role when every file is a .vtu/.pvd.
    let all_vtu = fem.iter().all(|p| fem_vtu::is_vtk_path(p));
    let (columns, arrays) = match columns {
        Some(s) if all_vtu => (
            Vec::new(),
            fem_vtu::parse_arrays_option(s).map_err(|e| option_err(format!("columns: {e}")))?,
        ),
        Some(s) => (
            fem_csv::parse_columns_option(s).map_err(|e| option_err(format!("columns: {e}")))?,
            Vec::new(),
        ),
        None => (Vec::new(), Vec::new()),
    };
    let units = match fem_units {
        Some(s) => {
            fem_csv::parse_units_option(s).map_err(|e| option_err(format!("fem_units: {e}")))?
        }
        None => Default::default(),
    };
    // None: GeoStudio's for tables and .gsz, OpenGeoSys's for .vtu/.pvd.
    let sign = match fem_sign {
        None => None,
        Some("geostudio") => Some(SignConvention::GeoStudio),
        Some("tension-positive" | "tension_positive") => Some(SignConvention::TensionPositive),
        Some("ogs") => Some(SignConvention::Ogs),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
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
        return Err(PyValueError::new_err(format!(
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
        return Err(PyValueError::new_err(format!(
            "points: {point_dim} columns, but nodes have {dim}"
        )));
    }
    let n_fields = values.shape()[1];
    if values.shape()[0] != node_xyz.len() {
        return Err(PyValueError::new_err(format!(
            "values: {} rows, but nodes has {}",
            values.shape()[0],
            node_xyz.len()
        )));
    }
    if !(h.is_finite() && h > 0.0) {
        return Err(PyValueError::new_err(format!(
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
            return Err(PyValueError::new_err(format!(
                "{name}: {} entries, expected {n}",
                a.len()
            )));
        }
        Ok(Some(a.as_array().to_vec()))
    };
    let node_group = groups("node_regions", &node_regions, node_xyz.len())?;
    let point_group = groups("point_regions", &point_regions, point_xyz.len())?;
    if node_group.is_some() != point_group.is_some() {
        return Err(PyValueError::new_err(
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
        .map_err(|e| A3dInitError::new_err(e.to_string()))?;
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
        return Err(PyValueError::new_err(format!(
            "values: {} rows, but nodes has {}",
            values.shape()[0],
            xyz.len()
        )));
    }
    let n_fields = values.shape()[1];
    let names = fields.unwrap_or_else(|| (0..n_fields).map(|k| format!("field{k}")).collect());
    if names.len() != n_fields {
        return Err(PyValueError::new_err(format!(
            "fields: {} names for {n_fields} columns of values",
            names.len()
        )));
    }
    let norm = match norm {
        "l1" => Norm::L1,
        "l2" => Norm::L2,
        "relative" => Norm::Relative,
        _ => {
            return Err(PyValueError::new_err(format!(
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
#[pyo3(signature = (fem, columns=None, fem_units=None, fem_sign=None, fem_mesh=None, analysis=None, step="last"))]
#[allow(clippy::too_many_arguments)]
fn read_fem<'py>(
    py: Python<'py>,
    fem: Vec<PathBuf>,
    columns: Option<&str>,
    fem_units: Option<&str>,
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
    let xyz =
        Array2::from_shape_vec((n, 3), flat).map_err(|e| A3dInitError::new_err(e.to_string()))?;
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
#[pyo3(signature = (fem, model, out=None, force=false, h=None, kernel="cubic", seed=1, stress="auto", outside="error", min_shepard=0.02, material_map=None, mixed_state="mean", generate_cps=false, fem_vtu=false, columns=None, fem_units=None, fem_sign=None, fem_mesh=None, analysis=None, step="last", k0_consistent=true))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn map<'py>(
    py: Python<'py>,
    fem: Vec<PathBuf>,
    model: PathBuf,
    out: Option<PathBuf>,
    force: bool,
    h: Option<&str>,
    kernel: &str,
    seed: u64,
    stress: &str,
    outside: &str,
    min_shepard: f64,
    material_map: Option<&str>,
    mixed_state: &str,
    generate_cps: bool,
    fem_vtu: bool,
    columns: Option<&str>,
    fem_units: Option<&str>,
    fem_sign: Option<&str>,
    fem_mesh: Option<PathBuf>,
    analysis: Option<String>,
    step: &str,
    k0_consistent: bool,
) -> PyResult<(String, PathBuf, Vec<String>, Bound<'py, PyDict>)> {
    let h = match h {
        None => SmoothingLength::SpacingRule,
        Some("auto") => SmoothingLength::Calibrate { seed },
        Some(text) => match text.parse::<f64>() {
            Ok(v) if v > 0.0 && v.is_finite() => SmoothingLength::Metres(v),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "h: expected a positive number of metres or 'auto', got {text:?}"
                )));
            }
        },
    };
    let parse =
        |what: &str, e: &dyn std::fmt::Display| PyValueError::new_err(format!("{what}: {e}"));
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
            .map(str::parse)
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
        .detach(|| pipeline::mapping::map(&job, Destination::new(out.as_deref(), force)))
        .map_err(py_err)?;
    let states = &mapped.states;
    let state = PyDict::new(py);
    let n = states.len();
    let tensor = |f: &dyn Fn(&a3d_init::model::MpState) -> [f64; 6]| -> PyResult<Array2<f64>> {
        let flat: Vec<f64> = states.iter().flat_map(f).collect();
        Array2::from_shape_vec((n, 6), flat).map_err(|e| A3dInitError::new_err(e.to_string()))
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
        _ => Err(PyValueError::new_err(
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
            PyValueError::new_err(format!(
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
        .detach(|| pipeline::fos::fos(&source, &options, Destination::new(out.as_deref(), force)))
        .map_err(py_err)?;
    let report = pipeline::fos::json(&analysis).map_err(py_err)?;
    Ok((json(&report)?, written))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("A3dInitError", py.get_type::<A3dInitError>())?;
    m.add("InputFileError", py.get_type::<InputFileError>())?;
    m.add("OptionValueError", py.get_type::<OptionValueError>())?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add("NumericalError", py.get_type::<NumericalError>())?;
    m.add("OutputError", py.get_type::<OutputError>())?;
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
