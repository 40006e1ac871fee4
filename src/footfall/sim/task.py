"""The walking task: the referee of a run, and its record.

A :class:`WalkTask` watches the simulated robot the way the testbed's
operator does -- from the simulator's true state, never from the
controller's estimates -- and decides how a run ends: at the goal line
(the hind hips ``goal_margin`` past the start of the last module, when the
robot stops stepping there), or in failure: a fall (trunk roll or pitch
beyond ``fall_tilt``, or the trunk touching the terrain), a stuck robot (no
swing-leg candidate, or less than ``stuck_progress`` of forward progress in
``stuck_time``), the step limit or the time limit. It keeps the run log: every
step the controller plans (:mod:`footfall.control.journal`) with where its foot
really touched down and how far it slipped before it lifted again
(:func:`foot_slip`), the reflex events, the stability margin of every swing,
the flight recorder (:mod:`footfall.sim.trace`) and, for a failed run, its
account of the end (:func:`footfall.sim.explain.explain_run`).
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING

import numpy as np

from footfall.control.cog import support_margin
from footfall.control.journal import (
    LiftOff,
    Note,
    ReflexEvent,
    Settled,
    StepCalledOff,
    StepPlanned,
    TouchDown,
)
from footfall.control.legs import OTHER_LEGS
from footfall.core.errors import FootfallError
from footfall.core.files import plain_json
from footfall.core.heightmap import HeightMap, module_records
from footfall.core.robot import LEG_NAMES, RobotDescription
from footfall.data.runlog import RunRecord, RunStep
from footfall.sim.explain import explain_run
from footfall.sim.simulation import Simulation
from footfall.sim.trace import RunTrace, trace_row

if TYPE_CHECKING:
    from footfall.sim.episode import WalkConfig

MAX_EVENTS = 200  # reflex events kept in a run's result (every one is counted)
WALL_CLOCK_FIELDS = ("planning_ms_per_step", "wall_seconds", "setup_seconds", "real_time_factor")
# result fields that measure the computer, not the run (they differ between identical runs)


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


class WalkTask:
    """The referee and recorder of one run (see the module's docstring).

    Parameters
    ----------
    goal_x : float
        [m] the goal line: the body origin past it when the robot stops stepping.
    config : WalkConfig
        Its fall, progress, time and flight-recorder settings.
    robot : RobotDescription
    period : float
        [s] the control period (a flight-recorder row per period).
    """

    def __init__(self, goal_x: float, config: WalkConfig, robot: RobotDescription,
                 period: float) -> None:
        self.goal_x, self.config, self.robot = goal_x, config, robot
        self.trace = RunTrace(config.trace_window, period)  # the last seconds, at 100 Hz
        self.steps: list[dict] = []  # one per step taken: its plan and what became of it
        self.outcome: dict | None = None  # how the run ended, once it has
        self._stood: dict[int, tuple[int, np.ndarray]] = {}  # leg -> (step, centre at touch-down)
        self._com: list[np.ndarray] = []  # (2,) [m] centre of mass during swings
        self._support: list[np.ndarray] = []  # (3, 2) [m] stance feet during swings
        self._planned: list[float] = []  # [m] planned least COG margin of each swing
        self._plan_seconds: list[float] = []  # [s] wall clock
        self._events: list[dict] = []  # reflex events, the first MAX_EVENTS
        self._reflex_counts: dict[str, int] = {}  # reflex events by kind

    def start(self, sim: Simulation) -> None:
        """The robot stands at its start."""
        x = sim.body_pose()[0][0]
        self._start_x = x  # [m] where progress counts from (after the settle time)
        self._best_x, self._best_t = x, 0.0  # [m], [s] the farthest forward so far, and when

    # ------------------------------------------------------------------ the record
    def review(self, notes: list[Note], sim: Simulation) -> None:
        """Log what the controller did since the last review, positions from the simulator."""
        for note in notes:
            if isinstance(note, ReflexEvent):
                self._event(note)
            elif isinstance(note, StepPlanned):
                self.steps.append({"k": note.k, "plan": note.plan, "t_liftoff": math.nan,
                                   "t_touchdown": math.nan, "touchdown": np.full(3, np.nan),
                                   "slip": math.nan})
                self._planned.append(note.margin)
                self._plan_seconds.append(note.seconds)
            elif isinstance(note, StepCalledOff):
                self.steps.pop()
            elif isinstance(note, LiftOff):
                centre = sim.foot_positions()[note.leg]
                if note.leg in self._stood:  # the slip of the stance it ends
                    j, down = self._stood.pop(note.leg)
                    self.steps[j]["slip"] = float(foot_slip(down, centre))
                self.steps[note.k]["t_liftoff"] = note.time
            elif isinstance(note, TouchDown):
                centre = sim.foot_positions()[note.leg]
                self.steps[note.k]["t_touchdown"] = note.time
                self.steps[note.k]["touchdown"] = centre.copy()
                self._stood[note.leg] = (note.k, centre.copy())
            elif isinstance(note, Settled):
                self._start_x = sim.body_pose()[0][0]

    def _event(self, note: ReflexEvent) -> None:
        self._reflex_counts[note.kind] = self._reflex_counts.get(note.kind, 0) + 1
        if len(self._events) < MAX_EVENTS:
            self._events.append({"t": round(note.time, 3), "event": note.kind,
                                 "leg": None if note.leg is None else LEG_NAMES[note.leg],
                                 **note.details})

    # ------------------------------------------------------------------ the referee
    def judge(self, sim: Simulation, stance: np.ndarray, down: np.ndarray,
              swing: int | None) -> bool:
        """After a control period: record it, and whether the run ends in a fall, stuck or out
        of time (then :attr:`outcome` says how). ``stance`` (4,) bool, ``down`` (4, 3) [m] and
        ``swing`` (a leg, or None) are the controller's legs' roles, touch-down points and
        swing leg, for the flight recorder."""
        cfg = self.config
        pos, rpy = sim.body_pose()
        com, feet = sim.centre_of_mass(), sim.foot_positions()
        self.trace.record(trace_row(sim.time, pos, rpy, com, feet, sim.foot_forces(noise=False),
                                    stance, down, sim.joint_angles(), sim.joint_torques(),
                                    swing))
        if swing is not None:  # the measured stability margin of the swings
            self._com.append(com[:2])
            self._support.append(feet[OTHER_LEGS[swing], :2])
        reason = None
        if abs(rpy[0]) > cfg.fall_tilt or abs(rpy[1]) > cfg.fall_tilt:
            reason = "fall: trunk tilted"
        elif sim.trunk_touches_terrain():
            reason = "fall: trunk touched the terrain"
        elif pos[0] > self._best_x + cfg.stuck_progress:
            self._best_x, self._best_t = pos[0], sim.time
        elif sim.time - self._best_t > cfg.stuck_time:
            reason = "stuck: no progress"
        if reason is None and sim.time > cfg.time_limit:
            reason = "time limit"
        if reason is not None:
            self.outcome = {"success": False, "reason": reason}
        return reason is not None

    def stopped(self, reason: str, sim: Simulation) -> None:
        """The controller stopped stepping for ``reason`` ("goal", "step limit", "no foothold
        for LEG"): a success if the body is past the goal line."""
        if sim.body_pose()[0][0] >= self.goal_x:
            self.outcome = {"success": True, "reason": "goal"}
        elif reason.startswith("no foothold"):
            self.outcome = {"success": False, "reason": f"stuck: {reason}"}
        else:
            self.outcome = {"success": False, "reason": reason}

    # ------------------------------------------------------------------ the run log
    def record(self, sim: Simulation, hmap: HeightMap, seed: int, settings: dict,
               wall0: float, setup_seconds: float) -> RunRecord:
        """The run log of the ended run: ``settings`` (JSON) and the result; ``wall0`` [s]
        (``time.perf_counter``) when the run began and ``setup_seconds`` [s] before it."""
        outcome = dict(self.outcome)
        outcome["distance"] = float(sim.body_pose()[0][0] - self._start_x)
        if not outcome["success"]:  # the flight recorder's account of the end (--explain)
            outcome["explanation"] = explain_run(self.trace.series(), outcome, self.robot)
        outcome.update(self._measures(sim, outcome["distance"], wall0, setup_seconds))
        sim_time = sim.time
        # Each step is logged with the state its candidates were computed for (the body as
        # predicted at touch-down), so that the expert and the learner judge F as the planner did.
        run_steps = tuple(RunStep(s["k"], s["plan"].state, s["plan"].candidates,
                                  np.nan_to_num(s["plan"].reward, nan=-np.inf), s["plan"].index,
                                  s["t_liftoff"] if np.isfinite(s["t_liftoff"]) else sim_time,
                                  s["t_touchdown"], s["touchdown"], s["slip"])
                          for s in self.steps)
        return RunRecord(hmap.content_hash(), seed, settings,
                         plain_json(outcome, nonfinite="null"), run_steps)

    def _measures(self, sim: Simulation, distance: float, wall0: float,
                  setup_seconds: float) -> dict:
        """The run's measures: reflex events, time, speed, slip, stability, the computer's."""
        sim_time, robot = sim.time, self.robot
        slips = np.array([s["slip"] for s in self.steps if np.isfinite(s["slip"])])
        margins = (support_margin(np.array(self._support), np.array(self._com))
                   if self._com else np.zeros(0))
        wall = time.perf_counter() - wall0
        speed = distance / sim_time if sim_time > 0 else 0.0
        return {
            "reflexes": dict(self._reflex_counts),  # reflex events by kind
            "events": list(self._events),  # the first MAX_EVENTS of them: t [s], event, leg
            "time": sim_time,  # [s] simulated
            "steps": len(self.steps),
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
            "setup_seconds": setup_seconds,
            "real_time_factor": sim_time / wall if wall > 0 else None,
        }
