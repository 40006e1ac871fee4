"""The student's walking learning curve (``footfall student-curve``): crossings against labels.

How much does the student need, and of which kind of supervision? Each **draw** is one
reproduction (a ``footfall reproduce`` folder, e.g. a seed of ``footfall study``) whose loop
labels every step of the student's own runs (DAgger, ``ReproduceConfig.every_step``). The
curve continues that loop by its own rule -- the student walks the training boards, the teacher
labels every step, the student is learned again -- to ``rounds`` rounds, in a folder of the
curve's own: the reproduction's store and round models are copied there once, its runs and
models reused by their keys, nothing of the source written.

**Points.** The labels after ``points`` rounds, in the loop's order (a point is what the loop
had learned from by then: on-policy labels, the student's own states). At each point and draw
each **variant** -- a feature set, a kind of supervision
(:mod:`footfall.learning.supervision`) and whether a veto is learned beside the ranker -- is
learned from exactly those labels with the loop's round settings. The loop's own students
(its feature set, supervision and veto) are its round models, learned once.

**Walking.** Every function walks the same boards with the same run seeds, and the teacher
choosing every foothold and the hand-tuned reward walk them too, as lines: every comparison is
paired (:mod:`footfall.experiments.paired`). The boards are named by their modules and board
seeds (:data:`DEFAULT_BOARDS`: boards of the test kinds at and above the reproduction's test
difficulties, and one fresh board of each training kind), never a board any draw trained,
calibrated or was tested on.

**Flattening**, decided before any curve was walked: a variant's curve flattens at the
smallest point whose crossings, pooled over the draws, are not separated from the last
point's (exact McNemar p >= 0.05) and stay so at every later point.

Every run is stored under ``walk/DRAW/VARIANT/pPOINT/BOARD/sSEED`` (the references under
``walk/REFERENCE/BOARD/sSEED``, shared by the draws) in ``OUT/curve.sqlite`` as it arrives; a
rerun walks and learns only what is missing.
"""

from __future__ import annotations

import json
import re
import shutil
import sqlite3
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from footfall.core.atomic import write_text_atomic
from footfall.core.compute import usable_cores
from footfall.core.errors import FootfallError
from footfall.core.files import distinct_inputs
from footfall.core.folders import holding_folders
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, at_least, param
from footfall.data.store import DemoStore
from footfall.experiments.executors import Executor, LocalPool
from footfall.experiments.paired import RunOutcome, compare
from footfall.experiments.reproduce import (
    STORE_NAME,
    ReproduceConfig,
    correction_rounds,
    is_board_spec,
    round_labels,
)
from footfall.experiments.reproduce_learning import learn_saved
from footfall.experiments.runs import RunJob, Runner, board_files, claim_folder
from footfall.experiments.workspace import ROBOT_FEATURE_SET, Spec, Workspace, open_workspace
from footfall.learning.supervision import SUPERVISIONS
from footfall.plots.curves import save_student_curve_figure

CURVE_STORE = "curve.sqlite"
REFERENCES = ("teacher", "hand-tuned")  # the teacher choosing every foothold; the reward
# learning starts from
VARIANT = re.compile(r"^(?P<fs>[a-z+]+):(?P<sup>[a-z]+)(?P<veto>\+veto)?$")


def parse_variant(text: str) -> tuple[str, str, bool]:
    """``FEATURES:SUPERVISION`` or ``FEATURES:SUPERVISION+veto`` -> (features, kind, veto)."""
    m = VARIANT.match(text) if isinstance(text, str) else None
    if m is None or m["sup"] not in SUPERVISIONS:
        raise FootfallError(f"a variant is FEATURES:SUPERVISION[+veto] with a supervision of "
                            f"{', '.join(SUPERVISIONS.names())}, got {text!r}")
    return m["fs"], m["sup"], m["veto"] is not None


def _variants_ok(v: object) -> bool:
    if not isinstance(v, tuple) or not v or len(set(v)) != len(v):
        return False
    try:
        [parse_variant(x) for x in v]
    except FootfallError:
        return False
    return True


def _boards_ok(v: object) -> bool:
    return (isinstance(v, tuple) and len(v) > 0
            and all(isinstance(b, tuple) and len(b) == 3 and is_board_spec(b[0])
                    and isinstance(b[1], int) and isinstance(b[2], int) and b[2] >= 1
                    for b in v)
            and len({b[1] for b in v}) == len(v))


def _rocky_steps(d: float) -> Spec:
    return (("rocky", d), ("steps", d))


