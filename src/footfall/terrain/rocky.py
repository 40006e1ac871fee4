"""Rocky terrain modules: a bed of irregular rocks with slanted faces, cracks, holes and hollows.

The hardest of the paper's module kinds (§IV-A), and the one the experiments
test on: a :data:`~footfall.terrain.geometry.Generator` registered as the kind
"rocky" in :mod:`footfall.terrain.kinds`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter
from scipy.spatial import cKDTree

from footfall.terrain.geometry import MODULE_CELLS, MODULE_SIZE, cell_centres, cell_window, lerp

# Rocky modules (see :func:`rocky`).
_ROCK_SPACING = 0.055  # [m] spacing of the jittered grid of rock seeds
_ROCK_MERGE_SHARE = 0.3  # [-] share of seeds that join a neighbour's rock
_ROCK_MAX_HEIGHT = 0.10  # [m] cap on rock heights
_ROCK_STRIP = 0.01  # [m] bare board at both ends of the module
_ROCK_HOLLOWS = 14  # mild hollows pressed into the rocks
_ROCK_MAX_HOLES = 4  # holes drawn (1 + round(3 d) of them are pressed in)


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
    x, y = cell_centres()
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

    base = 0.008 + lerp(difficulty, 0.012, 0.057) * rng.uniform(0.0, 1.0, n_seeds)  # [m]
    tilt = np.radians(lerp(difficulty, 4.0, 30.0)) * np.sqrt(rng.uniform(0.0, 1.0, n_seeds))
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
        wi, wj = cell_window(cx, cy, 3 * s)
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
        wi, wj = cell_window(cx, cy, rad)
        rho = np.sqrt((x[wi] - cx) ** 2 + (y[:, wj] - cy) ** 2)
        z[wi, wj] -= depth * np.clip((rad - rho) / (0.4 * rad), 0.0, 1.0)


def _add_texture(z: np.ndarray, difficulty: float, rng: np.random.Generator) -> None:
    """Add a fine texture to ``z`` [m] in place: grain of a few cells plus gentle waviness."""
    amplitude = lerp(difficulty, 0.0002, 0.0006)  # [m] of the waviness; grain is half
    grain = gaussian_filter(rng.standard_normal(z.shape), sigma=1.5)
    wave = gaussian_filter(rng.standard_normal(z.shape), sigma=8.0)
    z += amplitude * (0.5 * grain / grain.std() + wave / wave.std())

