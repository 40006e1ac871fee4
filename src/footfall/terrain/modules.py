"""LittleDog-like terrain modules and boards built from them.

The paper's testbed (§IV-A) is a row of interchangeable 61 x 61 cm terrain
modules scanned at 1 mm: flat, steps, barriers, slopes, logs and rocky
terrain of varying difficulty. This module makes such modules and boards as
:class:`~footfall.core.heightmap.HeightMap` objects, deterministically from a
seed, from the registered kinds (:mod:`footfall.terrain.kinds`) in the module
frame of :mod:`footfall.terrain.geometry`.

A board may also hold a user's own height-map files as modules, next to the
generated kinds (:mod:`footfall.terrain.file_modules`).
"""

from __future__ import annotations

import numbers
import os
from collections.abc import Iterable
from typing import Union

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.limits import check_cells
from footfall.terrain.file_modules import (
    FILE_SUFFIX,
    BoardGrid,
    FileModule,
    fit_to_board,
    module_cells,
)
from footfall.terrain.geometry import MODULE_CELLS, MODULE_ORIGIN, MODULE_RESOLUTION, MODULE_SIZE
from footfall.terrain.kinds import KINDS

DEFAULT_DIFFICULTY = 0.5  # [-] difficulty of a spec such as "rocky" without ":<difficulty>"
GENERATOR = "footfall.terrain"  # provenance tag stored in HeightMap.metadata["generator"]
BOARD_GRID = BoardGrid(MODULE_RESOLUTION, MODULE_CELLS)  # the grid file modules are resampled to


def _check_kind(kind: object) -> str:
    if not isinstance(kind, str) or kind not in KINDS:  # (a kind may come from a plugin)
        raise FootfallError(f"unknown terrain module kind {kind!r}; "
                            f"known kinds: {', '.join(KINDS)}")
    return kind


def _check_difficulty(difficulty: object) -> float:
    if isinstance(difficulty, bool) or not isinstance(difficulty, numbers.Real):
        raise FootfallError(f"difficulty must be a number in [0, 1], got {difficulty!r}")
    value = float(difficulty)
    if not (0.0 <= value <= 1.0):  # also rejects NaN
        raise FootfallError(f"difficulty must be in [0, 1], got {difficulty!r}")
    return value


