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
walk's own planner (or its :attr:`TapedWalk.branch_planner`: another chooser
continuing the branches). Forcing the recorded choice gives the recorded run, bit
for bit to its end (tests/test_branch.py); a branch costs its replay (the
control periods before the decision, no physics and no planning) and its own
walking. During the run, at the decision it is making,
:meth:`TapedWalk.try_candidates` forks the process instead: each copy is the
run at that moment and walks on as its branch, nothing replayed, and returns
what its judge says as JSON -- the same answers as the replay (about half its
cost: ``footfall bench branch``). A fork copies a process that must not hold
running threads (a run holds none: it walks on one core).
"""

from __future__ import annotations

import copy
import json
import os
import time
from collections.abc import Callable
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
    physics_cpu: float = 0.0  # [s] CPU time of the branch's own physics steps (benchmarks)


@dataclass
class Tape:
    """What a taped run keeps: every measurement its controller read, in order (the first at
    the start, then one a control period), and every decision."""

    measurements: list[Measurements] = field(default_factory=list)
    decisions: list[Decision] = field(default_factory=list)


class _Recorded:
    """The footstep planner of a run, its calls seen by ``on_plan(planner, index, state,
    first)`` (which plans); everything else is the planner's."""

    def __init__(self, planner, on_plan, in_branch: Callable[[], object] = lambda: None
                 ) -> None:
        self._planner, self._on_plan, self._calls = planner, on_plan, 0
        self._in_branch = in_branch  # the planner of a forked branch's own decisions (None: this)

    def plan(self, state: RobotState) -> FootstepPlan:
        index, self._calls = self._calls, self._calls + 1
        try:
            return self._on_plan(self._planner, index, state)
        except _BranchHere as here:  # a forked copy of the run: it goes on from here, this way
            return (self._in_branch() or self._planner).plan(state, first=here.first)


class _BranchHere(BaseException):
    """Raised in a forked copy of a run at its decision, to take candidate ``first`` there
    (None: the planner's own choice); caught where the planner was called. A BaseException,
    so that nothing between catches it as an error."""

    def __init__(self, first: int | None) -> None:
        super().__init__(first)
        self.first = first


class _Varied(Walk):
    """A walk whose physics can be varied from a moment on (:class:`BranchVariation`)."""

    _variation: BranchVariation | None = None
    _push_until: float = -np.inf  # [s] simulated time the push ends

    def _vary(self, v: BranchVariation) -> None:
        """The walk's own noise, friction and push from here on."""
        sim = self.sim
        self._variation = v
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
            self.sim.data.xfrc_applied[self._trunk, :3] = self._variation.push if on else 0.0
            self._push_until = self._push_until if on else -np.inf

    def __getattr__(self, name: str):
        return getattr(self._planner, name)


