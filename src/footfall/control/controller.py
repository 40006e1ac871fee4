"""The walking controller: measurements in, joint targets out, one control period at a time.

The controller is what runs on the robot. It knows the map (given once), its
mission (the body path to the goal) and what its sensors say each control
period (:class:`~footfall.control.measurements.Measurements`), and answers
with set-points for the servos (:class:`~footfall.control.measurements.JointTargets`).
It never sees the simulator: whatever steps the physics (the episode,
:mod:`footfall.sim.episode`) passes measurements in and targets out.

Inside, the paper's control stack (§IV-B): a step is planned (footstep
planner, COG trajectory, pose: :mod:`footfall.control.step_motion`) from the
feet where they stand, then runs through its phases
(:mod:`footfall.control.phases`: shift, lift-off gate, swing, touch-down,
touch-down check, load); the legs' set-points come from
:class:`~footfall.control.legs.Legs` every period. The reflexes
(:mod:`footfall.control.reflexes`) are parts with their own settings: every
period the stance watch (slip and tilt reflexes) looks at what was measured
and may raise an alarm, on which the step is called off or its foot brought
down, and the robot recovers before the next step.

Each period is :meth:`Controller.sense` (this period's measurements; the
stance watch) then :meth:`Controller.act` (the next period's targets;
:meth:`Controller.step` does both): two calls, so that whoever runs the robot
may end the run between them, on what was just measured, before the
controller plans on. The phases are generators (see
:mod:`footfall.control.phases` for why): ``act`` resumes the walk where the
last period left it. What happens (steps planned and taken,
reflexes acting) is told to whoever records the run through :meth:`notes`.
"""

from __future__ import annotations

import time
from collections.abc import Generator
from typing import Protocol

import numpy as np

from footfall.control.body_path import BodyPath, BodyPathConfig, plan_body_path
from footfall.control.cog import CogConfig
from footfall.control.estimate import BodyEstimate
from footfall.control.footstep import (
    FootstepConfig,
    FootstepPlan,
    FootstepPlanner,
    NoFootholdError,
)
from footfall.control.journal import (
    LiftOff,
    Note,
    ReflexEvent,
    Settled,
    StepCalledOff,
    StepPlanned,
    TouchDown,
)
from footfall.control.judged import JudgedFootstepPlanner
from footfall.control.legs import Legs
from footfall.control.lowlevel import LowLevelConfig
from footfall.control.measurements import JointTargets, Measurements
from footfall.control.phases import come_down, shift, swing, touch_down
from footfall.control.pose_finder import PoseConfig
from footfall.control.reflexes import ReflexConfig
from footfall.control.reflexes.gate import LiftOffGate
from footfall.control.reflexes.rebase import Rebase
from footfall.control.reflexes.recovery import recover
from footfall.control.reflexes.slip import SlipReflex
from footfall.control.reflexes.tilt import TiltReflex
from footfall.control.reflexes.touchdown import TouchdownCheck
from footfall.control.step_motion import BodyMotion, body_motion
from footfall.control.swing import SwingConfig, swing_trajectory
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.features.scorer import FootholdScorer, RewardFor

Steps = Generator[JointTargets, None, bool]


class ControlSettings(Protocol):
    """The settings the controller reads; :class:`footfall.sim.episode.WalkConfig` declares
    each (unit, range, meaning) and is what a run passes."""

    footstep: FootstepConfig  # the footstep planner
    cog: CogConfig  # the COG planner
    swing: SwingConfig  # the swing-foot trajectory
    pose: PoseConfig  # the pose finder
    lowlevel: LowLevelConfig  # the 100 Hz closed loop (its period [s] is the control period)
    reflexes: ReflexConfig  # the reflexes' switches and thresholds
    path: BodyPathConfig  # the body path planner (with plan_path)
    plan_path: bool  # plan the body path by Dijkstra; False: straight along the board
    settle_time: float  # [s] standing still before the first step
    touchdown_force: float  # [N] vertical foot force that means the foot is down
    touchdown_early: float  # [-] share of the swing after which a contact ends it
    touchdown_reach: float  # [m] a contact counts only this close to the foothold
    touchdown_approach: float  # [m] the swing ends this far above the foothold
    touchdown_search: float  # [m] how far below the foothold the foot keeps looking
    touchdown_speed: float  # [m/s] how fast the foot goes down while looking
    max_steps: int | None  # stop after this many steps; None: at the goal only


