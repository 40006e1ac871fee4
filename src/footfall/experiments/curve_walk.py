"""Walking a learning curve's points (``footfall curve-walk``): the offline measure tied to crossings.

A learning curve (:mod:`footfall.experiments.learning_curve`) measures every
point on held-out *decisions*: how often a function's pick falls short of the
expert's best. Whether a point that ranks better also walks better is a
question only walking answers. ``curve-walk`` walks the saved models of one
feature set and learner -- every draw's model at each chosen size -- on
held-out walking boards, with the same run seeds for every model and for the
references (the hand-tuned reward that learning starts from, and optionally
the walking expert choosing every foothold), so every comparison is paired
(:mod:`footfall.experiments.paired`).

**Boards.** ``boards`` boards of the modules ``board`` (by default
``rocky:0.7 steps:0.7``, the reproduction's test board at the difficulty its
calibration chose), with seeds from the curve's stream "boards" at index 2:
the curve's training boards draw from index 0 and its held-out decisions from
index 1, so no walking board was trained on or measured offline. Run seeds come
from the curve's stream "evaluation runs" (which the curve itself does not
use), the same on every board.

**What it reports**, per size (pooled over the draws, and per draw): the
crossings, the mean slip of the crossing runs' footholds, the share of the
runs' steps whose shortfall against the expert's best in F is above the
correction margin (the expert's verdict on every step, as the reproduction
reports it), the point's offline share above the margin beside it, and the
paired comparison with the hand-tuned reward (exact McNemar over the
(draw, board, seed) units: the reference's run of a unit is the same for
every draw, so the pooled pairs share their reference side) and of the largest
size with the smallest (each draw's two models on the same units).

Every run is stored under ``METHOD/BOARD/sSEED`` in ``CURVE/walk/walks.sqlite``
as it arrives; a rerun walks only what is missing, and other sizes, feature
sets, learners or references in the same folder add their runs (other boards,
runs or walking settings are refused).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError
from footfall.core.folders import holding_folders
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, at_least, param
from footfall.core.seeds import SeedStreams
from footfall.data.store import DemoStore
from footfall.experiments.curve_report import read_curve
from footfall.experiments.executors import Executor, LocalPool
from footfall.experiments.learning_curve import point_model_path
from footfall.experiments.paired import RunOutcome, compare
from footfall.experiments.reproduce import is_board_spec, reproduction_walk
from footfall.experiments.runs import RunJob, Runner, board_files, claim_folder
from footfall.experiments.workspace import Spec
from footfall.expert.corrections import DEFAULT_MARGIN, step_verdicts
from footfall.expert.synthetic import SyntheticExpert, walking_expert
from footfall.learning.learner import LEARNERS
from footfall.sim.episode import WalkConfig

FOLDER = "walk"  # inside the curve's folder
STORE_NAME = "walks.sqlite"
REFERENCES = ("hand-tuned", "expert")  # the reward learning starts from; the teacher choosing
@dataclass(frozen=True)
class CurveWalkConfig(Params):
    """Which curve points walk, where and how often; written next to the runs."""

    sizes: tuple[int, ...] = param((100, 1600), check=lambda v: isinstance(v, tuple) and len(
        v) > 0 and all(isinstance(n, int) and n >= 1 for n in v) and list(v) == sorted(set(v)),
        must="increasing whole numbers", doc="the curve's sizes (demonstrations) walked")
    feature_set: str = param("both", check=lambda v: isinstance(v, str) and bool(v),
                             must="a feature set of the curve", doc="the points' feature set")
    learner: str = param("lambdarank", check=lambda v: v in LEARNERS,
                         must="a registered learner", doc="the points' learner")
    references: tuple[str, ...] = param(
        ("hand-tuned",), check=lambda v: isinstance(v, tuple) and "hand-tuned" in v
        and set(v) <= set(REFERENCES) and len(set(v)) == len(v),
        must="'hand-tuned', optionally with 'expert'",
        doc="the references walked on the same units (the expert's runs cost several "
            "hand-tuned ones)")
    board: Spec = param((("rocky", 0.7), ("steps", 0.7)), check=is_board_spec,
                        must="a tuple of (known kind, difficulty in [0, 1])",
                        doc="the modules of every walking board")
    boards: int = param(4, range=at_least(1), doc="walking boards (seeds of their own)")
    runs: int = param(8, range=at_least(1), doc="runs on each board (the same seeds on each)")
    walk: WalkConfig = param(factory=reproduction_walk,
                             doc="the walk: the reproduction's (F within its search radius)")


FREE = ("sizes", "feature_set", "learner", "references")  # choose which runs, not how


def _unit_seeds(curve_seed: int, config: CurveWalkConfig) -> tuple[list[int], list[int]]:
    """The walking boards' seeds and the run seeds (the curve's streams, see the module)."""
    streams = SeedStreams("learning curve", curve_seed)
    return ([streams.seed_for("boards", 2, i) for i in range(config.boards)],
            [streams.seed_for("evaluation runs", r) for r in range(config.runs)])


def _methods(curve: dict, out: Path, config: CurveWalkConfig) -> dict[str, str | None]:
    """Method name -> model file (None: a reference) of every model walked."""
    fs, ln = config.feature_set, config.learner
    methods: dict[str, str | None] = {r: None for r in config.references}
    for n in config.sizes:
        draws = sorted({p["draw"] for p in curve["points"]
                        if (p["n"], p["feature_set"], p["learner"]) == (n, fs, ln)})
        if not draws:
            raise FootfallError(f"the curve holds no point {fs}/{ln} at {n} demonstrations; "
                                f"measure it with footfall learning-curve first")
        for d in draws:
            path = point_model_path(out, d, n, fs, ln)
            if not path.exists():
                raise FootfallError(f"{path} is missing: the curve's model of that point")
            methods[f"{fs}-{ln}-{n}-draw{d}"] = str(path)
    return methods


def _jobs(methods: dict[str, str | None], paths: dict[str, Path], seeds: list[int],
          walk: WalkConfig) -> list[RunJob]:
    """Every run: the references first, then the models (key ``METHOD/BOARD/sSEED``)."""
    jobs = []
    for m, model in methods.items():
        for name, path in paths.items():
            jobs += [RunJob(f"{m}/{name}/s{s}", str(path), model, s, walk,
                            expert=walking_expert(walk.footstep.lead), judge=m == "expert")
                     for s in seeds]
    return jobs


@holding_folders
def run_curve_walk(curve_out: str | Path, config: CurveWalkConfig | None = None,
                   processes: int | None = None, log: Callable[[str], None] = print,
                   executor: Executor | None = None) -> dict:
    """Walk (or resume) the points into ``CURVE/walk/``; return the summary (also
    ``walk-FEATURES-LEARNER.json`` and ``.md`` there: one report per walked feature set and
    learner, so walking another keeps the first's)."""
    config = CurveWalkConfig() if config is None else config
    curve_out = Path(curve_out)
    curve = read_curve(curve_out)
    out = curve_out / FOLDER
    methods = _methods(curve, curve_out, config)
    claim_folder(out, config.to_dict(), "a curve's walks", free=FREE)
    board_seeds, run_seeds = _unit_seeds(int(curve["config"]["seed"]), config)
    paths = board_files(out, {f"walk{i}": (config.board, s, True)
                              for i, s in enumerate(board_seeds)})
    maps = {n: HeightMap.load(p) for n, p in paths.items()}
    jobs = _jobs(methods, paths, run_seeds, config.walk)
    with DemoStore(out / STORE_NAME, create=True) as store:
        Runner(store, {m.content_hash(): m for m in maps.values()},
               executor or LocalPool(processes), None, log).run(jobs, "curve walks")
        runs = {r["key"]: store.run(r["id"]) for r in store.runs()
                if r["key"] in {j.key for j in jobs}}
    log("the expert's verdict on every step of the runs")
    expert = SyntheticExpert(walking_expert(config.walk.footstep.lead))
    summary = summarise_walks(curve, config, methods, runs, maps, expert)
    name = report_name(config)
    write_text_atomic(out / f"{name}.json", json.dumps(summary, indent=1, sort_keys=True))
    write_text_atomic(out / f"{name}.md", walk_markdown(summary))
    return summary


def report_name(config: CurveWalkConfig) -> str:
    """The stem of the walk's report files in ``CURVE/walk/``: its feature set and learner."""
    return f"walk-{config.feature_set}-{config.learner}"


# ------------------------------------------------------------------ results
def _method_figures(records: list, maps: dict[str, HeightMap], expert: SyntheticExpert,
                    margin: float) -> dict:
    """Crossings, mean slip [mm] of the crossings' footholds and the expert's verdict on every
    step of some runs."""
    by_hash = {m.content_hash(): m for m in maps.values()}
    ok = [r for r in records if r.result["success"]]
    slips = np.concatenate([r.slips() for r in ok]) if ok else np.zeros(0)
    shortfall = np.concatenate([step_verdicts(r, by_hash[r.terrain_hash], expert)[1]
                                for r in records] or [np.zeros(0)])
    return {"successes": len(ok), "runs": len(records),
            "slip_mm": float(1e3 * slips.mean()) if slips.size else None,
            "steps": int(shortfall.size),
            "above_margin": float(np.mean(shortfall > margin)) if shortfall.size else None}


def _outcomes(runs: dict, method: str, draw_tag: str) -> dict:
    """Paired unit (draw/board, seed) -> outcome of ``method``'s runs."""
    out = {}
    for key, record in runs.items():
        m, board, seed = key.split("/")
        if m == method:
            out[(f"{draw_tag}/{board}", int(seed[1:]))] = RunOutcome.of(record.result,
                                                                         record.slips())
    return out


def summarise_walks(curve: dict, config: CurveWalkConfig, methods: dict[str, str | None],
                    runs: dict, maps: dict[str, HeightMap], expert: SyntheticExpert) -> dict:
    """The figures of every size and reference (see the module)."""
    margin = float(DEFAULT_MARGIN)
    fs, ln = config.feature_set, config.learner
    of = {m: [r for k, r in sorted(runs.items()) if k.split("/")[0] == m] for m in methods}
    refs = {m: _method_figures(of[m], maps, expert, margin) for m in config.references}
    offline = {(p["n"], p["draw"]): p["above_margin"] for p in curve["points"]
               if (p["feature_set"], p["learner"]) == (fs, ln)}
    sizes, outcomes = {}, {}
    for n in config.sizes:
        draws = sorted(int(m.rsplit("draw", 1)[1]) for m in methods
                       if m.startswith(f"{fs}-{ln}-{n}-draw"))
        per_draw = {d: _method_figures(of[f"{fs}-{ln}-{n}-draw{d}"], maps, expert, margin)
                    for d in draws}
        pooled = _method_figures([r for d in draws for r in of[f"{fs}-{ln}-{n}-draw{d}"]],
                                 maps, expert, margin)
        outcomes[n] = {k: v for d in draws
                       for k, v in _outcomes(runs, f"{fs}-{ln}-{n}-draw{d}", f"d{d}").items()}
        hand = {k: v for d in draws for k, v in _outcomes(runs, "hand-tuned", f"d{d}").items()}
        sizes[str(n)] = {**pooled, "draws": {str(d): {**f, "offline_above_margin":
                                                      offline.get((n, d))}
                                             for d, f in per_draw.items()},
                         "offline_above_margin": float(np.mean([offline[(n, d)]
                                                                for d in draws])),
                         "against_hand_tuned": compare({"m": outcomes[n], "h": hand}, "m", "h")}
    small, large = min(config.sizes), max(config.sizes)
    growth = (compare({"l": outcomes[large], "s": outcomes[small]}, "l", "s")
              if large != small else None)
    return {"feature_set": fs, "learner": ln, "margin": margin, "config": config.to_dict(),
            "curve_seed": curve["config"]["seed"], "references": refs, "sizes": sizes,
            "largest_against_smallest": growth,
            "offline_lines": {k: v["above_margin"] for k, v in curve["lines"].items()}}


def _crossed(f: dict) -> str:
    slip = "-" if f["slip_mm"] is None else f"{f['slip_mm']:.1f}"
    above = "-" if f["above_margin"] is None else f"{f['above_margin']:.3f}"
    return f"{f['successes']} / {f['runs']} | {slip} | {above}"


def walk_markdown(summary: dict) -> str:
    """The walks as Markdown: a row per size and reference, then the paired tests."""
    c = summary["config"]
    board = " ".join(f"{k}:{d:g}" for k, d in c["board"])
    out = ["# A learning curve's points, walked", "",
           f"{summary['feature_set']} / {summary['learner']}: every draw's model at each size "
           f"on {c['boards']} boards {board} never trained on, {c['runs']} runs each, the same "
           f"run seeds for every method. Steps above margin: the expert's verdict on every "
           f"step (shortfall above {summary['margin']:g} value unit); offline: the curve's "
           f"share of held-out decisions above it.", "",
           "| method | crossed | slip of crossings [mm] | steps above margin | offline above "
           "margin |", "| --- | --- | --- | --- | --- |"]
    for name, f in summary["references"].items():
        line = summary["offline_lines"].get(name)
        out.append(f"| {name} | {_crossed(f)} | "
                   f"{'-' if line is None else f'{line:.3f}'} |")
    for n, f in summary["sizes"].items():
        out.append(f"| {n} demonstrations ({len(f['draws'])} draws) | {_crossed(f)} | "
                   f"{f['offline_above_margin']:.3f} |")
        for d, g in f["draws"].items():
            off = g["offline_above_margin"]
            out.append(f"| &nbsp; draw {d} | {_crossed(g)} | "
                       f"{'-' if off is None else f'{off:.3f}'} |")
    out += ["", "Paired (exact McNemar over the (draw, board, seed) units; a reference's run "
                "of a unit is the same for every draw):", ""]
    for n, f in summary["sizes"].items():
        a = f["against_hand_tuned"]
        out.append(f"- {n} demonstrations against the hand-tuned reward: only the function "
                   f"crossed {a['a_only']}, only the hand-tuned reward {a['b_only']} of "
                   f"{a['pairs']} pairs, p = {a['p_value']:.3g} ({a['success_verdict']})")
    g = summary["largest_against_smallest"]
    if g is not None:
        out.append(f"- the largest size against the smallest: only the larger crossed "
                   f"{g['a_only']}, only the smaller {g['b_only']} of {g['pairs']} pairs, "
                   f"p = {g['p_value']:.3g}")
    return "\n".join(out) + "\n"
