"""The terrain as MuJoCo geoms: height-field tiles of the map's cells, and boxes where it is flat.

A map becomes the simulated terrain here: its holes filled
(:func:`terrain_surface`), its cells decimated to vertices at most
:data:`MAX_HFIELD_SPACING` apart, the vertex grid cut into tiles, flat tiles
merged into boxes, and the whole moved rigidly by the registration error
(:func:`terrain_layout`). :mod:`footfall.sim.mjcf` writes the tiles into the model.
"""

from __future__ import annotations

import math
from itertools import pairwise

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.sim.variants import VARIANT

TERRAIN_BASE = 0.02  # [m] thickness of the solid slab under the height field's lowest point
MAX_HFIELD_SPACING = 0.002  # [m] coarsest height-field vertex spacing; finer maps are decimated
# (MuJoCo tests every grid cell under a geom's bounding box against it: a 1 cm ball covers
# 4x as many cells at 1 mm as at 2 mm, and collision is most of the cost of a step)
TILE_CELLS = 32  # [cells] side of a terrain tile (64 mm at 2 mm): small enough that flat
# stretches become boxes and a geom's bounding box meets few tiles' elevation ranges


def terrain_surface(hmap: HeightMap) -> np.ndarray:
    """The heights [m] the simulator uses, shape (nx, ny): the map with its holes filled.

    The planner sees the map with NaN cells (no data) and never steps on
    them; the simulator needs a surface. A NaN cell becomes a hole down to
    the map's lowest valid height -- what a missing scan of a terrain module
    usually is (a shadow behind a step, a gap between modules) -- so that
    nothing the robot might lean on appears where there is no data.
    """
    h = np.asarray(hmap.heights, dtype=np.float64)
    return np.where(np.isnan(h), np.nanmin(h), h)


def hfield_decimation(hmap: HeightMap, max_spacing: float | None = MAX_HFIELD_SPACING) -> int:
    """Keep every k-th map cell as a height-field vertex: the largest k with k * resolution <= max_spacing.

    1 (full resolution) for maps already that coarse, or with ``max_spacing`` None.
    """
    if max_spacing is None:
        return 1
    if not (isinstance(max_spacing, (int, float)) and math.isfinite(max_spacing)
            and max_spacing > 0):
        raise FootfallError(f"max_spacing must be a number > 0 [m] or None, got {max_spacing!r}")
    k = max(1, math.floor(max_spacing / hmap.resolution + 1e-9))
    return min(k, min(hmap.shape) - 1)  # keep at least 2 x 2 vertices


