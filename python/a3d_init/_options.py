"""The choices and structured options of the Python API, and the checks that
turn a wrong type into ``TypeError`` and a wrong value into
:class:`~a3d_init.OptionValueError` (a ``ValueError``), each naming the
argument."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any, Dict, List, Literal, Mapping, Optional, Sequence, Tuple, TypedDict, Union

from ._errors import OptionValueError

Kernel = Literal["cubic", "gaussian", "wendland"]
Outside = Literal["error", "nearest", "skip"]
StressSource = Literal["auto", "fem", "geostatic", "equilibrium", "zero"]
MixedState = Literal["mean", "per-mp"]
FemSign = Literal["geostudio", "tension-positive", "ogs"]
FosMethod = Literal["srm", "morgenstern-price", "spencer", "bishop", "janbu", "ordinary"]
Norm = Literal["l1", "l2", "relative"]
#: A column mapping's fields (CSV tables).
ColumnField = Literal[
    "x", "y", "z", "node", "region", "pwp", "sxx", "syy", "szz", "sxy", "syz", "sxz", "esxx", "esyy", "eszz"
]
#: A VTU array's roles (``.vtu`` and ``.pvd`` results).
ArrayRole = Literal["pwp", "stress", "saturation", "displacement", "region"]

PathLike = Union[str, "os.PathLike[str]"]


class FemUnits(TypedDict, total=False):
    """Units of the FEM files where their headers give none: ``length``
    (``m``, ``ft``, ``mm``, …) and ``pressure`` (``kPa``, ``Pa``, ``psf``, …)."""

    length: str
    pressure: str


@dataclass(frozen=True)
class Time:
    """A saved step chosen by its time: the step saved at ``seconds``
    (``step=Time(5616.0)``, or ``Time.hours(1.56)``)."""

    seconds: float

    @classmethod
    def hours(cls, hours: float) -> "Time":
        return cls(float(hours) * 3600.0)


#: A saved step of a ``.gsz`` analysis or ``.pvd`` series: its number, the
#: last, the first at which the slope fails (``map`` only), or a time.
Step = Union[int, Literal["last", "failure"], Time]


def choice(name: str, value: Any, allowed: Sequence[str]) -> str:
    """``value`` if it is one of ``allowed``: TypeError when it is no string,
    OptionValueError when it is another."""
    if not isinstance(value, str):
        raise TypeError(f"{name}: expected a string, one of {', '.join(map(repr, allowed))}, got {type(value).__name__}")
    if value not in allowed:
        raise OptionValueError(f"{name}: expected one of {', '.join(map(repr, allowed))}, got {value!r}")
    return value


def optional_choice(name: str, value: Any, allowed: Sequence[str]) -> Optional[str]:
    return None if value is None else choice(name, value, allowed)


def flag(name: str, value: Any) -> bool:
    """``value`` if it is a bool, else TypeError."""
    if not isinstance(value, bool):
        raise TypeError(f"{name}: expected True or False, got {type(value).__name__}")
    return value


def number(name: str, value: Any, *, optional: bool = False) -> Optional[float]:
    """``value`` as a float if it is a real number (not a bool), else TypeError."""
    if value is None and optional:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"{name}: expected a number, got {type(value).__name__}")
    return float(value)


def integer(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"{name}: expected an int, got {type(value).__name__}")
    return value


def path(name: str, value: Any, *, optional: bool = True) -> Optional[str]:
    if value is None and optional:
        return None
    if not isinstance(value, (str, os.PathLike)):
        raise TypeError(f"{name}: expected a path (str or os.PathLike), got {type(value).__name__}")
    return os.fspath(value)


def paths(name: str, value: Any) -> List[str]:
    if isinstance(value, (str, os.PathLike)):
        return [os.fspath(value)]
    if isinstance(value, (list, tuple)):
        return [path(name, v, optional=False) for v in value]  # type: ignore[misc]
    raise TypeError(f"{name}: expected a path or a list of paths, got {type(value).__name__}")


def pairs(name: str, value: Any) -> Optional[List[Tuple[str, str]]]:
    """A mapping of strings as (key, value) pairs, in order; TypeError for
    anything else (a ``"a=b,…"`` string included: give a dict)."""
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise TypeError(f"{name}: expected a dict, got {type(value).__name__}")
    out = []
    for k, v in value.items():
        if not isinstance(k, str) or not isinstance(v, (str, int)) or isinstance(v, bool):
            raise TypeError(f"{name}: expected str keys and str values, got {k!r}: {v!r}")
        out.append((k, str(v)))
    return out


def units(value: Any) -> Tuple[Optional[str], Optional[str]]:
    given = pairs("fem_units", value) or []
    known = {"length", "pressure"}
    for k, _ in given:
        if k not in known:
            raise OptionValueError(f"fem_units: expected the keys 'length' and 'pressure', got {k!r}")
    d = dict(given)
    return d.get("length"), d.get("pressure")


def smoothing_length(value: Any) -> Tuple[Optional[float], bool]:
    """``h`` as (metres or None, calibrate): a positive number of metres,
    ``"auto"`` (leave-one-out calibration) or None (the spacing rule)."""
    if value is None:
        return None, False
    if value == "auto":
        return None, True
    if isinstance(value, str):
        raise OptionValueError(f"h: expected a positive number of metres, 'auto' or None, got {value!r}")
    h = number("h", value)
    if not (h > 0.0 and math.isfinite(h)):  # type: ignore[operator]
        raise OptionValueError(f"h: expected a positive number of metres, 'auto' or None, got {value!r}")
    return h, False


def step(value: Any) -> str:
    """A step as the library reads it."""
    if isinstance(value, Time):
        seconds = number("step", value.seconds)
        if not math.isfinite(seconds):  # type: ignore[arg-type]
            raise OptionValueError(f"step: the time must be a finite number of seconds, got {value.seconds!r}")
        return f"time={seconds!r}"
    if isinstance(value, bool):
        raise TypeError("step: expected an int, 'last', 'failure' or Time, got bool")
    if isinstance(value, int):
        if value < 0:
            raise OptionValueError(f"step: expected a step number of 0 or more, got {value}")
        return str(value)
    if isinstance(value, str):
        return choice("step", value, ("last", "failure"))
    raise TypeError(f"step: expected an int, 'last', 'failure' or Time, got {type(value).__name__}")


# Reports, documented: the top-level keys of the JSON files each call writes.


class MapReport(TypedDict, total=False):
    """``report.json`` of :func:`a3d_init.map` (formats/report-json.md)."""

    tool: str
    inputs: List[Dict[str, Any]]
    fem: List[Dict[str, Any]]
    conventions: List[str]
    kernel: str
    smoothing_length: float
    smoothing_length_rule: str
    fem_spacing: float
    gaussian_truncated_mass: Optional[float]
    stress_source: str
    computation_method: str
    mixed_state: Optional[str]
    calibration: Optional[Dict[str, Any]]
    material_separation: str
    materials: List[Dict[str, Any]]
    fem_nodes: int
    material_points: int
    null_points: int
    null_point_policy: str
    mapf_smoothing_length: float
    min_mp_spacing: float
    pwp_range: List[float]
    sigma_yy_range: List[float]
    assumed_defaults: List[Dict[str, Any]]
    equilibrium: Dict[str, Any]
    failure: Dict[str, Any]
    notes: List[str]
    warnings: List[str]
    timings_ms: List[Tuple[str, float]]


class VerifyReport(TypedDict, total=False):
    """``verify.json`` of :func:`a3d_init.verify`, with ``folder`` added."""

    equilibrium: bool
    causes: List[str]
    anura3d: Dict[str, Any]
    run: Dict[str, Any]
    folder: str


class FosReport(TypedDict, total=False):
    """``fos.json`` of :func:`a3d_init.fos`, with ``folder`` added: the
    factor, its method and, by method, the strength-reduction trials or the
    critical slip surface."""

    factor: float
    method: str
    converged: bool
    trials: List[Dict[str, Any]]
    critical_surface: List[List[float]]
    warnings: List[str]
    folder: str


class FemRead(TypedDict):
    """What :func:`a3d_init.read_fem` returns."""

    positions: Any
    dim: int
    ids: Any
    regions: Any
    fields: Dict[str, Any]
    reports: List[Dict[str, Any]]
    notes: List[str]
