"""LittleDog-like terrain modules and boards built from them.

The paper's testbed (§IV-A) is a row of interchangeable 61 x 61 cm terrain
modules scanned at 1 mm: flat, steps, barriers, slopes, logs and rocky
terrain of varying difficulty. This module generates such modules as
:class:`~footfall.core.heightmap.HeightMap` objects, deterministically from a seed.

Module frame: x in [0, 0.61) m forward, y in [-0.305, 0.305) m left, z up;
heights >= 0 above the ground plane z = 0.

A board may also hold a user's own height-map files as modules, next to the
generated kinds (:mod:`footfall.terrain.file_modules`).
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Callable, Union

import numpy as np
from scipy.ndimage import gaussian_filter
from scipy.spatial import cKDTree

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.limits import check_cells
from footfall.core.plugins import load_plugins
from footfall.terrain.file_modules import (
    FILE_KIND,
    FILE_SUFFIX,
    BoardGrid,
    FileModule,
    fit_to_board,
    module_cells,
)

MODULE_SIZE = 0.61  # [m] side length of a square terrain module (61 cm)
MODULE_RESOLUTION = 0.001  # [m/cell] scan resolution (1 mm)
MODULE_CELLS = int(round(MODULE_SIZE / MODULE_RESOLUTION))  # [cells] per side (610)
MODULE_ORIGIN = (0.5 * MODULE_RESOLUTION, -0.5 * MODULE_SIZE + 0.5 * MODULE_RESOLUTION)
# [m] centre of cell (0, 0) of a module: (0.0005, -0.3045)
DEFAULT_DIFFICULTY = 0.5  # [-] difficulty of a spec such as "rocky" without ":<difficulty>"
GENERATOR = "footfall.terrain"  # provenance tag stored in HeightMap.metadata["generator"]
BOARD_GRID = BoardGrid(MODULE_RESOLUTION, MODULE_CELLS)  # the grid file modules are resampled to

Generator = Callable[[float, np.random.Generator], np.ndarray]
"""A module generator: ``(difficulty, rng) -> heights``. ``difficulty`` in [0, 1] [-] sets the
obstacle sizes (each generator's docstring gives its mapping); ``rng`` (numpy.random.Generator)
is the source of all randomness; ``heights`` (610, 610) [m] are indexed [x, y] in the module
frame, cell centres at :data:`MODULE_ORIGIN` + index * :data:`MODULE_RESOLUTION`."""

# Rocky modules (see :func:`rocky`).
_ROCK_SPACING = 0.055  # [m] spacing of the jittered grid of rock seeds
_ROCK_MERGE_SHARE = 0.3  # [-] share of seeds that join a neighbour's rock
_ROCK_MAX_HEIGHT = 0.10  # [m] cap on rock heights
_ROCK_STRIP = 0.01  # [m] bare board at both ends of the module
_ROCK_HOLLOWS = 14  # mild hollows pressed into the rocks
_ROCK_MAX_HOLES = 4  # holes drawn (1 + round(3 d) of them are pressed in)


# --------------------------------------------------------------------- helpers
def _cell_centres() -> tuple[np.ndarray, np.ndarray]:
    """Cell-centre coordinates of a module, as broadcastable arrays.

    Returns
    -------
    x : ndarray, shape (610, 1)
        Forward coordinate of each row of cells [m].
    y : ndarray, shape (1, 610)
        Lateral coordinate of each column of cells [m].
    """
    idx = np.arange(MODULE_CELLS)
    x = MODULE_ORIGIN[0] + idx * MODULE_RESOLUTION
    y = MODULE_ORIGIN[1] + idx * MODULE_RESOLUTION
    return x[:, None], y[None, :]


def _lerp(difficulty: float, easy: float, hard: float) -> float:
    """Linear map of difficulty in [0, 1] onto [easy, hard] (any unit)."""
    return easy + (hard - easy) * difficulty


def _window(cx: float, cy: float, radius: float) -> tuple[slice, slice]:
    """Index slices of the module cells within ``radius`` [m] of (cx, cy) [m]."""
    i0 = max(int(math.floor((cx - radius - MODULE_ORIGIN[0]) / MODULE_RESOLUTION)), 0)
    i1 = min(int(math.ceil((cx + radius - MODULE_ORIGIN[0]) / MODULE_RESOLUTION)) + 1, MODULE_CELLS)
    j0 = max(int(math.floor((cy - radius - MODULE_ORIGIN[1]) / MODULE_RESOLUTION)), 0)
    j1 = min(int(math.ceil((cy + radius - MODULE_ORIGIN[1]) / MODULE_RESOLUTION)) + 1, MODULE_CELLS)
    return slice(i0, max(i0, i1)), slice(j0, max(j0, j1))


# ------------------------------------------------------------------ generators
def flat(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A flat module: every height 0 [m] (``difficulty`` and ``rng`` are ignored)."""
    return np.zeros((MODULE_CELLS, MODULE_CELLS))


def steps(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Steps up onto a platform and back down to the ground; heights in [0, 0.10] m.

    Flat approach, 1-3 steps up (number drawn from the seed), a platform,
    1-3 steps down (drawn independently), flat exit; the module starts and
    ends at z = 0. The step edges run across the path, yawed together by a
    small angle.

    Difficulty mapping (d in [0, 1]):

    * platform height ``H = (0.015 + 0.085 d) * U(0.85, 1.0)`` [m]:
      0.013-0.015 m at d = 0, up to 0.10 m at d = 1; split into risers of
      unequal height (each 0.6-1.4 x the mean riser).
    * tread depth U(0.05, 0.07) m, flat approach/exit U(0.07, 0.10) m,
      edge yaw U(-0.08, 0.08) rad: independent of d.
    """
    x, y = _cell_centres()
    n_up, n_down = (int(n) for n in rng.integers(1, 4, size=2))
    total = _lerp(difficulty, 0.015, 0.10) * rng.uniform(0.85, 1.0)  # [m]
    up = rng.uniform(0.6, 1.4, size=3)[:n_up]
    down = rng.uniform(0.6, 1.4, size=3)[:n_down]
    up_risers = total * up / up.sum()  # [m]
    down_risers = total * down / down.sum()  # [m]
    tread = rng.uniform(0.05, 0.07)  # [m]
    margin_in, margin_out = rng.uniform(0.07, 0.10, size=2)  # [m]
    yaw = rng.uniform(-0.08, 0.08)  # [rad]
    along = x + math.tan(yaw) * y  # [m] position along the path, skewed with the edges
    up_levels = np.concatenate([[0.0], np.cumsum(up_risers)])  # [m] after 0..n_up edges
    down_levels = total - np.concatenate([[0.0], np.cumsum(down_risers)])  # [m]
    up_levels[-1], down_levels[-1] = total, 0.0  # exact platform and exit heights
    up_edges = margin_in + tread * np.arange(n_up)  # [m]
    down_edges = MODULE_SIZE - margin_out - tread * np.arange(n_down)[::-1]  # [m]
    passed_up = (along[..., None] >= up_edges).sum(axis=-1)  # edges behind each cell
    passed_down = (along[..., None] >= down_edges).sum(axis=-1)
    return np.minimum(up_levels[passed_up], down_levels[passed_down])


def barrier(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Bars lying across the path, with 45-degree chamfered top edges; heights in [0, 0.10] m.

    1-3 bars (number drawn from the seed), each in its own slot of the middle
    of the module ``x in [0.12, 0.49]`` m, slightly yawed; the module starts
    and ends at z = 0.

    Difficulty mapping (d in [0, 1]):

    * bar height ``(0.01 + 0.09 d) * U(0.7, 1.0)`` [m]: 0.007-0.01 m at d = 0,
      up to 0.10 m at d = 1.
    * bar width U(0.02, 0.08) m, yaw U(-0.05, 0.05) rad, chamfer
      min(3 mm, width / 4, height / 2): independent of d.
    """
    x, y = _cell_centres()
    n = int(rng.integers(1, 4))
    heights = _lerp(difficulty, 0.01, 0.10) * rng.uniform(0.7, 1.0, size=3)  # [m]
    widths = rng.uniform(0.02, 0.08, size=3)  # [m]
    jitter = rng.uniform(-0.5, 0.5, size=3)  # [-] of the free room in a slot
    yaws = rng.uniform(-0.05, 0.05, size=3)  # [rad]
    start, end = 0.12, 0.49  # [m] stretch of the module holding the bars
    slot = (end - start) / n  # [m]
    z = np.zeros((MODULE_CELLS, MODULE_CELLS))
    for k in range(n):
        h, w, yaw = heights[k], widths[k], yaws[k]
        centre = start + (k + 0.5) * slot + jitter[k] * (slot - w - 0.04)
        u = np.abs((x - centre) * math.cos(yaw) + y * math.sin(yaw))  # [m] from the bar axis
        chamfer = min(0.003, w / 4, h / 2)  # [m]
        bar = np.where(u <= w / 2, np.minimum(h, h - chamfer + (w / 2 - u)), 0.0)
        z = np.maximum(z, bar)
    return z


def slope(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A ramp up, a plateau and a ramp down, tilted sideways; heights in [0, 0.102] m.

    The profile along x rises linearly from z = 0, holds, and falls back to
    z = 0 before the end of the module. A lateral tilt drawn from the seed
    scales the profile by ``1 + k y / 0.305`` with k in U(-0.35, 0.35), so the
    plateau leans left or right while the module's ends stay at z = 0.

    Difficulty mapping (d in [0, 1]):

    * plateau height on the centre line ``H = 0.015 + 0.06 d`` [m]:
      0.015 m at d = 0, 0.075 m at d = 1 (0.10 m at the high side with the
      largest tilt).
    * ramp angles ``(8 + 17 d) deg * U(0.8, 1.0)`` each: 6-8 deg at d = 0,
      20-25 deg (0.35-0.44 rad) at d = 1.
    * flat approach/exit U(0.04, 0.08) m: independent of d.
    """
    x, y = _cell_centres()
    height = _lerp(difficulty, 0.015, 0.075)  # [m]
    angles = np.radians(_lerp(difficulty, 8.0, 25.0)) * rng.uniform(0.8, 1.0, size=2)  # [rad]
    run_up, run_down = height / np.tan(angles)  # [m] horizontal length of each ramp
    margin_in, margin_out = rng.uniform(0.04, 0.08, size=2)  # [m]
    tilt = rng.uniform(-0.35, 0.35)  # [-] relative height change at the side edges
    rise = (x - margin_in) / run_up
    fall = (MODULE_SIZE - margin_out - x) / run_down
    profile = height * np.clip(np.minimum(rise, fall), 0.0, 1.0)  # (610, 1) [m]
    return profile * (1.0 + tilt * y / (0.5 * MODULE_SIZE))


def logs(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Half-cylinder logs lying across the path at slight random angles; heights in [0, 0.09] m.

    1-3 logs (number drawn from the seed, reduced so that the logs fit with
    a gap of at least 3 cm), each centred in its own slot of
    ``x in [0.075, 0.535]`` m; the module starts and ends at z = 0.

    Difficulty mapping (d in [0, 1]):

    * log radius = height ``(0.015 + 0.075 d) * U(0.8, 1.0)`` [m]:
      0.012-0.015 m at d = 0, up to 0.09 m at d = 1 (then at most 2 logs).
    * yaw U(-0.1, 0.1) rad: independent of d.
    """
    x, y = _cell_centres()
    n_drawn = int(rng.integers(1, 4))
    max_radius = _lerp(difficulty, 0.015, 0.09)  # [m]
    radii = max_radius * rng.uniform(0.8, 1.0, size=3)  # [m]
    yaws = rng.uniform(-0.1, 0.1, size=3)  # [rad]
    jitter = rng.uniform(-0.5, 0.5, size=3)  # [-] of the free room in a slot
    start, end = 0.075, 0.535  # [m] stretch of the module holding the logs
    n = max(1, min(n_drawn, int((end - start) // (2 * max_radius + 0.03))))
    slot = (end - start) / n  # [m]
    z = np.zeros((MODULE_CELLS, MODULE_CELLS))
    for k in range(n):
        r, yaw = radii[k], yaws[k]
        centre = start + (k + 0.5) * slot + jitter[k] * max(slot - 2 * r - 0.03, 0.0)
        u = (x - centre) * math.cos(yaw) + y * math.sin(yaw)  # [m] from the log's axis
        z = np.maximum(z, np.sqrt(np.clip(r * r - u * u, 0.0, None)))
    return z


def rocky(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A bed of irregular rocks with slanted faces, cracks, holes, hollows; heights in [0, 0.10] m.

    Rocks are the Voronoi cells (found with :class:`scipy.spatial.cKDTree`)
    of a jittered 5.5 cm grid of seed points plus 40 % more seeds scattered
    at random; about a fifth of the seeds join their nearest neighbour's
    rock, so the rocks are irregular polygons of roughly 1.5-10 cm. Each
    rock has a planar, tilted top (a slanted face) whose edges are rounded
    with a fillet of radius 4-10 mm; between rocks runs a narrow crack
    (1-3 mm wide) down to 0-40 % of the lower neighbour's height. A few
    small steep-walled holes (radius 6-12 mm, depth 1-3 cm) and mild
    hollows (Gaussian dents 2-5 mm deep, sigma 5-15 mm, so 1-3 cm across)
    are pressed into the rocks, and a fine texture (grain of a few cells
    plus a gentle waviness of the faces) is added. A 1 cm strip of bare
    board (z = 0) lines both ends of the module in x.

    Difficulty mapping (d in [0, 1]):

    * height of a rock's face at its seed point
      ``0.008 + (0.012 + 0.045 d) * U(0, 1)`` [m]: 0.008-0.02 m at d = 0,
      0.008-0.065 m at d = 1 (faces reach about 0.09 m with their tilt);
      heights are capped at 0.10 m.
    * face tilt ``(4 + 26 d) deg * sqrt(U(0, 1))``: up to 4 deg at d = 0, up
      to 30 deg (0.52 rad) at d = 1, in a random direction.
    * number of holes ``1 + round(3 d)``: 1 at d = 0, 4 at d = 1.
    * fine texture: grain (correlation ~1.5 mm) of standard deviation
      ``0.0001 + 0.0002 d`` [m] and waviness (~8 mm) of standard deviation
      ``0.0002 + 0.0004 d`` [m].
    * rock size, crack width, fillets, hole and hollow sizes: independent
      of d.
    """
    x, y = _cell_centres()
    rocks = _draw_rocks(difficulty, rng)
    points = np.stack([a.ravel() for a in np.broadcast_arrays(x, y)], axis=1)  # (610 * 610, 2)
    z = _rock_bed(rocks, points).reshape(MODULE_CELLS, MODULE_CELLS)
    _press_hollows(z, x, y, rng)
    _press_holes(z, x, y, difficulty, rng)
    _add_texture(z, difficulty, rng)
    on_board = (_from_ends(points) < 0.0).reshape(MODULE_CELLS, MODULE_CELLS)
    return np.where(on_board, 0.0, np.clip(z, 0.0, _ROCK_MAX_HEIGHT))


@dataclass(frozen=True, eq=False)
class _Rocks:
    """The rocks of a rocky module, one entry per seed point; a rock is the seeds that name it."""

    seeds: np.ndarray  # (n, 2) [m] seed points: a jittered grid, then the scattered extra seeds
    tree: cKDTree  # of the seeds
    rock_of: np.ndarray  # (n,) the seed whose rock each seed's Voronoi cell belongs to
    base: np.ndarray  # (n,) [m] height of the rock's face at its seed point
    gradient: np.ndarray  # (n, 2) [-] slope of the face along x and y
    fillet: np.ndarray  # (n,) [m] radius of the rounded edges
    crack: np.ndarray  # (n,) [m] half-width of the crack around the rock
    fill: np.ndarray  # (n,) [-] crack floor as a fraction of the rock height


def _draw_rocks(difficulty: float, rng: np.random.Generator) -> _Rocks:
    """The rocks' seed points, which rock each joins, and every rock's face (see :func:`rocky`)."""
    spacing = _ROCK_SPACING
    # Seeds: a jittered grid reaching one spacing beyond the module, plus
    # scattered extra seeds that split rocks into smaller ones.
    gx = np.arange(-spacing, MODULE_SIZE + 1.5 * spacing, spacing)
    gy = np.arange(-0.5 * MODULE_SIZE - spacing, 0.5 * MODULE_SIZE + 1.5 * spacing, spacing)
    grid = np.stack(np.meshgrid(gx, gy, indexing="ij"), axis=-1).reshape(-1, 2)
    grid = grid + rng.uniform(-0.45, 0.45, size=grid.shape) * spacing
    extra = rng.uniform((gx[0], gy[0]), (gx[-1], gy[-1]), size=(int(0.4 * len(grid)), 2))
    seeds = np.concatenate([grid, extra])
    n_seeds = seeds.shape[0]
    tree = cKDTree(seeds)
    # Rocks: most seeds make their own rock; some join their nearest neighbour's
    # rock, making larger, elongated rocks.
    nearest = tree.query(seeds, k=2)[1][:, 1]
    joins = rng.uniform(0.0, 1.0, n_seeds) < _ROCK_MERGE_SHARE
    rock_of = np.where(joins & ~joins[nearest], nearest, np.arange(n_seeds))

    base = 0.008 + _lerp(difficulty, 0.012, 0.057) * rng.uniform(0.0, 1.0, n_seeds)  # [m]
    tilt = np.radians(_lerp(difficulty, 4.0, 30.0)) * np.sqrt(rng.uniform(0.0, 1.0, n_seeds))
    heading = rng.uniform(0.0, 2 * np.pi, n_seeds)  # [rad] direction of steepest ascent
    gradient = np.tan(tilt)[:, None] * np.stack([np.cos(heading), np.sin(heading)], axis=1)
    fillet = rng.uniform(0.004, 0.010, n_seeds)
    crack = rng.uniform(0.0005, 0.0015, n_seeds)
    fill = rng.uniform(0.0, 0.4, n_seeds)
    return _Rocks(seeds, tree, rock_of, base, gradient, fillet, crack, fill)


def _from_ends(points: np.ndarray) -> np.ndarray:
    """Distance [m] of points (n, 2) [m] from the bare strips at the x ends (< 0: on a strip)."""
    return np.minimum(points[:, 0], MODULE_SIZE - points[:, 0]) - _ROCK_STRIP


def _rock_bed(rocks: _Rocks, points: np.ndarray) -> np.ndarray:
    """Height [m] (n,) of the rock faces at points (n, 2) [m], with rounded edges and cracks."""
    # The three nearest seeds of every cell.
    dist, idx = rocks.tree.query(points, k=3)
    rock_of, seeds = rocks.rock_of, rocks.seeds
    own = rock_of[idx[:, 0]]
    # Distance to the rock's edge: the nearest bisector between the nearest
    # seed and a neighbour seed of another rock (a border inside a rock is none).
    bisector = np.full(own.shape, np.inf)
    other = own.copy()
    for j in (2, 1):  # the second-nearest seed wins a tie
        gap = np.linalg.norm(seeds[idx[:, j]] - seeds[idx[:, 0]], axis=1)
        b = (dist[:, j] ** 2 - dist[:, 0] ** 2) / (2.0 * gap)  # [m]
        closer = (rock_of[idx[:, j]] != own) & (b <= bisector)
        bisector = np.where(closer, b, bisector)
        other = np.where(closer, rock_of[idx[:, j]], other)
    border = bisector  # [m], inf where the nearest seeds all belong to one rock

    top = _face(rocks, points, own)
    edge = np.clip(np.minimum(border, _from_ends(points)), 0.0, None)  # [m] to the rock's edge
    r = rocks.fillet[own]
    t = np.clip(1.0 - edge / r, 0.0, 1.0)
    drop = r * (1.0 - np.sqrt(1.0 - t * t))  # quarter-circle fillet: r at the edge, 0 inside
    z = top - np.minimum(drop, 0.7 * top)
    in_crack = border < rocks.crack[own]
    floor = rocks.fill[own] * np.minimum(top, _face(rocks, points, other))
    return np.where(in_crack, np.minimum(z, floor), z)


def _face(rocks: _Rocks, points: np.ndarray, rock: np.ndarray) -> np.ndarray:
    """Height [m] of each point (n, 2) [m] on the face of its rock, ``rock`` (n,) [index]."""
    offset = points - rocks.seeds[rock]
    return np.clip(rocks.base[rock] + np.einsum("ij,ij->i", rocks.gradient[rock], offset), 0.0,
                   _ROCK_MAX_HEIGHT)


def _press_hollows(z: np.ndarray, x: np.ndarray, y: np.ndarray, rng: np.random.Generator) -> None:
    """Press mild hollows, shallow Gaussian dents, into heights ``z`` (610, 610) [m] in place."""
    n_hollows = _ROCK_HOLLOWS
    hollow_x = rng.uniform(0.0, MODULE_SIZE, n_hollows)
    hollow_y = rng.uniform(-0.5 * MODULE_SIZE, 0.5 * MODULE_SIZE, n_hollows)
    hollow_depth = rng.uniform(0.002, 0.005, n_hollows)  # [m]
    hollow_sigma = rng.uniform(0.005, 0.015, n_hollows)  # [m]
    for cx, cy, a, s in zip(hollow_x, hollow_y, hollow_depth, hollow_sigma):  # 14 small windows
        wi, wj = _window(cx, cy, 3 * s)
        rho2 = (x[wi] - cx) ** 2 + (y[:, wj] - cy) ** 2
        z[wi, wj] -= a * np.exp(-rho2 / (2 * s * s))


def _press_holes(z: np.ndarray, x: np.ndarray, y: np.ndarray, difficulty: float,
                 rng: np.random.Generator) -> None:
    """Press small holes (flat bottom, steep conical walls) into ``z`` (610, 610) [m] in place."""
    max_holes, strip = _ROCK_MAX_HOLES, _ROCK_STRIP
    hole_x = rng.uniform(strip + 0.03, MODULE_SIZE - strip - 0.03, max_holes)
    hole_y = rng.uniform(-0.5 * MODULE_SIZE + 0.03, 0.5 * MODULE_SIZE - 0.03, max_holes)
    hole_radius = rng.uniform(0.006, 0.012, max_holes)  # [m]
    hole_depth = rng.uniform(0.01, 0.03, max_holes)  # [m]
    n_holes = 1 + int(round(3 * difficulty))
    for cx, cy, rad, depth in list(zip(hole_x, hole_y, hole_radius, hole_depth))[:n_holes]:
        wi, wj = _window(cx, cy, rad)
        rho = np.sqrt((x[wi] - cx) ** 2 + (y[:, wj] - cy) ** 2)
        z[wi, wj] -= depth * np.clip((rad - rho) / (0.4 * rad), 0.0, 1.0)


def _add_texture(z: np.ndarray, difficulty: float, rng: np.random.Generator) -> None:
    """Add a fine texture to ``z`` [m] in place: grain of a few cells plus gentle waviness."""
    amplitude = _lerp(difficulty, 0.0002, 0.0006)  # [m] of the waviness; grain is half
    grain = gaussian_filter(rng.standard_normal(z.shape), sigma=1.5)
    wave = gaussian_filter(rng.standard_normal(z.shape), sigma=8.0)
    z += amplitude * (0.5 * grain / grain.std() + wave / wave.std())


KINDS: dict[str, Generator] = {
    "flat": flat,
    "steps": steps,
    "barrier": barrier,
    "slope": slope,
    "logs": logs,
    "rocky": rocky,
}
"""Terrain module kinds: name -> generator ``(difficulty, rng) -> heights (610, 610) [m]``."""
BUILTIN_KINDS = tuple(KINDS)  # the paper's module kinds (§IV-A)


def register_kind(name: str, generator: Generator) -> Generator:
    """Make a terrain module kind available by name (to modules, boards and the CLI).

    ``generator(difficulty, rng)`` returns the module's heights, shape
    (MODULE_CELLS, MODULE_CELLS) [m], for a difficulty in [0, 1], drawing
    every random number from ``rng``; the edges that meet a neighbouring
    module should be at height 0. Returns the generator (usable as a decorator
    with :func:`functools.partial`).
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"a terrain kind needs a name like 'craters', got {name!r}")
    if name == FILE_KIND:
        raise ValueError(f"{FILE_KIND!r} names the board modules read from files; "
                         f"choose another name")
    if name in KINDS and KINDS[name] is not generator:
        raise ValueError(f"terrain kind {name!r} is already registered")
    if not callable(generator):
        raise ValueError(f"the generator of terrain kind {name!r} must be callable")
    KINDS[name] = generator
    return generator


def unregister_kind(name: str) -> None:
    """Forget a kind registered with :func:`register_kind` (the built-in ones stay)."""
    if name not in BUILTIN_KINDS:
        KINDS.pop(name, None)


# ------------------------------------------------------------------ public API
def _check_kind(kind: object) -> str:
    load_plugins()  # a kind may come from a plugin (footfall.core.plugins)
    if not isinstance(kind, str) or kind not in KINDS:
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
    heights = KINDS[kind](difficulty, np.random.default_rng(seed))
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