def _check_seed(seed: object) -> int:
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise FootfallError(f"seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def _module_record(kind: str, difficulty: float, seed: int, x_start: float) -> dict:
    return {"kind": kind, "difficulty": difficulty, "seed": seed,
            "x_start": x_start, "x_end": x_start + MODULE_SIZE}


def _module_heights(kind: str, difficulty: float, seed: int) -> np.ndarray:
    heights = KINDS.get(kind)(difficulty, np.random.default_rng(seed))
    if heights.shape != (MODULE_CELLS, MODULE_CELLS):  # guards the registry
        raise AssertionError(f"generator {kind!r} returned shape {heights.shape}")
    return heights


def make_module(kind: str, difficulty: float, seed: int) -> HeightMap:
    """Generate one 61 x 61 cm terrain module at 1 mm resolution.

    Parameters
    ----------
    kind : str
        One of :data:`KINDS`: flat, steps, barrier, slope, logs, rocky.
    difficulty : float
        Difficulty in [0, 1] [-]; obstacle heights grow with it up to about
        0.10 m at 1 (see each generator for its mapping).
    seed : int
        Non-negative seed; the same (kind, difficulty, seed) always gives the
        same heights.

    Returns
    -------
    HeightMap
        610 x 610 cells of 0.001 m; cell centres at x = 0.0005 + i * 0.001,
        y = -0.3045 + j * 0.001 [m]; heights >= 0 [m]. ``metadata`` is
        ``{"generator": "footfall.terrain", "modules": [{"kind",
        "difficulty", "seed", "x_start", "x_end"}]}`` with x in [m].

    Raises
    ------
    FootfallError
        For an unknown kind, a difficulty outside [0, 1] or a bad seed.
    """
    kind = _check_kind(kind)
    difficulty = _check_difficulty(difficulty)
    seed = _check_seed(seed)
    return HeightMap(_module_heights(kind, difficulty, seed), MODULE_RESOLUTION, MODULE_ORIGIN,
                     metadata={"generator": GENERATOR,
                               "modules": [_module_record(kind, difficulty, seed, 0.0)]})


BoardSpec = Union[tuple[str, float], FileModule]
"""One module of a board: a generated ``(kind, difficulty)`` or a height-map file."""


def _check_board_spec(spec: object, specs: object) -> BoardSpec:
    """A (kind, difficulty) pair checked, or a :class:`FileModule` as it is."""
    if isinstance(spec, FileModule):
        return spec
    try:
        kind, difficulty = spec  # type: ignore[misc]
    except (TypeError, ValueError):
        raise FootfallError(f"board specs must be (kind, difficulty) pairs or FileModules, "
                            f"got {specs!r}") from None
    return _check_kind(kind), _check_difficulty(difficulty)


def _with_flat_ends(row: list[BoardSpec]) -> list[BoardSpec]:
    """``row`` with a flat module before and after it, unless it starts / ends with one."""
    def is_flat(spec: BoardSpec) -> bool:
        return not isinstance(spec, FileModule) and spec[0] == "flat"

    return ([] if is_flat(row[0]) else [("flat", 0.0)]) + row + \
        ([] if is_flat(row[-1]) else [("flat", 0.0)])


def _x(cells: int) -> float:
    """Length [m] of ``cells`` board cells (k modules: exactly k * MODULE_SIZE)."""
    return cells / MODULE_CELLS * MODULE_SIZE


def _board_module(spec: BoardSpec, seed: int, start: int) -> tuple[np.ndarray, dict]:
    """Heights (n, 610) [m] and record of one module of a board starting at cell ``start``.

    A file module ends at the start of the next module, ``x_end = _x(start + n)`` [m]; a
    generated one at ``x_start + MODULE_SIZE``, as boards were always recorded.
    """
    if isinstance(spec, FileModule):
        heights, record = fit_to_board(spec, BOARD_GRID)
        return heights, {**record, "x_start": _x(start), "x_end": _x(start + heights.shape[0])}
    kind, difficulty = spec
    return (_module_heights(kind, difficulty, seed),
            _module_record(kind, difficulty, seed, _x(start)))


def make_board(specs: Iterable[BoardSpec], seed: int, flat_ends: bool = True) -> HeightMap:
    """Lay terrain modules in a row along +x.

    A generated module is 0.61 m long; a :class:`~footfall.terrain.file_modules.FileModule`
    (a height-map file) keeps its own length, rounded to whole 1 mm cells, and is
    resampled to 1 mm, padded with no data (NaN) or cropped to the board's width and
    shifted to stand on z = 0 (see :mod:`footfall.terrain.file_modules`). Every module
    spans the full width ``y in [-0.305, 0.305)`` m.

    Parameters
    ----------
    specs : iterable of (str, float) or FileModule
        (kind, difficulty) of each generated module, or a file module, in order along +x.
    seed : int
        Non-negative board seed; module seeds are drawn from
        ``np.random.SeedSequence(seed).spawn`` (one per module, flat ends and file
        modules included), so the board is deterministic.
    flat_ends : bool
        If true, put a flat module before the first spec unless it is flat,
        and after the last spec unless it is flat, so the robot starts and
        stops on flat ground (a file module is not flat).

    Returns
    -------
    HeightMap
        (cells of all modules along x) x 610 cells of 0.001 m, cell (0, 0) at
        (0.0005, -0.3045) m. ``metadata["modules"]`` lists each module's x_start and
        x_end [m] and kind; a generated one's difficulty and seed (reproduces it with
        :func:`make_module`); a file module's ``kind`` "file", file name, content hash,
        resolution [m/cell], width [m], width_fit and z_shift [m].

    Raises
    ------
    FootfallError
        For an empty spec list, a malformed spec, an unknown kind, a
        difficulty outside [0, 1], a bad seed, or a board above the
        ``max_map_cells`` limit (checked before any module is made).
    """
    seed = _check_seed(seed)
    try:
        items = list(specs)
    except TypeError:
        raise FootfallError(f"board specs must be (kind, difficulty) pairs or FileModules, "
                            f"got {specs!r}") from None
    row = [_check_board_spec(spec, specs) for spec in items]
    if not row:
        raise FootfallError("a board needs at least one module")
    if flat_ends:
        row = _with_flat_ends(row)
    lengths = [module_cells(s, BOARD_GRID) if isinstance(s, FileModule) else MODULE_CELLS
               for s in row]
    files = [s.name for s in row if isinstance(s, FileModule)]
    check_cells((sum(lengths), MODULE_CELLS), f"{', '.join(files)}: the board" if files
                else "the board")
    children = np.random.SeedSequence(seed).spawn(len(row))
    seeds = [int(child.generate_state(1)[0]) for child in children]
    starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])  # [cells]
    parts = [_board_module(spec, s, int(start)) for spec, s, start in zip(row, seeds, starts)]
    return HeightMap(np.concatenate([heights for heights, _ in parts], axis=0),
                     MODULE_RESOLUTION, MODULE_ORIGIN,
                     metadata={"generator": GENERATOR, "board_seed": seed,
                               "modules": [record for _, record in parts]})


def parse_module_spec(spec: str) -> tuple[str, float]:
    """Parse a module spec ``"kind[:difficulty]"``, e.g. ``"rocky:0.5"``.

    Parameters
    ----------
    spec : str
        Kind name, optionally followed by ``:`` and a difficulty in [0, 1].

    Returns
    -------
    (str, float)
        The kind and the difficulty [-] (0.5 when omitted).

    Raises
    ------
    FootfallError
        For an empty or malformed spec, an unknown kind or a difficulty that
        is not a number in [0, 1].
    """
    if not isinstance(spec, str):
        raise FootfallError(f"module spec must be a string like 'rocky:0.5', got {spec!r}")
    kind, sep, value = spec.strip().partition(":")
    kind = kind.strip().lower()
    if not kind:
        raise FootfallError(f"bad module spec {spec!r}: expected 'kind[:difficulty]', "
                            f"e.g. 'rocky:0.5'")
    _check_kind(kind)
    if not sep:
        return kind, DEFAULT_DIFFICULTY
    try:
        difficulty = float(value)
    except ValueError:
        raise FootfallError(f"bad module spec {spec!r}: difficulty {value.strip()!r} "
                            f"is not a number") from None
    return kind, _check_difficulty(difficulty)


def parse_board_spec(spec: str) -> BoardSpec:
    """Parse one module of a board: ``"kind[:difficulty]"`` or a height-map file.

    A spec ending in ``.npz`` (any case) is a module file, read by
    :meth:`FileModule.load`; so is one that is not a valid ``kind[:difficulty]`` but
    names an existing file (which must then be a ``.npz``).

    Raises
    ------
    FootfallError
        As :func:`parse_module_spec`, or naming the file: missing, not a footfall
        height map (``.npz``), damaged, too large or without data.
    """
    if isinstance(spec, str) and spec.strip().lower().endswith(FILE_SUFFIX):
        return FileModule.load(spec.strip())
    try:
        return parse_module_spec(spec)
    except FootfallError:
        if isinstance(spec, str) and os.path.isfile(spec):
            return FileModule.load(spec)  # refuses another suffix, with how to import it
        raise
