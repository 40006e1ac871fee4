"""The ball-centre surface: how high a sphere's centre sits when it is lowered onto the map.

``B(c) = max over cells c' within r of h(c') + sqrt(r^2 - |c - c'|^2)``, a
grey-scale dilation of the heights by a sphere of radius r: for the ball foot
(r the foot radius) its slopes are the ball's contact normals, for the shin
(r the lower leg's radius) its height is the clearance the leg needs. The
synthetic expert (:mod:`footfall.expert.synthetic`) reads every terrain term
from it; a map's surface is dilated once per radius and sampled in windows.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import distance_transform_edt

from footfall.core.ball import ball_centre_surface
from footfall.core.bilinear import surface_along_rays, surface_at
from footfall.core.heightmap import HeightMap


# ----------------------------------------------------------------- geometry
@dataclass(frozen=True, eq=False)
class SphereSurface:
    """A sphere's centre-height surface on a window of map cells (see :func:`sphere_surface`)."""

    filled: np.ndarray  # (wx, wy) [m] centre heights, 0 where unknown
    known: np.ndarray  # (wx, wy) 1.0 where the height is known, else 0.0
    origin: np.ndarray  # (2,) [m] position of window cell (0, 0)
    resolution: float  # [m/cell]
    complete: bool  # every height in the window is known

    def at(self, points: np.ndarray) -> np.ndarray:
        """Bilinear height [m] at points (..., 2); NaN outside the window or where unknown.

        The weights of corners with a known height are renormalised (as in
        :meth:`HeightMap.height_at`), but a point whose nearest cell is unknown is NaN.
        """
        points = np.asarray(points, dtype=np.float64)
        flat = np.ascontiguousarray(points.reshape(-1, 2))
        out = surface_at(self.filled, self.known, self.origin[0], self.origin[1],
                         self.resolution, self.complete, flat[:, 0], flat[:, 1])
        return out.reshape(points.shape[:-1])

    def along_rays(self, xy: np.ndarray, directions: np.ndarray, distances: np.ndarray
                   ) -> np.ndarray:
        """Heights (n, K, J) [m] at ``xy`` (n, 2) [m] + ``distances`` (J,) [m] along each of the
        ``directions`` (K, 2) (unit vectors): :meth:`at` of those points, without making them."""
        xy = np.ascontiguousarray(xy, dtype=np.float64)
        d = np.ascontiguousarray(directions, dtype=np.float64)
        s = np.ascontiguousarray(distances, dtype=np.float64)
        return surface_along_rays(self.filled, self.known, self.origin[0], self.origin[1],
                                  self.resolution, self.complete, xy, d, s)


_BOARD_SURFACES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
# map -> {radius [m]: SphereSurface | None}: each map's sphere surface, dilated once over the map


def board_sphere(hmap: HeightMap, radius: float) -> SphereSurface | None:
    """The sphere's centre-height surface over the whole map, computed once per map and radius
    (a map's heights are read-only); ``None`` if no height of it is known.

    Every sample of it is a function of the point alone -- the same window, origin and
    renormalisation rule whatever else is sampled -- so values sampled from it can be
    remembered per point.
    """
    per_map = _BOARD_SURFACES.setdefault(hmap, {})
    if radius not in per_map:
        surface = ball_centre_surface(hmap.heights, hmap.resolution, radius)
        known = np.isfinite(surface)
        filled = np.where(known, surface, 0.0)
        weights = known.astype(np.float64)
        for a in (filled, weights):
            a.setflags(write=False)
        per_map[radius] = None if not known.any() else SphereSurface(
            filled, weights, np.asarray(hmap.origin, dtype=np.float64), hmap.resolution,
            bool(known.all()))
    return per_map[radius]


