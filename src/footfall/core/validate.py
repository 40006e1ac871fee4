"""Checks that a value read from a user's file is what a field needs, or one clear error.

Each check takes the value and ``what``, the field's name as the message should show it
(``groups.front.families[0].name``), and returns the value in the form the caller uses
(a float, a float64 array) or raises a :class:`FootfallError` "``what`` must be ...,
got ...". The checks are pure: no I/O, no state. The caller prefixes the file's path.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError

_TYPE_NAMES = {dict: "an object (dict)", list: "a list", str: "a string", bool: "true or false",
               int: "an integer", float: "a number"}


def shown(value: Any, limit: int = 60) -> str:
    """A short ``repr`` of ``value`` for a message (long ones cut with an ellipsis)."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def require_type(value: Any, types: type | tuple[type, ...], what: str) -> Any:
    """``value`` if it is an instance of ``types`` (a bool is never taken for an int)."""
    types = types if isinstance(types, tuple) else (types,)
    if isinstance(value, bool) and bool not in types:
        ok = False
    else:
        ok = isinstance(value, types)
    if not ok:
        words = " or ".join(_TYPE_NAMES.get(t, t.__name__) for t in types)
        raise FootfallError(f"{what} must be {words}, got {type(value).__name__} {shown(value)}")
    return value


def require_keys(value: Any, what: str, required: Iterable[str] = (),
                 optional: Iterable[str] = ()) -> dict:
    """``value`` as a dict holding every ``required`` key and no key outside both lists."""
    require_type(value, dict, what)
    required, optional = tuple(required), tuple(optional)
    missing = [k for k in required if k not in value]
    if missing:
        raise FootfallError(f"{what} lacks {', '.join(repr(k) for k in missing)}")
    unknown = sorted((str(k) for k in value if k not in required + optional))
    if unknown:
        raise FootfallError(f"{what} has unknown key(s) {', '.join(repr(k) for k in unknown)}")
    return value


def require_number(value: Any, what: str, low: float = -math.inf, high: float = math.inf,
                   low_open: bool = False) -> float:
    """``value`` as a float: a real, finite number (not a bool) in [low, high] ((low, high] if
    ``low_open``)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise FootfallError(f"{what} must be a number, got {type(value).__name__} {shown(value)}")
    number = float(value)
    inside = (number > low if low_open else number >= low) and number <= high
    if not math.isfinite(number) or not inside:
        raise FootfallError(f"{what} must be a finite number {_interval(low, high, low_open)}, "
                            f"got {shown(value)}")
    return number


def _interval(low: float, high: float, low_open: bool) -> str:
    if high == math.inf:
        return "" if low == -math.inf else f"{'>' if low_open else '>='} {low:g}"
    return f"in {'(' if low_open else '['}{low:g}, {high:g}]"


def require_int(value: Any, what: str, minimum: int | None = None,
                below: int | None = None) -> int:
    """``value`` as an int (not a bool, not a float), at least ``minimum`` and less than
    ``below`` (an index into ``below`` items, say)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise FootfallError(f"{what} must be an integer, got {type(value).__name__} "
                            f"{shown(value)}")
    if minimum is not None and value < minimum:
        raise FootfallError(f"{what} must be >= {minimum}, got {value}")
    if below is not None and value >= below:
        raise FootfallError(f"{what} must be < {below}, got {value}")
    return int(value)


def require_str_list(value: Any, what: str, length: int | None = None) -> list[str]:
    """``value`` as a list of strings (of ``length`` items, if given)."""
    require_type(value, list, what)
    for k, item in enumerate(value):
        require_type(item, str, f"{what}[{k}]")
    if length is not None and len(value) != length:
        raise FootfallError(f"{what} must hold {length} items, got {len(value)}")
    return list(value)


def require_float_array(value: Any, what: str, shape: tuple[int | None, ...] | None = None,
                        finite: bool = True, bound: float | None = None) -> np.ndarray:
    """``value`` as a float64 array: of a real floating-point dtype (not integer, complex,
    object, string or bool), of ``shape`` (None entries take any length), all finite if ``finite``,
    and every magnitude at most ``bound`` if given."""
    if not isinstance(value, np.ndarray):
        raise FootfallError(f"{what} must be an array, got {type(value).__name__}")
    if value.dtype.kind != "f":
        raise FootfallError(f"{what} must hold real floating-point numbers, "
                            f"got dtype {value.dtype}")
    if shape is not None and (value.ndim != len(shape) or any(
            n is not None and n != m for n, m in zip(shape, value.shape))):
        wanted = "(" + ", ".join("n" if n is None else str(n) for n in shape) + \
            ("," if len(shape) == 1 else "") + ")"
        raise FootfallError(f"{what} must have shape {wanted}, got {value.shape}")
    out = np.asarray(value, dtype=np.float64)
    if finite and not np.isfinite(out).all():
        raise FootfallError(f"{what} must be finite (no NaN or infinity)")
    if bound is not None and np.any(np.abs(out[np.isfinite(out)]) > bound):
        raise FootfallError(f"{what} must lie within +-{bound:g}, "
                            f"got {np.nanmax(np.abs(out[np.isfinite(out)])):g}")
    return out
