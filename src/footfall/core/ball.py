"""A rigid ball lowered onto a height grid: where its centre comes to rest, for every cell.

``B(c) = max over cells c' within radius of h(c') + sqrt(radius^2 - |c - c'|^2)``,
a grey-scale dilation of the heights by the ball's cap. The walking expert
judges footholds on it (:mod:`footfall.expert.synthetic`), the footstep
planner the leg's clearance (:mod:`footfall.core.clearance`); a ball foot's
single contact in the pad physics variant follows it
(:mod:`footfall.sim.foot_pads`). Compiled (Numba): the dilation is one
running maximum per offset of the cap over a block of rows that stays in
the cache, the same numbers as ``scipy.ndimage.grey_dilation`` with the cap as
its structure (tests/test_ball.py), 6-7x faster on a board.
"""

from __future__ import annotations

import math

import numba
import numpy as np

_ROWS = 64  # output rows dilated together: they and the input rows they read stay in the cache


@numba.njit(cache=True, nogil=True, fastmath={"nnan", "nsz"})
def _dilate(h, di, dj, cap, rows):  # pragma: no cover - compiled
    # h (nx, ny) with -inf where there is no support (no NaN); offsets (di, dj) with cap values.
    nx, ny = h.shape
    out = np.full((nx, ny), -np.inf)
    for r0 in range(0, nx, rows):
        r1 = min(nx, r0 + rows)
        for k in range(di.size):
            a, b, c = di[k], dj[k], cap[k]
            i0, i1 = max(r0, -a), min(r1, nx - a)
            j0, j1 = max(0, -b), min(ny, ny - b)
            for i in range(i0, i1):
                src = h[i + a, j0 + b:j1 + b]  # slices: the loop below has no index wrap-around
                dst = out[i, j0:j1]
                for j in range(j1 - j0):
                    dst[j] = max(dst[j], src[j] + c)
    return out


def ball_centre_surface(heights: np.ndarray, resolution: float, radius: float) -> np.ndarray:
    """Centre height [m] of a ball of ``radius`` [m] resting over each cell of ``heights`` [m].

    Cells are points at their centres, ``resolution`` [m] apart; -inf or NaN
    cells give no support, and so does everything beyond the grid. A cell
    with no supporting cell within ``radius`` gets -inf.
    """
    reach = int(math.ceil(radius / resolution))
    off = np.arange(-reach, reach + 1) * resolution
    d2 = off[:, None] ** 2 + off[None, :] ** 2
    footprint = d2 <= radius * radius * (1 + 1e-9)
    cap = np.sqrt(np.clip(radius * radius - d2, 0.0, None))
    di, dj = np.nonzero(footprint)
    h = np.where(np.isnan(heights), -np.inf, np.asarray(heights, dtype=np.float64))
    return _dilate(np.ascontiguousarray(h), (di - reach).astype(np.int64),
                   (dj - reach).astype(np.int64), np.ascontiguousarray(cap[di, dj]), _ROWS)
