"""Footing: whether a ball foot put down on a foothold stays there under its load.

A ball foot of radius r whose centre comes down vertically above a point p
rests on the terrain cell q* that first touches it: the one that maximises
``z(q) + sqrt(r^2 - |q - p|^2)`` over the cells within r of p (horizontal
distances). The contact normal points from q* to the ball's centre, so its
tilt from the vertical is ``arcsin(|q* - p| / r)``: 0 on flat ground, the
ground's slope on a plane, up to 90 degrees where the ball hangs over an edge.

Under a vertical load (the robot's weight; the horizontal forces of a slow
crawl are small beside it) the foot holds if the load lies inside the
friction cone about that normal: tilt <= atan(friction). With a safety factor
s on the friction coefficient the limit is ``atan(friction / s)``
(:func:`tilt_limit`). A foot lands within a few millimetres of where it was
aimed, so a foothold holds only if every point within a placement margin of
it holds (:func:`footing_grid`).
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import maximum_filter

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import RobotDescription
from footfall.features.dense import lattice_index, whole_ratio

_EQUATOR = 1.0 - 1e-9  # a cell counts only strictly inside the ball's footprint: one at its
# equator (distance = radius) would hang the ball on a corner it only grazes


def tilt_limit(friction: float, safety: float) -> float:
    """Largest contact tilt [rad] at which a vertical load stays inside the friction cone of
    coefficient ``friction`` [-] reduced by the safety factor ``safety`` [-] (>= 1)."""
    if not friction > 0 or not safety > 0:
        raise FootfallError(f"friction and safety factor must be > 0, got {friction}, {safety}")
    return math.atan(friction / safety)


def _disc_offsets(radius: float, resolution: float) -> np.ndarray:
    """Cell offsets (m, 2) int of every cell centre within ``radius`` [m] of a cell centre,
    padded by one cell (a point between cell centres reaches a little further)."""
    k = int(math.ceil(radius / resolution)) + 1
    i, j = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1), indexing="ij")
    keep = (np.hypot(i, j) - 1.0) * resolution <= radius
    return np.column_stack([i[keep], j[keep]])


def contact_tilt(hmap: HeightMap, points: np.ndarray, radius: float) -> np.ndarray:
    """Tilt [rad] of the contact normal of a ball foot of ``radius`` [m] put down vertically
    with its centre above each point (n, 2) [m] -> (n,).

    The terrain is its cells' centres: the tilt is exact for points at cell centres and, on
    flat ground, within ``arcsin(resolution / (sqrt(2) radius))`` elsewhere (the planner's
    lattice points are cell centres). Cells without data (NaN) and outside the map do not
    support the ball; NaN where no cell within ``radius`` of a point has data. Vectorised over
    the points; the loop runs over the (few hundred) cell offsets of the ball's footprint.
    """
    if not radius > 0:
        raise FootfallError(f"the foot radius must be > 0, got {radius}")
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    res = hmap.resolution
    centre = hmap.position_to_index(p)  # (n, 2) the cell containing each point
    nx, ny = hmap.shape
    best = np.full(p.shape[0], -np.inf)  # highest ball-centre height so far [m]
    reach = np.full(p.shape[0], np.nan)  # horizontal distance of its contact cell [m]
    origin = np.asarray(hmap.origin)
    for off in _disc_offsets(radius, res):  # the ball's footprint, not the map's cells
        cell = centre + off
        inside = (cell[:, 0] >= 0) & (cell[:, 0] < nx) & (cell[:, 1] >= 0) & (cell[:, 1] < ny)
        ci = np.clip(cell[:, 0], 0, nx - 1)
        cj = np.clip(cell[:, 1], 0, ny - 1)
        d2 = np.sum((origin + cell * res - p) ** 2, axis=1)
        z = hmap.heights[ci, cj] + np.sqrt(np.maximum(radius * radius - d2, 0.0))
        z = np.where(inside & (d2 < _EQUATOR * radius * radius) & ~np.isnan(z), z, -np.inf)
        higher = z > best
        best = np.where(higher, z, best)
        reach = np.where(higher, np.sqrt(d2), reach)
    return np.arcsin(np.clip(reach / radius, 0.0, 1.0))


def _lattice_tilt(heights: np.ndarray, resolution: float, step: int, radius: float,
                  na: int, nb: int) -> np.ndarray:
    """:func:`contact_tilt` (na, nb) [rad] at the lattice of every ``step``-th cell from cell
    (0, 0): the points are cell centres, so each footprint offset is a strided view of the
    heights (padded with no data) and its distance a constant."""
    k = int(math.floor(radius / resolution + 1e-9))
    padded = np.pad(np.where(np.isnan(heights), -np.inf, heights), k, constant_values=-np.inf)
    best = np.full((na, nb), -np.inf)  # highest ball-centre height so far [m]
    reach = np.full((na, nb), np.nan)  # horizontal distance of its contact cell [m]
    for di in range(-k, k + 1):  # the ball's footprint, not the map's cells
        for dj in range(-k, k + 1):
            d2 = (di * di + dj * dj) * resolution * resolution
            if d2 >= _EQUATOR * radius * radius:
                continue
            view = padded[k + di:k + di + (na - 1) * step + 1:step,
                          k + dj:k + dj + (nb - 1) * step + 1:step]
            z = view + math.sqrt(radius * radius - d2)
            higher = z > best
            best = np.where(higher, z, best)
            reach = np.where(higher, math.sqrt(d2), reach)
    return np.arcsin(np.clip(reach / radius, 0.0, 1.0))


@dataclass(frozen=True)
class FootingGrid:
    """The worst contact tilt within a placement margin of every lattice point of a map."""

    x: np.ndarray  # (na,) [m] lattice x coordinates
    y: np.ndarray  # (nb,) [m] lattice y coordinates
    tilt: np.ndarray  # (na, nb) [rad] worst contact tilt within the margin; pi/2 where a point
    # within the margin has no data
    spacing: float  # [m] lattice spacing
    radius: float  # [m] foot radius
    margin: float  # [m] placement margin

    def at(self, xy: np.ndarray) -> np.ndarray:
        """Tilt [rad] (...) at the lattice point nearest each position (..., 2) [m]; pi/2 off
        the lattice."""
        i, j = lattice_index(self.x[0], self.y[0], xy, self.spacing)
        on = (i >= 0) & (i < self.x.size) & (j >= 0) & (j < self.y.size)
        out = np.full(i.shape, math.pi / 2)
        out[on] = self.tilt[i[on], j[on]]
        return out


def footing_grid(hmap: HeightMap, spacing: float, radius: float, margin: float) -> FootingGrid:
    """:class:`FootingGrid` of a map on the lattice of ``spacing`` [m] from cell (0, 0)'s
    centre (the candidates' lattice): the contact tilt of a foot of ``radius`` [m] at every
    lattice point, then the largest within ``margin`` [m] of each. Kept per map object and
    settings for the process (a map's heights are read-only)."""
    if not spacing > 0 or not margin >= 0:
        raise FootfallError(f"footing needs spacing > 0 and margin >= 0 m, got {spacing}, "
                            f"{margin}")
    key = (float(spacing), float(radius), float(margin))
    cache = _FOOTING.setdefault(hmap, {})
    if key not in cache:
        lx, ly = hmap.length
        x = hmap.origin[0] + np.arange(int(math.floor((lx - hmap.resolution) / spacing + 1e-9))
                                       + 1) * spacing
        y = hmap.origin[1] + np.arange(int(math.floor((ly - hmap.resolution) / spacing + 1e-9))
                                       + 1) * spacing
        xx, yy = np.meshgrid(x, y, indexing="ij")
        pts = np.column_stack([xx.ravel(), yy.ravel()])
        step = whole_ratio(spacing, hmap.resolution)
        tilt = (contact_tilt(hmap, pts, radius).reshape(x.size, y.size) if step is None else
                _lattice_tilt(hmap.heights, hmap.resolution, step, radius, x.size, y.size))
        no_data = np.isnan(hmap.height_at(pts)).reshape(x.size, y.size)
        tilt = np.where(np.isnan(tilt) | no_data, math.pi / 2, tilt)
        k = int(math.floor(margin / spacing + 1e-9))
        if k > 0:
            i, j = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1), indexing="ij")
            tilt = maximum_filter(tilt, footprint=np.hypot(i, j) * spacing <= margin + 1e-12,
                                  mode="nearest")
        tilt.setflags(write=False)
        cache[key] = FootingGrid(x, y, tilt, float(spacing), float(radius), float(margin))
    return cache[key]