DEFAULT_BOARDS: tuple[tuple[Spec, int, int], ...] = (
    *((_rocky_steps(0.9), s, 3) for s in range(7220, 7225)),
    *((_rocky_steps(1.0), s, 3) for s in range(7225, 7230)),
    *(((kind,), 7300 + i, 2) for i, kind in enumerate(
        (("rocky", 0.4), ("rocky", 0.6), ("steps", 0.5), ("barrier", 0.5), ("slope", 0.5),
         ("logs", 0.5))))
)  # the student's validation boards (docs/learning/student.md) and a fresh board of each of
# the reproduction's training kinds: (modules, board seed, runs)


@dataclass(frozen=True)
class StudentCurveConfig(Params):
    """The curve's loop, points, variants and walking boards; written next to its runs."""

    rounds: int = param(7, range=at_least(1), doc="rounds the draws' loops are continued to")
    points: tuple[int, ...] = param(
        (1, 2, 4, 7), check=lambda v: isinstance(v, tuple) and len(v) > 0 and all(
            isinstance(n, int) and n >= 1 for n in v) and list(v) == sorted(set(v)),
        must="increasing whole numbers of rounds",
        doc="the points: the labels after this many rounds")
    variants: tuple[str, ...] = param(
        ("both:choice", "both:refusals+veto", "both:graded+veto", "terrain:graded+veto",
         "templates:graded+veto"), check=_variants_ok,
        must="distinct FEATURES:SUPERVISION[+veto]", doc="the functions learned at each point")
    boards: tuple[tuple[Spec, int, int], ...] = param(
        DEFAULT_BOARDS, check=_boards_ok, must="(modules, distinct board seed, runs >= 1)",
        doc="the walking boards: modules, board seed, runs (run seeds 1000, 1001, ...)")
    first_run_seed: int = param(1000, range=at_least(0), doc="the first run seed on a board")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.points[-1] > self.rounds:
            raise FootfallError(f"a point after {self.points[-1]} rounds needs rounds >= "
                                f"{self.points[-1]}, got {self.rounds}")


FREE = ("variants",)  # chooses which functions are learned and walked, not how


@dataclass(frozen=True)
class Draw:
    """One draw: its continued loop's workspace and the labels of each point, in loop order."""

    name: str  # draw0, draw1, ...
    ws: Workspace
    labels: dict[int, list]  # point (rounds) -> the labels after that many rounds


def _copy_store(source: Path, target: Path) -> None:
    """A consistent copy of a SQLite store (its write-ahead log folded in), made atomically."""
    part = target.with_name(target.name + ".part")
    part.unlink(missing_ok=True)
    with sqlite3.connect(f"file:{source}?mode=ro", uri=True) as src, \
            sqlite3.connect(part) as dst:
        src.backup(dst)
    part.replace(target)


def continue_loop(source: str | Path, out: Path, rounds: int, runner_for: Callable,
                  log: Callable[[str], None]) -> Workspace:
    """The reproduction at ``source`` copied to ``out`` once (its store, boards and round
    models) and its labelling loop continued there to ``rounds`` rounds."""
    source = Path(source)
    try:
        held = ReproduceConfig.from_dict(json.loads((source / "config.json").read_text()))
    except (OSError, ValueError) as exc:
        raise FootfallError(f"{source}: not a reproduction's folder ({exc})") from None
    if not held.every_step:
        raise FootfallError(f"{source}: its loop labels the worst steps only, not every step "
                            f"of the student's runs; a student curve continues a DAgger loop")
    config = replace(held, rounds=max(rounds, held.rounds), extra_rounds=0)
    if not (out / STORE_NAME).exists():
        (out / "models").mkdir(parents=True, exist_ok=True)
        for model in sorted((source / "models").glob("round*.npz")):
            shutil.copyfile(model, out / "models" / model.name)
        (out / "terrain").mkdir(exist_ok=True)  # its boards, checked again when opened
        for board in sorted((source / "terrain").glob("*.npz")):
            shutil.copyfile(board, out / "terrain" / board.name)
        _copy_store(source / STORE_NAME, out / STORE_NAME)
    ws = open_workspace(out, config)
    with DemoStore(out / STORE_NAME, create=True) as store:
        correction_rounds(ws, runner_for(store, ws.by_hash))
    return ws


def _labels(ws: Workspace, points: Sequence[int]) -> dict[int, list]:
    with DemoStore(ws.out / STORE_NAME, read_only=True) as store:
        return {p: round_labels(store, p) for p in points}


def variant_name(variant: str) -> str:
    """A variant as a file and key name: ``both-graded-veto``."""
    fs, sup, veto = parse_variant(variant)
    return f"{fs.replace('+', '_')}-{sup}" + ("-veto" if veto else "")


