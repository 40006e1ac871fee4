"""A walking run: the simulated robot crosses a board with the paper's control stack (§IV-B).

The hierarchy, top to bottom, each stage in its own module:

1. body path (:mod:`footfall.control.body_path`) -- fixed and straight by
   default, as in the paper's evaluation; planned by Dijkstra on request;
2. footstep planner (:mod:`footfall.control.footstep`) -- the foothold of
   the swing leg by the reward function, with a five-step look-ahead;
3. pose finder (:mod:`footfall.control.pose_finder`) -- body height, roll,
   pitch and yaw for the stance after touch-down;
4. COG trajectory (:mod:`footfall.control.cog`) -- through the support
   triangles of the next steps, the ZMP kept inside with a margin;
5. swing trajectory (:mod:`footfall.control.swing`) -- over the convex hull
   of the terrain;
6. low-level control (:mod:`footfall.control.lowlevel`) -- inverse
   kinematics at 100 Hz, closed on the true body pose, with each stance
   foot's height set by its force sensor so that it carries its share of
   the weight and the torques that carry that share fed forward to its
   servos (:mod:`footfall.control.load`), and the simulator's 400 Hz PD
   servo.

A step goes through its phases (:meth:`Walk._step`): *plan* (foothold, COG
trajectory, pose; a receding horizon, five steps planned and one executed,
from the feet where they actually stand), *shift* (four feet down, the body
moving into the swing's triangle), *swing* (the foot to a point
``touchdown_approach`` above its foothold), *touch-down* (down the rest of
the way slowly until its force sensor feels the ground; a contact on the
way counts only near the end of the swing and close to the foothold) and
*load transfer* (over ``LowLevelConfig.transfer_time``). Through all of
them a *stance watch* reads the measured state every control period, and
the reflexes of :mod:`footfall.control.reflexes` act on what it sees (each
a switch of ``WalkConfig.reflexes``, each action an event in the run log):
the lift-off gate, the touch-down check, the tilt reflex and the stance slip
reflex. A flight recorder (:mod:`footfall.sim.trace`) keeps the last
seconds at the control rate; a failed run's result holds its account of the
end (:func:`footfall.sim.explain.explain_run`). A run ends at the goal line, or in failure: a fall (trunk
roll or pitch beyond ``fall_tilt``, or the trunk touching the terrain), a
stuck robot (no swing leg candidate, or less than ``stuck_progress`` of
forward progress in ``stuck_time``), or the time limit. Every step goes
into the run log (:mod:`footfall.data.runlog`), with the slip of its foot
(:func:`foot_slip`) once the foot lifts off again.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from footfall.control.body_path import BodyPath, BodyPathConfig, plan_body_path
from footfall.control.cog import CogConfig, CogTrajectory, plan_cog, support_margin
from footfall.control.footstep import (
    FootstepConfig,
    FootstepPlan,
    FootstepPlanner,
    JudgedFootstepPlanner,
    NoFootholdError,
)
from footfall.control.load import load_offsets, load_shares, support_torques
from footfall.control.lowlevel import (
    BodyCorrection,
    LowLevelConfig,
    body_rotation,
    handed_over,
    joint_targets,
    reanchor,
    rolled,
    shin_rotations,
    transfer_weight,
)
from footfall.control.pose_finder import PoseConfig, find_pose
from footfall.control.reflexes import (
    ReflexConfig,
    com_in_triangle,
    gate_step,
    next_best_candidate,
    slipped,
    tilt_error,
)
from footfall.control.swing import SwingConfig, swing_trajectory
from footfall.core.errors import FootfallError
from footfall.core.files import plain_json
from footfall.core.heightmap import HeightMap, module_records
from footfall.core.params import Params, at_least, param, within
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.core.state import RobotState, nominal_state
from footfall.data.runlog import RunRecord, RunStep
from footfall.features.scorer import FootholdScorer, RewardFor
from footfall.sim.explain import explain_run
from footfall.sim.simulation import PerturbationConfig, Simulation
from footfall.sim.trace import RunTrace, trace_row

_OTHER_LEGS = np.array([[j for j in range(4) if j != k] for k in range(4)])  # stance legs while
# leg k swings, in order (an index array: np.delete's overhead counts at 100 Hz)
SNAPSHOT_PERIOD = 0.5  # [s] of simulated time between candidate snapshot frames
MAX_EVENTS = 200  # reflex events kept in a run's result (every one is counted)
DROP_SPEED = 0.3  # [m/s] a swing foot brought down by a reflex drops this fast to near the ground
REPLACE_TIME = 0.25  # [s] a re-placed foot's swing to above its new foothold
WALL_CLOCK_FIELDS = ("planning_ms_per_step", "wall_seconds", "setup_seconds", "real_time_factor")
# result fields that measure the computer, not the run (they differ between identical runs)


# The walk's limits take inf for "none" (a time_limit of inf: the run ends at the goal or a fall).
_POSITIVE_OR_INF = within(0, math.inf, low_open=True)
_NONNEGATIVE_OR_INF = within(0, math.inf)


# A walk's own planner and COG settings (docs/configuration.md gives the runs behind them).
def _walk_footstep() -> FootstepConfig:
    return FootstepConfig(bias_weight=60.0, step_advance=0.025)


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
    trace_window: float = param(5.0, unit="s", range=_POSITIVE_OR_INF,
                                doc="the flight recorder keeps this much of the run's end, at "
                                    "the control rate (footfall walk --explain)")
    max_steps: int | None = param(None, unit="steps", range=at_least(1),
                                  doc="stop (reason \"step limit\", no success) after this many "
                                      "steps; None: no limit (short test runs)")


@dataclass
class Frames:
    """Requests for pictures of a run: snapshot times and a video frame rate."""

    snapshot_count: int = 0  # frames evenly spaced over the run (0: none)
    video_fps: float = 0.0  # [1/s] video frame rate (0: no video)
    width: int = 480
    height: int = 360
    snapshots: list = field(default_factory=list)  # filled: (time [s], image (h, w, 3) uint8)
    video: list = field(default_factory=list)  # filled: images (h, w, 3) uint8


def foot_slip(touchdown: np.ndarray, liftoff: np.ndarray) -> np.ndarray:
    """Slip [m] of stance feet: how far each ball-foot centre moved while it stood.

    The paper's measure (Table II): the distance between the foot's position
    when it touched down and when it lifted off again -- sliding, and the
    ball rolling, alike.

    Parameters
    ----------
    touchdown, liftoff : array of shape (..., 3)
        World positions [m] of the ball-foot centre at touch-down and at the
        next lift-off of the same foot.

    Returns
    -------
    ndarray of shape (...)
        Euclidean distance [m].
    """
    a = np.asarray(touchdown, dtype=np.float64)
    b = np.asarray(liftoff, dtype=np.float64)
    if a.shape[-1:] != (3,) or b.shape[-1:] != (3,):
        raise FootfallError(f"foot_slip needs positions (..., 3), got {a.shape} and {b.shape}")
    return np.linalg.norm(b - a, axis=-1)


def board_line(hmap: HeightMap, robot: RobotDescription, config: WalkConfig
               ) -> tuple[np.ndarray, float]:
    """Start body position (2,) [m] and goal line x [m] of a board.

    The robot starts on the first module ``start_setback`` before its end; the
    goal is reached when the hind hips are ``goal_margin`` past the start of
    the last module (a board from :func:`footfall.terrain.make_board` ends
    with a flat module). A map without module records is treated as one
    module spanning the whole map.
    """
    x0, x1, y0, y1 = hmap.bounds
    modules = module_records(hmap.metadata)
    if len(modules) >= 2:
        first_end = x0 + float(modules[0]["x_end"]) - float(modules[0]["x_start"])
        last_start = x0 + float(modules[-1]["x_start"])
    else:
        first_end, last_start = x0 + 0.5 * (x1 - x0), x1 - 2 * robot.hip_x - 0.1
    start = np.array([first_end - config.start_setback, 0.5 * (y0 + y1)])
    goal = last_start + robot.hip_x + config.goal_margin
    if not start[0] - robot.hip_x - 0.05 > x0 or not goal > start[0]:
        raise FootfallError("the terrain is too short for a walking run")
    return start, goal


class _Failure(Exception):
    """A run ends in failure (the message is the reason)."""


class Walk:
    """One run of the simulated robot over a board (use :func:`walk`)."""

    def __init__(self, hmap: HeightMap, reward_for: RewardFor, seed: int,
                 config: WalkConfig = WalkConfig(), robot: RobotDescription = LITTLEDOG,
                 frames: Frames | None = None, judge: FootholdScorer | None = None) -> None:
        if not isinstance(hmap, HeightMap):
            raise FootfallError(f"a walk needs a HeightMap, got {type(hmap).__name__}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise FootfallError(f"seed must be a non-negative integer, got {seed!r}")
        self.hmap, self.reward_for, self.seed = hmap, reward_for, int(seed)
        self.config, self.robot, self.frames = config, robot, frames
        t0 = time.perf_counter()
        self.start_xy, self.goal_x = board_line(hmap, robot, config)
        goal_xy = np.array([self.goal_x + 0.3, self.start_xy[1]])
        if config.plan_path:
            self.path = plan_body_path(hmap, reward_for, self.start_xy, goal_xy, robot,
                                       config.path)
        else:
            self.path = BodyPath.straight(self.start_xy, goal_xy)
        self.judge_name = None if judge is None else judge.name
        self.planner = (FootstepPlanner(hmap, reward_for, self.path, robot, config.footstep)
                        if judge is None else
                        JudgedFootstepPlanner(hmap, judge, self.path, robot, config.footstep))
        self.sim = Simulation.from_seed(robot, hmap, self.seed, config.perturbation)
        self.setup_seconds = time.perf_counter() - t0
        self.goal = goal_xy
        self.period = config.lowlevel.period
        follow = config.lowlevel.anchor_follow_time  # [s] or None (slipped feet held)
        self._follow_rate = 0.0 if follow is None else 1.0 - math.exp(-self.period / follow)
        self.ticks = round(self.period / self.sim.timestep)
        if self.ticks < 1 or abs(self.ticks * self.sim.timestep - self.period) > 1e-9:
            raise FootfallError("the control period must be a whole number of servo periods")
        self._lift = np.array([0.0, 0.0, robot.foot_radius])  # contact point -> ball centre
        self._weight = robot.total_mass * -float(self.sim.model.opt.gravity[2])  # [N]
        self.trace = RunTrace(config.trace_window, self.period)  # the last seconds, at 100 Hz

    # ------------------------------------------------------------ the 100 Hz loop
    def _capture(self) -> None:
        f = self.frames
        if f is None:
            return
        t = self.sim.time
        if f.video_fps > 0 and t + 1e-9 >= len(f.video) / f.video_fps:
            f.video.append(self.sim.render(width=f.width, height=f.height))
        if f.snapshot_count > 0 and t + 1e-9 >= len(self._all_frames) * SNAPSHOT_PERIOD:
            self._all_frames.append((t, self.sim.render(width=f.width, height=f.height)))

    def _set_role(self, leg: int, stance: bool) -> None:
        """Leg ``leg`` starts passing its load on (stance) or off (swing) now."""
        self._stance[leg] = stance
        self._since[leg] = self.sim.time
        self._unload[leg] = 1.0

    def _tick(self, position: np.ndarray, rpy: np.ndarray, swing: int | None) -> None:
        """One control period toward the desired body pose; raises _Failure on a fall or stall.

        The flight recorder keeps the period; the stance watch (:meth:`_watch`) may raise an
        alarm for the phase to act on; while a leg swings, the measured centre of mass and the
        stance feet are logged for the stability margin.
        """
        cfg, sim = self.config, self.sim
        mpos, mrpy = self._pose
        cpos, crpy = self._correction.update(position, rpy, mpos, mrpy)
        rot = body_rotation(crpy), body_rotation(mrpy)  # commanded, measured
        ramp = transfer_weight(sim.time - self._since, cfg.lowlevel.transfer_time)
        weight = np.where(self._stance, ramp, 1.0 - ramp)
        # Stance feet: where they touched down, moved on as far as their balls have rolled since.
        stance = self._stance
        forces = (sim.foot_forces()[:, 2]  # [N] the force sensors' vertical readings
                  if cfg.lowlevel.load_gain > 0 or self._follow_rate > 0 or cfg.reflexes.slip_reflex
                  else None)
        if self._follow_rate > 0:  # slipped feet re-anchored where they stand
            # (a foot that carries nothing, being unloaded or just set down, is not let go of:
            # its gap is the body dragging it, not a slip)
            loaded = stance & (ramp >= 1.0) & (self._unload >= 1.0) & (
                forces > cfg.touchdown_force)
            self._anchor, shift = reanchor(self._anchor, self._targets, self._feet_before,
                                           loaded, stance, self._follow_rate)
            self._correction.shift(shift)
        self._targets[stance] = self._anchor[stance] + rolled(
            self._shin0[stance], shin_rotations(sim.joint_angles(), rot[1])[stance],
            self.robot.foot_radius)
        torque = None
        if cfg.lowlevel.load_gain > 0 or cfg.lowlevel.support_feedforward > 0:
            shares = load_shares(self._feet_before[:, :2], self._com_before,
                                 np.where(stance, ramp, 0.0) * self._unload)
        if cfg.lowlevel.load_gain > 0:  # each stance foot carries its share (its force sensor)
            self._press = load_offsets(self._press, forces, shares, stance,
                                       cfg.lowlevel.load_gain * self.period,
                                       cfg.lowlevel.load_limit)
            self._targets[:, 2] += self._press
        if cfg.lowlevel.support_feedforward > 0:  # the servos are given the torques that carry it
            torque = support_torques(sim.foot_jacobians(),
                                     cfg.lowlevel.support_feedforward * self._weight * shares)
        q, _ = joint_targets(self.robot, self._targets, (cpos, rot[0]), (mpos, rot[1]), weight,
                             self._q)
        sim.set_targets(q, (q - self._q) / self.period, torque)
        self._q = q
        sim.step(self.ticks)
        self._capture()
        self._pose = mpos, mrpy = sim.body_pose()
        com, feet = sim.centre_of_mass(), sim.foot_positions()
        self._com_before = com[:2]
        self.trace.record(trace_row(sim.time, mpos, mrpy, com, feet, sim.foot_forces(noise=False),
                                    stance, self._down, sim.joint_angles(), sim.joint_torques(),
                                    swing))
        if swing is not None:
            self._com.append(com[:2])
            self._support.append(feet[_OTHER_LEGS[swing], :2])
        self._watch(feet, ramp >= 1.0, mrpy, rpy, forces)
        if abs(mrpy[0]) > cfg.fall_tilt or abs(mrpy[1]) > cfg.fall_tilt:
            raise _Failure("fall: trunk tilted")
        if sim.trunk_touches_terrain():
            raise _Failure("fall: trunk touched the terrain")
        if mpos[0] > self._best_x + cfg.stuck_progress:
            self._best_x, self._best_t = mpos[0], sim.time
        elif sim.time - self._best_t > cfg.stuck_time:
            raise _Failure("stuck: no progress")
        if sim.time > cfg.time_limit:
            raise _Failure("time limit")

    def _watch(self, feet: np.ndarray, settled: np.ndarray, measured_rpy: np.ndarray,
               desired_rpy: np.ndarray, forces: np.ndarray | None) -> None:
        """Stance watch: raise the alarm of a slipping stance foot or a tipping trunk.

        ``feet`` (4, 3) [m] are the measured foot centres, ``forces`` (4,) [N] the force sensors'
        vertical readings (read whenever the slip reflex is on), ``settled`` (4,) the legs whose role
        change is complete; one alarm at a time, until the phase has acted on it.
        """
        rc = self.config.reflexes
        speed = np.hypot(*(feet[:, :2] - self._feet_before[:, :2]).T) / self.period  # [m/s]
        self._feet_before = feet
        if self._alarm is not None:
            return
        if rc.slip_reflex:
            loaded = self._stance & settled & (forces > self.config.touchdown_force)
            bad = slipped(feet[:, :2], self._targets[:, :2], loaded,
                          rc.slip_distance) & (speed > rc.slip_speed)
            if bad.any():
                leg = int(np.flatnonzero(bad)[0])
                self._alarm = ("slip", leg)
                self._event("stance slip", leg, moved_mm=round(
                    1e3 * float(np.hypot(*(feet[leg, :2] - self._down[leg, :2]))), 1))
                return
        error = tilt_error(measured_rpy, desired_rpy) if rc.tilt_reflex else 0.0
        if error > rc.tilt_threshold and not self._recovering:
            self._alarm = ("tilt", None)
            self._event("tilt", None, error_rad=round(error, 3))

    def _event(self, kind: str, leg: int | None, **details) -> None:
        """Log a reflex's action in the run log (kept in the result's ``events``)."""
        self._reflex_counts[kind] = self._reflex_counts.get(kind, 0) + 1
        if len(self._events) < MAX_EVENTS:
            self._events.append({"t": round(self.sim.time, 3), "event": kind,
                                 "leg": None if leg is None else LEG_NAMES[leg], **details})

    def _touching_down(self, leg: int) -> bool:
        """Whether the foot force sensor of ``leg`` says the foot is down."""
        return bool(self.sim.foot_forces()[leg, 2] > self.config.touchdown_force)

    # --------------------------------------------------------------- one step
    def _step(self, k: int) -> bool:
        """Step ``k`` in its phases: plan, shift, swing, touch-down, load transfer.

        The stance watch runs through all of them; an alarm calls the step off before lift-off,
        or brings the swing foot down at once after it, and the posture is recovered before the
        next step is planned. Returns whether the step was taken (False: plan it anew).
        """
        replacing = self._replace is not None
        leg = LEG_NAMES[self._replace] if replacing else self.robot.gait_order[self._gait % 4]
        s = LEG_NAMES.index(leg)
        tp = time.perf_counter()
        feet, plan, record = self._plan(k, leg)
        traj, times, positions, attitudes = self._body_motion(feet, s, plan)
        self._plan_seconds.append(time.perf_counter() - tp)
        t_begin = self.sim.time
        i_lift = self._shift(s, traj, times, positions, attitudes)
        if i_lift is None:  # called off before lift-off: the robot did not take this step
            self._steps.pop()
            self._recover()
            return False
        landed = i_lift == times.size or self._swing(
            s, plan, traj, times[i_lift:], positions[i_lift:], attitudes[i_lift:], record)
        if self._alarm is not None:
            found = self._come_down(s)
        else:
            found = landed or self._touch_down(s, plan.foothold)
        self._place(k, s, plan, found, record)
        if replacing:
            self._replace = None
        else:
            self._gait += 1
        if self._alarm is not None or self._held:
            self._recover()
        else:
            elapsed = min(self.sim.time - t_begin, float(traj.touch_down[0]))
            self._cog = traj.position(elapsed), traj.velocity(elapsed)
            self._desired[0][:2] = self._cog[0]
        return True

    def _plan(self, k: int, leg: str) -> tuple[np.ndarray, FootstepPlan, dict]:
        """Plan step ``k`` of ``leg`` from the feet where they stand now, and log it.

        Returns the feet's contact points (4, 3) [m], the plan and the step's log record.
        """
        feet = self.sim.foot_positions() - self._lift  # where the feet stand now: contact points
        state = RobotState(feet, *self._pose, leg, self.goal)
        record = {"k": k, "plan": None, "t_liftoff": math.nan,
                  "t_touchdown": math.nan, "touchdown": np.full(3, np.nan), "slip": math.nan}
        try:
            plan = self.planner.plan(state)
        except NoFootholdError:
            raise _Failure(f"stuck: no foothold for {leg}") from None
        record["plan"] = plan
        self._steps.append(record)
        return feet, plan, record

    def _body_motion(self, feet: np.ndarray, s: int, plan: FootstepPlan
                     ) -> tuple[CogTrajectory, np.ndarray, np.ndarray, np.ndarray]:
        """The COG trajectory of the step, and the desired body pose at every control period of it.

        Returns the trajectory, the times (n,) [s] from the start of the shift, and the body
        positions (n, 3) [m] and attitudes (n, 3) [rad] at those times.
        """
        cfg, robot = self.config, self.robot
        traj = plan_cog(feet, plan.steps, self._cog[0], self._cog[1], cfg.cog, robot)
        after = feet.copy()
        after[s] = plan.foothold
        pose = find_pose(self.hmap, after, traj.waypoints[0, 1], float(plan.body_yaw[0]),
                         robot, cfg.pose)
        t_lift, t_down = float(traj.lift_off[0]), float(traj.touch_down[0])
        self._planned.append(float(np.min(support_margin(
            traj.triangles[0], traj.position(np.linspace(t_lift, t_down, 20))))))
        # The desired body pose at every control period of the step, at once.
        n = max(1, round(t_down / self.period))
        times = np.minimum(np.arange(1, n + 1) * self.period, t_down)
        u = transfer_weight(times, t_down)[:, None]  # smoothstep from this pose to the next
        z0, rpy0 = self._desired[0][2], self._desired[1]
        rpy1 = np.array(pose.rpy)
        rpy1[2] = rpy0[2] + ((rpy1[2] - rpy0[2] + np.pi) % (2 * np.pi) - np.pi)
        positions = np.column_stack([traj.position(times), z0 + (pose.height - z0) * u[:, 0]])
        attitudes = rpy0 + (rpy1 - rpy0) * u
        return traj, times, positions, attitudes

    def _shift(self, s: int, traj: CogTrajectory, times: np.ndarray, positions: np.ndarray,
               attitudes: np.ndarray) -> int | None:
        """Shift phase: all four feet down, the body moving into the swing's triangle.

        Returns the index into ``times`` of the first swing period (``times.size``: the step is
        too short to lift the foot), or None if the step is called off (an alarm, or the
        lift-off gate's timeout).
        """
        t_lift = float(traj.lift_off[0])
        unload = self.config.lowlevel.unload_time
        self._held = False
        for i in range(times.size):
            if times[i] > t_lift:
                return i if self._gate(s) else None
            if unload > 0:  # the swing leg passes its load on to the others before it lifts
                self._unload[s] = 1.0 - float(transfer_weight(times[i] - (t_lift - unload),
                                                              unload))
            self._desired = positions[i].copy(), attitudes[i].copy()
            self._tick(*self._desired, None)
            if self._alarm is not None:
                return None
        return times.size

    def _gate(self, s: int) -> bool:
        """Lift-off gate: wait, moving the body, until the centre of mass is inside the triangle.

        Returns whether leg ``s`` may lift (False: the wait timed out or an alarm came). After a
        wait the body holds its place through the swing (``_held``).
        """
        rc, sim = self.config.reflexes, self.sim
        if not rc.lift_off_gate:
            return True
        t0 = sim.time
        while True:
            com, tri = sim.centre_of_mass()[:2], sim.foot_positions()[_OTHER_LEGS[s], :2]
            if com_in_triangle(com, tri, rc.gate_margin):
                if self._held:
                    self._event("lift-off gate", s, waited_s=round(sim.time - t0, 3))
                return True
            if sim.time - t0 >= rc.gate_timeout:
                self._event("lift-off gate timeout", s,
                            margin_mm=round(1e3 * float(support_margin(tri, com)), 1))
                return False
            self._held = True
            self._desired[0][:2] = gate_step(com, self._desired[0][:2], tri, rc.gate_speed,
                                             self.period)
            self._tick(*self._desired, None)
            if self._alarm is not None:
                return False

    def _swing(self, s: int, plan: FootstepPlan, traj: CogTrajectory, times: np.ndarray,
               positions: np.ndarray, attitudes: np.ndarray, record: dict) -> bool:
        """Swing leg ``s`` along its trajectory, a control period at a time, from lift-off.

        Returns whether the foot is down: it touched down near the end of the swing, close to
        the foothold. Returns False at once on an alarm (the caller brings the foot down).
        """
        cfg, sim = self.config, self.sim
        t_lift, t_down = float(traj.lift_off[0]), float(traj.touch_down[0])
        swing_time = t_down - t_lift
        # The foot swings to a point `approach` above the foothold and comes down the rest of the
        # way slowly, so that a terrain a little higher or lower than the map meets it gently.
        descent = min(cfg.touchdown_approach / cfg.touchdown_speed, 0.5 * swing_time)
        reach = swing_time - descent  # [s] after lift-off: above the foothold
        above = plan.foothold + [0.0, 0.0, descent * cfg.touchdown_speed]
        path = self._lift_off(s, above, reach, times - t_lift, record)
        hold = self._desired[0][:2].copy() if self._held else None
        for i in range(times.size):  # control periods, each a simulated tick
            self._targets[s] = path[i]
            position = positions[i].copy()
            if hold is not None:  # after a wait at the gate, the body stays where it waited
                position[:2] = hold
            self._desired = position, attitudes[i].copy()
            self._tick(*self._desired, s)
            if self._alarm is not None:
                return False
            if times[i] - t_lift > cfg.touchdown_early * reach and self._touching_down(s) \
                    and np.hypot(*(sim.foot_positions()[s, :2] - above[:2])) < cfg.touchdown_reach:
                return True
        return False

    def _lift_off(self, s: int, above: np.ndarray, reach: float, after_lift: np.ndarray,
                  record: dict) -> np.ndarray:
        """Lift foot ``s`` now: log the slip of its last stance and plan its swing to ``above``
        (3,) [m], reached ``reach`` [s] after lift-off; returns the foot-centre targets (m, 3)
        [m] at the control periods ``after_lift`` (m,) [s] after lift-off."""
        sim = self.sim
        centre = sim.foot_positions()[s]
        if s in self._stood:
            j, down = self._stood.pop(s)
            self._steps[j]["slip"] = float(foot_slip(down, centre))
        record["t_liftoff"] = sim.time
        path = self._swing_path(centre, above, reach, after_lift)
        self._set_role(s, stance=False)
        return path

    def _swing_path(self, centre: np.ndarray, above: np.ndarray, reach: float,
                    after_lift: np.ndarray) -> np.ndarray:
        """Foot-centre targets (m, 3) [m] from ``centre`` (3,) to ``above`` (3,) [m] in ``reach``
        [s] over the terrain's hull, then on down at touchdown_speed, at ``after_lift`` (m,) [s]."""
        cfg = self.config
        swing = swing_trajectory(self.hmap, centre - self._lift, above, reach, self.robot,
                                 cfg.swing)
        path = swing.position(after_lift) + self._lift
        path[:, 2] -= cfg.touchdown_speed * np.maximum(after_lift - reach, 0.0)
        return path

    def _touch_down(self, s: int, foothold: np.ndarray) -> bool:
        """Not down yet: keep foot ``s`` going down at its foothold (3,) [m] until it feels the
        ground; returns whether it did within ``touchdown_search`` below the foothold."""
        cfg = self.config
        bottom = foothold[2] + self.robot.foot_radius - cfg.touchdown_search
        while True:
            self._targets[s, 2] -= cfg.touchdown_speed * self.period
            if self._targets[s, 2] < bottom:
                return False  # nothing there within reach
            self._tick(*self._desired, s)
            if self._touching_down(s):
                return True

    def _come_down(self, s: int) -> bool:
        """Swing foot ``s`` down at once, straight below where it is (an alarm during its swing).

        It drops fast to ``touchdown_approach`` above the mapped ground there, then feels for
        the ground at touchdown_speed; returns whether it found it.
        """
        cfg = self.config
        centre = self.sim.foot_positions()[s]
        self._targets[s] = centre
        ground = float(self.hmap.height_at(centre[None, :2])[0])
        if not np.isfinite(ground):
            ground = float(np.nanmin(self._targets[self._stance, 2])) - self.robot.foot_radius
        slow_from = ground + self.robot.foot_radius + cfg.touchdown_approach
        while self._targets[s, 2] > slow_from and not self._touching_down(s):
            self._targets[s, 2] = max(slow_from, self._targets[s, 2] - DROP_SPEED * self.period)
            self._tick(*self._desired, s)
        if self._touching_down(s):
            return True
        return self._touch_down(s, np.array([*centre[:2], ground]))

    def _place(self, k: int, s: int, plan: FootstepPlan, found: bool, record: dict) -> None:
        """Touch-down check, then load transfer, of foot ``s`` of step ``k``.

        A foot that lands more than ``touchdown_tolerance`` off its foothold, or finds no
        ground, is lifted again and put on the next-best candidate of F (by reward plus path
        bias) away from every spot tried, at most ``max_replacements`` times; then it stands
        where it is and takes its load.
        """
        rc = self.config.reflexes
        tried, target = [plan.foothold[:2].copy()], plan.foothold
        for _ in range(rc.max_replacements if rc.touchdown_check else 0):
            off = float(np.hypot(*(self.sim.foot_positions()[s, :2] - target[:2])))
            if self._alarm is not None or (found and off <= rc.touchdown_tolerance):
                break
            j = next_best_candidate(plan.candidates, plan.total, np.array(tried),
                                    rc.replace_separation)
            if j is None:
                break
            self._event("touch-down re-placed", s, off_mm=round(1e3 * off, 1),
                        ground=bool(found))
            target = plan.candidates[j]
            tried.append(target[:2].copy())
            found = self._re_place(s, target)
        self._load(k, s, record)

    def _re_place(self, s: int, foothold: np.ndarray) -> bool:
        """Lift foot ``s`` (not yet loaded) and put it on ``foothold`` (3,) [m], the body held;
        returns whether it found the ground there."""
        cfg = self.config
        centre = self.sim.foot_positions()[s]
        approach = cfg.touchdown_approach
        reach = REPLACE_TIME
        n = round((reach + approach / cfg.touchdown_speed) / self.period)
        after = np.arange(1, n + 1) * self.period
        path = self._swing_path(centre, foothold + [0.0, 0.0, approach], reach, after)
        for i in range(n):
            self._targets[s] = path[i]
            self._tick(*self._desired, s)
            if self._alarm is not None:
                return self._come_down(s)
            if after[i] > cfg.touchdown_early * reach and self._touching_down(s):
                return True
        return self._touch_down(s, foothold)

    def _load(self, k: int, s: int, record: dict) -> None:
        """Foot ``s`` stands where it touched down and starts to take its load; log it."""
        sim = self.sim
        centre = sim.foot_positions()[s]
        self._hand_over()
        self._down[s] = centre
        self._anchor_here(s, centre)
        self._set_role(s, stance=True)
        record["t_touchdown"] = sim.time
        record["touchdown"] = centre.copy()
        self._stood[s] = (k, centre.copy())

    def _hand_over(self) -> None:
        """A foot is about to take a new anchor where it stands: with ``hand_over``, the
        horizontal body correction passes to the stance feet's anchors (their set-points stay),
        so that the foot enters a commanded frame without it (:func:`handed_over`)."""
        if not self.config.lowlevel.hand_over:
            return
        taken = self._correction.take_horizontal()
        self._anchor = handed_over(self._anchor, self._stance, taken)  # (the stance targets
        # follow from the anchors at the next control period)

    def _rebase(self, off: float) -> None:
        """Take the stance as it is: the body, ``off`` [m] from where it is wanted, is wanted
        where it stands, and every stance foot is anchored where it stands (the touch-down
        points, from which slip and the flight recorder measure, stay)."""
        self._correction.take_horizontal()
        self._desired[0][:2] = self._pose[0][:2]
        stance = self._stance.copy()
        self._anchor_here(stance, self.sim.foot_positions()[stance])
        self._event("re-based", None, off_mm=round(1e3 * off, 1))

    def _anchor_here(self, legs: int | np.ndarray, centres: np.ndarray) -> None:
        """Anchor ``legs`` (an index or a mask) at their foot centres ``centres`` [m], where
        they stand now, with their shins' orientation now (the ball's rolling counts from
        here)."""
        self._anchor[legs] = self._targets[legs] = centres
        self._shin0[legs] = shin_rotations(self.sim.joint_angles(),
                                           body_rotation(self._pose[1]))[legs]

    def _settle(self, leg: int, t0: float) -> None:
        """The body held, wait until slipped foot ``leg`` stops sliding (or recover_timeout
        after ``t0`` [s])."""
        rc, sim = self.config.reflexes, self.sim
        while sim.time - t0 < rc.recover_timeout:
            before = sim.foot_positions()[leg, :2]
            self._tick(*self._desired, None)
            if np.hypot(*(self._feet_before[leg, :2] - before)) < 0.5 * rc.slip_speed * self.period:
                return

    def _recover(self) -> None:
        """After an alarm, or a wait at the gate: the body stops; a slipped foot is taken to
        stand where it now is (and steps first if it went far); the posture is recovered, or,
        if it cannot be within recover_timeout, accepted as it is."""
        rc, sim = self.config.reflexes, self.sim
        t0 = sim.time
        while self._alarm is not None:
            kind, leg = self._alarm
            if kind == "slip":
                self._settle(leg, t0)
                centre = sim.foot_positions()[leg]
                moved = float(np.hypot(*(centre[:2] - self._down[leg, :2])))
                self._hand_over()
                self._down[leg] = centre
                self._anchor_here(leg, centre)
                if moved > rc.replace_distance:
                    self._replace = leg
            self._alarm = None
            self._recovering = True  # (a tilt does not set the tilt reflex off again meanwhile)
            while (tilt_error(self._pose[1], self._desired[1]) > rc.tilt_recovered
                   and sim.time - t0 < rc.recover_timeout and self._alarm is None):
                self._tick(*self._desired, None)
            self._recovering = False
            error = tilt_error(self._pose[1], self._desired[1])
            if self._alarm is None and error > rc.tilt_threshold:
                # A posture the legs cannot reach from where the feet stand (joints at their
                # limits): the gait goes on from the one it has rather than waiting for ever.
                self._event("posture accepted", None, error_rad=round(error, 3))
                self._correction.rebase(self._desired[1], self._pose[1])
                self._desired[1][:2] = self._pose[1][:2]
        self._held = False
        self._unload[:] = 1.0  # a step called off keeps its leg's load
        if rc.rebase_distance is not None:
            off = float(np.hypot(*(self._pose[0][:2] - self._desired[0][:2])))
            if off > rc.rebase_distance:
                self._rebase(off)
        self._cog = self._desired[0][:2].copy(), np.zeros(2)  # the body at rest where it is

    # ------------------------------------------------------------------ a run
    def run(self) -> RunRecord:
        """Walk until the goal or a failure; return the run log with its result."""
        # A run is one core's work on small matrices: BLAS threads would only spin beside it
        # (and steal the cores that walk-many's parallel runs need).
        with threadpool_limits(limits=1):
            return self._run()

    def _run(self) -> RunRecord:
        cfg, robot, sim = self.config, self.robot, self.sim
        wall0 = time.perf_counter()
        state0 = nominal_state(self.hmap, self.start_xy, 0.0, robot.gait_order[0],
                               goal=self.goal, robot=robot)
        sim.stand(state0.body_position, state0.body_rpy, state0.feet)
        self._all_frames: list = []
        self._q = sim.joint_angles().copy()  # (4, 3) [rad] last set-points
        self._targets = np.array(state0.feet) + self._lift  # (4, 3) [m] foot-centre targets
        self._stance = np.ones(4, dtype=bool)  # role of each leg
        self._since = np.full(4, -np.inf)  # [s] when each leg took its role
        self._correction = BodyCorrection(cfg.lowlevel)
        self._pose = sim.body_pose()  # measured (position (3,), rpy (3,))
        self._anchor = self._targets.copy()  # (4, 3) [m] stance feet's targets at touch-down
        self._down = self._targets.copy()  # (4, 3) [m] stance feet's centres at touch-down
        self._shin0 = shin_rotations(self._q, body_rotation(self._pose[1]))  # (4, 3, 3) shins then
        # The robot stands where the start error put it: the plan starts from there, so that the
        # first set-points do not jerk the body (and drag the unloaded feet) to the nominal pose.
        self._desired = self._pose[0].copy(), self._pose[1].copy()
        self._cog = self._desired[0][:2].copy(), np.zeros(2)  # planned COG position, velocity
        self._stood: dict[int, tuple[int, np.ndarray]] = {}  # leg -> (step, centre at touch-down)
        self._steps: list[dict] = []
        self._com: list[np.ndarray] = []  # (2,) [m] centre of mass during swings
        self._support: list[np.ndarray] = []  # (3, 2) [m] stance feet during swings
        self._planned: list[float] = []  # [m] planned least COG margin of each swing
        self._plan_seconds: list[float] = []
        self._feet_before = sim.foot_positions()  # (4, 3) [m] at the last control period
        self._com_before = sim.centre_of_mass()[:2]  # (2,) [m] at the last control period
        self._press = np.zeros(4)  # [m] stance feet's load control offsets (target heights)
        self._unload = np.ones(4)  # [-] availability of each leg to carry load (1 - unloading)
        self._alarm: tuple[str, int | None] | None = None  # the stance watch's alarm, not yet acted on
        self._events: list[dict] = []  # reflex events, the first MAX_EVENTS
        self._reflex_counts: dict[str, int] = {}  # reflex events by kind
        self._gait = 0  # steps taken in gait order
        self._replace: int | None = None  # a slipped leg to step next, out of gait order
        self._held = False  # the body waited at the lift-off gate and holds still this swing
        self._recovering = False  # the posture is recovering after an alarm
        self._best_x, self._best_t = self._pose[0][0], 0.0
        start_x = self._pose[0][0]
        outcome: dict = {"success": False, "reason": "time limit"}
        try:
            for _ in range(max(1, round(cfg.settle_time / self.period))):
                self._tick(*self._desired, None)
            start_x = self._pose[0][0]
            k = 0
            while True:
                if self._pose[0][0] >= self.goal_x:
                    outcome = {"success": True, "reason": "goal"}
                    break
                if cfg.max_steps is not None and k >= cfg.max_steps:
                    outcome["reason"] = "step limit"
                    break
                if self._step(k):
                    k += 1
        except _Failure as failure:
            outcome["reason"] = str(failure)
        outcome["distance"] = float(self._pose[0][0] - start_x)
        if not outcome["success"]:  # the flight recorder's account of the end (--explain)
            outcome["explanation"] = explain_run(self.trace.series(), outcome, self.robot)
        return self._finish(outcome, wall0)

    def _finish(self, outcome: dict, wall0: float) -> RunRecord:
        sim, robot = self.sim, self.robot
        sim_time = sim.time
        steps = self._steps
        slips = np.array([s["slip"] for s in steps if np.isfinite(s["slip"])])
        margins = (support_margin(np.array(self._support), np.array(self._com))
                   if self._com else np.zeros(0))
        wall = time.perf_counter() - wall0
        speed = outcome["distance"] / sim_time if sim_time > 0 else 0.0
        outcome.update({
            "reflexes": dict(self._reflex_counts),  # reflex events by kind
            "events": list(self._events),  # the first MAX_EVENTS of them: t [s], event, leg
            "time": sim_time,  # [s] simulated
            "steps": len(steps),
            "speed_cm_s": 100.0 * speed,
            "speed_body_lengths_s": speed / robot.overall_length,
            "slip_mean_mm": 1e3 * float(slips.mean()) if slips.size else None,
            "slip_std_mm": 1e3 * float(slips.std()) if slips.size else None,
            "slip_count": int(slips.size),
            "min_stability_margin_mm": 1e3 * float(margins.min()) if margins.size else None,
            "planned_min_stability_margin_mm": (1e3 * min(self._planned) if self._planned
                                                else None),
            "planning_ms_per_step": (1e3 * float(np.mean(self._plan_seconds))
                                     if self._plan_seconds else None),
            "wall_seconds": wall,
            "setup_seconds": self.setup_seconds,
            "real_time_factor": sim_time / wall if wall > 0 else None,
        })
        if self.frames is not None and self.frames.snapshot_count > 0:
            kept = self._all_frames
            if kept:
                pick = np.unique(np.linspace(0, len(kept) - 1,
                                             self.frames.snapshot_count).round().astype(int))
                self.frames.snapshots = [kept[i] for i in pick]
        # Each step is logged with the state its candidates were computed for (the body as
        # predicted at touch-down), so that the expert and the learner judge F as the planner did.
        run_steps = tuple(RunStep(s["k"], s["plan"].state, s["plan"].candidates,
                                  np.nan_to_num(s["plan"].reward, nan=-np.inf), s["plan"].index,
                                  s["t_liftoff"] if np.isfinite(s["t_liftoff"]) else sim_time,
                                  s["t_touchdown"], s["touchdown"], s["slip"])
                          for s in steps)
        settings = {"walk": plain_json(self.config.to_dict(), nonfinite="null"),
                    "perturbation": sim.perturbation.to_dict(), "robot": robot.name,
                    # which reward ranked the footholds (e.g. "hand-tuned default",
                    # "both/l1/front" and "both/l1/hind"), as a person reviewing the run sees it
                    "reward": sorted({str(getattr(self.reward_for(leg), "name", "reward"))
                                      for leg in LEG_NAMES})}
        if self.judge_name is not None:  # the footholds were chosen by a judge, not a reward
            settings["judge"] = self.judge_name
        self.sim.close()
        return RunRecord(self.hmap.content_hash(), self.seed, settings, plain_json(outcome, nonfinite="null"),
                         run_steps)


def walk(hmap: HeightMap, reward_for: RewardFor, seed: int, config: WalkConfig = WalkConfig(),
         robot: RobotDescription = LITTLEDOG, frames: Frames | None = None,
         judge: FootholdScorer | None = None) -> RunRecord:
    """One seeded run over ``hmap`` with the reward ``reward_for(leg)``; the same seed, the same run.

    With ``judge`` (e.g. ``ExpertScorer(SyntheticExpert(...))``), the judge chooses
    the footholds instead of the reward (:class:`JudgedFootstepPlanner`);
    ``reward_for`` then only plans the body path if ``config.plan_path``.
    """
    return Walk(hmap, reward_for, seed, config, robot, frames, judge).run()
