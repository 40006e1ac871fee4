"""The stance slip reflex: a loaded stance foot sliding away raises the stance watch's alarm.

Settings (:class:`~footfall.control.reflexes.ReflexConfig`): ``slip_reflex``
(the switch), ``slip_distance`` [m], ``slip_speed`` [m/s],
``replace_distance`` [m] and ``recover_timeout`` [s]; a foot is loaded when
its force sensor reads more than the walk's ``touchdown_force`` [N]. On the
alarm the body stops; once the slipped foot has stopped it is taken to stand
where it now is, and, if it went farther than ``replace_distance``, it steps
first, to a new foothold (the recovery, :mod:`footfall.control.reflexes.recovery`).
"""

from __future__ import annotations

from collections.abc import Generator
from typing import TYPE_CHECKING

import numpy as np

from footfall.control.measurements import JointTargets
from footfall.control.reflexes import ReflexConfig, slipped

if TYPE_CHECKING:
    from footfall.control.controller import Controller


class SlipReflex:
    """Watch the loaded stance feet for a slide; after one, let the slipped foot settle."""

    def __init__(self, config: ReflexConfig, touchdown_force: float) -> None:
        self.on = config.slip_reflex
        self.distance = config.slip_distance  # [m]
        self.speed = config.slip_speed  # [m/s]
        self.replace_distance = config.replace_distance  # [m]
        self.timeout = config.recover_timeout  # [s]
        self.touchdown_force = touchdown_force  # [N]

    def watch(self, feet: np.ndarray, speed: np.ndarray, targets: np.ndarray,
              settled_stance: np.ndarray, forces: np.ndarray | None) -> int | None:
        """The first stance foot (a LEG_NAMES index) that is sliding, or None.

        ``feet`` (4, 3) [m]: measured foot centres; ``speed`` (4,) [m/s]: their horizontal
        speeds over the last period; ``targets`` (4, 3) [m]: where the stance feet are held
        (moved on by the ball's rolling); ``settled_stance`` (4,) bool: stance legs whose load
        transfer is complete; ``forces`` (4,) [N]: vertical force sensor readings.
        """
        if not self.on:
            return None
        loaded = settled_stance & (forces > self.touchdown_force)
        bad = slipped(feet[:, :2], targets[:, :2], loaded, self.distance) & (speed > self.speed)
        return int(np.flatnonzero(bad)[0]) if bad.any() else None

    def settle(self, ctl: Controller, leg: int, t0: float) -> Generator[JointTargets, None, None]:
        """The body held, wait until slipped foot ``leg`` stops sliding (or ``recover_timeout``
        after ``t0`` [s])."""
        while ctl.est.time - t0 < self.timeout:
            before = ctl.est.feet[leg, :2]
            yield from ctl.tick(*ctl.desired, None)
            if np.hypot(*(ctl.est.feet[leg, :2] - before)) < 0.5 * self.speed * ctl.period:
                return

    def stand(self, ctl: Controller, leg: int) -> bool:
        """Take slipped foot ``leg`` to stand where it is now; returns whether it went so far
        from where it was put down that it should step first."""
        centre = ctl.est.feet[leg]
        legs = ctl.legs
        moved = float(np.hypot(*(centre[:2] - legs.down[leg, :2])))
        legs.hand_over()
        legs.down[leg] = centre
        legs.anchor_here(leg, centre, ctl.est.q, ctl.pose[1])
        return moved > self.replace_distance