def point_model(draw: Draw, variant: str, point: int, log: Callable[[str], None],
                threads: int = 1) -> Path:
    """The variant's function at ``point``: the loop's own round model where the variant is the
    loop's student, else learned (once) from exactly the point's labels with the loop's round
    settings."""
    fs, sup, veto = parse_variant(variant)
    c = draw.ws.config
    if (fs, sup, veto) == (ROBOT_FEATURE_SET, c.supervision, c.veto) and point < c.rounds:
        path = draw.ws.model_path(f"round{point}")
        if not path.exists():
            raise FootfallError(f"{path} is missing: the loop's student after {point} rounds")
        return path
    ws = replace(draw.ws, config=replace(c, supervision=sup, veto=veto))
    name = f"curve-{variant_name(variant)}-p{point}"
    learn_saved(ws, name, draw.labels[point], fs, c.round_bandwidth_rms, log, threads)
    return ws.model_path(name)


def _board_name(spec: Spec, seed: int) -> str:
    return "-".join(f"{k}{d:g}" for k, d in spec) + f"-{seed}"


def curve_jobs(config: StudentCurveConfig, walk_config, expert, teacher: str,
               boards: dict[str, Path], models: dict[str, str]) -> list[RunJob]:
    """Every run: the references, then every model (``models``: method key -> file)."""
    runs = {_board_name(s, seed): n for s, seed, n in config.boards}
    seeds = {name: [config.first_run_seed + k for k in range(n)] for name, n in runs.items()}
    jobs = []
    for ref in REFERENCES:
        jobs += [RunJob(f"walk/{ref}/{b}/s{s}", str(boards[b]), None, s, walk_config,
                        expert=expert, judge=ref == "teacher", teacher=teacher)
                 for b in boards for s in seeds[b]]
    for method, model in models.items():
        jobs += [RunJob(f"walk/{method}/{b}/s{s}", str(boards[b]), model, s, walk_config,
                        expert=expert, teacher=teacher)
                 for b in boards for s in seeds[b]]
    return jobs


@holding_folders
def run_student_curve(sources: Sequence[str | Path], out: str | Path,
                      config: StudentCurveConfig | None = None, processes: int | None = None,
                      log: Callable[[str], None] = print, executor: Executor | None = None
                      ) -> dict:
    """Continue each source's loop, learn every variant at every point, walk them all with the
    references; return the summary (also ``curve.json``, ``.md``, ``.png`` in ``out``)."""
    config = StudentCurveConfig() if config is None else config
    out = Path(out)
    sources = [Path(s) for s in distinct_inputs(sources, "reproduction")]
    if not sources:
        raise FootfallError("a student curve needs at least one reproduction to continue")
    claim_folder(out, {**config.to_dict(), "sources": [str(s.resolve()) for s in sources]},
                 "a student curve", free=FREE)
    executor = executor or LocalPool(processes)
    threads = max(1, min(getattr(executor, "processes", None) or 1, usable_cores()))  # learns
    # while no run is walked, on this machine
    draws = []
    for k, source in enumerate(sources):
        log(f"draw{k}: {source}, its loop to {config.rounds} rounds")
        ws = continue_loop(source, out / f"draw{k}", config.rounds,
                           lambda store, maps: Runner(store, maps, executor, None, log), log)
        draws.append(Draw(f"draw{k}", ws, _labels(ws, config.points)))
    models = {}
    for draw in draws:
        for p in config.points:
            for v in config.variants:
                key = f"{draw.name}/{variant_name(v)}/p{p}"
                models[key] = str(point_model(draw, v, p, log, threads))
    first = draws[0].ws.config
    paths = board_files(out, {_board_name(s, seed): (s, seed, True)
                              for s, seed, _ in config.boards})
    maps = {n: HeightMap.load(p) for n, p in paths.items()}
    jobs = curve_jobs(config, first.walk, first.expert, first.teacher, paths, models)
    with DemoStore(out / CURVE_STORE, create=True) as store:
        Runner(store, {m.content_hash(): m for m in maps.values()}, executor, None,
               log).run(jobs, "student curve walks")
        keys = {j.key for j in jobs}
        runs = {r["key"]: store.run(r["id"]) for r in store.runs() if r["key"] in keys}
    summary = summarise(config, draws, runs)
    write_text_atomic(out / "curve.json", json.dumps(summary, indent=1, sort_keys=True))
    write_text_atomic(out / "curve.md", curve_markdown(summary))
    save_student_curve_figure(summary, out / "curve.png")
    return summary


