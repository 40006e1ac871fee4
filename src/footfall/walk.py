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
   kinematics at 100 Hz, closed on the true body pose, and the simulator's
   400 Hz PD servo.

Each step is planned when the previous foot has touched down (a receding
horizon: five steps planned, one executed). A run ends at the goal line,
or in failure: a fall (trunk roll or pitch beyond ``fall_tilt``, or the
trunk touching the terrain), a stuck robot (no swing leg candidate, or less
than ``stuck_progress`` of forward progress in ``stuck_time``), or the time
limit. Every step goes into the run log (:mod:`footfall.runlog`).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from footfall.control.body_path import BodyPath, BodyPathConfig, plan_body_path
from footfall.control.cog import CogConfig, plan_cog, support_margin
from footfall.control.footstep import FootstepConfig, FootstepPlanner, NoFootholdError
from footfall.control.lowlevel import BodyCorrection, LowLevelConfig, joint_targets
from footfall.control.pose_finder import PoseConfig, find_pose
from footfall.control.swing import SwingConfig, swing_trajectory
from footfall.errors import FootfallError
from footfall.heightmap import HeightMap
from footfall.reward import LinearReward
from footfall.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.runlog import RunRecord, RunStep
from footfall.sim.simulation import PerturbationConfig, Simulation
from footfall.state import RobotState, nominal_state

RewardFor = Callable[[str], LinearReward]
SNAPSHOT_PERIOD = 0.5  # [s] of simulated time between candidate snapshot frames


@dataclass(frozen=True)
class WalkConfig:
    """Every setting of a walking run; written next to its result."""

    footstep: FootstepConfig = field(default_factory=FootstepConfig)
    cog: CogConfig = field(default_factory=CogConfig)
    swing: SwingConfig = field(default_factory=SwingConfig)
    pose: PoseConfig = field(default_factory=PoseConfig)
    lowlevel: LowLevelConfig = field(default_factory=LowLevelConfig)
    path: BodyPathConfig = field(default_factory=BodyPathConfig)
    perturbation: PerturbationConfig = field(default_factory=PerturbationConfig)
    plan_path: bool = False  # False: the fixed straight path along the board's axis (as the paper)
    start_setback: float = 0.35  # [m] body start this far before the end of the first module
    goal_margin: float = 0.02  # [m] goal line: hind hips this far past the last non-final module
    settle_time: float = 0.3  # [s] standing still before the first step
    touchdown_force: float = 2.0  # [N] vertical foot force that means the foot is down
    touchdown_early: float = 0.7  # [-] share of the swing after which a contact ends it early
    touchdown_search: float = 0.02  # [m] how far below the planned foothold the foot keeps looking
    touchdown_speed: float = 0.1  # [m/s] how fast it goes down while looking
    fall_tilt: float = 0.6  # [rad] trunk roll or pitch beyond this is a fall
    stuck_time: float = 10.0  # [s] a robot that advanced less than stuck_progress in this long is stuck
    stuck_progress: float = 0.02  # [m]
    time_limit: float = 240.0  # [s] of simulated time

    def to_dict(self) -> dict:
        """Plain JSON-serialisable settings."""
        return asdict(self)


@dataclass
class Frames:
    """Requests for pictures of a run: snapshot times and a video frame rate."""

    snapshot_count: int = 0  # frames evenly spaced over the run (0: none)
    video_fps: float = 0.0  # [1/s] video frame rate (0: no video)
    width: int = 480
    height: int = 360
    snapshots: list = field(default_factory=list)  # filled: (time [s], image (h, w, 3) uint8)
    video: list = field(default_factory=list)  # filled: images (h, w, 3) uint8


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
    modules = hmap.metadata.get("modules") if isinstance(hmap.metadata, dict) else None
    if modules and len(modules) >= 2:
        first_end = x0 + float(modules[0]["x_end"]) - float(modules[0]["x_start"])
        last_start = x0 + float(modules[-1]["x_start"])
    else:
        first_end, last_start = x0 + 0.5 * (x1 - x0), x1 - 2 * robot.hip_x - 0.1
    start = np.array([first_end - config.start_setback, 0.5 * (y0 + y1)])
    goal = last_start + robot.hip_x + config.goal_margin
    if not start[0] - robot.hip_x - 0.05 > x0 or not goal > start[0]:
        raise FootfallError("the terrain is too short for a walking run")
    return start, goal


