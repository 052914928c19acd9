"""a3d-init from Python: carry a FEM seepage/stress state onto the material
points of an Anura3D MPM model.

Every function is one call of the Rust library's pipeline (``a3d_init::pipeline``),
never of the command line. Long work releases the GIL. Reports come back as
dicts, fields as numpy arrays. Notes and warnings of a run go to the
``a3d_init`` logger (``logging.getLogger("a3d_init")``), never to the terminal.

Errors raise :class:`A3dInitError` subclasses carrying the library's positioned
message (``path:line:col: …``) and a ``kind`` attribute: ``InputFileError``
(``kind == "input_file"``), ``OptionValueError``, ``ModelError``,
``NumericalError``, ``OutputError``. Arrays of the wrong shape or dtype raise
``ValueError`` naming the argument.

Units and signs are Anura3D's: m, kPa, tension positive, pore pressure negative
in compression; y up.
"""

from __future__ import annotations

import json
import logging
import os
from typing import Any, Dict, Iterable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native
from ._native import (
    A3dInitError,
    InputFileError,
    ModelError,
    NumericalError,
    OptionValueError,
    OutputError,
)

__all__ = [
    "A3dInitError",
    "InputFileError",
    "ModelError",
    "NumericalError",
    "OptionValueError",
    "OutputError",
    "Model",
    "Mapped",
    "calibrate",
    "fos",
    "inspect",
    "interpolate",
    "map",
    "read_fem",
    "verify",
]

__version__ = _native.__version__

log = logging.getLogger("a3d_init")
# A library logs, it does not print: nothing reaches the terminal unless the
# application configures logging.
log.addHandler(logging.NullHandler())

PathLike = Union[str, "os.PathLike[str]"]


def _path(p: Optional[PathLike]) -> Optional[str]:
    return None if p is None else os.fspath(p)


def _paths(p: Union[PathLike, Sequence[PathLike]]) -> list:
    if isinstance(p, (str, os.PathLike)):
        return [os.fspath(p)]
    return [os.fspath(x) for x in p]


def _float_array(name: str, a: Any, ndim: int, columns: Optional[Iterable[int]] = None) -> np.ndarray:
    """``a`` as a float64 numpy array of ``ndim`` dimensions, else ValueError naming it."""
    if not isinstance(a, np.ndarray):
        raise ValueError(f"{name}: expected a numpy array, got {type(a).__name__}")
    if a.dtype != np.float64:
        raise ValueError(f"{name}: expected dtype float64, got {a.dtype}")
    if a.ndim != ndim:
        raise ValueError(f"{name}: expected {ndim} dimensions, got shape {a.shape}")
    if columns is not None and a.shape[1] not in tuple(columns):
        raise ValueError(f"{name}: expected {' or '.join(str(c) for c in columns)} columns, got shape {a.shape}")
    return a


def _log_report(report: Dict[str, Any]) -> None:
    for note in report.get("notes", []):
        log.info("%s", note)
    for warning in report.get("warnings", []):
        log.warning("%s", warning)


class Model:
    """An Anura3D project as a3d-init reads it (:func:`inspect`).

    ``points`` holds the material points Anura3D will create, in its order, as
    numpy arrays: ``id``, ``element`` (1-based), ``material``, ``x``, ``y``,
    ``z``, ``volume``. ``summary`` is what ``a3d-init inspect --json`` prints.
    """

    def __init__(self, summary: Dict[str, Any], points: Dict[str, np.ndarray]):
        self.summary = summary
        self.points = points

    @property
    def materials(self) -> list:
        """Each material's record, element and MP counts and dry unit weight."""
        return self.summary["materials"]

    @property
    def computation_method(self) -> str:
        """``MPM-MIXED``, ``MPM-MP``, ``FEM`` or ``UL-FEM`` (from the CPS)."""
        return self.summary["computation_method"]

    def __repr__(self) -> str:
        return (
            f"Model({self.summary['files']['name']!r}, {self.summary['dimension']}, "
            f"{len(self.points['id'])} MPs, {self.computation_method})"
        )


class Mapped(dict):
    """What :func:`map` wrote: the report (this dict, as report.json), the
    folder and files written, and the mapped state per MP as numpy arrays
    (``state``: ``pwp``, ``total_stress`` and ``effective_stress`` (n, 6) in the
    order xx, yy, zz, xy, yz, xz, ``saturation``, ``neighbours``, ``shepard``).
    """

    folder: str
    files: list
    state: Dict[str, np.ndarray]


def inspect(model: PathLike) -> Model:
    """Reads an Anura3D project (a GOM, ``.GOM_stage<k>``, ``-2.dat``,
    ``.CPS_<nnn>`` or a project folder) and predicts its material points."""
    summary, points = _native.inspect(_path(model))
    return Model(json.loads(summary), points)


