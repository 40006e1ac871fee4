"""Re-basing: after a recovery that leaves the body far from where it is wanted, take the stance
as it is.

Setting (:class:`~footfall.control.reflexes.ReflexConfig`): ``rebase_distance``
[m] (None: never). The whole robot has slid, and the legs push on feet that
are no longer where they were put: every stance foot is re-anchored where it
stands, the body is wanted where it is, the horizontal body correction is
cleared, and the next step is planned from there. The touch-down points, from
which slip and the flight recorder measure, stay.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from footfall.control.reflexes import ReflexConfig

if TYPE_CHECKING:
    from footfall.control.controller import Controller


class Rebase:
    """Re-base the stance after a recovery when the body is farther than ``rebase_distance``
    (horizontally) from where it is wanted."""

    def __init__(self, config: ReflexConfig) -> None:
        self.distance = config.rebase_distance  # [m] or None

    def due(self, position: np.ndarray, wanted: np.ndarray) -> float | None:
        """How far [m] the body at ``position`` (3,) [m] is from ``wanted`` (3,) [m]
        horizontally, if that calls for re-basing; else None."""
        if self.distance is None:
            return None
        off = float(np.hypot(*(position[:2] - wanted[:2])))
        return off if off > self.distance else None

    def after_recovery(self, ctl: Controller) -> None:
        """Re-base ``ctl``'s stance if it is due."""
        off = self.due(ctl.pose[0], ctl.desired[0])
        if off is None:
            return
        legs = ctl.legs
        legs.correction.take_horizontal()
        ctl.desired[0][:2] = ctl.pose[0][:2]
        stance = legs.stance.copy()
        legs.anchor_here(stance, ctl.est.feet[stance], ctl.est.q, ctl.pose[1])
        ctl.event("re-based", None, off_mm=round(1e3 * off, 1))