def _smooth(u: float) -> tuple[float, float]:
    """Smoothstep 3u^2 - 2u^3 of u in [0, 1] and its derivative."""
    u = min(max(u, 0.0), 1.0)
    return u * u * (3 - 2 * u), 6 * u * (1 - u)


class Walk:
    """One run of the simulated robot over a board (use :func:`walk`)."""

    def __init__(self, hmap: HeightMap, reward_for: RewardFor, seed: int,
                 config: WalkConfig = WalkConfig(), robot: RobotDescription = LITTLEDOG,
                 frames: Frames | None = None) -> None:
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
        self.planner = FootstepPlanner(hmap, reward_for, self.path, robot, config.footstep)
        self.sim = Simulation.from_seed(robot, hmap, self.seed, config.perturbation)
        self.setup_seconds = time.perf_counter() - t0
        self.goal = goal_xy
        self.period = config.lowlevel.period
        self.ticks = round(self.period / self.sim.timestep)
        if self.ticks < 1 or abs(self.ticks * self.sim.timestep - self.period) > 1e-9:
            raise FootfallError("the control period must be a whole number of servo periods")

    # ------------------------------------------------------------------ pieces
    def _measure(self) -> tuple[np.ndarray, np.ndarray]:
        return self.sim.body_pose()

    def _capture(self) -> None:
        f = self.frames
        if f is None:
            return
        t = self.sim.time
        if f.video_fps > 0 and t + 1e-9 >= len(f.video) / f.video_fps:
            f.video.append(self.sim.render(width=f.width, height=f.height))
        if f.snapshot_count > 0 and t + 1e-9 >= len(self._all_frames) * SNAPSHOT_PERIOD:
            self._all_frames.append((t, self.sim.render(width=f.width, height=f.height)))

    def run(self) -> RunRecord:
        """Walk until the goal or a failure; return the run log with its result."""
        cfg, robot, sim = self.config, self.robot, self.sim
        r = robot.foot_radius
        wall0 = time.perf_counter()
        state0 = nominal_state(self.hmap, self.start_xy, 0.0, robot.gait_order[0],
                               goal=self.goal, robot=robot)
        sim.stand(state0.body_position, state0.body_rpy, state0.feet)
        self._all_frames: list = []
        feet = np.array(state0.feet)  # (4, 3) [m] stance contact points, LEG_NAMES order
        targets = feet + np.array([0.0, 0.0, r])  # (4, 3) [m] commanded foot centres
        q_prev = sim.joint_angles().copy()
        correction = BodyCorrection(cfg.lowlevel)
        desired_pos = np.array(state0.body_position)
        desired_rpy = np.array(state0.body_rpy)
        cog_xy, cog_v = desired_pos[:2].copy(), np.zeros(2)
        touchdown_at: dict[int, tuple[int, np.ndarray]] = {}  # leg -> (step, centre at touch-down)
        steps: list[dict] = []
        margins: list[float] = []
        planned_margins: list[float] = []
        plan_seconds: list[float] = []
        outcome: dict = {"success": False, "reason": "time limit"}
        best_x, best_t = desired_pos[0], 0.0

        def tick(swing: int | None, feet_centres: np.ndarray, pos: np.ndarray, rpy: np.ndarray,
                 triangle: np.ndarray | None) -> str | None:
            """One 100 Hz control period; returns a failure reason or None."""
            nonlocal q_prev, best_x, best_t
            mpos, mrpy = self._measure()
            cpos, crpy = correction.update(pos, rpy, mpos, mrpy)
            q, _ = joint_targets(robot, feet_centres, cpos, crpy, swing, mpos, mrpy, q_prev)
            sim.set_targets(q, (q - q_prev) / self.period)
            q_prev = q
            sim.step(self.ticks)
            self._capture()
            mpos, mrpy = self._measure()
            if triangle is not None:
                com = sim.data.subtree_com[sim._trunk][:2]
                margins.append(float(support_margin(triangle, com)))
            if abs(mrpy[0]) > cfg.fall_tilt or abs(mrpy[1]) > cfg.fall_tilt:
                return "fall: trunk tilted"
            if sim.trunk_touches_terrain():
                return "fall: trunk touched the terrain"
            if mpos[0] > best_x + cfg.stuck_progress:
                best_x, best_t = mpos[0], sim.time
            elif sim.time - best_t > cfg.stuck_time:
                return "stuck: no progress"
            if sim.time > cfg.time_limit:
                return "time limit"
            return None

        # Settle on the start stance.
        for _ in range(max(1, round(cfg.settle_time / self.period))):
            reason = tick(None, targets, desired_pos, desired_rpy, None)
            if reason:
                outcome["reason"] = reason
                return self._finish(steps, outcome, margins, planned_margins, plan_seconds, wall0)
        k = 0
        start_x = sim.body_pose()[0][0]
        while True:
            mpos, mrpy = self._measure()
            if mpos[0] >= self.goal_x:
                outcome = {"success": True, "reason": "goal"}
                break
            leg = robot.gait_order[k % 4]
            s = LEG_NAMES.index(leg)
            tp = time.perf_counter()
            state = RobotState(feet, mpos, mrpy, leg, self.goal)
            try:
                plan = self.planner.plan(state)
            except NoFootholdError:
                outcome["reason"] = f"stuck: no foothold for {leg}"
                break
            traj = plan_cog(feet, plan.steps, cog_xy, cog_v, cfg.cog, robot)
            after = feet.copy()
            after[s] = plan.foothold
            td_xy = traj.waypoints[0, 1]
            pose = find_pose(self.hmap, after, td_xy, float(plan.body_yaw[0]), robot, cfg.pose)
            t_lift, t_down = float(traj.lift_off[0]), float(traj.touch_down[0])
            plan_seconds.append(time.perf_counter() - tp)
            t_begin = sim.time
            z0, rpy0 = desired_pos[2], desired_rpy.copy()
            z1, rpy1 = pose.height, np.array(pose.rpy)
            rpy1[2] = rpy0[2] + ((rpy1[2] - rpy0[2] + np.pi) % (2 * np.pi) - np.pi)
            triangle = traj.triangles[0]
            planned_margins.append(float(np.min(support_margin(
                triangle, traj.position(np.linspace(t_lift, t_down, 20))))))
            record = {"k": k, "state": state, "plan": plan, "t_liftoff": math.nan,
                      "t_touchdown": math.nan, "touchdown": np.full(3, np.nan), "slip": math.nan}
            steps.append(record)
            swing = None
            reason = None
            landed = False
            n_ticks = max(1, round(t_down / self.period))
            for i in range(1, n_ticks + 1):  # shift, then swing along the planned trajectories
                t = min(i * self.period, t_down)
                u, _ = _smooth(t / t_down)
                desired_pos = np.array([*traj.position(t), z0 + (z1 - z0) * u])
                desired_rpy = rpy0 + (rpy1 - rpy0) * u
                if t > t_lift and swing is None:  # lift-off: the slip of this foot's last stance ends
                    centre = sim.foot_positions()[s]
                    if s in touchdown_at:
                        j, down = touchdown_at.pop(s)
                        steps[j]["slip"] = float(np.linalg.norm(centre - down))
                    record["t_liftoff"] = sim.time
                    swing = swing_trajectory(self.hmap, centre - [0, 0, r], plan.foothold,
                                             t_down - t_lift, robot, cfg.swing)
                if swing is not None:
                    targets[s] = swing.position(t - t_lift) + [0, 0, r]
                reason = tick(s if swing is not None else None, targets, desired_pos,
                              desired_rpy, triangle if swing is not None else None)
                if reason:
                    break
                if swing is not None and (t - t_lift) > cfg.touchdown_early * (t_down - t_lift) \
                        and sim.foot_forces()[s, 2] > cfg.touchdown_force:
                    landed = True
                    break
            if reason:
                outcome["reason"] = reason
                break
            if swing is None:  # a step too short to lift: count it as landed where it stands
                landed = True
            searched = 0.0
            while not landed:  # not down yet: keep going down at the foothold
                searched += cfg.touchdown_speed * self.period
                if searched > cfg.touchdown_search:
                    break  # nothing there within reach: put the weight on it anyway
                targets[s, 2] -= cfg.touchdown_speed * self.period
                reason = tick(s, targets, desired_pos, desired_rpy, triangle)
                if reason:
                    break
                landed = sim.foot_forces()[s, 2] > cfg.touchdown_force
            if reason:
                outcome["reason"] = reason
                break
            centre = sim.foot_positions()[s]
            targets[s] = centre
            feet[s] = centre - [0, 0, r]
            record["t_touchdown"] = sim.time
            record["touchdown"] = centre.copy()
            touchdown_at[s] = (k, centre.copy())
            cog_xy = traj.position(min(sim.time - t_begin, t_down))
            cog_v = traj.velocity(min(sim.time - t_begin, t_down))
            desired_pos[:2] = cog_xy
            k += 1
        outcome["distance"] = float(sim.body_pose()[0][0] - start_x)
        return self._finish(steps, outcome, margins, planned_margins, plan_seconds, wall0)

    def _finish(self, steps: list[dict], outcome: dict, margins: list, planned: list,
                plan_seconds: list, wall0: float) -> RunRecord:
        sim, robot = self.sim, self.robot
        sim_time = sim.time
        outcome.setdefault("distance", float(sim.body_pose()[0][0] - self.start_xy[0]))
        slips = np.array([s["slip"] for s in steps if np.isfinite(s["slip"])])
        wall = time.perf_counter() - wall0
        speed = outcome["distance"] / sim_time if sim_time > 0 else 0.0
        outcome.update({
            "time": sim_time,  # [s] simulated
            "steps": len(steps),
            "speed_cm_s": 100.0 * speed,
            "speed_body_lengths_s": speed / robot.overall_length,
            "slip_mean_mm": 1e3 * float(slips.mean()) if slips.size else None,
            "slip_std_mm": 1e3 * float(slips.std()) if slips.size else None,
            "slip_count": int(slips.size),
            "min_stability_margin_mm": 1e3 * min(margins) if margins else None,
            "planned_min_stability_margin_mm": 1e3 * min(planned) if planned else None,
            "planning_ms_per_step": 1e3 * float(np.mean(plan_seconds)) if plan_seconds else None,
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
        run_steps = tuple(RunStep(s["k"], s["state"], s["plan"].candidates,
                                  np.nan_to_num(s["plan"].reward, nan=-np.inf), s["plan"].index,
                                  s["t_liftoff"] if np.isfinite(s["t_liftoff"]) else sim_time,
                                  s["t_touchdown"], s["touchdown"], s["slip"])
                          for s in steps)
        settings = {"walk": _jsonable(self.config.to_dict()),
                    "perturbation": sim.perturbation.to_dict(), "robot": robot.name}
        self.sim.close()
        return RunRecord(self.hmap.content_hash(), self.seed, settings, _jsonable(outcome),
                         run_steps)


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def walk(hmap: HeightMap, reward_for: RewardFor, seed: int, config: WalkConfig = WalkConfig(),
         robot: RobotDescription = LITTLEDOG, frames: Frames | None = None) -> RunRecord:
    """One seeded run over ``hmap`` with the reward ``reward_for(leg)``; the same seed, the same run."""
    return Walk(hmap, reward_for, seed, config, robot, frames).run()