_FOOTING: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
# map -> {(spacing, radius, margin): FootingGrid}, made once per process


@dataclass(frozen=True)
class FrictionCheck:
    """Which footholds of a map hold: the worst contact tilt within the margin of each
    (:class:`FootingGrid`) against the friction cone reduced by a safety factor."""

    grid: FootingGrid
    limit: float  # [rad] largest contact tilt that holds

    @classmethod
    def of(cls, hmap: HeightMap, spacing: float, robot: RobotDescription, safety: float,
           margin: float) -> FrictionCheck:
        """The check of ``robot``'s ball foot on ``hmap``'s lattice of ``spacing`` [m], its
        friction reduced by ``safety`` [-], within ``margin`` [m] of each foothold."""
        return cls(footing_grid(hmap, spacing, robot.foot_radius, margin),
                   tilt_limit(robot.foot_friction, safety))

    def holds(self, xy: np.ndarray) -> np.ndarray:
        """Whether a foot put down at each position (..., 2) [m] holds -> (...) bool."""
        return self.grid.at(xy) <= self.limit

    def keep(self, footholds: np.ndarray, usable: np.ndarray) -> np.ndarray:
        """``usable`` (n,) bool less the footholds (n, >= 2) [m] that do not hold -- unless
        none of the usable ones holds: a foot must go somewhere, and then nothing is dropped."""
        held = usable & self.holds(footholds[:, :2])
        return held if np.any(held) else usable