def map(
    fem: Union[PathLike, Sequence[PathLike]],
    model: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    *,
    mpm: Optional[PathLike] = None,
    force: bool = False,
    h: Union[None, str, float] = None,
    kernel: str = "cubic",
    seed: int = 1,
    stress: str = "auto",
    outside: str = "error",
    min_shepard: float = 0.02,
    material_map: Optional[str] = None,
    mixed_state: str = "mean",
    generate_cps: bool = False,
    fem_vtu: bool = False,
    columns: Optional[str] = None,
    fem_units: Optional[str] = None,
    fem_sign: Optional[str] = None,
    fem_mesh: Optional[PathLike] = None,
    analysis: Optional[str] = None,
    step: str = "last",
    k0_consistent: bool = True,
) -> Mapped:
    """``a3d-init map``: maps the FEM fields onto the model's MPs and writes a
    ready-to-run Anura3D project into ``out`` (default
    ``<project>.a3d-init/`` beside the model). The keywords are the CLI's long
    flags (``model`` may also be given as ``mpm``); ``h`` is metres,
    ``"auto"`` (leave-one-out calibration) or ``None`` (the spacing rule).
    ``stress="equilibrium"`` solves for the stress at rest under gravity on
    Anura3D's own discretisation (report key ``"equilibrium"``), with
    ν = K0/(1 + K0) unless ``k0_consistent=False``.
    """
    if model is None:
        model = mpm
    elif mpm is not None:
        raise ValueError("give model or mpm, not both")
    if model is None:
        raise ValueError("model: the Anura3D model (GOM, CPS or folder) is needed")
    if h is not None and not isinstance(h, str):
        h = repr(float(h))
    report, folder, files, state = _native.map(
        _paths(fem),
        _path(model),
        _path(out),
        force,
        h,
        kernel,
        seed,
        stress,
        outside,
        min_shepard,
        material_map,
        mixed_state,
        generate_cps,
        fem_vtu,
        columns,
        fem_units,
        fem_sign,
        _path(fem_mesh),
        analysis,
        step,
        k0_consistent,
    )
    result = Mapped(json.loads(report))
    result.folder = folder
    result.files = files
    result.state = state
    _log_report(result)
    return result


