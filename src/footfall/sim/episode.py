"""A walking run: the simulator, the controller and the task, stepped together.

In the shape of dm_control's composer: the *controller*
(:class:`footfall.control.controller.Controller`) is what runs on the robot --
it reads the robot's measurements and answers joint targets, and never sees
the simulator; the *task* (:class:`footfall.sim.task.WalkTask`) is the referee
-- it reads the simulator's truth, decides how the run ends and keeps the run
log; the *simulator* (:class:`footfall.sim.simulation.Simulation`) is the robot
on the board. This module only steps them, one control period (100 Hz) at a
time: targets from the controller to the servos, the physics stepped at the
servo rate, the measurements read back and passed to the controller, the
task's judgement. :class:`WalkConfig` holds every setting of a run.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from footfall.control.body_path import BodyPathConfig
from footfall.control.cog import CogConfig
from footfall.control.controller import Controller, footstep_planner
from footfall.control.footstep import FootstepConfig
from footfall.control.lowlevel import LowLevelConfig
from footfall.control.measurements import JointTargets, Measurements
from footfall.control.pose_finder import PoseConfig
from footfall.control.reflexes import ReflexConfig
from footfall.control.swing import SwingConfig
from footfall.core.errors import FootfallError
from footfall.core.files import plain_json
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, at_least, param, within
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.core.state import RobotState, nominal_state
from footfall.data.runlog import RunRecord
from footfall.expert.synthetic import WALKER_PLACEMENT_ERROR
from footfall.features.scorer import FootholdScorer, RewardFor
from footfall.sim.frames import SNAPSHOT_PERIOD, FrameRecorder, Frames
from footfall.sim.simulation import PerturbationConfig, Simulation
from footfall.sim.task import MAX_EVENTS, WALL_CLOCK_FIELDS, WalkTask, board_line, foot_slip

__all__ = ["MAX_EVENTS", "SNAPSHOT_PERIOD", "WALL_CLOCK_FIELDS", "Frames", "Walk", "WalkConfig",
           "board_line", "foot_slip", "walk"]



# The walk's limits take inf for "none" (a time_limit of inf: the run ends at the goal or a fall).
_POSITIVE_OR_INF = within(0, math.inf, low_open=True)
_NONNEGATIVE_OR_INF = within(0, math.inf)


SEEN_FOOTING = LITTLEDOG.foot_radius + WALKER_PLACEMENT_ERROR  # [m] the walk's seen footing:
# a foothold this near a place where the ball has no map data under it leaves F, so that a ball
# landing the walking expert's placement error off its aim stands wholly over seen ground
# (docs/terrain-suite.md, "A training kind with holes"; adopted by round 7 of the ablation)


# A walk's own planner and COG settings (docs/configuration.md gives the runs behind them).
def _walk_footstep() -> FootstepConfig:
    return FootstepConfig(bias_weight=60.0, step_advance=0.025, leg_clearance=0.005,
                          seen_footing=SEEN_FOOTING)


def _walk_cog() -> CogConfig:
    return CogConfig(swing_duration=0.4, centring=100.0, slowdown=4.0, reach=0.08)


@dataclass(frozen=True)
class WalkConfig(Params):
    """Every setting of a walking run; written next to its result (docs/configuration.md)."""

    footstep: FootstepConfig = param(factory=_walk_footstep,
                                     doc="the footstep planner (path bias, stride)")
    cog: CogConfig = param(factory=_walk_cog,
                           doc="the COG planner (swing and shift timing, the legs' reach)")
    swing: SwingConfig = param(factory=SwingConfig, doc="the swing-foot trajectory")
    pose: PoseConfig = param(factory=PoseConfig, doc="the pose finder")
    lowlevel: LowLevelConfig = param(factory=LowLevelConfig, doc="the 100 Hz closed loop")
    reflexes: ReflexConfig = param(factory=ReflexConfig,
                                   doc="the reflexes: lift-off gate, slip, touch-down check, tilt")
    path: BodyPathConfig = param(factory=BodyPathConfig,
                                 doc="the body path planner (used with plan_path)")
    perturbation: PerturbationConfig = param(factory=PerturbationConfig,
                                             doc="how much runs differ from one another")
    plan_path: bool = param(False, doc="plan the body path by Dijkstra; False: the fixed "
                                       "straight path along the board's axis (as the paper)")
    start_setback: float = param(0.35, unit="m",
                                 doc="body start this far before the end of the first module")
    goal_margin: float = param(0.02, unit="m", range=_NONNEGATIVE_OR_INF,
                               doc="goal line: hind hips this far past the last non-final module")
    settle_time: float = param(0.3, unit="s", range=_NONNEGATIVE_OR_INF,
                               doc="standing still before the first step")
    touchdown_force: float = param(2.0, unit="N", range=_POSITIVE_OR_INF,
                                   doc="vertical foot force that means the foot is down")
    touchdown_early: float = param(0.7, unit="-", range=within(0, 1),
                                   doc="share of the swing (to above the foothold) after which "
                                       "a contact ends it early")
    touchdown_reach: float = param(0.015, unit="m", range=_POSITIVE_OR_INF,
                                   doc="a contact counts as touch-down only this close to the "
                                       "foothold horizontally")
    touchdown_approach: float = param(0.008, unit="m", range=_NONNEGATIVE_OR_INF,
                                      doc="the swing ends this far above the foothold; the foot "
                                          "comes down the rest of the way at touchdown_speed")
    touchdown_search: float = param(0.02, unit="m", range=_NONNEGATIVE_OR_INF,
                                    doc="how far below the planned foothold the foot keeps "
                                        "looking")
    touchdown_speed: float = param(0.1, unit="m/s", range=_POSITIVE_OR_INF,
                                   doc="how fast the foot goes down while looking")
    fall_tilt: float = param(0.6, unit="rad", range=_POSITIVE_OR_INF,
                             doc="trunk roll or pitch beyond this is a fall")
    stuck_time: float = param(10.0, unit="s", range=_POSITIVE_OR_INF,
                              doc="a robot that advanced less than stuck_progress in this long "
                                  "is stuck")
    stuck_progress: float = param(0.02, unit="m",
                                  doc="forward progress in stuck_time that counts as moving")
    time_limit: float = param(240.0, unit="s", range=_POSITIVE_OR_INF,
                              doc="longest run, in simulated time")
    trace_window: float = param(10.0, unit="s", range=_POSITIVE_OR_INF,
                                doc="the flight recorder keeps this much of the run's end, at "
                                    "the control rate (footfall walk --explain); inf: the "
                                    "whole run")
    max_steps: int | None = param(None, unit="steps", range=at_least(1),
                                  doc="stop (reason \"step limit\", no success) after this many "
                                      "steps; None: no limit (short test runs)")


class Walk:
    """One run of the simulated robot over a board (use :func:`walk`).

    Built from the board, the reward (or a judge) and the seed: the goal line,
    the controller with its footstep planner, the simulator with this seed's
    perturbation, and the task. :attr:`controller_class` is the controller a
    run drives (a test stages a scene with its own).
    """

    controller_class: type[Controller] = Controller

    def __init__(self, hmap: HeightMap, reward_for: RewardFor, seed: int,
                 config: WalkConfig = WalkConfig(), robot: RobotDescription = LITTLEDOG,
                 frames: Frames | None = None, judge: FootholdScorer | None = None) -> None:
        if not isinstance(hmap, HeightMap):
            raise FootfallError(f"a walk needs a HeightMap, got {type(hmap).__name__}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise FootfallError(f"seed must be a non-negative integer, got {seed!r}")
        self.hmap, self.reward_for, self.seed = hmap, reward_for, int(seed)
        self.config, self.robot, self.judge = config, robot, judge
        t0 = time.perf_counter()
        self.start_xy, self.goal_x = board_line(hmap, robot, config)
        self.goal = np.array([self.goal_x + 0.3, self.start_xy[1]])  # [m] the body path's end
        self.judge_name = None if judge is None else judge.name
        planner = footstep_planner(hmap, reward_for, self.start_xy, self.goal, config, robot,
                                   judge)
        self.controller = self.controller_class(hmap, planner, self.goal, self.goal_x, config,
                                                robot)
        self.sim = Simulation.from_seed(robot, hmap, self.seed, config.perturbation)
        self.setup_seconds = time.perf_counter() - t0
        period = config.lowlevel.period
        self.ticks = round(period / self.sim.timestep)  # servo periods per control period
        if self.ticks < 1 or abs(self.ticks * self.sim.timestep - period) > 1e-9:
            raise FootfallError("the control period must be a whole number of servo periods")
        self.task = WalkTask(self.goal_x, config, robot, period)
        self.trace = self.task.trace  # the flight recorder (footfall walk --explain)
        self.frames = FrameRecorder(frames)

    def run(self) -> RunRecord:
        """Walk until the goal or a failure; return the run log with its result."""
        # A run is one core's work on small matrices: BLAS threads would only spin beside it
        # (and steal the cores that walk-many's parallel runs need).
        with threadpool_limits(limits=1):
            return self._run()

    def start_state(self) -> RobotState:
        """Where the run starts: the robot standing on its nominal footholds at the board's start."""
        return nominal_state(self.hmap, self.start_xy, 0.0, self.robot.gait_order[0],
                             goal=self.goal, robot=self.robot)

    def _run(self) -> RunRecord:
        wall0 = time.perf_counter()
        state0 = self.start_state()
        self.sim.stand(state0.body_position, state0.body_rpy, state0.feet)
        self.controller.start(self._measure(), state0.feet)
        self.task.start(self.sim)
        return self._periods(wall0)

    def _periods(self, wall0: float) -> RunRecord:
        """The control periods from here to the run's end (``wall0`` [s]: when it began, by
        ``time.perf_counter``); the run log."""
        sim, controller, task = self.sim, self.controller, self.task
        while True:
            targets = controller.act()
            task.review(controller.notes(), sim)
            if targets is None:  # the controller stopped stepping (at the goal, or not)
                task.stopped(controller.stopped, sim)
                break
            self._actuate(targets)
            sim.step(self.ticks)
            self.frames.capture(sim)
            controller.sense(self._measure())
            task.review(controller.notes(), sim)
            if task.judge(sim, controller.stance, controller.down, controller.swing):
                break
        self.frames.finish()
        record = task.record(sim, self.hmap, self.seed, self._settings(), wall0,
                             self.setup_seconds)
        sim.close()
        return record

    def _measure(self) -> Measurements:
        """What the robot's sensors read now."""
        sim = self.sim
        position, rpy = sim.body_pose()
        return Measurements(sim.time, sim.joint_angles(), position, rpy,
                            sim.foot_forces(frame="sensor"))

    def _actuate(self, targets: JointTargets) -> None:
        """The controller's set-points to the servos, held until the next control period."""
        self.sim.set_targets(targets.q, targets.qd, targets.torque)

    def _settings(self) -> dict:
        """The run's settings as the run log keeps them (JSON)."""
        settings = {"walk": plain_json(self.config.to_dict(), nonfinite="null"),
                    "perturbation": self.sim.perturbation.to_dict(), "robot": self.robot.name,
                    # which reward ranked the footholds (e.g. "hand-tuned default",
                    # "both/l1/front" and "both/l1/hind"), as a person reviewing the run sees it
                    "reward": sorted({str(getattr(self.reward_for(leg), "name", "reward"))
                                      for leg in LEG_NAMES})}
        if self.judge_name is not None:  # the footholds were chosen by a judge, not a reward
            settings["judge"] = self.judge_name
        return settings


def walk(hmap: HeightMap, reward_for: RewardFor, seed: int, config: WalkConfig = WalkConfig(),
         robot: RobotDescription = LITTLEDOG, frames: Frames | None = None,
         judge: FootholdScorer | None = None) -> RunRecord:
    """One seeded run over ``hmap`` with the reward ``reward_for(leg)``; the same seed, the same run.

    With ``judge`` (e.g. ``ExpertScorer(SyntheticExpert(...))``), the judge chooses
    the footholds instead of the reward (:class:`JudgedFootstepPlanner`);
    ``reward_for`` then only plans the body path if ``config.plan_path``.
    """
    return Walk(hmap, reward_for, seed, config, robot, frames, judge).run()