def board_surface(hmap: HeightMap, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The sphere's centre-height surface over the whole map: (heights [m], 0 where unknown;
    1.0 where known), computed once per map and radius."""
    whole = board_sphere(hmap, radius)
    if whole is None:
        return np.zeros(hmap.shape), np.zeros(hmap.shape)
    return whole.filled, whole.known


def sphere_surface(hmap: HeightMap, lo: np.ndarray, hi: np.ndarray, radius: float
                    ) -> SphereSurface | None:
    """Centre height [m] of a sphere of ``radius`` [m] lowered onto the map, on a window of cells.

    ``B(c) = max over cells c' within radius of h(c') + sqrt(radius^2 - |c - c'|^2)``, a
    grey-scale dilation of the heights by the sphere. Covers at least the positions
    in [lo, hi] (x, y) [m] that lie on the map; the window is padded by the
    sphere's reach, so every value sampled inside [lo, hi] is the whole map's
    (:func:`board_surface`, dilated once per map: the maximum over the same cells,
    bit for bit), and only the map's own border truncates (beyond it there is nothing
    to touch). Cells are points at their centres; cells without data give no
    support; where no cell with data lies within ``radius``, the height is
    unknown. ``None`` if nothing in the window is known.
    """
    res = hmap.resolution
    reach = int(math.ceil(radius / res))
    nx, ny = hmap.shape
    lo_idx = np.floor((np.asarray(lo) - hmap.origin) / res).astype(int) - reach - 1
    hi_idx = np.ceil((np.asarray(hi) - hmap.origin) / res).astype(int) + reach + 2
    i0, j0 = max(lo_idx[0], 0), max(lo_idx[1], 0)
    i1, j1 = min(hi_idx[0], nx), min(hi_idx[1], ny)
    if i1 - i0 < 2 or j1 - j0 < 2:
        return None
    filled, known = board_surface(hmap, radius)
    known = known[i0:i1, j0:j1]
    if not known.any():
        return None
    return SphereSurface(filled[i0:i1, j0:j1], known,
                    np.array([hmap.origin[0] + i0 * res, hmap.origin[1] + j0 * res]), res,
                    bool(known.all()))


def sample_surface(surface: SphereSurface | None, points: np.ndarray) -> np.ndarray:
    """Height [m] of a sphere surface at points (..., 2); NaN where unknown."""
    if surface is None:
        return np.full(points.shape[:-1], np.nan)
    return surface.at(points)


def no_data(hmap: HeightMap, points: np.ndarray) -> np.ndarray:
    """Whether the map has no data at points (..., 2) [m]: off the map or a NaN cell."""
    inside, i, j = _cells(hmap, points)
    return ~inside | np.isnan(hmap.heights[i, j])


def _cells(hmap: HeightMap, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cell holding each point (..., 2) [m]: whether it is on the map, and its indices
    (clipped onto the map where it is not)."""
    idx = hmap.position_to_index(points)
    nx, ny = hmap.shape
    inside = (idx[..., 0] >= 0) & (idx[..., 0] < nx) & (idx[..., 1] >= 0) & (idx[..., 1] < ny)
    return inside, np.clip(idx[..., 0], 0, nx - 1), np.clip(idx[..., 1], 0, ny - 1)


_BLIND_DISTANCES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
# map -> {radius [m]: distance [m] from each cell to the nearest where a sphere of that radius
# has nothing under it, or None where there is no such cell}


def seen_under_sphere(hmap: HeightMap, points: np.ndarray, radius: float, reach: float
                      ) -> np.ndarray:
    """Whether a sphere of ``radius`` [m] has some map data under it everywhere within ``reach``
    [m] of each point (..., 2) [m]: bool (...); False for a point off the map.

    A sphere has nothing under it where no cell with data lies within its radius
    (its centre-height surface, :func:`board_sphere`, is unknown there): a hole in
    a scan wider than the sphere, which it could drop into unseen. The distances to
    those places are found once per map and radius (a Euclidean distance transform,
    cell centre to cell centre); a map without them answers True for every point on it.
    """
    per_map = _BLIND_DISTANCES.setdefault(hmap, {})
    if radius not in per_map and not np.isnan(hmap.heights).any():
        per_map[radius] = None  # a sphere has data under it wherever a map has it everywhere
    if radius not in per_map:
        blind = board_surface(hmap, radius)[1] == 0.0
        per_map[radius] = (distance_transform_edt(~blind) * hmap.resolution
                           if blind.any() else None)
    distance = per_map[radius]
    inside, i, j = _cells(hmap, points)
    return inside if distance is None else inside & (distance[i, j] > reach)
