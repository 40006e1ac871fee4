"""Recovery after an alarm of the stance watch, or a wait at the lift-off gate.

The body stops where it is wanted; a slipped foot is taken to stand where it
now is (:meth:`~footfall.control.reflexes.slip.SlipReflex.stand`; it steps
first if it went far); the posture is recovered -- roll and pitch back within
``tilt_recovered`` [rad] of the plan -- or, if it cannot be within
``recover_timeout`` [s] (joints at their limits), accepted as it is (an event
"posture accepted" once it is still off by more than ``tilt_threshold``);
then re-basing (:mod:`footfall.control.reflexes.rebase`) may take the stance
as it is. The next step is planned from the body at rest.
"""

from __future__ import annotations

from collections.abc import Generator
from typing import TYPE_CHECKING

import numpy as np

from footfall.control.measurements import JointTargets
from footfall.control.reflexes import tilt_error

if TYPE_CHECKING:
    from footfall.control.controller import Controller


def recover(ctl: Controller) -> Generator[JointTargets, None, None]:
    """Recover, a control period at a time, from every alarm raised meanwhile."""
    t0 = ctl.est.time
    while ctl.alarm is not None:
        kind, leg = ctl.alarm
        if kind == "slip":
            yield from ctl.slip.settle(ctl, leg, t0)
            if ctl.slip.stand(ctl, leg):
                ctl.replace = leg
        ctl.alarm = None
        yield from _posture(ctl, t0)
    ctl.held = False
    ctl.legs.hold_yields = False  # (the load hold acts again)
    ctl.legs.unload[:] = 1.0  # a step called off keeps its leg's load
    ctl.rebase.after_recovery(ctl)
    ctl.cog = ctl.desired[0][:2].copy(), np.zeros(2)  # the body at rest where it is


def _posture(ctl: Controller, t0: float) -> Generator[JointTargets, None, None]:
    """Hold the body until its roll and pitch are back near the plan (or recover_timeout after
    ``t0`` [s], or a new alarm); a posture still off is accepted as it is."""
    rc = ctl.config.reflexes
    ctl.recovering = True  # (a tilt does not set the tilt reflex off again meanwhile)
    while (tilt_error(ctl.pose[1], ctl.desired[1]) > rc.tilt_recovered
           and ctl.est.time - t0 < rc.recover_timeout and ctl.alarm is None):
        yield from ctl.tick(*ctl.desired, None)
    ctl.recovering = False
    error = tilt_error(ctl.pose[1], ctl.desired[1])
    if ctl.alarm is None and error > rc.tilt_threshold:
        # A posture the legs cannot reach from where the feet stand (joints at their limits):
        # the gait goes on from the one it has rather than waiting for ever.
        ctl.event("posture accepted", None, error_rad=round(error, 3))
        ctl.legs.correction.rebase(ctl.desired[1], ctl.pose[1])
        ctl.desired[1][:2] = ctl.pose[1][:2]
