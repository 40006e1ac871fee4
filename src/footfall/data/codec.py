"""How the store keeps values in SQLite columns: a NumPy array as a blob beside its shape and dtype.

Every array is written as raw little-endian float64 bytes, row-major, with its shape as JSON;
reading checks all three against each other, so a damaged row is reported, never reshaped.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError

DTYPE = "<f8"  # every array is stored as little-endian float64, nothing else is read


def encode(array: np.ndarray) -> tuple[bytes, str, str]:
    """The three column values of an array: raw bytes, JSON shape ``"[n, 3]"`` and dtype ``"<f8"``.

    Parameters
    ----------
    array : array-like of any shape
        Numbers; converted to float64 (an integer or float32 array is stored as float64).
    """
    a = np.ascontiguousarray(array, dtype=DTYPE)
    return a.tobytes(), json.dumps(list(a.shape)), DTYPE


def decode(blob: bytes, shape_json: str, dtype: str, what: str) -> np.ndarray:
    """Rebuild an array from its three columns; any inconsistency is a corrupt store.

    Parameters
    ----------
    blob, shape_json, dtype
        The column values :func:`encode` wrote.
    what : str
        Names the value in the error message, e.g. ``"its candidates"``.

    Returns
    -------
    array of shape ``json.loads(shape_json)``, float64, read-only (a view of ``blob``).

    Raises
    ------
    FootfallError
        For a dtype other than ``"<f8"``, a shape that is not a JSON list of
        integers >= 0, or a blob whose length does not match the shape.
    """
    if dtype != DTYPE:
        raise FootfallError(f"{what} has unsupported dtype {dtype!r}")
    try:
        shape = json.loads(shape_json)
    except (TypeError, ValueError):
        raise FootfallError(f"{what} has a malformed shape {shape_json!r}") from None
    if (not isinstance(shape, list) or not all(isinstance(s, int) and not isinstance(s, bool)
                                               and s >= 0 for s in shape)):
        raise FootfallError(f"{what} has a malformed shape {shape_json!r}")
    if not isinstance(blob, bytes) or len(blob) != math.prod(shape) * np.dtype(dtype).itemsize:
        raise FootfallError(f"{what} holds {len(blob) if isinstance(blob, bytes) else 'no'} "
                            f"bytes, not the {math.prod(shape)} numbers of shape {tuple(shape)}")
    return np.frombuffer(blob, dtype=dtype).reshape(shape)


def text(value: Any, what: str) -> str:
    """A TEXT column's value, checked: SQLite would hand back whatever a damaged row holds."""
    if not isinstance(value, str):
        raise FootfallError(f"{what} is not text")
    return value
