"""The rollout teacher: each candidate foothold tried in branches of the run, the best taught.

At a decision of a run (:mod:`footfall.sim.branch`), the teacher tries the
base chooser's best ``candidates`` of F by its plan's value (the base chooser
is the walk's own planner: its reward, or a learned function) and, if asked,
the synthetic expert's best. Each is walked in ``branches`` branches of the
run for ``horizon`` steps after its own -- the base chooser choosing after it
-- each branch with its own variation (sensor noise, friction, a push on the
trunk), the same variations for every candidate (common random numbers: the
candidates are compared on the same luck). A branch's value is what followed,
with the weights of :class:`RolloutConfig`:

    value = - w_fall * fell - w_failed * (another failure)
            - w_slide * max(0, slide - STANCE_SLID) - w_miss * max(0, miss - MISSED)
            + w_progress * progress

``slide`` [m]: the most a foot put down in the branch travelled while it stood
(to its next lift-off, or to the branch's end for a foot still standing);
``miss`` [m]: the furthest a foot put down in the branch touched down from its
foothold; ``progress`` [m]: the body's advance along x from the decision. A
candidate's value is the mean over its branches; the best is taught if it is
above the base chooser's own choice by more than ``margin``, else the base's. By the rollout algorithm's policy-improvement
property the teacher walks at least as well as its base chooser in
expectation, to the extent the branches' value measures what matters.
"""

from __future__ import annotations

import copy
import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from footfall.control.footstep import FootstepPlan, FootstepPlanner
from footfall.core.errors import FootfallError
from footfall.core.params import Params, at_least, param, within
from footfall.core.robot import LEG_NAMES
from footfall.core.state import RobotState
from footfall.data.demonstration import Demonstration
from footfall.data.outcomes import MISSED, STANCE_SLID
from footfall.data.runlog import RunRecord
from footfall.expert.corrections import source_of
from footfall.expert.protocol import Expert, kept_verdict, teacher_verdict
from footfall.features.scorer import RewardFor
from footfall.sim.branch import Branched, BranchVariation, TapedWalk
from footfall.sim.task import foot_slip

__all__ = ["BranchOutcome", "RolloutConfig", "RolloutVerdict", "RolloutWalk", "branch_lines",
           "branch_variations", "refused_of", "rollout_verdict", "verdict_demonstrations",
           "verdict_record"]


BASES = ("teacher", "walker")  # RolloutConfig.base: whose choices the rollout improves on


@dataclass(frozen=True)
class RolloutConfig(Params):
    """What the rollout teacher tries at a decision and how it values what followed."""

    candidates: int = param(3, unit="candidates", range=at_least(1),
                            doc="K: the base chooser's best candidates of F tried, by its plan's "
                                "value")
    expert_best: bool = param(True, doc="also try the synthetic expert's best candidate")
    horizon: int = param(4, unit="steps", range=at_least(0),
                         doc="steps a branch walks after the decision's own (4: a crawl-gait "
                             "cycle)")
    branches: int = param(2, unit="branches", range=at_least(1),
                          doc="S: branches of each candidate, each with its own variation")
    friction: float = param(0.1, unit="-", range=within(0, 1, high_open=True),
                            doc="a branch's friction scale is uniform in 1 +- this")
    push: float = param(2.0, unit="N", range=at_least(0),
                        doc="largest horizontal push on the trunk: its size uniform up to this, "
                            "its direction uniform")
    push_time: float = param(0.2, unit="s", range=at_least(0),
                             doc="how long a branch's push lasts from the decision")
    margin: float = param(0.05, unit="value", range=at_least(0),
                          doc="another candidate is taught only if its value is above the base "
                              "chooser's by more than this (5 cm of progress, or 5 mm of slide)")
    refuse: float = param(0.5, unit="value", range=at_least(0),
                          doc="as labels: a tried candidate this far below the taught one is "
                              "refused (half a fall: it fell in at least half its branches "
                              "more than the taught one did, or as much worse)")
    w_fall: float = param(1.0, unit="value", range=at_least(0), doc="a fall in the branch")
    w_failed: float = param(0.5, unit="value", range=at_least(0),
                            doc="another failure in the branch: stuck, no foothold, out of time")
    w_slide: float = param(10.0, unit="value/m", range=at_least(0),
                           doc="per metre beyond STANCE_SLID (15 mm) a foot put down in the "
                               "branch travelled while it stood")
    w_miss: float = param(10.0, unit="value/m", range=at_least(0),
                          doc="per metre beyond MISSED (20 mm) a foot put down in the branch "
                              "touched down off its foothold")
    w_progress: float = param(1.0, unit="value/m", range=at_least(0),
                              doc="per metre the body advanced in the branch")
    base: str = param("teacher", choices=BASES,
                      doc="labelling a run another function walks: who is improved on -- the "
                          "teacher's own base (the accepted teacher) or the function walking "
                          "(the walker: policy iteration, the rollout over the student)")


