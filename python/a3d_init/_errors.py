"""The exceptions a3d-init raises: one hierarchy under :class:`A3dInitError`.

Option errors are ``ValueError``\\ s and file errors ``OSError``\\ s, so the
standard ``except`` clauses catch them; ``kind`` names the library's category
(``input_file``, ``option_value``, ``model``, ``numerical``, ``output``).
Arguments of the wrong type raise ``TypeError``; arrays of the wrong shape or
dtype raise :class:`OptionValueError` naming the argument.
"""

from __future__ import annotations


class A3dInitError(Exception):
    """Any a3d-init error; ``kind`` says which."""

    kind: str = "other"


class InputFileError(A3dInitError, OSError):
    """An input file is missing, unreadable or malformed; the message is
    positioned (``path:line:col: …``)."""

    kind = "input_file"


class OutputError(A3dInitError, OSError):
    """An output cannot or may not be written (it exists, is or holds an
    input, a write or sync failed)."""

    kind = "output"


class OptionValueError(A3dInitError, ValueError):
    """An argument's value cannot be used (an unknown choice, a smoothing
    length of zero, an array of the wrong shape)."""

    kind = "option_value"


class ModelError(A3dInitError):
    """The model has something this step does not support."""

    kind = "model"


class NumericalError(A3dInitError):
    """A numerical failure (no convergence, a singular system)."""

    kind = "numerical"


#: The class the native module raises for each library kind.
BY_KIND = {
    "input_file": InputFileError,
    "option_value": OptionValueError,
    "model": ModelError,
    "numerical": NumericalError,
    "output": OutputError,
    "other": A3dInitError,
}
