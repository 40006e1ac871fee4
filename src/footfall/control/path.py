"""The body path: a polyline the body's horizontal position follows, with arc-length helpers.

The body path planner (:mod:`footfall.control.body_path`) plans one over the
terrain, or the path is the straight line of the paper's evaluation; the
footstep planner (:mod:`footfall.control.footstep`) walks along it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from footfall.core.errors import FootfallError


@dataclass(frozen=True, eq=False)
class BodyPath:
    """A polyline for the body's horizontal position, with arc-length helpers.

    ``s`` is the arc length [m] from the first waypoint. Positions beyond
    either end are clamped to the end.
    """

    waypoints: np.ndarray  # (n, 2) [m] world x, y, n >= 2, consecutive points distinct
    _s: np.ndarray = field(init=False, repr=False)  # (n,) [m] arc length at each waypoint

    def __post_init__(self) -> None:
        w = np.array(self.waypoints, dtype=np.float64)
        if w.ndim != 2 or w.shape[1] != 2 or w.shape[0] < 2:
            raise FootfallError(f"a body path needs waypoints of shape (n >= 2, 2), got {w.shape}")
        if not np.isfinite(w).all():
            raise FootfallError("body path waypoints must be finite")
        keep = np.concatenate([[True], np.linalg.norm(np.diff(w, axis=0), axis=1) > 1e-12])
        w = w[keep]
        if w.shape[0] < 2:
            raise FootfallError("a body path needs two distinct waypoints")
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(w, axis=0), axis=1))])
        w.setflags(write=False)
        s.setflags(write=False)
        object.__setattr__(self, "waypoints", w)
        object.__setattr__(self, "_s", s)

    @classmethod
    def straight(cls, start_xy, goal_xy) -> "BodyPath":
        """The straight path from ``start_xy`` to ``goal_xy`` [m] (the paper's fixed evaluation path)."""
        return cls(np.array([start_xy, goal_xy], dtype=np.float64))

    @property
    def length(self) -> float:
        """Total arc length [m]."""
        return float(self._s[-1])

    @property
    def arc_lengths(self) -> np.ndarray:
        """Arc length [m] at each waypoint, shape (n,)."""
        return self._s

    def point_at(self, s) -> np.ndarray:
        """Position [m] at arc length ``s`` [m], (...) -> (..., 2)."""
        s = np.clip(np.asarray(s, dtype=np.float64), 0.0, self.length)
        return np.stack([np.interp(s, self._s, self.waypoints[:, 0]),
                         np.interp(s, self._s, self.waypoints[:, 1])], axis=-1)

    def heading_at(self, s) -> np.ndarray:
        """Heading [rad] of the segment at arc length ``s`` [m], (...) -> (...)."""
        d = np.diff(self.waypoints, axis=0)
        seg = np.clip(np.searchsorted(self._s, np.asarray(s, dtype=np.float64), side="right") - 1,
                      0, d.shape[0] - 1)
        return np.arctan2(d[seg, 1], d[seg, 0])

    def closest(self, xy) -> np.ndarray:
        """Arc length [m] of the path point nearest to each position [m], (..., 2) -> (...)."""
        p = np.asarray(xy, dtype=np.float64)
        if p.shape[-1:] != (2,):
            raise FootfallError(f"positions must have shape (..., 2), got {p.shape}")
        a, d = self.waypoints[:-1], np.diff(self.waypoints, axis=0)  # (m, 2)
        seg_len2 = np.einsum("ij,ij->i", d, d)
        rel = p[..., None, :] - a  # (..., m, 2)
        t = np.clip(np.einsum("...ij,ij->...i", rel, d) / seg_len2, 0.0, 1.0)
        dist2 = np.sum((rel - t[..., None] * d) ** 2, axis=-1)
        best = np.argmin(dist2, axis=-1)
        t_best = np.take_along_axis(t, best[..., None], axis=-1)[..., 0]
        return self._s[best] + t_best * np.sqrt(seg_len2[best])
