"""Benchmark of the rankers: learning time, and scoring 45 000 candidates with each learned
function against the linear function of the paper, in the same process.

``bench_rankers``: the L1 learner, the kernel ranker and the boosted ranker learn the
templates + features set from the same demonstrations (the learning benchmark's problem,
fixed bandwidths); each function then values one candidate set of 45 000 footholds on a rocky
board from patches already extracted (every feature, then the function: what a planner pays
for a non-separable value, and for a linear one through the same path). The boosted function's forest evaluation alone
is timed too (the tests check it against LightGBM's own predictions).
"""

from __future__ import annotations

import time

import numpy as np

from footfall.core.seeds import check_seed_span
from footfall.core.state import nominal_state
from footfall.expert.collect import collect_demonstrations
from footfall.expert.synthetic import SyntheticExpert
from footfall.features.family import Candidates
from footfall.learning.train import TrainingDemo, learn_model
from footfall.terrain import make_board

N_CANDIDATES = 45_000  # the candidates scored at once (a 150 x 300 lattice at 2 mm)
LEARNERS = ("l1", "kernel", "lambdarank")


def bench_rankers(n_demos: int = 100, library_size: int = 1000, repeats: int = 3,
                  seed: int = 0) -> dict:
    """Learning and scoring figures per learner; ratios against the L1 (linear) function."""
    check_seed_span(seed, 5, "the seed")
    boards = [make_board([(k, d)], seed + i) for i, (k, d) in
              enumerate([("rocky", 0.5), ("rocky", 0.8), ("steps", 0.6), ("barrier", 0.6),
                          ("slope", 0.6)])]
    maps = {b.content_hash(): b for b in boards}
    demos = collect_demonstrations(boards, SyntheticExpert(), n_demos, seed)
    training = [TrainingDemo.of(d, maps[d.terrain_hash]) for d in demos]
    board = boards[1]
    state = nominal_state(board, (0.0, 0.0), 0.0, "LF")
    x0, x1, y0, y1 = board.bounds
    xs = np.linspace(-0.15, 0.15, 300)
    ys = np.linspace(-0.15, 0.15, N_CANDIDATES // 300)
    xy = np.stack(np.meshgrid(xs, ys, indexing="ij"), axis=-1).reshape(-1, 2)
    xy = np.clip(xy, [x0 + 0.05, y0 + 0.05], [x1 - 0.05, y1 - 0.05])
    footholds = np.column_stack([xy, board.height_at(xy)])
    out: dict = {"demonstrations": len(training), "candidates": int(footholds.shape[0]),
                 "library_size": library_size, "learners": {}}
    for name in LEARNERS:
        t0 = time.perf_counter()
        model = learn_model(training, "both", name, library_size=library_size,
                            bandwidth_rms=(0.004,) * 3, seed=seed)
        learn = time.perf_counter() - t0
        scorer = model.reward_for("LF")
        times, values = [], None
        for _ in range(repeats):
            c = Candidates.of_state(board, state, footholds, model.config)
            c.patches  # the patches are every scorer's common cost: extracted before the clock
            t0 = time.perf_counter()
            values = scorer.values(c)
            times.append(time.perf_counter() - t0)
        f = model.functions["front"]
        out["learners"][name] = {
            "learn_seconds": learn, "score_seconds": float(np.median(times)),
            "valid_finite": int(np.isfinite(values).sum()),
            "templates_kept": model.templates_kept()["front"]["kept"],
            "trees": f.info.get("trees")}
        if name == "lambdarank":
            # the forest alone, on the valid candidates' features
            c = Candidates.of_state(board, state, footholds, model.config)
            X = np.hstack([fam.compute(c) for fam in f.families])[c.patches.valid]
            t0 = time.perf_counter()
            f.predict(X)
            out["forest_seconds"], out["forest_rows"] = time.perf_counter() - t0, int(X.shape[0])
    linear = out["learners"]["l1"]["score_seconds"]
    for r in out["learners"].values():
        r["score_vs_linear"] = r["score_seconds"] / linear
    return out


def format_rankers(r: dict) -> str:
    """Human-readable summary of :func:`bench_rankers`."""
    lines = [f"rankers: {r['demonstrations']} demonstrations, library {r['library_size']}, "
             f"{r['candidates']} candidates valued at once"]
    for name, v in r["learners"].items():
        lines.append(f"  {name:10s} learn {v['learn_seconds']:7.1f} s, score "
                     f"{v['score_seconds']:6.2f} s ({v['score_vs_linear']:.2f} x linear), "
                     f"templates kept {v['templates_kept']}"
                     + (f", {v['trees']} trees" if v["trees"] else ""))
    lines.append(f"  forest alone on {r['forest_rows']} rows: {r['forest_seconds']:.3f} s")
    return "\n".join(lines)
