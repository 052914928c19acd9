"""a3d-init from Python: carry a FEM seepage/stress state onto the material
points of an Anura3D MPM model.

Every function is one call of the Rust library's pipeline (``a3d_init::pipeline``),
never of the command line. Long work releases the GIL. Choices are ``Literal``
strings (:data:`Kernel`, :data:`StressSource`, …), structured options are
dicts (``columns={"pwp": "PWP (kPa)"}``, ``fem_units={"length": "ft"}``,
``material_map={"mat0": "silty_sand"}``), ``h`` is a float (or ``"auto"``) and
a step an int, ``"last"``, ``"failure"`` or :class:`Time`. Reports come back as
dicts whose keys the ``TypedDict``\ s :class:`MapReport`, :class:`VerifyReport`
and :class:`FosReport` document; fields as numpy arrays. Notes and warnings of
a run go to the ``a3d_init`` logger (``logging.getLogger("a3d_init")``), never
to the terminal.

Errors raise one hierarchy under :class:`A3dInitError`, carrying the library's
positioned message (``path:line:col: …``) and a ``kind``: ``InputFileError``
and ``OutputError`` are ``OSError``\ s, ``OptionValueError`` (an unusable
value, arrays of the wrong shape or dtype included) is a ``ValueError``;
``ModelError`` and ``NumericalError`` are the rest. A wrong type raises
``TypeError``. Messages name the keyword argument a setting comes from
(``the column mapping (columns=)``).

Units and signs are Anura3D's: m, kPa, tension positive, pore pressure negative
in compression; y up.
"""

from __future__ import annotations

import json
import logging
import os
from typing import Any, Dict, Iterable, Literal, Mapping, Optional, Sequence, Tuple, Union, get_args

import numpy as np

from . import _native
from . import _options as _o
from ._errors import (
    A3dInitError,
    InputFileError,
    ModelError,
    NumericalError,
    OptionValueError,
    OutputError,
)
from ._options import (
    ArrayRole,
    ColumnField,
    FemRead,
    FemSign,
    FemUnits,
    FosMethod,
    FosReport,
    Kernel,
    MapReport,
    MixedState,
    Norm,
    Outside,
    Step,
    StressSource,
    Time,
    VerifyReport,
)