def interpolate(
    nodes: np.ndarray,
    values: np.ndarray,
    points: np.ndarray,
    h: float,
    kernel: str = "cubic",
    regions: Optional[Tuple[np.ndarray, np.ndarray]] = None,
    *,
    node_volume: Optional[float] = None,
    outside: str = "nearest",
    min_shepard: float = 0.0,
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The paper's Shepard-normalised kernel interpolation (Eq. 1) on arrays
    alone. ``nodes`` (n, 2|3), ``values`` (n,) or (n, k), ``points`` (m, 2|3),
    all float64; ``h`` the smoothing length (m). ``regions`` =
    (node_regions (n,), point_regions (m,)) integer labels: a point is mapped
    from nodes of its own region only. Returns (values (m,) or (m, k), Shepard
    ratio (m,), neighbour count (m,)). ``node_volume`` scales the Shepard ratio
    (default l^dim, l the median nearest-node spacing)."""
    nodes = _float_array("nodes", nodes, 2, (2, 3))
    points = _float_array("points", points, 2, (2, 3))
    if not isinstance(values, np.ndarray) or values.dtype != np.float64:
        raise ValueError(f"values: expected a float64 numpy array, got {getattr(values, 'dtype', type(values).__name__)}")
    one = values.ndim == 1
    if one:
        values = values.reshape(-1, 1)
    _float_array("values", values, 2)
    if values.shape[0] != nodes.shape[0]:
        raise ValueError(f"values: {values.shape[0]} rows, but nodes has {nodes.shape[0]}")
    if points.shape[1] != nodes.shape[1]:
        raise ValueError(f"points: {points.shape[1]} columns, but nodes has {nodes.shape[1]}")
    node_regions = point_regions = None
    if regions is not None:
        node_regions, point_regions = (np.ascontiguousarray(r, dtype=np.uint32) for r in regions)
        if node_regions.shape != (nodes.shape[0],) or point_regions.shape != (points.shape[0],):
            raise ValueError("regions: expected (node_regions (n,), point_regions (m,))")
    mapped, shepard, neighbours = _native.interpolate(
        nodes, values, points, float(h), kernel, node_regions, point_regions, node_volume, outside, min_shepard
    )
    return (mapped[:, 0] if one else mapped), shepard, neighbours


def calibrate(
    nodes: np.ndarray,
    values: np.ndarray,
    kernel: str = "cubic",
    seed: int = 1,
    norm: str = "l1",
    fields: Optional[Sequence[str]] = None,
) -> Tuple[float, Dict[str, Any]]:
    """The smoothing length h by leave-one-out cross-validation (paper Eq. 4),
    minimised by seeded simulated annealing. ``values`` (n,) or (n, k); with
    several columns each is normalised by its standard deviation. Returns (h,
    statistics: spacing l, h/l, R², MAE, the objective curve, …)."""
    nodes = _float_array("nodes", nodes, 2, (2, 3))
    if not isinstance(values, np.ndarray) or values.dtype != np.float64:
        raise ValueError(f"values: expected a float64 numpy array, got {getattr(values, 'dtype', type(values).__name__)}")
    if values.ndim == 1:
        values = values.reshape(-1, 1)
    _float_array("values", values, 2)
    h, outcome = _native.calibrate(nodes, values, kernel, seed, norm, None if fields is None else list(fields))
    return h, json.loads(outcome)


def read_fem(
    fem: Union[PathLike, Sequence[PathLike]],
    *,
    columns: Optional[str] = None,
    fem_units: Optional[str] = None,
    fem_sign: Optional[str] = None,
    fem_mesh: Optional[PathLike] = None,
    analysis: Optional[str] = None,
    step: str = "last",
) -> Dict[str, Any]:
    """Reads FEM node files as ``map`` does (GeoStudio CSV tables, ``node.csv``
    with ``fem_mesh``, ``.gsz`` projects, ``.vtu``/``.pvd`` results from
    OpenGeoSys or ParaView), in Anura3D's units and signs. ``fem_sign`` None
    takes the format's own (GeoStudio's for tables, OpenGeoSys's for VTU).
    Returns ``positions`` (n, 3), ``dim``, ``ids``, ``regions`` (or None),
    ``fields`` {name: (n,)}, ``reports`` (how each file was read) and ``notes``."""
    out = _native.read_fem(_paths(fem), columns, fem_units, fem_sign, _path(fem_mesh), analysis, step)
    out["reports"] = json.loads(out["reports"])
    for note in out["notes"]:
        log.info("%s", note)
    return out


def verify(
    folder: Optional[PathLike] = None,
    *,
    model: Optional[PathLike] = None,
    state: Optional[PathLike] = None,
    max_steps: int = 20000,
    damping: Optional[float] = None,
    out: Optional[PathLike] = None,
    force: bool = False,
    drained: bool = False,
) -> Dict[str, Any]:
    """``a3d-init verify``: is the mapped state in equilibrium under gravity?
    Judges what Anura3D will hold (a map folder's GOM, CPS and MAPF) with the
    built-in explicit MPM runner. Returns verify.json as a dict (``equilibrium``,
    ``causes``, ``anura3d``, ``run``) with ``folder`` added. A negative verdict
    is a result, not an exception. ``drained=True`` holds every pore pressure
    (two-phase coupled materials otherwise run with their water flowing)."""
    outcome, written = _native.verify(
        _path(folder),
        _path(model),
        _path(state),
        max_steps,
        damping,
        _path(out),
        force,
        drained,
    )
    result = json.loads(outcome)
    result["folder"] = written
    for cause in result.get("causes", []):
        log.warning("%s", cause)
    return result


def fos(
    folder: Optional[PathLike] = None,
    *,
    model: Optional[PathLike] = None,
    state: Optional[PathLike] = None,
    method: str = "srm",
    damping: Optional[float] = None,
    tolerance: float = 0.01,
    window: Optional[float] = None,
    zero_pwp: bool = False,
    out: Optional[PathLike] = None,
    force: bool = False,
    drained: bool = True,
) -> Dict[str, Any]:
    """``a3d-init fos``: the factor of safety on the state Anura3D will hold,
    by strength reduction (``method="srm"``, the default here) or by a method
    of slices (``"morgenstern-price"``, ``"spencer"``, ``"bishop"``,
    ``"janbu"``, ``"ordinary"``; the command line's default is
    Morgenstern–Price). Returns fos.json as a dict (``factor``, ``method``,
    ``trials`` or ``critical_surface``, …) with ``folder`` added. Strength
    reduction holds every pore pressure, as limit equilibrium does;
    ``drained=False`` lets two-phase coupled materials run with their water
    (the command line's ``--coupled``)."""
    report, written = _native.fos(
        _path(folder),
        _path(model),
        _path(state),
        method,
        damping,
        tolerance,
        window,
        zero_pwp,
        _path(out),
        force,
        drained,
    )
    result = json.loads(report)
    result["folder"] = written
    return result
