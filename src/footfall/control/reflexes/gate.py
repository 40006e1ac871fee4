"""The lift-off gate: a leg lifts only with the measured centre of mass inside its triangle.

Settings (:class:`~footfall.control.reflexes.ReflexConfig`): ``lift_off_gate``
(the switch), ``gate_margin`` [m], ``gate_timeout`` [s], ``gate_speed`` [m/s].
"""

from __future__ import annotations

from collections.abc import Generator
from typing import TYPE_CHECKING

from footfall.control.cog import support_margin
from footfall.control.legs import OTHER_LEGS
from footfall.control.measurements import JointTargets
from footfall.control.reflexes import ReflexConfig, com_in_triangle, gate_step

if TYPE_CHECKING:
    from footfall.control.controller import Controller


class LiftOffGate:
    """Hold a leg's lift-off until the centre of mass is ``gate_margin`` inside the triangle of
    the other three feet, moving the body toward the triangle's incentre meanwhile; give up
    after ``gate_timeout`` (the step is then planned anew)."""

    def __init__(self, config: ReflexConfig) -> None:
        self.on = config.lift_off_gate
        self.margin = config.gate_margin  # [m]
        self.timeout = config.gate_timeout  # [s]
        self.speed = config.gate_speed  # [m/s]

    def open(self, com_xy, feet_xy) -> bool:
        """Whether a leg may lift: the centre of mass (2,) [m] is inside the triangle of the
        feet that stay down (3, 2) [m] by the margin."""
        return com_in_triangle(com_xy, feet_xy, self.margin)

    def wait(self, ctl: Controller, s: int) -> Generator[JointTargets, None, bool]:
        """Wait at the gate before leg ``s`` lifts, a control period at a time.

        Returns whether the leg may lift (False: the wait timed out or an alarm came). After a
        wait the body holds its place through the swing (``ctl.held``).
        """
        if not self.on:
            return True
        t0 = ctl.est.time
        while True:
            com, tri = ctl.est.com[:2], ctl.est.feet[OTHER_LEGS[s], :2]
            if self.open(com, tri):
                if ctl.held:
                    ctl.event("lift-off gate", s, waited_s=round(ctl.est.time - t0, 3))
                return True
            if ctl.est.time - t0 >= self.timeout:
                ctl.event("lift-off gate timeout", s,
                          margin_mm=round(1e3 * float(support_margin(tri, com)), 1))
                return False
            ctl.held = True
            ctl.desired[0][:2] = gate_step(com, ctl.desired[0][:2], tri, self.speed, ctl.period)
            yield from ctl.tick(*ctl.desired, None)
            if ctl.alarm is not None:
                return False
