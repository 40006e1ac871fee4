"""Bilinear sampling of gridded heights, compiled: one pass over the points, no temporaries.

Two rules for cells without data: a height map's (:meth:`HeightMap.height_at
<footfall.core.heightmap.HeightMap.height_at>`: NaN off the map and where the
nearest cell has no data, elsewhere the corners with data renormalised, the
border cells held for half a cell) and a sphere surface's
(:class:`footfall.core.sphere_surface.SphereSurface`: NaN outside its window). Each
function does the arithmetic of a vectorised NumPy evaluation in the same
order, so both give the same bits (``tests/test_bilinear.py``). Positions in
metres, heights in metres.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, inline="always")
def surface_point(filled, known, ox, oy, res, complete, px, py):  # pragma: no cover - compiled
    """A sphere surface's bilinear height at (px, py) [m]: NaN outside the window or where the
    nearest cell is unknown; else the known corners' weights renormalised (unless
    ``complete``: every cell known)."""
    wx, wy = filled.shape
    fi = (px - ox) / res
    fj = (py - oy) / res
    if not (fi >= 0.0 and fi <= wx - 1 and fj >= 0.0 and fj <= wy - 1):
        return np.nan
    i0 = min(int(fi), wx - 2)
    j0 = min(int(fj), wy - 2)
    ti = fi - i0
    tj = fj - j0
    w00 = (1 - ti) * (1 - tj)
    w10 = ti * (1 - tj)
    w01 = (1 - ti) * tj
    w11 = ti * tj
    num = w00 * filled[i0, j0] + w10 * filled[i0 + 1, j0] + w01 * filled[i0, j0 + 1] \
        + w11 * filled[i0 + 1, j0 + 1]
    if complete:
        return num
    den = w00 * known[i0, j0] + w10 * known[i0 + 1, j0] + w01 * known[i0, j0 + 1] \
        + w11 * known[i0 + 1, j0 + 1]
    if known[int(np.rint(fi)), int(np.rint(fj))] > 0 and den > 0:
        return num / den
    return np.nan


@numba.njit(cache=True, nogil=True)
def surface_at(filled, known, ox, oy, res, complete, px, py):  # pragma: no cover - compiled
    """The surface (``filled`` heights [m], 0 where unknown; ``known`` 1.0 / 0.0; cell (0, 0)
    at (ox, oy) [m], ``res`` [m/cell]) at the points (px, py) (m,) [m]."""
    out = np.empty(px.shape[0])
    for m in range(px.shape[0]):
        out[m] = surface_point(filled, known, ox, oy, res, complete, px[m], py[m])
    return out


@numba.njit(cache=True, nogil=True)
def surface_along_rays(filled, known, ox, oy, res, complete, xy, d, s):  # pragma: no cover
    """:func:`surface_at` at xy (n, 2) + s (J,) [m] along each direction d (K, 2): (n, K, J)."""
    out = np.empty((xy.shape[0], d.shape[0], s.shape[0]))
    for i in range(xy.shape[0]):
        for k in range(d.shape[0]):
            for j in range(s.shape[0]):
                out[i, k, j] = surface_point(filled, known, ox, oy, res, complete,
                                       xy[i, 0] + s[j] * d[k, 0], xy[i, 1] + s[j] * d[k, 1])
    return out


@numba.njit(cache=True, nogil=True, inline="always")
def _map_point(h, ox, oy, res, px, py):  # pragma: no cover - compiled
    """A height map's bilinear height at (px, py) [m] (see :meth:`HeightMap.height_at`)."""
    nx, ny = h.shape
    fi = (px - ox) / res
    fj = (py - oy) / res
    inside = fi >= -0.5 and fi < nx - 0.5 and fj >= -0.5 and fj < ny - 0.5
    if not inside:
        return np.nan
    fi = min(max(fi, 0.0), nx - 1.0)
    fj = min(max(fj, 0.0), ny - 1.0)
    i0 = min(int(np.floor(fi)), nx - 2)
    j0 = min(int(np.floor(fj)), ny - 2)
    nearest = h[int(np.floor(fi + 0.5)), int(np.floor(fj + 0.5))]
    if np.isnan(nearest):
        return np.nan
    ti = fi - i0
    tj = fj - j0
    num = 0.0
    den = 0.0
    for c, w in ((h[i0, j0], (1 - ti) * (1 - tj)), (h[i0 + 1, j0], ti * (1 - tj)),
                 (h[i0, j0 + 1], (1 - ti) * tj), (h[i0 + 1, j0 + 1], ti * tj)):
        if not np.isnan(c):
            num += c * w
            den += w
        else:
            num += 0.0
            den += 0.0
    if den > 0:
        return num / den
    return np.nan


@numba.njit(cache=True, nogil=True)
def map_at(h, ox, oy, res, px, py):  # pragma: no cover - compiled
    """The map's heights ``h`` (nx, ny) [m] (cell (0, 0) at (ox, oy) [m], ``res`` [m/cell])
    at the points (px, py) (m,) [m]."""
    out = np.empty(px.shape[0])
    for m in range(px.shape[0]):
        out[m] = _map_point(h, ox, oy, res, px[m], py[m])
    return out


@numba.njit(cache=True, nogil=True)
def map_patches(h, ox, oy, res, p, cos, sin, sign, u, v):  # pragma: no cover - compiled
    """The map at a patch grid around each centre p (n, 2) [m]: offsets u (nu,) along the
    heading (cos, sin) (n,) and ``sign`` (n,) * v (nv,) across it [m]; (n, nu, nv)."""
    out = np.empty((p.shape[0], u.shape[0], v.shape[0]))
    for k in range(p.shape[0]):
        c = cos[k]
        s = sin[k]
        for a in range(u.shape[0]):
            for b in range(v.shape[0]):
                vb = v[b] * sign[k]
                out[k, a, b] = _map_point(h, ox, oy, res, p[k, 0] + c * u[a] - s * vb,
                                          p[k, 1] + s * u[a] + c * vb)
    return out
