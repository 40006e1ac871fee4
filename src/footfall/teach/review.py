"""What the teaching page shows of a run step, as plain numbers (paper §II-B, Fig. 3a).

Pure functions, no server: the terrain around the swing foot as a small
height grid, the robot's body and legs at the step, which candidate of F a
click on the terrain labels, and the order in which a run's steps are worth
a look. Units: metres and radians throughout.
"""

from __future__ import annotations

import math

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import rotation_matrix
from footfall.core.robot import LEG_NAMES, RobotDescription
from footfall.core.state import RobotState

SNAP_RADIUS = 0.03  # [m] a click farther than this (horizontally) from every candidate of F
# labels nothing: it is not "the nearest candidate", it is a click beside the candidate set
WINDOW_HALF = 0.22  # [m] half the side of the terrain square shown around the swing foot: the
# robot's body and all four feet (the trunk is 0.24 m long, the legs reach ~0.1 m beyond)
WINDOW_CELLS = 112  # at most this many samples along each side of the shown terrain
FALL_LOOKBACK = 3  # steps: a step this close before a fall is one worth a look


def nearest_candidate(candidates: np.ndarray, point: np.ndarray,
                      radius: float = SNAP_RADIUS) -> int | None:
    """Index of the candidate of F (n, 3) [m] horizontally nearest ``point`` (x, y [m]), or None
    when none lies within ``radius`` [m]."""
    c = np.asarray(candidates, dtype=np.float64)
    p = np.asarray(point, dtype=np.float64).reshape(-1)
    if c.ndim != 2 or c.shape[0] == 0 or c.shape[1] < 2:
        raise FootfallError("the candidate set must be an (n, 3) array with n >= 1")
    if p.shape[0] < 2 or not np.isfinite(p[:2]).all():
        raise FootfallError("a clicked point is x, y [m], finite")
    d = np.hypot(c[:, 0] - p[0], c[:, 1] - p[1])
    i = int(np.argmin(d))
    return i if d[i] <= radius else None


def terrain_window(hmap: HeightMap, centre: np.ndarray, half: float = WINDOW_HALF,
                   max_cells: int = WINDOW_CELLS) -> dict:
    """The terrain in the square of half-side ``half`` [m] around ``centre`` (x, y [m]).

    Returns ``{"x": (nx,), "y": (ny,), "heights": (nx, ny) with None where the
    map has no data or the square leaves the map, "step": [m] sample spacing}``;
    every ``s``-th cell of the map, ``s`` chosen so that at most ``max_cells``
    samples lie along a side.
    """
    cx, cy = (float(v) for v in np.asarray(centre, dtype=np.float64)[:2])
    if not (math.isfinite(cx) and math.isfinite(cy)):
        raise FootfallError("the window's centre must be finite")
    r = hmap.resolution
    stride = max(1, math.ceil(2 * half / r / max_cells))
    i = np.arange(math.floor((cx - half - hmap.origin[0]) / r),
                  math.ceil((cx + half - hmap.origin[0]) / r) + 1, stride)
    j = np.arange(math.floor((cy - half - hmap.origin[1]) / r),
                  math.ceil((cy + half - hmap.origin[1]) / r) + 1, stride)
    nx, ny = hmap.shape
    ii, jj = np.meshgrid(i, j, indexing="ij")
    inside = (ii >= 0) & (ii < nx) & (jj >= 0) & (jj < ny)
    h = np.full(ii.shape, np.nan)
    h[inside] = hmap.heights[ii[inside], jj[inside]]
    return {"x": (hmap.origin[0] + i * r).tolist(), "y": (hmap.origin[1] + j * r).tolist(),
            "heights": [[None if not np.isfinite(v) else float(v) for v in row] for row in h],
            "step": stride * r}


def robot_pose(state: RobotState, robot: RobotDescription) -> dict:
    """The robot at a step: body position [m] and roll, pitch, yaw [rad], the trunk's size [m],
    each leg's hip (world position [m]) and foot contact point [m], and the swing leg."""
    hips = np.array([leg.hip for leg in robot.legs]) @ rotation_matrix(state.body_rpy).T \
        + state.body_position
    return {"body": {"position": state.body_position.tolist(), "rpy": state.body_rpy.tolist(),
                     "size": list(robot.trunk_size)},
            "legs": {name: {"hip": hips[i].tolist(), "foot": state.feet[i].tolist()}
                     for i, name in enumerate(LEG_NAMES)},
            "swing_leg": state.swing_leg, "foot_radius": robot.foot_radius}


def review_order(slips: np.ndarray, steps_to_fall: np.ndarray, shortfall: np.ndarray
                 ) -> np.ndarray:
    """The steps of a run in the order most worth a look first.

    Three signs of a bad foothold, each turned into a rank in [0, 1] (1: the
    most suspicious step of the run): the foot's slip [m] (NaN: not measured,
    ranked as none), closeness to a fall (``steps_to_fall`` steps until the
    run fell, -1 for a run that did not fall; only the last
    :data:`FALL_LOOKBACK` steps count), and the synthetic expert's shortfall
    [value units] of the robot's choice against its own best. A step's score
    is the largest of its three ranks, ties broken by their mean, then by
    step number: a step that stands out in one way comes before one that is
    middling in all three.
    """
    slips = np.nan_to_num(np.asarray(slips, dtype=np.float64), nan=0.0)
    to_fall = np.asarray(steps_to_fall)
    falls = np.where((to_fall >= 0) & (to_fall < FALL_LOOKBACK),
                     FALL_LOOKBACK - to_fall, 0).astype(np.float64)
    shortfall = np.nan_to_num(np.asarray(shortfall, dtype=np.float64), nan=0.0)
    if not slips.shape == falls.shape == shortfall.shape:
        raise FootfallError("one slip, fall distance and shortfall per step")
    ranks = np.stack([_rank(v) for v in (slips, falls, shortfall)])
    score_max, score_mean = ranks.max(axis=0), ranks.mean(axis=0)
    return np.lexsort((np.arange(slips.size), -score_mean, -score_max))


def _rank(values: np.ndarray) -> np.ndarray:
    """Each value's rank in [0, 1] among values > 0 (1: the largest); 0 for values <= 0."""
    out = np.zeros(values.shape)
    positive = values > 0
    if positive.any():
        order = np.argsort(np.argsort(values[positive], kind="stable"), kind="stable")
        out[positive] = (order + 1) / positive.sum()
    return out


def steps_to_fall(n_steps: int, fell: bool) -> np.ndarray:
    """For each step of a run of ``n_steps``: steps until the run ended in a fall, -1 if it did
    not fall (a run that failed otherwise, e.g. timed out, counts as not fallen; a run's
    ``result["reason"]`` starts with "fall" when it fell)."""
    return (n_steps - 1 - np.arange(n_steps)) if fell else np.full(n_steps, -1)
