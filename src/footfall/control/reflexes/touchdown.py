"""The touch-down check: a foot that lands far off its foothold, or on nothing, is re-placed.

Settings (:class:`~footfall.control.reflexes.ReflexConfig`):
``touchdown_check`` (the switch), ``touchdown_tolerance`` [m],
``replace_separation`` [m] and ``max_replacements``. The foot is lifted
again and put on the next-best candidate of F (by reward plus path bias)
away from every spot tried, reaching above it in ``REPLACE_TIME``.
"""

from __future__ import annotations

from collections.abc import Generator
from typing import TYPE_CHECKING

import numpy as np

from footfall.control.footstep import FootstepPlan
from footfall.control.measurements import JointTargets
from footfall.control.phases import come_down, touch_down
from footfall.control.reflexes import ReflexConfig, next_best_candidate

if TYPE_CHECKING:
    from footfall.control.controller import Controller

REPLACE_TIME = 0.25  # [s] a re-placed foot's swing to above its new foothold


class TouchdownCheck:
    """Check where a foot came down; re-place it on another candidate while it is off."""

    def __init__(self, config: ReflexConfig) -> None:
        self.on = config.touchdown_check
        self.tolerance = config.touchdown_tolerance  # [m]
        self.separation = config.replace_separation  # [m]
        self.max_replacements = config.max_replacements

    def place(self, ctl: Controller, s: int, plan: FootstepPlan, found: bool
              ) -> Generator[JointTargets, None, None]:
        """Foot ``s`` came down (``found``: on the ground) for ``plan``: while it is more than
        ``touchdown_tolerance`` off its foothold, or on nothing, put it on the next-best
        candidate, at most ``max_replacements`` times; then it stands where it is."""
        tried, target = [plan.foothold[:2].copy()], plan.foothold
        for _ in range(self.max_replacements if self.on else 0):
            off = float(np.hypot(*(ctl.est.feet[s, :2] - target[:2])))
            if ctl.alarm is not None or (found and off <= self.tolerance):
                break
            j = next_best_candidate(plan.candidates, plan.total, np.array(tried),
                                    self.separation)
            if j is None:
                break
            ctl.event("touch-down re-placed", s, off_mm=round(1e3 * off, 1), ground=bool(found))
            target = plan.candidates[j]
            tried.append(target[:2].copy())
            found = yield from self.re_place(ctl, s, target)

    def re_place(self, ctl: Controller, s: int, foothold: np.ndarray
                 ) -> Generator[JointTargets, None, bool]:
        """Lift foot ``s`` (not yet loaded) and put it on ``foothold`` (3,) [m], the body held;
        returns whether it found the ground there."""
        cfg = ctl.config
        centre = ctl.est.feet[s]
        approach = cfg.touchdown_approach
        reach = REPLACE_TIME
        n = round((reach + approach / cfg.touchdown_speed) / ctl.period)
        after = np.arange(1, n + 1) * ctl.period
        path = ctl.swing_path(centre, foothold + [0.0, 0.0, approach], reach, after)
        for i in range(n):
            ctl.legs.targets[s] = path[i]
            yield from ctl.tick(*ctl.desired, s)
            if ctl.alarm is not None:
                return (yield from come_down(ctl, s))
            if after[i] > cfg.touchdown_early * reach and ctl.touching_down(s):
                return True
        return (yield from touch_down(ctl, s, foothold))
