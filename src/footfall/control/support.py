"""The geometry of support: how far a point lies inside a support triangle, and polygons as
half-planes.

The COG plan (:mod:`footfall.control.cog`) keeps the COG and the ZMP inside
inset support triangles and polygons written as half-planes; the reflexes
(:mod:`footfall.control.reflexes`) and the walking episode watch the margin
of the body over its support. Lengths in metres, points (x, y) in the world's
horizontal plane.
"""

from __future__ import annotations

import numpy as np

from footfall.core.errors import FootfallError


def support_margin(triangle: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Signed distance [m] of points inside a triangle: > 0 inside, < 0 outside.

    Parameters
    ----------
    triangle : array of shape (..., 3, 2)
        Vertices [m], either orientation.
    points : array of shape (..., 2)
        Points [m]; broadcast against the triangles' leading shape.

    Returns
    -------
    ndarray of shape (...)
        The smallest signed distance to the three edge lines: inside, the
        distance to the boundary; outside, minus at most the distance to it.
        A triangle with a zero-length edge leaves no margin (0 on that edge).
    """
    tri = np.asarray(triangle, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64)
    if tri.shape[-2:] != (3, 2) or p.shape[-1:] != (2,):
        raise FootfallError(f"support_margin needs triangles (..., 3, 2) and points (..., 2), "
                            f"got {tri.shape} and {p.shape}")
    a, b, c = tri[..., 0, :], tri[..., 1, :], tri[..., 2, :]
    cross = (b - a)[..., 0] * (c - a)[..., 1] - (b - a)[..., 1] * (c - a)[..., 0]
    orient = np.where(cross >= 0, 1.0, -1.0)
    out = None
    for start, end in ((a, b), (b, c), (c, a)):  # the three edges
        edge = end - start
        length = np.hypot(edge[..., 0], edge[..., 1])
        rel = p - start
        signed = orient * (edge[..., 0] * rel[..., 1] - edge[..., 1] * rel[..., 0])
        dist = np.divide(signed, length, out=np.zeros(np.broadcast_shapes(signed.shape, length.shape)),
                         where=length > 0)
        out = dist if out is None else np.minimum(out, dist)
    return out


def incircle(triangle: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Incentres (..., 2) [m] and inradii (...) [m] of triangles (..., 3, 2).

    A triangle without area has inradius 0 (its incentre then lies on it;
    all three vertices on one spot give that spot).
    """
    tri = np.asarray(triangle, dtype=np.float64)
    opposite = np.linalg.norm(tri[..., [1, 2, 0], :] - tri[..., [2, 0, 1], :], axis=-1)
    perimeter = opposite.sum(axis=-1)
    e1, e2 = tri[..., 1, :] - tri[..., 0, :], tri[..., 2, :] - tri[..., 0, :]
    area = 0.5 * np.abs(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0])
    safe = np.where(perimeter > 0, perimeter, 1.0)
    centre = np.where((perimeter > 0)[..., None],
                      np.einsum("...k,...kd->...d", opposite, tri) / safe[..., None],
                      tri.mean(axis=-2))
    return centre, 2 * area / safe


def halfplanes(vertices: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Inward unit normals (m, 2) and offsets (m,) of a convex polygon's edges, inset by margin.

    A point p is inside the inset polygon iff ``normals @ p >= offsets``.
    """
    following = np.r_[1:len(vertices), 0]  # index of the next vertex
    edges = vertices[following] - vertices
    cross = np.sum(edges[:, 0] * edges[following, 1] - edges[:, 1] * edges[following, 0])
    sign = 1.0 if cross >= 0 else -1.0
    normals = sign * np.column_stack([-edges[:, 1], edges[:, 0]])
    length = np.linalg.norm(normals, axis=1)
    keep = length > 0
    normals = normals[keep] / length[keep, None]
    return normals, np.sum(normals * vertices[keep], axis=1) + margin


def triangle_halfplanes(triangles: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Inward unit normals (K, 3, 2) and offsets (K, 3) of triangles (K, 3, 2), inset by margin.

    A point p is inside the inset triangle k iff ``normals[k] @ p >= offsets[k]``; a
    zero-length edge gets a zero normal (callers skip such degenerate triangles).
    """
    edges = np.roll(triangles, -1, axis=1) - triangles
    cross = edges[:, 0, 0] * edges[:, 1, 1] - edges[:, 0, 1] * edges[:, 1, 0]
    sign = np.where(cross >= 0, 1.0, -1.0)[:, None, None]
    normals = sign * np.stack([-edges[..., 1], edges[..., 0]], axis=-1)
    length = np.linalg.norm(normals, axis=-1, keepdims=True)
    normals = np.divide(normals, length, out=np.zeros_like(normals), where=length > 0)
    return normals, np.sum(normals * triangles, axis=-1) + margin