def _finite(value, name: str, unit: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if not math.isfinite(v):
        raise FootfallError(f"{name} must be a finite number [{unit}], got {value!r}")
    return v


def registration_centre(hmap: HeightMap, max_spacing: float | None = MAX_HFIELD_SPACING
                        ) -> np.ndarray:
    """The point (2,) [m] the terrain's registration turns about: the vertex grid's centre."""
    if VARIANT.get("max_spacing") is not None:
        max_spacing = VARIANT["max_spacing"]
    k = hfield_decimation(hmap, max_spacing)
    n = (np.array(hmap.shape) - 1) // k + 1  # vertices along x and y
    step = k * hmap.resolution
    return np.asarray(hmap.origin) + 0.5 * (n - 1) * step


def terrain_layout(hmap: HeightMap, terrain_offset=(0.0, 0.0, 0.0), terrain_yaw: float = 0.0,
                   max_spacing: float | None = MAX_HFIELD_SPACING) -> list[dict]:
    """The simulated terrain as MuJoCo geoms: height-field tiles, and boxes where a tile is flat.

    Vertices are map cells: with decimation k (see :func:`hfield_decimation`;
    1 mm maps get k = 2), map cell (k i, k j) is a vertex at exactly that
    cell's position and height, so the vertex spacing is k * resolution and
    the terrain spans k * floor((n - 1) / k) cells along each axis (at most
    k - 1 cells short of the map's last cell centre). Between vertices
    MuJoCo's surface is two planar triangles per grid square. The vertex grid
    is cut into tiles of TILE_CELLS squares that share their edge vertices,
    so the surface is continuous. Tiles whose vertices all have one height
    become boxes with their top at that height, neighbours of equal height
    merged into one box (exactly the same surface, and MuJoCo collides a
    ball with a box in closed form instead of testing every triangle under
    it); every other tile is a height field whose vertex (row r, column c)
    is the tile's vertex (i0 + c, j0 + r) -- MuJoCo's rows run along y.
    Every tile is TERRAIN_BASE thick below its lowest point.

    The registration moves the terrain rigidly: a map point p becomes the
    world point ``c + Rz(terrain_yaw) (p - c) + terrain_offset``, where c is
    the centre of the vertex grid (at height 0).

    Returns
    -------
    list of dict
        One per geom: ``kind`` ("box" or "hfield"), ``pos`` (3,) [m] and
        ``quat`` (4,) (w, x, y, z) of the geom; a box has ``size`` (3,) [m]
        half extents; a height field has ``nrow``, ``ncol``, ``size`` (4,)
        MuJoCo's (x radius [m], y radius [m], elevation range [m], base
        thickness [m]) and ``data`` (nrow * ncol,) float32 heights
        normalised to [0, 1].
    """
    offset = np.asarray(terrain_offset, dtype=np.float64)
    if offset.shape != (3,) or not np.isfinite(offset).all():
        raise FootfallError(f"terrain_offset must be 3 finite numbers [m], got {terrain_offset!r}")
    yaw = _finite(terrain_yaw, "terrain_yaw", "rad")
    k = hfield_decimation(hmap, max_spacing)
    h = terrain_surface(hmap)[::k, ::k]
    nx, ny = h.shape
    step = k * hmap.resolution
    origin = np.asarray(hmap.origin)
    centre = registration_centre(hmap, max_spacing)
    rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    quat = np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
    edges_i = np.append(np.arange(0, nx - 1, TILE_CELLS), nx - 1)  # tile corner vertices
    edges_j = np.append(np.arange(0, ny - 1, TILE_CELLS), ny - 1)
    blocks = [[h[i0:i1 + 1, j0:j1 + 1] for j0, j1 in pairwise(edges_j)]
              for i0, i1 in pairwise(edges_i)]  # tiles, sharing their edge vertices
    lo = np.array([[block.min() for block in row] for row in blocks])
    hi = np.array([[block.max() for block in row] for row in blocks])
    flat = lo == hi

    def placed(i0: int, i1: int, j0: int, j1: int, z: float) -> tuple[np.ndarray, np.ndarray]:
        """World pose centre (3,) [m] and half extents (2,) [m] of vertex block [i0, i1] x [j0, j1]."""
        mid = origin + 0.5 * np.array([i0 + i1, j0 + j1]) * step
        xy = centre + rot @ (mid - centre) + offset[:2]
        return np.array([xy[0], xy[1], z + offset[2]]), 0.5 * np.array([i1 - i0, j1 - j0]) * step

    tiles = []
    for a, b in zip(*np.nonzero(~flat)):  # a loop over tiles (dozens), not over cells
        i0, i1, j0, j1 = edges_i[a], edges_i[a + 1], edges_j[b], edges_j[b + 1]
        t = blocks[a][b]
        pos, half = placed(i0, i1, j0, j1, lo[a, b])
        tiles.append({"kind": "hfield", "quat": quat, "pos": pos,
                      "nrow": j1 - j0 + 1, "ncol": i1 - i0 + 1,
                      "size": np.array([half[0], half[1], hi[a, b] - lo[a, b], TERRAIN_BASE]),
                      "data": ((t.T - lo[a, b]) / (hi[a, b] - lo[a, b])).astype(np.float32).ravel()})
    for a0, a1, b0, b1 in _merge_flat(flat, lo):
        pos, half = placed(edges_i[a0], edges_i[a1], edges_j[b0], edges_j[b1],
                           lo[a0, b0] - 0.5 * TERRAIN_BASE)
        tiles.append({"kind": "box", "quat": quat, "pos": pos,
                      "size": np.array([half[0], half[1], 0.5 * TERRAIN_BASE])})
    return tiles


def _merge_flat(flat: np.ndarray, height: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Greedy cover of the flat tiles by rectangles of equal height, as [a0, a1) x [b0, b1).

    Fewer, larger boxes mean fewer seams under a foot (each seam a second
    contact) and fewer geoms in MuJoCo's broad phase.
    """
    free = flat.copy()
    rects = []
    for a0, b0 in zip(*np.nonzero(flat)):  # tiles, not cells
        if not free[a0, b0]:
            continue
        z = height[a0, b0]
        b1 = b0 + 1
        while b1 < flat.shape[1] and free[a0, b1] and height[a0, b1] == z:
            b1 += 1
        a1 = a0 + 1
        while a1 < flat.shape[0] and free[a1, b0:b1].all() and (height[a1, b0:b1] == z).all():
            a1 += 1
        free[a0:a1, b0:b1] = False
        rects.append((int(a0), int(a1), int(b0), int(b1)))
    return rects
