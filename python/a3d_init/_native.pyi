"""Type stubs of the compiled extension ``a3d_init._native`` (Rust, PyO3).

Call the functions of the ``a3d_init`` package rather than these: they check
their arguments, turn the JSON reports into dicts and log notes. Each function
here is one call of the Rust library's pipeline, run with the GIL released.
"""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike[str]]

__version__: str

# The exceptions are raised from ``a3d_init._errors`` (one hierarchy: option
# errors are ValueErrors, file errors OSErrors), by the library's kind.

def interpolate(
    nodes: npt.NDArray[np.float64],
    values: npt.NDArray[np.float64],
    points: npt.NDArray[np.float64],
    h: float,
    kernel: str = "cubic",
    node_regions: Optional[npt.NDArray[np.uint32]] = None,
    point_regions: Optional[npt.NDArray[np.uint32]] = None,
    node_volume: Optional[float] = None,
    outside: str = "nearest",
    min_shepard: float = 0.0,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.uint32]]:
    """Shepard-normalised kernel interpolation (paper Eq. 1): values (m, k),
    Shepard ratio (m,), neighbour count (m,). ``nodes`` (n, 2|3), ``values``
    (n, k), ``points`` (m, 2|3), float64."""

def calibrate(
    nodes: npt.NDArray[np.float64],
    values: npt.NDArray[np.float64],
    kernel: str = "cubic",
    seed: int = 1,
    norm: str = "l1",
    fields: Optional[List[str]] = None,
) -> Tuple[float, str]:
    """h by leave-one-out cross-validation (paper Eq. 4): (h, outcome JSON)."""

def read_fem(
    fem: Sequence[_Path],
    columns: Optional[List[Tuple[str, str]]] = None,
    fem_units: Tuple[Optional[str], Optional[str]] = (None, None),
    fem_sign: Optional[str] = None,
    fem_mesh: Optional[_Path] = None,
    analysis: Optional[str] = None,
    step: str = "last",
) -> Dict[str, Any]:
    """FEM node files as ``map`` reads them: positions (n, 3), dim, ids,
    regions, fields {name: (n,)}, reports (JSON), notes."""

def inspect(model: _Path) -> Tuple[str, Dict[str, npt.NDArray[Any]]]:
    """A project's summary (JSON) and its MPs' columns (id, element,
    material, x, y, z, volume)."""

def map(
    fem: Sequence[_Path],
    model: _Path,
    out: Optional[_Path] = None,
    force: bool = False,
    h: Optional[float] = None,
    calibrate_h: bool = False,
    kernel: str = "cubic",
    seed: int = 1,
    stress: str = "auto",
    outside: str = "error",
    min_shepard: float = 0.02,
    material_map: Optional[List[Tuple[str, str]]] = None,
    mixed_state: str = "mean",
    generate_cps: bool = False,
    fem_vtu: bool = False,
    columns: Optional[List[Tuple[str, str]]] = None,
    fem_units: Tuple[Optional[str], Optional[str]] = (None, None),
    fem_sign: Optional[str] = None,
    fem_mesh: Optional[_Path] = None,
    analysis: Optional[str] = None,
    step: str = "last",
    k0_consistent: bool = True,
) -> Tuple[str, str, List[str], Dict[str, npt.NDArray[Any]]]:
    """``map`` (``h`` in metres or None, ``calibrate_h`` for leave-one-out;
    ``columns`` and ``material_map`` as pairs; ``step`` as the library reads
    it): (report JSON, folder, files written, state columns)."""

def verify(
    folder: Optional[_Path] = None,
    model: Optional[_Path] = None,
    state: Optional[_Path] = None,
    max_steps: int = 20000,
    damping: Optional[float] = None,
    out: Optional[_Path] = None,
    force: bool = False,
    drained: bool = False,
) -> Tuple[str, str]:
    """``verify``: (verify.json text, folder written)."""

def fos(
    folder: Optional[_Path] = None,
    model: Optional[_Path] = None,
    state: Optional[_Path] = None,
    method: str = "srm",
    damping: Optional[float] = None,
    tolerance: float = 0.01,
    window: Optional[float] = None,
    zero_pwp: bool = False,
    out: Optional[_Path] = None,
    force: bool = False,
    drained: bool = False,
) -> Tuple[str, str]:
    """``fos`` (``method``: ``"srm"``, strength reduction, or a method
    of slices such as ``"morgenstern-price"``): (fos.json text, folder written)."""
