"""Branching a run: its state at a decision kept, and the run continued from there another way.

A *decision* is the moment the footstep planner chooses: a call of
``planner.plan`` inside the controller's period (:mod:`footfall.control.controller`).
A :class:`TapedWalk` is a :class:`~footfall.sim.episode.Walk` that keeps what
it takes to go back to any of its decisions:

* every measurement its controller read -- the controller reads only its
  senses, so a fresh controller fed the same measurements ends in the same
  state, without physics (its phases are generators, which cannot be copied);
* at each decision, MuJoCo's integration state (``mj_getState`` with
  ``mjSTATE_INTEGRATION``: time, positions, velocities, controls, mocap, the
  constraint solver's warm start -- what the next step depends on), the state
  of the sensors' noise generator, a copy of the referee (the task, with the
  run log so far), the state the planner was given and the plan it made.

:meth:`TapedWalk.branch` builds the same walk afresh (board, reward, seed,
settings), replays its controller through the recorded measurements to the
decision (the recorded plans stand in for the planner there), restores the
physics, the noise and the referee, and walks on: at the decision the
candidate asked for (its look-ahead rolled out by the planner), after it the
walk's own planner. Forcing the recorded choice gives the recorded run, bit
for bit to its end (tests/test_branch.py); a branch costs its replay (the
control periods before the decision, no physics and no planning) and its own
walking.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np

from footfall.control.footstep import FootstepPlan
from footfall.control.measurements import Measurements
from footfall.core.errors import FootfallError
from footfall.core.state import RobotState
from footfall.core.validate import require_int
from footfall.data.runlog import RunRecord
from footfall.sim.episode import Walk
from footfall.sim.simulation import PHYSICS_STATE
from footfall.sim.task import WalkTask

__all__ = ["PHYSICS_STATE", "Branched", "BranchVariation", "Decision", "Tape", "TapedWalk"]


@dataclass(frozen=True)
class Decision:
    """A run at the moment its footstep planner chose (see the module's docstring)."""

    index: int  # the decision's number in the run: the planner's (index + 1)-th call
    periods: int  # control periods the controller had acted in before it
    physics: np.ndarray  # MuJoCo's integration state (Simulation.state: PHYSICS_STATE, SI units)
    noise: dict  # the sensors' noise generator's state (numpy's bit_generator.state)
    task: WalkTask  # the referee as it was (a private copy: the run log so far)
    state: RobotState  # what the planner was given: the feet, the measured body, the swing leg
    plan: FootstepPlan  # what it chose: F, the values, the chosen index and its look-ahead


@dataclass(frozen=True)
class BranchVariation:
    """How a branch differs from its run after the decision, so that one lucky branch does not
    decide: its own sensor noise, friction and a push on the trunk."""

    noise_seed: int | None = None  # the sensors' noise drawn afresh from this seed; None: the run's
    friction_scale: float = 1.0  # [-] factor on every robot-terrain friction coefficient
    push: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [N] force on the trunk's centre of mass
    push_time: float = 0.0  # [s] how long the push lasts from the decision

    def __post_init__(self) -> None:
        values = [self.friction_scale, self.push_time, *self.push]
        if len(self.push) != 3 or not np.isfinite(values).all() or self.friction_scale <= 0 \
                or self.push_time < 0:
            raise FootfallError("a branch variation: friction scale > 0, a push of 3 finite "
                                "components [N], a push time >= 0 [s]")


@dataclass(frozen=True)
class Branched:
    """A branch walked: its run log and where the robot stood at its end."""

    record: RunRecord  # the whole run's log, the steps before the decision the recorded run's
    feet: np.ndarray  # (4, 3) [m] foot centres at the branch's end (LEG_NAMES order)
    body: np.ndarray  # (3,) [m] body position at the branch's end


@dataclass
class Tape:
    """What a taped run keeps: every measurement its controller read, in order (the first at
    the start, then one a control period), and every decision."""

    measurements: list[Measurements] = field(default_factory=list)
    decisions: list[Decision] = field(default_factory=list)


class _Recorded:
    """The footstep planner of a run, its calls seen by ``on_plan(planner, index, state,
    first)`` (which plans); everything else is the planner's."""

    def __init__(self, planner, on_plan) -> None:
        self._planner, self._on_plan, self._calls = planner, on_plan, 0

    def plan(self, state: RobotState) -> FootstepPlan:
        index, self._calls = self._calls, self._calls + 1
        return self._on_plan(self._planner, index, state)

    def __getattr__(self, name: str):
        return getattr(self._planner, name)


class TapedWalk(Walk):
    """A walk that can be branched at any of its decisions (see the module's docstring).

    Built as :class:`~footfall.sim.episode.Walk` is; :meth:`run` walks and keeps
    :attr:`tape`; :meth:`branch` walks another run from one of its decisions.
    """

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.tape = Tape()
        self.controller.planner = _Recorded(self.controller.planner, self._decide)

    def _measure(self) -> Measurements:
        m = super()._measure()
        self.tape.measurements.append(m)
        return m

    def _decide(self, planner, index: int, state: RobotState) -> FootstepPlan:
        """A decision of the run: the state kept, then the planner's choice."""
        physics, noise = self.sim.state(), self.sim.sensors.noise_state()
        task = copy.deepcopy(self.task)
        periods = len(self.tape.measurements) - 1
        plan = planner.plan(state)
        self.tape.decisions.append(Decision(index, periods, physics, noise, task,
                                            copy.deepcopy(state), copy.deepcopy(plan)))
        return plan

    def branch(self, at: int, first: int | None = None, steps: int | None = None,
               variation: BranchVariation | None = None) -> Branched:
        """The run walked again from decision ``at`` (an index into ``tape.decisions``), there
        taking the candidate ``first`` of its F (an index into its plan's candidates; None: the
        recorded choice), after it choosing as this walk does; ``steps``: only that many steps
        after the decision's own (then "step limit"; None: to the run's end); ``variation``:
        the branch's own noise, friction and push."""
        decisions = self.tape.decisions
        if isinstance(at, bool) or not isinstance(at, (int, np.integer)) \
                or not 0 <= at < len(decisions):
            raise FootfallError(f"branch: no decision {at!r} in this run (it made "
                                f"{len(decisions)})")
        config = self.config
        if steps is not None:  # the steps taken before the decision, its own, then ``steps``
            limit = len(decisions[at].task.steps) + 1 + require_int(steps, "steps", 0)
            config = replace(config, max_steps=limit)
        walk = _Branch(self, int(at), first, config, variation or BranchVariation())
        record = walk.run()
        return Branched(record, walk.sim.foot_positions(), walk.sim.body_pose()[0])


class _Branch(Walk):
    """A walk from a decision of a taped one (:meth:`TapedWalk.branch`)."""

    def __init__(self, source: TapedWalk, at: int, first: int | None, config,
                 variation: BranchVariation) -> None:
        super().__init__(source.hmap, source.reward_for, source.seed, config, source.robot,
                         judge=source.judge)
        self.source, self.at, self.first, self.variation = source, at, first, variation
        self.controller.planner = _Recorded(self.controller.planner, self._decide)
        self._push_until = -np.inf  # [s] simulated time the push ends

    def _decide(self, planner, index: int, state: RobotState) -> FootstepPlan:
        """Before the decision the recorded plans (the state checked against the recorded
        one); at it the candidate asked for; after it the planner's own choice."""
        if index > self.at:
            return planner.plan(state)
        recorded = self.source.tape.decisions[index]
        if not (np.array_equal(state.to_vector(), recorded.state.to_vector())
                and state.swing_leg == recorded.state.swing_leg):
            raise FootfallError(f"branch: the replay left the recorded run at decision {index}")
        if index < self.at or self.first is None:
            return copy.deepcopy(recorded.plan)
        return planner.plan(state, first=self.first)

    def _run(self) -> RunRecord:
        wall0 = time.perf_counter()
        tape, decision = self.source.tape, self.source.tape.decisions[self.at]
        controller = self.controller
        controller.start(tape.measurements[0], self.start_state().feet)
        for i in range(decision.periods):  # the controller to where it decided, no physics
            controller.act()
            controller.notes()  # the referee's copy has logged them
            controller.sense(tape.measurements[i + 1])
        self.sim.restore(decision.physics)
        self.sim.sensors.set_noise_state(decision.noise)
        self._vary(self.variation)
        self.task = copy.deepcopy(decision.task)
        self.trace = self.task.trace
        return self._periods(wall0)

    def _vary(self, v: BranchVariation) -> None:
        """The branch's own noise, friction and push from here on."""
        sim = self.sim
        if v.noise_seed is not None:
            sim.sensors.set_noise_state(np.random.default_rng(v.noise_seed).bit_generator.state)
        if v.friction_scale != 1.0:  # the terrain's friction is 0: MuJoCo takes the robot's
            sim.model.geom_friction[:, 0] *= v.friction_scale
            sim.model.pair_friction[:, :2] *= v.friction_scale
        if v.push_time > 0 and any(v.push):
            self._trunk = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_BODY, "trunk")
            self._push_until = sim.time + v.push_time

    def _actuate(self, targets) -> None:
        super()._actuate(targets)
        if np.isfinite(self._push_until):  # on while the push lasts, then off for good
            on = self.sim.time < self._push_until - 1e-9
            self.sim.data.xfrc_applied[self._trunk, :3] = self.variation.push if on else 0.0
            self._push_until = self._push_until if on else -np.inf