@dataclass(frozen=True)
class BranchOutcome:
    """What followed one candidate in one branch."""

    candidate: int  # its index in the decision's F
    branch: int  # which variation (0 .. branches - 1)
    reason: str  # how the branch ended ("step limit": it walked its horizon; "goal")
    fell: bool  # the trunk tilted over or touched the terrain
    failed: bool  # another failure: stuck, no foothold, out of time
    slide: float  # [m] the most a foot put down in the branch travelled while it stood
    miss: float  # [m] the furthest a foot put down in the branch touched down off its foothold
    progress: float  # [m] the body's advance along x from the decision to the branch's end
    value: float  # [value units] by the weights of RolloutConfig

    def describe(self) -> str:
        """In a few words, for a person deciding ("slid 22 mm", "fell", "walked on")."""
        if self.fell:
            return "fell"
        if self.failed:
            return self.reason
        parts = []
        if self.slide > STANCE_SLID:
            parts.append(f"slid {1e3 * self.slide:.0f} mm")
        if self.miss > MISSED:
            parts.append(f"missed by {1e3 * self.miss:.0f} mm")
        return ", ".join(parts) or ("crossed" if self.reason == "goal" else "walked on")


@dataclass(frozen=True)
class RolloutVerdict:
    """The rollout teacher at one decision: what it tried, how each went, what it teaches."""

    decision: int  # the decision's index in the run
    base: int  # the base chooser's choice (index in F)
    tried: np.ndarray  # (m,) int: the candidates tried (indices in F), the base's first
    values: np.ndarray  # (m,) [value units] each one's mean value over its branches
    outcomes: tuple[BranchOutcome, ...]  # (m * branches,) candidate by candidate
    best: int  # the candidate taught (index in F): the best, unless within the margin of the base


def branch_variations(config: RolloutConfig, seed: int, decision: int) -> list[BranchVariation]:
    """The ``config.branches`` variations of the branches at ``decision`` of the run with seed
    ``seed``: the same for every candidate there, another draw at every decision."""
    out = []
    for s in range(config.branches):
        rng = np.random.default_rng([seed, decision, s])
        angle, size = rng.uniform(0.0, 2.0 * math.pi), rng.uniform(0.0, config.push)
        out.append(BranchVariation(
            noise_seed=int(rng.integers(2 ** 63)),
            friction_scale=1.0 + config.friction * rng.uniform(-1.0, 1.0),
            push=(size * math.cos(angle), size * math.sin(angle), 0.0),
            push_time=config.push_time))
    return out


def outcome_of(branched: Branched, first_step: int, start_x: float, candidate: int,
               branch: int, config: RolloutConfig) -> BranchOutcome:
    """What followed ``candidate`` in a branch whose steps from ``first_step`` on are its own;
    ``start_x`` [m]: the body's x at the decision."""
    record = branched.record
    reason = str(record.result["reason"])
    fell = reason.startswith("fall")
    failed = not record.result["success"] and not fell and reason != "step limit"
    slide = miss = 0.0
    last = {}  # leg -> its last touch-down in the branch
    for step in record.steps[first_step:]:
        if not np.isfinite(step.touchdown).all():
            continue
        miss = max(miss, float(np.hypot(*(step.touchdown[:2] - step.foothold[:2]))))
        if np.isfinite(step.slip):
            slide = max(slide, float(step.slip))
        last[step.swing_leg] = step
    for leg, step in last.items():  # feet still standing at the end: their travel so far
        if not np.isfinite(step.slip):
            moved = foot_slip(step.touchdown, branched.feet[LEG_NAMES.index(leg)])
            slide = max(slide, float(moved))
    progress = float(branched.body[0] - start_x)
    value = (-config.w_fall * fell - config.w_failed * failed
             - config.w_slide * max(0.0, slide - STANCE_SLID)
             - config.w_miss * max(0.0, miss - MISSED) + config.w_progress * progress)
    return BranchOutcome(candidate, branch, reason, fell, failed, slide, miss, progress,
                         float(value))


