"""A board's dense grids of foothold values, shared by the body path and footstep planners.

Each leg's scorer's terrain part (:meth:`FootholdScorer.dense
<footfall.features.scorer.FootholdScorer.dense>`) on a lattice over the
board, scored once per distinct (terrain part, mirroring) and kept per map
object for the process, and the look-ups of a lattice point's value.
"""

from __future__ import annotations

import weakref

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.features.dense import ScoreGrid, lattice_index
from footfall.features.scorer import FootholdScorer, RewardFor


def terrain_grids(hmap: HeightMap, reward_for: RewardFor, robot: RobotDescription = LITTLEDOG,
                  spacing: float = 0.005, yaw: float = 0.0) -> dict[str, ScoreGrid]:
    """Dense terrain-part grids of every leg, one ``dense`` per distinct (scorer part, mirror).

    Legs whose rewards have the same terrain part and the same mirroring
    (e.g. both left legs under one reward) share one grid object, and a map's
    grids are scored once per process: the next run on the same map object
    (see :func:`footfall.experiments.runs.execute`) reuses them.

    Parameters
    ----------
    reward_for : callable
        ``reward_for(leg_name) -> FootholdScorer``.
    spacing : float
        Lattice spacing [m] of the grids.
    yaw : float
        Body heading [rad] the patches are oriented by.

    Returns
    -------
    dict
        Leg name -> :class:`~footfall.features.scoring.ScoreGrid` (reward -inf where invalid).
    """
    cache = _GRIDS.setdefault(hmap, {})
    out = {}
    for name in LEG_NAMES:
        reward = reward_for(name)
        if not isinstance(reward, FootholdScorer):
            raise FootfallError(f"reward_for({name!r}) must return a FootholdScorer, "
                                f"got {type(reward).__name__}")
        mirror = robot.leg(name).mirrored
        key = (reward.key(state=False), mirror, float(spacing), float(yaw))
        if key not in cache:
            grid = reward.dense(hmap, spacing=spacing, yaw=yaw, mirror=mirror)
            for array in (grid.x, grid.y, grid.reward, grid.valid):
                array.setflags(write=False)  # shared by every run on the map
            cache[key] = grid
        out[name] = cache[key]
    return out


_GRIDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
# map -> {(reward's terrain key, mirror, spacing, yaw): ScoreGrid}: a board's grids, scored once
# per process (a map's heights are read-only; every run of a batch on one board shares them)


def grid_spacing(grid: ScoreGrid) -> float:
    """Lattice spacing [m] of a score grid."""
    return float((grid.x[-1] - grid.x[0]) / (grid.x.size - 1)) if grid.x.size > 1 else \
        float((grid.y[-1] - grid.y[0]) / max(grid.y.size - 1, 1))


def grid_index(grid: ScoreGrid, xy: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Lattice index (i, j) of the grid point nearest each position [m] (..., 2); may be off the grid."""
    return lattice_index(grid.x[0], grid.y[0], xy, spacing)


def grid_values(grid: ScoreGrid, xy: np.ndarray, spacing: float) -> np.ndarray:
    """Terrain reward at the lattice point nearest each position [m], (..., 2) -> (...); -inf: off."""
    i, j = grid_index(grid, xy, spacing)
    na, nb = grid.reward.shape
    inside = (i >= 0) & (i < na) & (j >= 0) & (j < nb)
    out = np.full(i.shape, -np.inf)
    out[inside] = grid.reward[i[inside], j[inside]]
    return out
