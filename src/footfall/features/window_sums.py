"""Sums over strided windows of a map, for every point of a lattice: the dense scorer's window sums.

A patch window of lattice point (a, b) takes the map's cells
``(x0[a] + tap * i, y0[b] + tap * j)``, i < nu, j < nv. Its sum (and the
sum of squares) for every lattice point is found separably: each row's
running sums along y, one per phase y mod tap, give every row's window
sums; running sums of those along x, one per phase x mod tap, give the
windows'. A running sum is at most one row or one column long, so a
window's sum keeps its digits beside the map's other windows (float64).
Compiled (Numba): on a board the NumPy version was mostly strided copies.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def _sums(q, tap, x0, y0, nu, nv):  # pragma: no cover - compiled
    px, py = q.shape
    na, nb = x0.size, y0.size
    # Every row's window sums of q and q^2: rows (px, nb, 2).
    rows = np.zeros((px, nb, 2))
    run1 = np.zeros(py + tap)  # run[k + tap] = sum of q[x, k], q[x, k - tap], ... (one phase)
    run2 = np.zeros(py + tap)
    for x in range(px):
        for k in range(py):
            v = q[x, k]
            run1[k + tap] = run1[k] + v
            run2[k + tap] = run2[k] + v * v
        for b in range(nb):
            last = y0[b] + tap * (nv - 1)  # the window's last sample along y
            rows[x, b, 0] = run1[last + tap] - run1[y0[b]]
            rows[x, b, 1] = run2[last + tap] - run2[y0[b]]
    # Running sums of the row sums along x, per phase x mod tap, then the windows.
    down = np.zeros((px + tap, nb, 2))
    for x in range(px):
        for b in range(nb):
            down[x + tap, b, 0] = down[x, b, 0] + rows[x, b, 0]
            down[x + tap, b, 1] = down[x, b, 1] + rows[x, b, 1]
    out = np.empty((2, na, nb))
    for a in range(na):
        last = x0[a] + tap * (nu - 1)
        for b in range(nb):
            out[0, a, b] = down[last + tap, b, 0] - down[x0[a], b, 0]
            out[1, a, b] = down[last + tap, b, 1] - down[x0[a], b, 1]
    return out


def window_sums(q: np.ndarray, tap: int, x0: np.ndarray, y0: np.ndarray, nu: int, nv: int
                ) -> tuple[np.ndarray, np.ndarray]:
    """Sums of q and of q^2 over the samples ``q[x0[a] + tap * i, y0[b] + tap * j]``, i < nu,
    j < nv, of every window (a, b): two arrays (na, nb), float64.

    ``q`` (px, py) must hold every window's samples (no index past its edge);
    NaN is not skipped (fill no-data cells with 0 first).
    """
    x0 = np.asarray(x0, dtype=np.int64)
    y0 = np.asarray(y0, dtype=np.int64)
    if x0.size and (x0.min() < 0 or x0.max() + tap * (nu - 1) >= q.shape[0]
                    or y0.min() < 0 or y0.max() + tap * (nv - 1) >= q.shape[1]):
        raise ValueError("a window reaches past the map's edge")
    out = _sums(np.ascontiguousarray(q, dtype=np.float64), int(tap), x0, y0, int(nu), int(nv))
    return out[0], out[1]