class TapedWalk(_Varied):
    """A walk that can be branched at any of its decisions (see the module's docstring).

    Built as :class:`~footfall.sim.episode.Walk` is; :meth:`run` walks and keeps
    :attr:`tape`; :meth:`branch` walks another run from one of its decisions.
    """

    branch_processes: int = 1  # forked branches walked at once (try_candidates)

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.tape = Tape()
        self.own_planner = self.controller.planner  # the walk's footstep planner, unwrapped
        self.branch_planner = None  # who chooses in a branch, at its decision and after it (a
        # footstep planner on the same body path); None: the walk's own planner
        self.controller.planner = _Recorded(self.controller.planner, self._decision,
                                            lambda: self.branch_planner)
        self._deciding: int | None = None  # the decision being made now
        self._forked: tuple[int, Callable, int] | None = None  # in a forked branch: its pipe,
        # its judge and its index among the tries

    def _measure(self) -> Measurements:
        m = super()._measure()
        self.tape.measurements.append(m)
        return m

    def _decision(self, planner, index: int, state: RobotState) -> FootstepPlan:
        self._deciding = index
        try:
            return self._decide(planner, index, state)
        finally:
            self._deciding = None

    def _decide(self, planner, index: int, state: RobotState) -> FootstepPlan:
        """A decision of the run: the state kept, then the planner's choice (in a forked
        branch, after its own decision: the planner's choice alone)."""
        if self._forked is not None:
            return (self.branch_planner or planner).plan(state)
        physics, noise = self.sim.state(), self.sim.sensors.noise_state()
        task = copy.deepcopy(self.task)
        periods = len(self.tape.measurements) - 1
        plan = planner.plan(state)
        self.tape.decisions.append(Decision(index, periods, physics, noise, task,
                                            copy.deepcopy(state), copy.deepcopy(plan)))
        return plan

    def try_candidates(self, at: int, tries: list[tuple[int | None, BranchVariation]],
                       steps: int, judge: Callable[[Branched, int], dict]) -> list[dict]:
        """``judge(branched, i)`` (a JSON object) of each try ``i``, a (candidate, variation)
        walked from decision ``at`` for ``steps`` steps after the decision's own.

        At the decision the run is making now (from within :meth:`_decide`), each try is a
        forked copy of this process (``os.fork``: nothing replayed, ``branch_processes`` at
        once; the judge runs in the copy and its answer comes back as JSON); at any other
        decision, or where there is no fork, :meth:`branch` (the replay). The two give the
        same answers (tests/test_branch.py).
        """
        if self._deciding == at and hasattr(os, "fork"):
            return self._forked_tries(tries, steps, judge)
        return [judge(self.branch(at, first, steps, v), i)
                for i, (first, v) in enumerate(tries)]

    def _forked_tries(self, tries, steps: int, judge) -> list[dict]:
        limit = len(self.task.steps) + 1 + require_int(steps, "steps", 0)
        answers: list[dict | None] = [None] * len(tries)
        running: dict[int, tuple[int, int]] = {}  # pid -> (read end, try)
        for i, (first, variation) in enumerate(tries):
            if len(running) >= max(1, self.branch_processes):
                self._collect(running, answers)
            read, write = os.pipe()
            pid = os.fork()
            if pid == 0:  # the branch: from here the run goes on as it
                os.close(read)
                self._forked = (write, judge, i)
                self.sim.physics_cpu = 0.0  # the branch's own from here
                self.controller.config = replace(self.controller.config, max_steps=limit)
                self._vary(variation)
                raise _BranchHere(first)
            os.close(write)
            running[pid] = (read, i)
        while running:
            self._collect(running, answers)
        return answers

    @staticmethod
    def _collect(running: dict, answers: list) -> None:
        """Wait for one forked branch; its answer into ``answers``."""
        pid, status = os.wait()
        read, i = running.pop(pid)
        with os.fdopen(read, "rb") as pipe:
            data = pipe.read()
        if os.waitstatus_to_exitcode(status) != 0 or not data:
            raise FootfallError(f"a forked branch (try {i}) failed: exit status "
                                f"{os.waitstatus_to_exitcode(status)}")
        answers[i] = json.loads(data)

    def _periods(self, wall0: float) -> RunRecord:
        # A forked branch is made inside this call and returns through it: whether it is one is
        # known only at the end. It ends here -- its answer to the pipe, and the copy is gone.
        try:
            record = super()._periods(wall0)
        except BaseException:
            if self._forked is not None:
                os._exit(70)
            raise
        if self._forked is None:
            return record
        write, judge, i = self._forked
        try:
            branched = Branched(record, self.sim.foot_positions(), self.sim.body_pose()[0],
                                self.sim.physics_cpu)
            data = json.dumps(judge(branched, i)).encode()
            while data:
                data = data[os.write(write, data):]
            os.close(write)
        except BaseException:
            os._exit(70)
        os._exit(0)

    def branch(self, at: int, first: int | None = None, steps: int | None = None,
               variation: BranchVariation | None = None) -> Branched:
        """The run walked again from decision ``at`` (an index into ``tape.decisions``), there
        taking the candidate ``first`` of its F (an index into its plan's candidates; None: the
        recorded choice), after it choosing as this walk does (its :attr:`branch_planner` if
        set, which also rolls out ``first``); ``steps``: only that many steps after the
        decision's own (then "step limit"; None: to the run's end); ``variation``: the
        branch's own noise, friction and push."""
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
        return Branched(record, walk.sim.foot_positions(), walk.sim.body_pose()[0],
                        walk.sim.physics_cpu)


class _Branch(_Varied):
    """A walk from a decision of a taped one (:meth:`TapedWalk.branch`)."""

    def __init__(self, source: TapedWalk, at: int, first: int | None, config,
                 variation: BranchVariation) -> None:
        super().__init__(source.hmap, source.reward_for, source.seed, config, source.robot,
                         judge=source.judge)
        self.source, self.at, self.first, self.variation = source, at, first, variation
        self.controller.planner = _Recorded(self.controller.planner, self._decide)

    def _decide(self, planner, index: int, state: RobotState) -> FootstepPlan:
        """Before the decision the recorded plans (the state checked against the recorded
        one); at it the candidate asked for; after it the planner's own choice."""
        chooser = self.source.branch_planner or planner
        if index > self.at:
            return chooser.plan(state)
        recorded = self.source.tape.decisions[index]
        if not (np.array_equal(state.to_vector(), recorded.state.to_vector())
                and state.swing_leg == recorded.state.swing_leg):
            raise FootfallError(f"branch: the replay left the recorded run at decision {index}")
        if index < self.at or self.first is None:
            return copy.deepcopy(recorded.plan)
        return chooser.plan(state, first=self.first)

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