def rollout_verdict(walk: TapedWalk, at: int, config: RolloutConfig = RolloutConfig(),
                    expert: Expert | None = None, base_plan: FootstepPlan | None = None
                    ) -> RolloutVerdict:
    """The rollout teacher at decision ``at`` of the walked ``walk`` (see the module);
    ``expert``: whose best candidate is tried too (with ``config.expert_best``);
    ``base_plan``: the base chooser's plan of the decision's state where the base is not the
    walk's own planner (it continues the branches: ``walk.branch_planner``)."""
    decisions = walk.tape.decisions
    if not 0 <= at < len(decisions):
        raise FootfallError(f"rollout: no decision {at} in this run (it made {len(decisions)})")
    decision = decisions[at]
    plan = decision.plan if base_plan is None else base_plan
    if not np.array_equal(plan.candidates, decision.plan.candidates):
        raise FootfallError(f"rollout: the base chooser's F at decision {at} is not the run's")
    ranked = np.argsort(-np.nan_to_num(plan.value, nan=-np.inf), kind="stable")
    ranked = ranked[np.isfinite(plan.value[ranked])][:config.candidates]
    tried = [plan.index] + [int(i) for i in ranked if i != plan.index]
    tried = tried[:config.candidates]
    if config.expert_best and expert is not None:
        best = int(np.argmax(expert.values(walk.hmap, plan.state, plan.candidates)))
        tried += [] if best in tried else [best]
    first_step = len(decision.task.steps)
    start_x = float(decision.state.body_position[0])
    variations = branch_variations(config, walk.seed, at)
    tries = [(c, v) for c in tried for v in variations]

    def judge(branched: Branched, i: int) -> dict:
        c, s = tries[i][0], i % config.branches
        return asdict(outcome_of(branched, first_step, start_x, c, s, config))

    outcomes = [BranchOutcome(**o) for o in walk.try_candidates(at, tries, config.horizon, judge)]
    values = np.array([o.value for o in outcomes]).reshape(len(tried), config.branches)
    values = values.mean(axis=1)
    top = int(np.argmax(values))
    best = tried[top] if values[top] > values[0] + config.margin else plan.index
    return RolloutVerdict(at, plan.index, np.array(tried), values, tuple(outcomes), int(best))