__all__ = [
    "A3dInitError",
    "InputFileError",
    "ModelError",
    "NumericalError",
    "OptionValueError",
    "OutputError",
    "ArrayRole",
    "ColumnField",
    "FemRead",
    "FemSign",
    "FemUnits",
    "FosMethod",
    "FosReport",
    "Kernel",
    "MapReport",
    "MixedState",
    "Norm",
    "Outside",
    "Step",
    "StressSource",
    "Time",
    "VerifyReport",
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

PathLike = _o.PathLike


def _float_array(name: str, a: Any, ndim: int, columns: Optional[Iterable[int]] = None) -> np.ndarray:
    """``a`` as a float64 numpy array of ``ndim`` dimensions: TypeError when it
    is no numpy array, OptionValueError (a ValueError) naming it otherwise."""
    if not isinstance(a, np.ndarray):
        raise TypeError(f"{name}: expected a numpy array, got {type(a).__name__}")
    if a.dtype != np.float64:
        raise OptionValueError(f"{name}: expected dtype float64, got {a.dtype}")
    if a.ndim != ndim:
        raise OptionValueError(f"{name}: expected {ndim} dimensions, got shape {a.shape}")
    if columns is not None and a.shape[1] not in tuple(columns):
        raise OptionValueError(f"{name}: expected {' or '.join(str(c) for c in columns)} columns, got shape {a.shape}")
    return a


def _values_array(values: Any) -> np.ndarray:
    if not isinstance(values, np.ndarray):
        raise TypeError(f"values: expected a numpy array, got {type(values).__name__}")
    if values.dtype != np.float64:
        raise OptionValueError(f"values: expected a float64 numpy array, got {values.dtype}")
    return values


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
    """What :func:`map` wrote: the report (this dict, as report.json; its keys
    are :class:`MapReport`'s), the
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
    summary, points = _native.inspect(_o.path("model", model, optional=False))
    return Model(json.loads(summary), points)


# The values each choice takes: the Literal types' own (one list per choice).
_KERNELS = get_args(Kernel)
_OUTSIDE = get_args(Outside)
_STRESS = get_args(StressSource)
_MIXED = get_args(MixedState)
_SIGNS = get_args(FemSign)
_METHODS = get_args(FosMethod)
_NORMS = get_args(Norm)


def _fem_arguments(
    fem: Any,
    columns: Any,
    fem_units: Any,
    fem_sign: Any,
    fem_mesh: Any,
    analysis: Any,
    step: Any,
) -> tuple:
    """The FEM-reading arguments, checked, as the native functions take them."""
    if analysis is not None and (isinstance(analysis, bool) or not isinstance(analysis, (str, int))):
        raise TypeError(f"analysis: expected a name or a 1-based index, got {type(analysis).__name__}")
    return (
        _o.paths("fem", fem),
        _o.pairs("columns", columns),
        _o.units(fem_units),
        _o.optional_choice("fem_sign", fem_sign, _SIGNS),
        _o.path("fem_mesh", fem_mesh),
        None if analysis is None else str(analysis),
        _o.step(step),
    )


def map(
    fem: Union[PathLike, Sequence[PathLike]],
    model: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    *,
    mpm: Optional[PathLike] = None,
    force: bool = False,
    h: Union[None, float, Literal["auto"]] = None,
    kernel: Kernel = "cubic",
    seed: int = 1,
    stress: StressSource = "auto",
    outside: Outside = "error",
    min_shepard: float = 0.02,
    material_map: Optional[Mapping[str, Union[str, int]]] = None,
    mixed_state: MixedState = "mean",
    generate_cps: bool = False,
    fem_vtu: bool = False,
    columns: Optional[Mapping[str, str]] = None,
    fem_units: Optional[FemUnits] = None,
    fem_sign: Optional[FemSign] = None,
    fem_mesh: Optional[PathLike] = None,
    analysis: Union[None, str, int] = None,
    step: Step = "last",
    k0_consistent: bool = True,
) -> Mapped:
    """Maps the FEM fields onto the model's MPs and writes a ready-to-run
    Anura3D project into ``out`` (default ``<project>.a3d-init/`` beside the
    model; ``force=True`` replaces an earlier output). ``model`` may also be
    given as ``mpm``.

    - ``h``: the smoothing length in metres, ``"auto"`` (leave-one-out
      calibration, seeded by ``seed``) or ``None`` (the spacing rule).
    - ``stress``: where the stresses come from; ``"equilibrium"`` solves for
      the stress at rest under gravity on Anura3D's own discretisation (report
      key ``"equilibrium"``), with ν = K0/(1 + K0) unless
      ``k0_consistent=False``.
    - ``columns``: field → header (CSV tables: ``x``, ``y``, ``pwp``, ``sxx``,
      … see :data:`ColumnField`) or role → array (VTU: :data:`ArrayRole`).
    - ``fem_units``: ``{"length": "ft", "pressure": "psf"}`` where headers give
      none; ``fem_sign``: the files' sign convention (default: the format's).
    - ``material_map``: FEM region → GOM material (name or 1-based index).
    - ``step``: a saved step number, ``"last"``, ``Time(seconds)``, or
      ``"failure"`` (the first saved step whose factor of safety is at most 1).
    """
    if model is None:
        model = mpm
    elif mpm is not None:
        raise OptionValueError("give model or mpm, not both")
    if model is None:
        raise OptionValueError("model: the Anura3D model (GOM, CPS or folder) is needed")
    metres, calibrate_h = _o.smoothing_length(h)
    fem_args = _fem_arguments(fem, columns, fem_units, fem_sign, fem_mesh, analysis, step)
    report, folder, files, state = _native.map(
        fem_args[0],
        _o.path("model", model, optional=False),
        _o.path("out", out),
        _o.flag("force", force),
        metres,
        calibrate_h,
        _o.choice("kernel", kernel, _KERNELS),
        _o.integer("seed", seed),
        _o.choice("stress", stress, _STRESS),
        _o.choice("outside", outside, _OUTSIDE),
        _o.number("min_shepard", min_shepard),
        _o.pairs("material_map", material_map),
        _o.choice("mixed_state", mixed_state, _MIXED),
        _o.flag("generate_cps", generate_cps),
        _o.flag("fem_vtu", fem_vtu),
        *fem_args[1:],
        _o.flag("k0_consistent", k0_consistent),
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
    kernel: Kernel = "cubic",
    regions: Optional[Tuple[np.ndarray, np.ndarray]] = None,
    *,
    node_volume: Optional[float] = None,
    outside: Outside = "nearest",
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
    values = _values_array(values)
    h = _o.number("h", h)
    one = values.ndim == 1
    if one:
        values = values.reshape(-1, 1)
    _float_array("values", values, 2)
    if values.shape[0] != nodes.shape[0]:
        raise OptionValueError(f"values: {values.shape[0]} rows, but nodes has {nodes.shape[0]}")
    if points.shape[1] != nodes.shape[1]:
        raise OptionValueError(f"points: {points.shape[1]} columns, but nodes has {nodes.shape[1]}")
    node_regions = point_regions = None
    if regions is not None:
        node_regions, point_regions = (np.ascontiguousarray(r, dtype=np.uint32) for r in regions)
        if node_regions.shape != (nodes.shape[0],) or point_regions.shape != (points.shape[0],):
            raise OptionValueError("regions: expected (node_regions (n,), point_regions (m,))")
    mapped, shepard, neighbours = _native.interpolate(
        nodes,
        values,
        points,
        h,
        _o.choice("kernel", kernel, _KERNELS),
        node_regions,
        point_regions,
        _o.number("node_volume", node_volume, optional=True),
        _o.choice("outside", outside, _OUTSIDE),
        _o.number("min_shepard", min_shepard),
    )
    return (mapped[:, 0] if one else mapped), shepard, neighbours


def calibrate(
    nodes: np.ndarray,
    values: np.ndarray,
    kernel: Kernel = "cubic",
    seed: int = 1,
    norm: Norm = "l1",
    fields: Optional[Sequence[str]] = None,
) -> Tuple[float, Dict[str, Any]]:
    """The smoothing length h by leave-one-out cross-validation (paper Eq. 4),
    minimised by seeded simulated annealing. ``values`` (n,) or (n, k); with
    several columns each is normalised by its standard deviation. Returns (h,
    statistics: spacing l, h/l, R², MAE, the objective curve, …)."""
    nodes = _float_array("nodes", nodes, 2, (2, 3))
    values = _values_array(values)
    if values.ndim == 1:
        values = values.reshape(-1, 1)
    _float_array("values", values, 2)
    if fields is not None and (isinstance(fields, str) or not all(isinstance(f, str) for f in fields)):
        raise TypeError("fields: expected a list of names")
    h, outcome = _native.calibrate(
        nodes,
        values,
        _o.choice("kernel", kernel, _KERNELS),
        _o.integer("seed", seed),
        _o.choice("norm", norm, _NORMS),
        None if fields is None else list(fields),
    )
    return h, json.loads(outcome)


def read_fem(
    fem: Union[PathLike, Sequence[PathLike]],
    *,
    columns: Optional[Mapping[str, str]] = None,
    fem_units: Optional[FemUnits] = None,
    fem_sign: Optional[FemSign] = None,
    fem_mesh: Optional[PathLike] = None,
    analysis: Union[None, str, int] = None,
    step: Step = "last",
) -> FemRead:
    """Reads FEM node files as ``map`` does (GeoStudio CSV tables, ``node.csv``
    with ``fem_mesh``, ``.gsz`` projects, ``.vtu``/``.pvd`` results from
    OpenGeoSys or ParaView), in Anura3D's units and signs. ``fem_sign`` None
    takes the format's own (GeoStudio's for tables, OpenGeoSys's for VTU).
    Returns ``positions`` (n, 3), ``dim``, ``ids``, ``regions`` (or None),
    ``fields`` {name: (n,)}, ``reports`` (how each file was read) and ``notes``."""
    out = _native.read_fem(*_fem_arguments(fem, columns, fem_units, fem_sign, fem_mesh, analysis, step))
    out["reports"] = json.loads(out["reports"])
    for note in out["notes"]:
        log.info("%s", note)
    return out  # type: ignore[return-value]


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
) -> VerifyReport:
    """Is the mapped state in equilibrium under gravity? Judges what Anura3D
    will hold (a map folder's GOM, CPS and MAPF), or ``model`` with a
    ``state`` table (an ``mps.csv``), with the built-in explicit MPM runner.
    Returns verify.json as a dict (``equilibrium``, ``causes``, ``anura3d``,
    ``run``) with ``folder`` added. A negative verdict is a result, not an
    exception. ``drained=True`` holds every pore pressure (two-phase coupled
    materials otherwise run with their water flowing)."""
    outcome, written = _native.verify(
        _o.path("folder", folder),
        _o.path("model", model),
        _o.path("state", state),
        _o.integer("max_steps", max_steps),
        _o.number("damping", damping, optional=True),
        _o.path("out", out),
        _o.flag("force", force),
        _o.flag("drained", drained),
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
    method: FosMethod = "srm",
    damping: Optional[float] = None,
    tolerance: float = 0.01,
    window: Optional[float] = None,
    zero_pwp: bool = False,
    out: Optional[PathLike] = None,
    force: bool = False,
    drained: bool = True,
) -> FosReport:
    """The factor of safety on the state Anura3D will hold, by strength
    reduction (``method="srm"``, the default here) or by a method of slices
    (``"morgenstern-price"``, ``"spencer"``, ``"bishop"``, ``"janbu"``,
    ``"ordinary"``; the command line's default is Morgenstern–Price). Returns
    fos.json as a dict (``factor``, ``method``, ``trials`` or
    ``critical_surface``, …) with ``folder`` added. Strength reduction holds
    every pore pressure, as limit equilibrium does; ``drained=False`` lets
    two-phase coupled materials run with their water."""
    report, written = _native.fos(
        _o.path("folder", folder),
        _o.path("model", model),
        _o.path("state", state),
        _o.choice("method", method, _METHODS),
        _o.number("damping", damping, optional=True),
        _o.number("tolerance", tolerance),
        _o.number("window", window, optional=True),
        _o.flag("zero_pwp", zero_pwp),
        _o.path("out", out),
        _o.flag("force", force),
        _o.flag("drained", drained),
    )
    result = json.loads(report)
    result["folder"] = written
    return result
