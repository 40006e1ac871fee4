"""What the robot did in the last seconds of a run, at the control rate: the flight recorder.

A :class:`RunTrace` keeps the last ``window`` seconds of a run, one row per
control period (100 Hz): the true trunk pose, the centre of mass, the
ball-foot centres, the true contact forces on the feet, the role of each
leg and where each stance foot was put down, the joint angles and servo
torques, and the swing leg. It is a ring buffer of fixed size, so a long
run costs no more than a short one, and a row costs one array copy.

:mod:`footfall.sim.explain` reads it to say why a run failed; the figure of
``footfall walk --explain-plot`` draws it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from footfall.core.errors import FootfallError

# The columns of a row: name -> (width of the flattened field, its shape in a row).
FIELDS: dict[str, tuple[int, tuple[int, ...]]] = {
    "time": (1, ()),  # [s] simulated time at the end of the control period
    "body_position": (3, (3,)),  # [m] true trunk origin, world frame
    "body_rpy": (3, (3,)),  # [rad] true trunk roll, pitch, yaw
    "com": (3, (3,)),  # [m] whole robot's centre of mass, world frame
    "feet": (12, (4, 3)),  # [m] ball-foot centres, LEG_NAMES order
    "forces": (12, (4, 3)),  # [N] true contact force on each foot (world frame; no sensor noise)
    "stance": (4, (4,)),  # 1 for a stance leg, 0 for a swing leg
    "anchor": (12, (4, 3)),  # [m] where each stance foot's centre was put down (swing: NaN)
    "q": (12, (4, 3)),  # [rad] joint angles
    "torque": (12, (4, 3)),  # [N m] servo torques
    "swing": (1, ()),  # index of the swinging leg (LEG_NAMES), -1: none
}
_OFFSETS: dict[str, slice] = {}
_width = 0
for _name, (_n, _) in FIELDS.items():
    _OFFSETS[_name] = slice(_width, _width + _n)
    _width += _n
ROW_WIDTH = _width  # floats per row


@dataclass(frozen=True)
class TraceSeries:
    """The recorded rows in time order: one array per field, rows first (n, *shape)."""

    time: np.ndarray  # (n,) [s]
    body_position: np.ndarray  # (n, 3) [m]
    body_rpy: np.ndarray  # (n, 3) [rad]
    com: np.ndarray  # (n, 3) [m]
    feet: np.ndarray  # (n, 4, 3) [m]
    forces: np.ndarray  # (n, 4, 3) [N]
    stance: np.ndarray  # (n, 4) bool
    anchor: np.ndarray  # (n, 4, 3) [m]
    q: np.ndarray  # (n, 4, 3) [rad]
    torque: np.ndarray  # (n, 4, 3) [N m]
    swing: np.ndarray  # (n,) int, -1: none

    def __len__(self) -> int:
        return int(self.time.size)


class RunTrace:
    """A ring buffer of the last ``window`` [s] of a run at ``period`` [s] per row; an infinite
    ``window`` keeps the whole run (the buffer grows)."""

    def __init__(self, window: float, period: float) -> None:
        if not (window > 0 and period > 0):
            raise FootfallError("a run trace needs a window and a period > 0 s")
        self.grows = not math.isfinite(window)  # keep every row
        self.size = 1024 if self.grows else max(1, int(round(window / period)))
        self._rows = np.full((self.size, ROW_WIDTH), np.nan)
        self._count = 0

    def record(self, row: np.ndarray) -> None:
        """Keep one row (ROW_WIDTH,), made by :func:`trace_row`; the oldest goes if full
        (unless the trace keeps the whole run)."""
        if self.grows and self._count == self.size:
            self._rows = np.vstack([self._rows, np.full((self.size, ROW_WIDTH), np.nan)])
            self.size *= 2
        self._rows[self._count % self.size] = row
        self._count += 1

    def series(self) -> TraceSeries:
        """The kept rows in time order, split into fields."""
        n = min(self._count, self.size)
        start = self._count % self.size if self._count > self.size else 0
        rows = np.roll(self._rows, -start, axis=0)[:n]
        out = {}
        for name, (_, shape) in FIELDS.items():
            out[name] = rows[:, _OFFSETS[name]].reshape((n, *shape))
        out["stance"] = out["stance"] > 0.5
        out["swing"] = out["swing"].astype(int)
        return TraceSeries(**out)


def trace_row(time: float, body_position: np.ndarray, body_rpy: np.ndarray, com: np.ndarray,
              feet: np.ndarray, forces: np.ndarray, stance: np.ndarray, anchor: np.ndarray,
              q: np.ndarray, torque: np.ndarray, swing: int | None) -> np.ndarray:
    """One row (ROW_WIDTH,) of a trace from the fields of :data:`FIELDS`, in their units."""
    anchors = np.where(np.asarray(stance, dtype=bool)[:, None], anchor, np.nan)
    return np.concatenate((
        (time,), body_position, body_rpy, com, np.ravel(feet), np.ravel(forces),
        np.asarray(stance, dtype=np.float64), anchors.ravel(), np.ravel(q), np.ravel(torque),
        (-1.0 if swing is None else float(swing),)))