class RolloutWalk(TapedWalk):
    """A walk whose footholds the rollout teacher chooses: at each decision the base chooser's
    plan (the walk's own planner), its verdict, and the foothold it teaches (:attr:`verdicts`
    keeps every verdict). Built as :class:`TapedWalk`, with the teacher's ``rollout``
    settings and the ``expert`` whose best candidate it tries too; ``take`` False: the walk's
    own planner walks on with its own choice and the verdicts are labels of its states
    (:func:`verdict_demonstrations`). ``base``: the base chooser's reward where it is not the
    walk's (e.g. the accepted teacher's, labelling a learned function's runs): it ranks the
    candidates tried and continues every branch, on the walk's body path."""

    def __init__(self, *args, rollout: RolloutConfig = RolloutConfig(),
                 expert: Expert | None = None, take: bool = True,
                 base: RewardFor | None = None, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.rollout, self.expert, self.take = rollout, expert, take
        self.verdicts: list[RolloutVerdict] = []
        if base is not None:
            own = self.own_planner
            self.branch_planner = FootstepPlanner(self.hmap, base, own.path, self.robot,
                                                  own.config)

    def _decide(self, planner, index: int, state: RobotState) -> FootstepPlan:
        if self._forked is not None:  # a branch: the base chooser from here on
            return (self.branch_planner or planner).plan(state)
        plan = super()._decide(planner, index, state)  # kept as the walk's planner planned
        base = None if self.branch_planner is None else self.branch_planner.plan(state)
        verdict = rollout_verdict(self, index, self.rollout, self.expert, base_plan=base)
        self.verdicts.append(verdict)
        if verdict.best == plan.index or not self.take:
            return plan
        taught = planner.plan(state, first=verdict.best)  # what the run takes, and replays
        decisions = self.tape.decisions
        decisions[index] = replace(decisions[index], plan=copy.deepcopy(taught))
        return taught

    def _settings(self) -> dict:
        settings = super()._settings()
        if self.take:
            settings["teacher"] = {"rollout": self.rollout.to_dict(),
                                   "expert_best": self.expert is not None}
        return settings


def verdict_record(verdict: RolloutVerdict) -> dict:
    """A verdict as its label keeps it (JSON, in the label's settings): the base chooser's
    choice, the candidates tried, each one's value [value units] and every branch's outcome."""
    return {"base": int(verdict.base), "tried": [int(c) for c in verdict.tried],
            "values": [float(v) for v in verdict.values],
            "outcomes": [asdict(o) for o in verdict.outcomes]}


def branch_lines(kept: dict) -> list[dict]:
    """What followed each candidate tried, for a person deciding (the teaching page): from a
    :func:`verdict_record`, per candidate its index in F, its value [value units], whether it
    was the base chooser's, and its branches' outcomes in words ("slid 22 mm", "fell")."""
    words: dict[int, list[str]] = {}
    for o in kept["outcomes"]:
        words.setdefault(int(o["candidate"]), []).append(BranchOutcome(**o).describe())
    return [{"candidate": int(c), "value": float(v), "base": int(c) == int(kept["base"]),
             "outcomes": words.get(int(c), [])} for c, v in zip(kept["tried"], kept["values"])]


def refused_of(verdict: RolloutVerdict, refuse: float) -> np.ndarray:
    """(m,) bool over ``verdict.tried``: the candidates more than ``refuse`` [value units]
    below the taught one's value."""
    best = verdict.values[list(verdict.tried).index(verdict.best)]
    return verdict.values < best - refuse


def verdict_demonstrations(walk: RolloutWalk, record: RunRecord, run_key: str,
                           every_step: bool = True, cap: int | None = None,
                           untried: Expert | None = None) -> list[Demonstration]:
    """The rollout teacher's labels of the steps of ``record`` (the run ``walk`` walked,
    stored as ``run_key``): one demonstration a step, sourced ``run:<run_key>:step:<k>``, its
    choice the verdict's best, the tried candidates refused where they lie more than
    ``rollout.refuse`` below it -- by their branches alone --, the untried ones where
    ``untried`` (the base teacher's face on a state alone) refuses them (None: never; no
    values are kept: the teacher valued only what it tried; its verdict, with every branch's
    outcome, is kept in the label's settings: :func:`verdict_record`); ``every_step`` False: only the
    steps where it taught another foothold than the run took; ``cap``: at most this many,
    those it valued most above the run's own choice (ties: the earlier). A step planned
    again after it was called off is labelled at its last decision."""
    last = {len(walk.tape.decisions[v.decision].task.steps): v for v in walk.verdicts}
    settings = {"class": f"{__name__}.RolloutVerdict", "config": walk.rollout.to_dict(),
                "expert_best": walk.expert is not None,
                "untried": None if untried is None else type(untried).__name__}
    out, gains = [], []
    for step in record.steps:
        verdict = last.get(step.k)
        if verdict is None or (not every_step and verdict.best == step.chosen):
            continue
        tried = list(verdict.tried)
        own = verdict.values[tried.index(step.chosen)] if step.chosen in tried else -np.inf
        gains.append(verdict.values[tried.index(verdict.best)] - own)
        plan = walk.tape.decisions[verdict.decision].plan
        if not np.array_equal(plan.candidates, step.candidates):
            raise FootfallError(f"rollout labels: step {step.k} is not its decision's")
        refused = np.zeros(step.candidates.shape[0], dtype=bool)
        if untried is not None:  # the base teacher's word where no branch was walked
            values, base_refused, judged = teacher_verdict(untried, walk.hmap, step.state,
                                                           step.candidates)
            refused = kept_verdict(values, base_refused, judged, verdict.best)[1].copy()
            refused[verdict.tried] = False
        refused[verdict.tried[refused_of(verdict, walk.rollout.refuse)]] = True
        out.append(Demonstration(record.terrain_hash, step.state, step.candidates,
                                 verdict.best, source=source_of(run_key, step.k),
                                 expert={**settings, "verdict": verdict_record(verdict)},
                                 refused=refused))
    if cap is not None and len(out) > cap:
        keep = np.sort(np.argsort(-np.array(gains), kind="stable")[:cap])
        out = [out[i] for i in keep]
    return out