# ------------------------------------------------------------------ results
def _outcomes(runs: dict, prefix: str, unit_tag: str = "") -> dict:
    """Paired unit (draw/board, seed) -> outcome of the runs under ``prefix``."""
    out = {}
    for key, record in runs.items():
        if key.startswith(prefix):
            board, seed = key[len(prefix):].split("/")
            out[(f"{unit_tag}{board}", int(seed[1:]))] = RunOutcome.of(record.result,
                                                                       record.slips())
    return out


def flattens_at(points: Sequence[int], p_against_last: dict[int, float]) -> int:
    """The smallest point not separated from the last (p >= 0.05) and none later separated."""
    at = points[-1]
    for p in reversed(points):
        if p_against_last[p] < 0.05:
            break
        at = p
    return at


def summarise(config: StudentCurveConfig, draws: list[Draw], runs: dict) -> dict:
    """Crossings of every variant at every point (pooled over draws and per draw), the
    references on the same units, the paired tests and where each curve flattens."""
    refs = {}
    for ref in REFERENCES:
        one = _outcomes(runs, f"walk/{ref}/")
        refs[ref] = {"successes": sum(o.success for o in one.values()), "runs": len(one)}
    variants = {}
    for v in config.variants:
        vn = variant_name(v)
        outcome = {p: {u: o for d in draws
                       for u, o in _outcomes(runs, f"walk/{d.name}/{vn}/p{p}/",
                                             f"{d.name}/").items()}
                   for p in config.points}
        hand = {u: o for d in draws
                for u, o in _outcomes(runs, "walk/hand-tuned/", f"{d.name}/").items()}
        teacher = {u: o for d in draws
                   for u, o in _outcomes(runs, "walk/teacher/", f"{d.name}/").items()}
        last = config.points[-1]
        rows = {}
        for p in config.points:
            mine = outcome[p]
            per_draw = {d.name: sum(o.success for u, o in mine.items()
                                    if u[0].startswith(d.name + "/")) for d in draws}
            rows[str(p)] = {
                "labels": [len(d.labels[p]) for d in draws],
                "successes": sum(o.success for o in mine.values()), "runs": len(mine),
                "per_draw": per_draw,
                "against_hand_tuned": compare({"a": mine, "b": hand}, "a", "b"),
                "against_teacher": compare({"a": mine, "b": teacher}, "a", "b"),
                "against_last": compare({"a": mine, "b": outcome[last]}, "a", "b")}
        p_last = {p: (1.0 if p == last else rows[str(p)]["against_last"]["p_value"])
                  for p in config.points}
        variants[v] = {"points": rows, "flattens_at": flattens_at(config.points, p_last)}
    return {"config": config.to_dict(), "draws": [str(d.ws.out) for d in draws],
            "references": refs, "variants": variants}


def curve_markdown(summary: dict) -> str:
    """The curve as Markdown: a row per variant and point, the references as lines."""
    c = summary["config"]
    units = sum(b[2] for b in c["boards"])
    draws = len(summary["draws"])
    out = ["# The student's walking learning curve", "",
           f"{draws} draws (reproductions whose loops were continued to {c['rounds']} rounds); "
           f"each function walks {len(c['boards'])} boards, {units} runs a draw, the same run "
           f"seeds for every method. Labels: the labelled steps after that many rounds, per "
           f"draw. Paired: exact McNemar, only this one crossed / only the other.", "",
           "![Crossings against labelled steps](curve.png)", "",
           "| reference | crossed (of the runs of one draw) |", "| --- | --- |"]
    for name, f in summary["references"].items():
        out.append(f"| {name} | {f['successes']} / {f['runs']} |")
    out += ["", "| variant | rounds | labels | crossed (pooled) | per draw | against the "
                "hand-tuned reward | against the teacher | against the last point |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for v, f in summary["variants"].items():
        for p, row in f["points"].items():
            pair = [row[k] for k in ("against_hand_tuned", "against_teacher", "against_last")]
            shown = [f"{a['a_only']} / {a['b_only']} (p = {a['p_value']:.3g})" for a in pair]
            out.append(f"| {v} | {p} | {', '.join(map(str, row['labels']))} | "
                       f"{row['successes']} / {row['runs']} | "
                       f"{', '.join(map(str, row['per_draw'].values()))} | "
                       + " | ".join(shown) + " |")
    out += ["", "Flattens (the smallest point not separated from the last, nor any later one): "
            + "; ".join(f"{v} after {f['flattens_at']} rounds"
                        for v, f in summary["variants"].items()) + "."]
    return "\n".join(out) + "\n"
