"""The support-polygon pose features, compiled: triangles' margins and the four feet's hull.

The footstep planner values a learned function's pose features for every
candidate of every rollout, a few dozen candidates a call and nine calls a
step; on arrays that small NumPy's per-call overhead is nearly all of
:func:`footfall.features.pose_features.triangle_margins` and ``hull_area``
(about 0.8 ms a call of the 2.2 ms of all 26 features). These kernels do the
same arithmetic, operation for operation and in NumPy's order (its sums of
three or four terms run left to right), so their values are those of the
NumPy definitions to the last bit (``tests/test_pose_features.py`` holds
them to it). Lengths in metres, areas in square metres.
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, inline="always")
def _least(a, b):  # pragma: no cover - compiled
    """``np.minimum(a, b)``: the smaller, NaN if either is NaN."""
    if a != a or b != b:
        return math.nan
    return a if a <= b else b


@numba.njit(cache=True, nogil=True, inline="always")
def _most(a, b):  # pragma: no cover - compiled
    """``np.maximum(a, b)``: the larger, NaN if either is NaN."""
    if a != a or b != b:
        return math.nan
    return a if a >= b else b


@numba.njit(cache=True, nogil=True)
def triangles_margins(tri, px, py):  # pragma: no cover - compiled
    """Inradius [m] and signed distance [m] of the point (px, py) from the nearest edge (> 0
    inside) of each triangle (n, 3, 2) [m] -> two (n,) arrays; a degenerate triangle has
    inradius 0 and a degenerate edge distance 0."""
    n = tri.shape[0]
    inradius = np.empty(n)
    margin = np.empty(n)
    for i in range(n):
        ax, ay = tri[i, 0, 0], tri[i, 0, 1]
        bx, by = tri[i, 1, 0], tri[i, 1, 1]
        cx, cy = tri[i, 2, 0], tri[i, 2, 1]
        abx, aby = bx - ax, by - ay
        bcx, bcy = cx - bx, cy - by
        cax, cay = ax - cx, ay - cy
        la = math.sqrt(abx * abx + aby * aby)
        lb = math.sqrt(bcx * bcx + bcy * bcy)
        lc = math.sqrt(cax * cax + cay * cay)
        cross = abx * (cy - ay) - aby * (cx - ax)
        area = 0.5 * abs(cross)
        semi = 0.5 * (la + lb + lc)
        inradius[i] = area / semi if semi > 0 else 0.0
        orient = 1.0 if cross >= 0 else -1.0
        least = 0.0
        for e in range(3):
            if e == 0:
                sx, sy, ex, ey, length = ax, ay, abx, aby, la
            elif e == 1:
                sx, sy, ex, ey, length = bx, by, bcx, bcy, lb
            else:
                sx, sy, ex, ey, length = cx, cy, cax, cay, lc
            signed = orient * (ex * (py - sy) - ey * (px - sx))
            d = signed / length if length > 0 else 0.0
            least = d if e == 0 else _least(least, d)
        margin[i] = least
    return inradius, margin


@numba.njit(cache=True, nogil=True, inline="always")
def _shoelace(p, i, o0, o1, o2, o3):  # pragma: no cover - compiled
    """Shoelace area [m^2] of row i's points in the order o0, o1, o2(, o3; o3 < 0: three)."""
    x0, y0 = p[i, o0, 0], p[i, o0, 1]
    x1, y1 = p[i, o1, 0], p[i, o1, 1]
    x2, y2 = p[i, o2, 0], p[i, o2, 1]
    if o3 < 0:
        s = (x0 * y1 - x1 * y0) + (x1 * y2 - x2 * y1) + (x2 * y0 - x0 * y2)
    else:
        x3, y3 = p[i, o3, 0], p[i, o3, 1]
        s = ((x0 * y1 - x1 * y0) + (x1 * y2 - x2 * y1) + (x2 * y3 - x3 * y2)
             + (x3 * y0 - x0 * y3))
    return 0.5 * abs(s)


@numba.njit(cache=True, nogil=True)
def hull_areas(points):  # pragma: no cover - compiled
    """Area [m^2] of the convex hull of 4 points, (n, 4, 2) [m] -> (n,): the largest of the
    three quadrilaterals' and four triangles' shoelace areas (see ``hull_area``)."""
    n = points.shape[0]
    out = np.empty(n)
    for i in range(n):
        best = _shoelace(points, i, 0, 1, 2, 3)
        best = _most(best, _shoelace(points, i, 0, 1, 3, 2))
        best = _most(best, _shoelace(points, i, 0, 2, 1, 3))
        best = _most(best, _shoelace(points, i, 0, 1, 2, -1))
        best = _most(best, _shoelace(points, i, 0, 1, 3, -1))
        best = _most(best, _shoelace(points, i, 0, 2, 3, -1))
        best = _most(best, _shoelace(points, i, 1, 2, 3, -1))
        out[i] = best
    return out
