"""Least squares under linear inequalities: min |G z + g|^2 subject to C z + c >= 0.

The COG plan's quadratic programme (:mod:`footfall.control.cog`) is solved
exactly by Lawson & Hanson's reduction to one non-negative least-squares solve.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_triangular
from scipy.optimize import nnls


def least_squares_inequality(G: np.ndarray, g: np.ndarray, C: np.ndarray, c: np.ndarray
                             ) -> np.ndarray | None:
    """Minimise |G z + g|^2 subject to C z + c >= 0; None if the constraints are incompatible.

    ``G`` (r, n) must have full column rank. Lawson & Hanson's reduction
    (Solving Least Squares Problems, 1974, ch. 23), the one SLSQP runs at
    every iteration: with G = QR and w = R z + Q^T g the problem becomes a
    least-distance programme, min |w| subject to E w >= f, whose solution
    comes from one non-negative least-squares solve (scipy.optimize.nnls)
    of size (n + 1, m). A QP this small solves in well under a millisecond.
    """
    q, r = np.linalg.qr(G)
    qg = q.T @ g
    if C.shape[0] == 0:
        return solve_triangular(r, -qg)
    e = solve_triangular(r, C.T, trans="T").T  # C R^-1, (m, n)
    f = e @ qg - c  # C z + c >= 0  <=>  E w >= f
    n = G.shape[1]
    lhs = np.vstack([e.T, f[None]])  # (n + 1, m)
    rhs = np.zeros(n + 1)
    rhs[n] = 1.0
    u, _ = nnls(lhs, rhs)
    res = lhs @ u - rhs
    if not res[n] < -1e-12:  # zero residual: the constraints are incompatible
        return None
    w = res[:n] / -res[n]
    return solve_triangular(r, w - qg)
