"""The phases of a step, each a generator that yields one control period's joint targets.

A step (:meth:`footfall.control.controller.Controller.step_phases`) goes through
*shift* (four feet down, the body moving into the swing's triangle, then the
lift-off gate), *swing* (the foot to a point ``touchdown_approach`` above its
foothold), *touch-down* (down the rest of the way slowly until its force
sensor feels the ground) and, when the stance watch raised an alarm during
the swing, *come down* (the foot straight down at once). Each phase runs as
many control periods as it needs -- ``yield from ctl.tick(...)`` is one -- and
returns what the step needs to know next; it reads the robot only through the
controller's estimate of this period (``ctl.est``).

Why generators: a phase reads as the sequence it is (move, look, decide)
while the controller is called once per control period with measurements and
answers targets. An explicit state machine would scatter each phase over
states and transitions and carry its loop variables in attributes; a
generator keeps them where they are used and suspends at each period.
"""

from __future__ import annotations

from collections.abc import Generator
from typing import TYPE_CHECKING

import numpy as np

from footfall.control.footstep import FootstepPlan
from footfall.control.lowlevel import transfer_weight
from footfall.control.measurements import JointTargets
from footfall.control.step_motion import BodyMotion

if TYPE_CHECKING:
    from footfall.control.controller import Controller

Periods = Generator[JointTargets, None, bool]  # a phase: targets per period, then its answer
DROP_SPEED = 0.3  # [m/s] a swing foot brought down by a reflex drops this fast to near the ground


def shift(ctl: Controller, s: int, motion: BodyMotion) -> Generator[JointTargets, None, int | None]:
    """Shift phase: all four feet down, the body moving into the swing's triangle of leg ``s``.

    Returns the index into ``motion.times`` of the first swing period
    (``motion.times.size``: the step is too short to lift the foot), or None
    if the step is called off (an alarm, or the lift-off gate's timeout).
    """
    t_lift = float(motion.traj.lift_off[0])
    unload = ctl.config.lowlevel.unload_time
    times = motion.times
    ctl.held = False
    for i in range(times.size):
        if times[i] > t_lift:
            return i if (yield from ctl.gate.wait(ctl, s)) else None
        if unload > 0:  # the swing leg passes its load on to the others before it lifts
            ctl.legs.unload[s] = 1.0 - float(transfer_weight(times[i] - (t_lift - unload),
                                                             unload))
        ctl.desired = motion.positions[i].copy(), motion.attitudes[i].copy()
        yield from ctl.tick(*ctl.desired, None)
        if ctl.alarm is not None:
            return None
    return times.size


def swing(ctl: Controller, k: int, s: int, plan: FootstepPlan, motion: BodyMotion,
          i_lift: int) -> Periods:
    """Swing leg ``s`` of step ``k`` along its trajectory from lift-off (period ``i_lift`` of
    ``motion``).

    Returns whether the foot is down: it touched down near the end of the
    swing, close to the foothold. Returns False at once on an alarm (the
    step then brings the foot down).
    """
    cfg = ctl.config
    t_lift, t_down = float(motion.traj.lift_off[0]), float(motion.traj.touch_down[0])
    times = motion.times[i_lift:]
    swing_time = t_down - t_lift
    # The foot swings to a point `approach` above the foothold and comes down the rest of the
    # way slowly, so that a terrain a little higher or lower than the map meets it gently.
    descent = min(cfg.touchdown_approach / cfg.touchdown_speed, 0.5 * swing_time)
    reach = swing_time - descent  # [s] after lift-off: above the foothold
    above = plan.foothold + [0.0, 0.0, descent * cfg.touchdown_speed]
    path = ctl.lift_off(k, s, above, reach, times - t_lift)
    hold = ctl.desired[0][:2].copy() if ctl.held else None
    for i in range(times.size):  # control periods
        ctl.legs.targets[s] = path[i]
        position = motion.positions[i_lift + i].copy()
        if hold is not None:  # after a wait at the gate, the body stays where it waited
            position[:2] = hold
        ctl.desired = position, motion.attitudes[i_lift + i].copy()
        yield from ctl.tick(*ctl.desired, s)
        if ctl.alarm is not None:
            return False
        if times[i] - t_lift > cfg.touchdown_early * reach and ctl.touching_down(s) \
                and np.hypot(*(ctl.est.feet[s, :2] - above[:2])) < cfg.touchdown_reach:
            return True
    return False


def touch_down(ctl: Controller, s: int, foothold: np.ndarray) -> Periods:
    """Not down yet: keep foot ``s`` going down at its foothold (3,) [m] until it feels the
    ground; returns whether it did within ``touchdown_search`` below the foothold."""
    cfg = ctl.config
    bottom = foothold[2] + ctl.robot.foot_radius - cfg.touchdown_search
    legs = ctl.legs
    while True:
        legs.targets[s, 2] -= cfg.touchdown_speed * ctl.period
        if legs.targets[s, 2] < bottom:
            return False  # nothing there within reach
        yield from ctl.tick(*ctl.desired, s)
        if ctl.touching_down(s):
            return True


def come_down(ctl: Controller, s: int) -> Periods:
    """Swing foot ``s`` down at once, straight below where it is (an alarm during its swing).

    It drops fast to ``touchdown_approach`` above the mapped ground there, then feels for
    the ground at touchdown_speed; returns whether it found it.
    """
    cfg, robot, legs = ctl.config, ctl.robot, ctl.legs
    centre = ctl.est.feet[s].copy()
    legs.targets[s] = centre
    ground = float(ctl.hmap.height_at(centre[None, :2])[0])
    if not np.isfinite(ground):
        ground = float(np.nanmin(legs.targets[legs.stance, 2])) - robot.foot_radius
    slow_from = ground + robot.foot_radius + cfg.touchdown_approach
    while legs.targets[s, 2] > slow_from and not ctl.touching_down(s):
        legs.targets[s, 2] = max(slow_from, legs.targets[s, 2] - DROP_SPEED * ctl.period)
        yield from ctl.tick(*ctl.desired, s)
    if ctl.touching_down(s):
        return True
    return (yield from touch_down(ctl, s, np.array([*centre[:2], ground])))
