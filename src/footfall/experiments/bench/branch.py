"""Benchmark of branching a run: what trying a candidate foothold from a decision costs.

``bench_branch`` walks the controller test board with the hand-tuned reward and, at
decisions spread over the run, tries the same candidates (the planner's best ``tries``,
one branch each, a crawl-gait cycle long) both ways a run can be branched: in a copy of the
process forked at the decision (how the rollout teacher walks) and by replay after the run
(:meth:`~footfall.sim.branch.TapedWalk.branch`: a fresh walk, its controller replayed
through the recorded measurements). Each branch's CPU time is set against the CPU time of
its own physics steps (MuJoCo's, counted by the simulation) -- the floor no branching can go
under -- and the two ways against each other. The answers of the two ways must agree.
"""

from __future__ import annotations

import platform
import time

import numpy as np

from footfall.features.reward import default_reward
from footfall.sim.branch import Branched, BranchVariation, TapedWalk
from footfall.sim.episode import WalkConfig
from footfall.terrain import make_board

TEST_BOARD = ([("rocky", 0.7), ("steps", 0.7)], 500)  # the controller test board and its seed
BRANCH_PHYSICS_TARGET = 1.3  # [-] a forked branch's CPU at most this many times its physics'


def _judge(branched: Branched, i: int) -> dict:
    """A branch's answer: how it ended, where the body got, and its CPU times [s] (in a forked
    copy: the copy's own CPU, which starts at 0 at the fork)."""
    return {"reason": branched.record.result["reason"], "x": float(branched.body[0]),
            "physics_cpu": branched.physics_cpu, "cpu": time.process_time()}


class _Timed(TapedWalk):
    """The hand-tuned reward's run, its candidates tried in forked copies at some decisions."""

    def __init__(self, *args, at: set[int], tries: int, steps: int, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.at, self.tries, self.steps = at, tries, steps
        self.forked: dict[int, tuple[list[int], list[dict], float]] = {}

    def _decide(self, planner, index, state):
        plan = super()._decide(planner, index, state)
        if self._forked is None and index in self.at:
            order = np.argsort(-np.nan_to_num(plan.value, nan=-np.inf), kind="stable")
            firsts = [int(c) for c in order[:self.tries]]
            t0 = time.perf_counter()
            answers = self.try_candidates(index, [(c, BranchVariation()) for c in firsts],
                                          self.steps, _judge)
            self.forked[index] = (firsts, answers, time.perf_counter() - t0)
        return plan


def bench_branch(seed: int = 5000, decisions: int = 4, tries: int = 3, steps: int = 4) -> dict:
    """CPU time of a branch forked at a decision and of one replayed after the run, against
    the physics of its own steps (see the module): ``decisions`` decisions spread over one
    run (seed ``seed``), ``tries`` candidates each, ``steps`` steps after the decision's own."""
    specs, board_seed = TEST_BOARD
    hmap = make_board(specs, seed=board_seed)
    reward = default_reward()
    config = WalkConfig()
    probe = TapedWalk(hmap, lambda leg: reward, seed, config)
    probe.run()
    n = len(probe.tape.decisions)
    at = {int(k) for k in np.linspace(1, n - 2, decisions).round()}
    walk = _Timed(hmap, lambda leg: reward, seed, config, at=at, tries=tries, steps=steps)
    walk.run()
    rows, agree = [], True
    for index in sorted(walk.forked):
        firsts, answers, wall = walk.forked[index]
        for c, forked in zip(firsts, answers):
            t0 = time.process_time()
            replayed = walk.branch(index, c, steps)
            cpu = time.process_time() - t0
            again = _judge(replayed, 0)
            agree &= (again["reason"], again["x"]) == (forked["reason"], forked["x"])
            rows.append({"decision": index, "of": n, "forked_cpu_s": forked["cpu"],
                         "replayed_cpu_s": cpu, "physics_cpu_s": forked["physics_cpu"]})
        rows[-1]["decision_wall_s"] = wall
    f = np.array([r["forked_cpu_s"] for r in rows])
    r = np.array([r["replayed_cpu_s"] for r in rows])
    p = np.array([r["physics_cpu_s"] for r in rows])
    return {"machine": platform.processor() or platform.machine(), "board": "rocky 0.7 | steps "
            "0.7, board seed 500", "seed": seed, "decisions": n, "tries": tries, "steps": steps,
            "branches": rows, "agree": bool(agree),
            "forked_over_physics": float(np.median(f / p)),
            "replayed_over_physics": float(np.median(r / p)),
            "replayed_over_forked": float(np.median(r / f)),
            "target_forked_over_physics": BRANCH_PHYSICS_TARGET}


def format_branch(result: dict) -> str:
    """The benchmark as a table and its ratios."""
    lines = [f"branching a run: {result['board']}, run seed {result['seed']} "
             f"({result['decisions']} decisions), {result['tries']} candidates at each decision "
             f"timed, {result['steps']} steps after it",
             "decision | forked CPU [s] | replayed CPU [s] | its physics CPU [s]"]
    for row in result["branches"]:
        lines.append(f"{row['decision']:>4} of {row['of']} | {row['forked_cpu_s']:.3f} | "
                     f"{row['replayed_cpu_s']:.3f} | {row['physics_cpu_s']:.3f}")
    lines.append(f"median ratios: forked / physics {result['forked_over_physics']:.2f} "
                 f"(target <= {result['target_forked_over_physics']:g}), replayed / physics "
                 f"{result['replayed_over_physics']:.2f}, replayed / forked "
                 f"{result['replayed_over_forked']:.2f}; the two ways agree: {result['agree']}")
    return "\n".join(lines)