def footstep_planner(hmap: HeightMap, reward_for: RewardFor,
                     start_xy: np.ndarray, goal_xy: np.ndarray, config: ControlSettings,
                     robot: RobotDescription = LITTLEDOG, judge: FootholdScorer | None = None
                     ) -> FootstepPlanner:
    """The footstep planner of a walk from ``start_xy`` to ``goal_xy`` (2,) [m]: along the
    planned body path (``plan_path``) or the straight one, choosing by the reward
    ``reward_for(leg)`` -- or by ``judge`` (e.g. ``ExpertScorer(SyntheticExpert(...))``) if given."""
    if config.plan_path:
        path = plan_body_path(hmap, reward_for, start_xy, goal_xy, robot, config.path)
    else:
        path = BodyPath.straight(start_xy, goal_xy)
    if judge is None:
        return FootstepPlanner(hmap, reward_for, path, robot, config.footstep)
    return JudgedFootstepPlanner(hmap, judge, path, robot, config.footstep)


class _NoFoothold(Exception):
    """The swing leg has no candidate foothold (the message says which)."""


class Controller:
    """The walking controller of one run (see the module's docstring).

    Parameters
    ----------
    hmap : HeightMap
        The map, as the robot was given it.
    planner : FootstepPlanner
        The footstep planner (:func:`footstep_planner`).
    goal : ndarray (2,)
        [m] where the body path ends (the planner's goal).
    goal_x : float
        [m] the body is done when its origin is past this x at the end of a step.
    config : ControlSettings
        The settings (a :class:`footfall.sim.episode.WalkConfig`).
    robot : RobotDescription

    Attributes
    ----------
    est : BodyEstimate
        This period's view of the robot.
    desired : (ndarray (3,), ndarray (3,))
        Desired body position [m] and roll, pitch, yaw [rad].
    alarm : (str, int | None) or None
        The stance watch's alarm ("slip", leg) or ("tilt", None), not yet acted on.
    stopped : str or None
        Why the controller stopped stepping: "goal", "step limit" or "no foothold for LEG".
    """

    def __init__(self, hmap: HeightMap, planner: FootstepPlanner, goal: np.ndarray,
                 goal_x: float, config: ControlSettings, robot: RobotDescription = LITTLEDOG
                 ) -> None:
        self.hmap, self.planner, self.goal, self.goal_x = hmap, planner, goal, goal_x
        self.config, self.robot = config, robot
        self.period = config.lowlevel.period  # [s]
        rc = config.reflexes
        self.legs = Legs(robot, config.lowlevel, config.touchdown_force, rc.slip_reflex)
        self.gate, self.check, self.rebase = LiftOffGate(rc), TouchdownCheck(rc), Rebase(rc)
        self.slip, self.tilt = SlipReflex(rc, config.touchdown_force), TiltReflex(rc)
        self.stopped: str | None = None
        self._notes: list[Note] = []

    # ------------------------------------------------------------------ the interface
    def start(self, m: Measurements, footholds: np.ndarray) -> None:
        """The robot stands on ``footholds`` (4, 3) [m] (contact points, LEG_NAMES order) and
        measures ``m``: the walk starts from there."""
        self.est = est = BodyEstimate(m, self.robot)
        self.pose = est.pose  # measured (position (3,) [m], rpy (3,) [rad])
        self.legs.start(est, footholds)
        # The robot stands where the start error put it: the plan starts from there, so that the
        # first set-points do not jerk the body (and drag the unloaded feet) to the nominal pose.
        self.desired = self.pose[0].copy(), self.pose[1].copy()
        self.cog = self.desired[0][:2].copy(), np.zeros(2)  # planned COG position, velocity
        self.alarm: tuple[str, int | None] | None = None
        self.held = False  # the body waited at the lift-off gate and holds still this swing
        self.recovering = False  # the posture is recovering after an alarm
        self.replace: int | None = None  # a slipped leg to step next, out of gait order
        self.gait = 0  # steps taken in gait order
        self.swing: int | None = None  # the leg swinging in the last period
        self._feet_before = est.feet  # (4, 3) [m] at the last period (the watch's speeds)
        self._watched: np.ndarray | None = None  # desired rpy [rad] of the period to watch
        self._walk = self._walking()

    def sense(self, m: Measurements) -> None:
        """Take this period's measurements; the stance watch looks at them."""
        self.est = BodyEstimate(m, self.robot)
        self.pose = self.est.pose
        if self._watched is not None:
            self._watch(self._watched)

    def act(self) -> JointTargets | None:
        """The joint targets of the next control period; None once the controller has stopped
        (:attr:`stopped` says why)."""
        if self.stopped is not None:
            return None
        try:
            return next(self._walk)
        except StopIteration:
            return None

    def step(self, m: Measurements) -> JointTargets | None:
        """:meth:`sense` then :meth:`act`: one control period."""
        self.sense(m)
        return self.act()

    def notes(self) -> list[Note]:
        """What happened since the last call: steps planned, lift-offs, reflex events, ..."""
        out, self._notes = self._notes, []
        return out

    @property
    def stance(self) -> np.ndarray:
        """Each leg's role (4,) bool: True stance."""
        return self.legs.stance

    @property
    def down(self) -> np.ndarray:
        """Where each stance foot's centre was put down (4, 3) [m]."""
        return self.legs.down

    # ------------------------------------------------------------------ a period
    def tick(self, position: np.ndarray, rpy: np.ndarray, swing: int | None
             ) -> Generator[JointTargets, None, None]:
        """One control period toward the desired body ``position`` (3,) [m] and ``rpy`` (3,)
        [rad], leg ``swing`` swinging (None: none); resumes with the next measurements."""
        targets = self.legs.set_points(position, rpy, self.est)
        self._watched, self.swing = rpy, swing
        yield targets

    def _watch(self, desired_rpy: np.ndarray) -> None:
        """Stance watch: raise the alarm of a slipping stance foot or a tipping trunk (one at
        a time, until a phase has acted on it)."""
        feet, legs = self.est.feet, self.legs
        speed = np.hypot(*(feet[:, :2] - self._feet_before[:, :2]).T) / self.period  # [m/s]
        self._feet_before = feet
        if self.alarm is not None:
            return
        leg = self.slip.watch(feet, speed, legs.targets, legs.stance & legs.settled, legs.forces)
        if leg is not None:
            self.alarm = ("slip", leg)
            legs.hold_yields = True
            self.event("stance slip", leg, moved_mm=round(
                1e3 * float(np.hypot(*(feet[leg, :2] - legs.down[leg, :2]))), 1))
            return
        error = self.tilt.watch(self.pose[1], desired_rpy, self.recovering)
        if error is not None:
            self.alarm = ("tilt", None)
            legs.hold_yields = True
            self.event("tilt", None, error_rad=round(error, 3))

    def touching_down(self, leg: int) -> bool:
        """Whether the foot force sensor of ``leg`` says the foot is down."""
        return bool(self.est.forces()[leg, 2] > self.config.touchdown_force)

    def event(self, kind: str, leg: int | None, **details) -> None:
        """A reflex acted: note it for the run log."""
        self._notes.append(ReflexEvent(self.est.time, kind, leg, details))

    # ------------------------------------------------------------------ the walk
    def _walking(self) -> Generator[JointTargets, None, None]:
        """Stand still the settle time, then step until the goal (or the step limit)."""
        for _ in range(max(1, round(self.config.settle_time / self.period))):
            yield from self.tick(*self.desired, None)
        self._notes.append(Settled(self.est.time))
        k = 0
        while True:
            if self.pose[0][0] >= self.goal_x:
                self.stopped = "goal"
                return
            if self.config.max_steps is not None and k >= self.config.max_steps:
                self.stopped = "step limit"
                return
            try:
                if (yield from self.step_phases(k)):
                    k += 1
            except _NoFoothold as stuck:
                self.stopped = str(stuck)
                return

    def step_phases(self, k: int) -> Steps:
        """Step ``k`` in its phases: plan, shift, swing, touch-down, touch-down check, load.

        The stance watch runs through all of them; an alarm calls the step off before lift-off,
        or brings the swing foot down at once after it, and the posture is recovered before the
        next step is planned. Returns whether the step was taken (False: plan it anew).
        """
        replacing = self.replace is not None
        leg = LEG_NAMES[self.replace] if replacing else self.robot.gait_order[self.gait % 4]
        s = LEG_NAMES.index(leg)
        tp = time.perf_counter()
        feet, plan = self._plan(leg)
        motion = self.body_motion(feet, s, plan)
        self._notes.append(StepPlanned(self.est.time, k, plan, motion.margin,
                                       time.perf_counter() - tp))
        t_begin = self.est.time
        i_lift = yield from shift(self, s, motion)
        if i_lift is None:  # called off before lift-off: the robot did not take this step
            self._notes.append(StepCalledOff(self.est.time, k))
            yield from recover(self)
            return False
        landed = i_lift == motion.times.size or (yield from swing(self, k, s, plan, motion,
                                                                  i_lift))
        if self.alarm is not None:
            found = yield from come_down(self, s)
        else:
            found = landed or (yield from touch_down(self, s, plan.foothold))
        yield from self.check.place(self, s, plan, found)
        self._load(k, s)
        if replacing:
            self.replace = None
        else:
            self.gait += 1
        if self.alarm is not None or self.held:
            yield from recover(self)
        else:
            elapsed = min(self.est.time - t_begin, float(motion.traj.touch_down[0]))
            self.cog = motion.traj.position(elapsed), motion.traj.velocity(elapsed)
            self.desired[0][:2] = self.cog[0]
        return True

    def _plan(self, leg: str) -> tuple[np.ndarray, FootstepPlan]:
        """The feet's contact points (4, 3) [m] where they stand now, and the plan of ``leg``'s
        step from there."""
        feet = self.est.feet - self.legs.lift
        state = RobotState(feet, *self.pose, leg, self.goal)
        try:
            return feet, self.planner.plan(state)
        except NoFootholdError:
            raise _NoFoothold(f"no foothold for {leg}") from None

    def body_motion(self, feet: np.ndarray, s: int, plan: FootstepPlan) -> BodyMotion:
        """The body motion of the step of leg ``s`` (:func:`footfall.control.step_motion.body_motion`)."""
        cfg = self.config
        return body_motion(self.hmap, feet, s, plan, self.cog, self.desired, self.period,
                           cfg.cog, cfg.pose, self.robot)

    def lift_off(self, k: int, s: int, above: np.ndarray, reach: float,
                 after_lift: np.ndarray) -> np.ndarray:
        """Lift foot ``s`` now for step ``k`` and plan its swing to ``above`` (3,) [m], reached
        ``reach`` [s] after lift-off; returns the foot-centre targets (m, 3) [m] at the control
        periods ``after_lift`` (m,) [s] after lift-off."""
        self._notes.append(LiftOff(self.est.time, k, s))
        path = self.swing_path(self.est.feet[s], above, reach, after_lift)
        self.legs.set_role(s, False, self.est.time)
        return path

    def swing_path(self, centre: np.ndarray, above: np.ndarray, reach: float,
                   after_lift: np.ndarray) -> np.ndarray:
        """Foot-centre targets (m, 3) [m] from ``centre`` (3,) to ``above`` (3,) [m] in ``reach``
        [s] over the terrain's hull, then on down at touchdown_speed, at ``after_lift`` (m,) [s]."""
        cfg, lift = self.config, self.legs.lift
        trajectory = swing_trajectory(self.hmap, centre - lift, above, reach, self.robot,
                                      cfg.swing)
        path = trajectory.position(after_lift) + lift
        path[:, 2] -= cfg.touchdown_speed * np.maximum(after_lift - reach, 0.0)
        return path

    def _load(self, k: int, s: int) -> None:
        """Foot ``s`` stands where it is for step ``k`` and starts to take its load."""
        centre = self.est.feet[s]
        self.legs.hand_over()
        self.legs.down[s] = centre
        self.legs.anchor_here(s, centre, self.est.q, self.pose[1])
        self.legs.set_role(s, True, self.est.time)
        self._notes.append(TouchDown(self.est.time, k, s))
