"""Size limits on what footfall reads and on the counts it accepts, so that bad input fails fast.

A hostile or mistaken input -- a compressed file that inflates to gigabytes, a height map of
10^12 cells, ``-n 10**15`` -- must fail with one clear line before anything is inflated or
allocated, not eat the machine. Every limit has a generous default for real use and can be
raised by the user:

* on the command line, ``footfall --limit max_map_cells=400000000 ...`` (repeatable);
* for a library user or a worker process, the environment variable named after the field,
  ``FOOTFALL_MAX_MAP_CELLS=400000000`` (the command-line option sets it too, so that worker
  processes inherit it);
* in code, ``with use_limits(Limits(max_map_cells=...)):``.

The fields are documented in docs/configuration.md (generated from the declarations below).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import numbers
import os
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from footfall.core.errors import FootfallError
from footfall.core.params import Params, at_least, param

ENV_PREFIX = "FOOTFALL_"  # FOOTFALL_<FIELD NAME IN CAPITALS> overrides a default

GiB = 1 << 30


@dataclass(frozen=True)
class Limits(Params):
    """The largest inputs footfall accepts; raise one when a real input needs more."""

    max_map_cells: int = param(
        50_000_000, unit="cells", range=at_least(4),
        doc="the largest height map read, imported or made (50 M cells: 7 m x 7 m at 1 mm)")
    max_array_bytes: int = param(
        GiB, unit="bytes", range=at_least(1),
        doc="the largest array one file may hold once decompressed (checked before inflating)")
    max_file_bytes: int = param(
        4 * GiB, unit="bytes", range=at_least(1),
        doc="the largest file read, and the most all arrays of one file may inflate to")
    max_metadata_bytes: int = param(
        16 << 20, unit="bytes", range=at_least(1),
        doc="the longest JSON metadata a file may carry")
    max_metadata_depth: int = param(
        32, unit="levels", range=at_least(1),
        doc="the deepest nesting of lists and objects in a file's JSON metadata")
    max_scan_points: int = param(
        50_000_000, unit="points", range=at_least(1),
        doc="the most points an imported point cloud (PLY, XYZ) may hold")
    max_count: int = param(
        100_000, unit="-", range=at_least(1),
        doc="the largest count a command accepts (demonstrations, runs, steps, repeats)")


_override: Limits | None = None


def _from_environment() -> Limits:
    values: dict[str, Any] = {}
    for f in dataclasses.fields(Limits):
        raw = os.environ.get(ENV_PREFIX + f.name.upper())
        if raw is not None:
            values[f.name] = _parse(f.name, raw, source=ENV_PREFIX + f.name.upper())
    return Limits(**values)


def _parse(name: str, raw: str, source: str) -> int | float:
    field = next((f for f in dataclasses.fields(Limits) if f.name == name), None)
    if field is None:
        known = ", ".join(f.name for f in dataclasses.fields(Limits))
        raise FootfallError(f"unknown limit {name!r} (known: {known})")
    try:
        number = float(raw.replace("_", ""))
    except ValueError:
        raise FootfallError(f"{source}: limit {name} must be a number, got {raw!r}") from None
    if not math.isfinite(number) or number < 1:
        raise FootfallError(f"{source}: limit {name} must be a finite number >= 1, got {raw!r}")
    if field.type in (int, "int"):
        if number != int(number):
            raise FootfallError(f"{source}: limit {name} must be a whole number, got {raw!r}")
        return int(number)
    return number


def current_limits() -> Limits:
    """The limits in force: those set by :func:`use_limits`, else the environment's, else the defaults."""
    return _override if _override is not None else _from_environment()


@contextlib.contextmanager
def use_limits(limits: Limits) -> Iterator[Limits]:
    """Run a block with ``limits`` in force (in this process)."""
    global _override
    before = _override
    _override = limits
    try:
        yield limits
    finally:
        _override = before


def apply_assignments(assignments: tuple[str, ...] | list[str]) -> Limits:
    """Put ``name=value`` limits (``--limit``) in force for this process and its workers.

    Raises
    ------
    FootfallError
        For an unknown name, a malformed assignment or a value that is not a number >= 1.
    """
    for item in assignments:
        name, sep, raw = item.partition("=")
        if not sep:
            raise FootfallError(f"--limit takes NAME=VALUE, got {item!r}")
        value = _parse(name.strip(), raw.strip(), source="--limit")
        os.environ[ENV_PREFIX + name.strip().upper()] = str(value)
    return current_limits()


@contextlib.contextmanager
def limits_of_one_command() -> Iterator[None]:
    """Undo, after the block, what :func:`apply_assignments` put in the environment."""
    names = [ENV_PREFIX + f.name.upper() for f in dataclasses.fields(Limits)]
    before = {n: os.environ.get(n) for n in names}
    try:
        yield
    finally:
        for n, value in before.items():
            if value is None:
                os.environ.pop(n, None)
            else:
                os.environ[n] = value


def check_count(value: Any, what: str, minimum: int = 0) -> int:
    """``value`` as a count from ``minimum`` to the ``max_count`` limit.

    Raises
    ------
    FootfallError
        Naming ``what`` for a non-integer, one below ``minimum`` or one above the limit.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise FootfallError(f"{what} must be a whole number, got {value!r}")
    limit = current_limits().max_count
    if value < minimum:
        raise FootfallError(f"{what} must be >= {minimum}, got {value}")
    if value > limit:
        raise FootfallError(f"{what} = {value} is above the limit of {limit} "
                            f"(raise it with --limit max_count=N)")
    return int(value)


def check_cells(shape: tuple[int, ...], what: str) -> None:
    """Refuse a grid of more cells than the ``max_map_cells`` limit, before it is allocated."""
    cells = math.prod(int(s) for s in shape)
    limit = current_limits().max_map_cells
    if cells > limit:
        raise FootfallError(f"{what} would have {cells:.3g} cells, above the limit of {limit} "
                            f"(raise it with --limit max_map_cells=N)")
