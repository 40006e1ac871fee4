"""Learning curves (``footfall learning-curve``): how each feature set and learner improves with
the number of demonstrations, measured on held-out decisions.

Every draw has its own training boards (every kind at every difficulty, board
seeds from the draw's own stream, so no two draws share a board) and its own
demonstrations: the walking expert demonstrates ``max(sizes)`` footholds on
them with the kinematic walker, and each size learns from the first n of one
random order of those (nested: a larger size adds demonstrations to a
smaller one's). The held-out decisions come from test boards of their own
seeds, the same for every draw and never trained on: the walking expert's
decisions on them, each judged by the expert's values of all its candidates.

Each point is measured as ``footfall rank-eval`` measures a scorer: the
share of decisions whose expert shortfall is above the correction margin
(the number the issue's targets are in) and above the severe threshold, the
mean shortfall with a bootstrap interval, top-1 and within 1 cm, and the
templates kept per scale. The hand-tuned reward and the expert's own value
(the ceiling: no shortfall by construction) are measured on the same
decisions as lines. With ``path_bias`` set every scorer, the lines too, is
ranked as the footstep planner picks (its values less the planner's path
bias: :class:`~footfall.learning.evaluation.PathBias`) -- how the planner walks
it. Results are written after every point and a rerun with the same settings
resumes where it stopped.

Every point's RBF bandwidths are fixed (``bandwidth_rms``, the reproduction's
rounds' value) unless set to None: choosing them by cross-validation at every
point multiplies the learning time several times over.
"""

from __future__ import annotations

import contextlib
import json
import math
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from footfall.control.footstep import FootstepConfig
from footfall.core.atomic import write_text_atomic
from footfall.core.compute import worker_pool
from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz
from footfall.core.folders import hold_folder, holding_folders
from footfall.core.robot import LITTLEDOG
from footfall.data.demonstration import Demonstration
from footfall.data.store import DemoStore
from footfall.expert.collect import collect_demonstrations
from footfall.expert.corrections import DEFAULT_MARGIN, SEVERE_SHORTFALL
from footfall.expert.scorer import ExpertScorer, settings_hash
from footfall.expert.synthetic import SyntheticExpert, walking_expert
from footfall.features.reward import default_reward
from footfall.learning.evaluation import (
    EveryLeg,
    PathBias,
    RankScores,
    decision_rows,
    rank_scores_many,
    scores_of_rows,
)
from footfall.learning.model import FootholdModel
from footfall.learning.train import TrainingDemo, learn_model
from footfall.plots.curves import save_curve_figure
from footfall.terrain import make_board

from .curve_config import EXTENSIBLE, CurveConfig
from .curve_report import FORMAT, curve_report, curve_table

VALUES_FORMAT = "footfall.learning-curve.values"  # the expert's values of the held-out decisions
VERSION = 1
COLLECT_MORE = 1.25  # a draw collects this many times its largest size: the legs do not take
# turns exactly, and each leg group's prefix must reach half of every size
def _point(scores: RankScores, **extra) -> dict:
    """A point's figures: ``extra`` (the point's draw, n, feature set, learner ...), the
    rank-eval measures and the number of decisions as ``decisions``; the per-decision
    shortfalls [value units] in decision order, for paired comparisons of points."""
    d = scores.as_dict()
    d["decisions"] = d.pop("n")
    return {**d, **extra}


def _expert() -> SyntheticExpert:
    """The teacher and judge: the walking expert (the reproduction's corrections' expert)."""
    return SyntheticExpert(walking_expert(FootstepConfig().lead))


def _stored_demos(path: Path, specs: list[tuple[str, float, int]], n: int, seed: int,
                  source: str, expert: SyntheticExpert, log: Callable[[str], None],
                  search_radius: float | None) -> tuple[list[Demonstration], dict]:
    """The expert's ``n`` demonstrations on the boards ``specs``, F within ``search_radius``
    [m] of the gait-nominal foothold (None: all reachable), from the store at ``path``
    (collected into it the first time: a rerun reads them back)."""
    boards = [make_board([(kind, d)], s) for kind, d, s in specs]
    maps = {b.content_hash(): b for b in boards}
    with DemoStore(path, create=True) as store:
        demos = store.demonstrations(source_prefix=source)
        if not demos:
            log(f"collecting {n} demonstrations on {len(boards)} boards ({path.name})")
            store.add_demonstrations(collect_demonstrations(
                boards, expert, n, seed=seed, source=source, search_radius=search_radius,
                lead=expert.config.stance_lead), terrains=boards)
            demos = store.demonstrations(source_prefix=source)
    if {d.terrain_hash for d in demos} - set(maps):
        raise FootfallError(f"{path} holds demonstrations of other boards; use another --out")
    return demos, maps


def balanced_order(front: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A random order of demonstrations (``front`` (n,) bool: a front leg's) that alternates
    front and hind legs while both last, so that every prefix -- every curve point -- holds
    both leg groups in equal numbers (each learns its own function)."""
    groups = [rng.permutation(np.flatnonzero(front)), rng.permutation(np.flatnonzero(~front))]
    k = min(g.size for g in groups)
    order = np.column_stack([groups[0][:k], groups[1][:k]]).ravel()
    return np.concatenate([order, groups[0][k:], groups[1][k:]])


def point_model_path(out: Path, draw: int, n: int, fs: str, ln: str) -> Path:
    """The saved model of a curve point: draw, size, feature set, learner."""
    return out / "models" / f"{fs}-{ln}-{n}-draw{draw}.npz"


def _resumed(results_path: Path, config: CurveConfig) -> tuple[list[dict], dict | None]:
    """The points and lines a results file of the same settings holds ([] and None without
    one)."""
    if not results_path.exists():
        return [], None
    try:
        old = json.loads(results_path.read_text())
    except (OSError, ValueError) as exc:
        raise FootfallError(f"{results_path}: cannot be read ({exc}); remove it to start "
                            f"again") from None
    new = json.loads(json.dumps(config.to_dict()))
    was = old.get("config") if isinstance(old.get("config"), dict) else {}
    # a setting added since the file was written has its default there: every new setting's
    # default measures what the curve measured before it existed
    was = {**json.loads(json.dumps(CurveConfig().to_dict())), **was}
    differ = sorted(k for k in set(new) | set(was) if k not in new or k not in was
                    or (k not in EXTENSIBLE and was[k] != new[k]))
    if old.get("format") != FORMAT or differ:
        raise FootfallError(f"{results_path} holds a curve of other settings "
                            f"({', '.join(differ) or 'format'}); use another --out or remove it")
    return old["points"], old.get("lines")


@dataclass
class _HeldOut:
    """The held-out decisions, their terrains and the expert's values of their candidates."""

    decisions: list[Demonstration]
    terrain: Callable[[str], object]
    values: list[np.ndarray]
    bias: PathBias | None = None  # ranked as the planner picks, or each scorer alone

    def measure(self, models: dict) -> dict[str, RankScores]:
        """rank-eval's measures of every model on the decisions (their patches made once)."""
        return rank_scores_many(models, self.decisions, self.terrain, values=self.values,
                                margin=DEFAULT_MARGIN, severe_above=SEVERE_SHORTFALL,
                                path_bias=self.bias)

    def rows(self, models: dict, start: int, stop: int) -> dict[str, list[tuple]]:
        """The rows of decisions ``start:stop`` for ``models`` (a worker's slice)."""
        return decision_rows(models, self.decisions[start:stop], self.terrain,
                             self.values[start:stop], self.bias)


def _held_out(out: Path, config: CurveConfig, expert: SyntheticExpert,
              log: Callable[[str], None]) -> _HeldOut:
    test, maps = _stored_demos(out / "test.sqlite", config.test_boards(),
                               config.test_decisions, config.streams.seed_for("demonstrations", 1),
                               "walker:test", expert, log, config.search_radius)
    if len(test) < config.test_decisions:
        raise FootfallError(f"the test boards gave {len(test)} decisions, fewer than "
                            f"{config.test_decisions}")
    test = test[:config.test_decisions]
    return _HeldOut(test, maps.__getitem__,
                    _expert_values(out / "test-values.npz", test, maps, expert),
                    None if config.path_bias is None else
                    PathBias(config.path_bias, expert.config.stance_lead))


def _expert_values(path: Path, decisions: list[Demonstration], maps: dict,
                   expert: SyntheticExpert) -> list[np.ndarray]:
    """The expert's values of every candidate of the decisions, from ``path`` when it holds
    those of the same decisions and expert (else computed and written there)."""
    key = {"expert": settings_hash(expert.config), "decisions": [d.id for d in decisions]}
    sizes = [d.candidates.shape[0] for d in decisions]
    if path.exists():
        try:
            _, arrays, meta = load_npz(path, VALUES_FORMAT, 1, allow_nonfinite=True)
            if meta == key and arrays["values"].shape == (sum(sizes),):
                return np.split(arrays["values"], np.cumsum(sizes)[:-1])
        except (FootfallError, KeyError):
            pass  # another file: computed again
    values = [expert.values(maps[d.terrain_hash], d.state, d.candidates) for d in decisions]
    save_npz(path, VALUES_FORMAT, 1, {"values": np.concatenate(values)}, key)
    return values


def _draw_training(out: Path, config: CurveConfig, draw: int, expert: SyntheticExpert,
                   log: Callable[[str], None]) -> list[TrainingDemo]:
    """Draw ``draw``'s demonstrations in the order its points take prefixes of (collected into
    its store the first time)."""
    demos, maps = _stored_demos(out / f"draw{draw}.sqlite", config.training_boards(draw),
                                math.ceil(COLLECT_MORE * max(config.sizes)),
                                config.streams.seed_for("demonstrations", 0, draw),
                                f"walker:draw{draw}", expert, log, config.search_radius)
    front = np.array([LITTLEDOG.leg(d.state.swing_leg).front for d in demos])
    order = balanced_order(front, config.streams.generator("demonstrations", 2, draw))
    return [TrainingDemo.of(demos[k], maps[demos[k].terrain_hash]) for k in order]


def _learn_point(out: Path, config: CurveConfig, key: tuple, training: list[TrainingDemo]
                 ) -> float:
    """Learn and save the model of point ``key`` (draw, n, feature set, learner) from the first
    n of its draw's demonstrations; its learning time [s]."""
    draw, n, fs, ln = key
    t0 = time.perf_counter()
    rms = None if config.bandwidth_rms is None else (config.bandwidth_rms,) * 3
    learn_model(training[:n], fs, ln, library_size=config.library_size,
                library_capped=config.library_capped, bandwidth_rms=rms,
                folds=config.folds, selection=config.selection,
                template_budget=config.template_budget,
                seed=config.streams.seed_for("learning", draw, n)
                ).save(point_model_path(out, draw, n, fs, ln))
    return time.perf_counter() - t0


_WORKER_TRAINING: dict[tuple, list[TrainingDemo]] = {}  # a worker process's draws, read once


def _prepare_in_worker(out: Path, config: CurveConfig, draw: int | None) -> None:
    """A worker's part of the start: draw ``draw``'s demonstrations collected into its store,
    or (``draw`` None) the held-out decisions and the expert's values of them."""
    quiet = lambda _: None  # noqa: E731 -- the driver logs
    if draw is None:
        _held_out(out, config, _expert(), quiet)
    else:
        _draw_training(out, config, draw, _expert(), quiet)


def _learn_in_worker(out: Path, config: CurveConfig, key: tuple) -> tuple[tuple, float]:
    """A worker's part of a size: one point's model learned and saved; (key, seconds)."""
    cache = (str(out), key[0])
    if cache not in _WORKER_TRAINING:
        _WORKER_TRAINING[cache] = _draw_training(out, config, key[0], _expert(), lambda _: None)
    return key, _learn_point(out, config, key, _WORKER_TRAINING[cache])


_WORKER_HELD_OUT: dict[str, _HeldOut] = {}  # a worker process's held-out decisions, read once


def _measure_in_worker(out: Path, config: CurveConfig, keys: list[tuple], start: int,
                       stop: int) -> dict[tuple, list[tuple]]:
    """A worker's part of measuring a size: the rows of held-out decisions ``start:stop`` for
    the saved models of ``keys``."""
    if str(out) not in _WORKER_HELD_OUT:
        _WORKER_HELD_OUT[str(out)] = _held_out(out, config, _expert(), lambda _: None)
    held = _WORKER_HELD_OUT[str(out)]
    models = {k: FootholdModel.load(point_model_path(out, *k)) for k in keys}
    return held.rows(models, start, stop)


def _measure(held_out: _HeldOut, out: Path, config: CurveConfig, models: dict[tuple, FootholdModel],
             pool: ProcessPoolExecutor | None, processes: int) -> dict[tuple, RankScores]:
    """rank-eval's measures of ``models`` (saved points, by key) on the held-out decisions: in
    this process, or the decisions in ``processes`` slices, one a worker reading the saved
    models (the same figures)."""
    if pool is None:
        return held_out.measure(models)
    keys = list(models)
    cuts = np.linspace(0, len(held_out.decisions), processes + 1).round().astype(int)
    parts = [pool.submit(_measure_in_worker, out, config, keys, int(a), int(b))
             for a, b in zip(cuts[:-1], cuts[1:]) if b > a]
    rows: dict[tuple, list[tuple]] = {k: [] for k in keys}
    for f in parts:  # in the decisions' order
        for k, r in f.result().items():
            rows[k].extend(r)
    return {k: scores_of_rows(r, DEFAULT_MARGIN, SEVERE_SHORTFALL) for k, r in rows.items()}


def _work_order(keys: list[tuple]) -> list[tuple]:
    """The points of a size in the order a pool takes them: the slowest learners first, so
    that the last to finish is a short one."""
    slow = {"lambdarank": 0, "l1": 1, "kernel": 2}
    weight = {"both": 0, "templates": 1, "terrain": 2}
    return sorted(keys, key=lambda k: (slow.get(k[3], 3), weight.get(k[2], 3), k))


def _model_point(key: tuple, model: FootholdModel, scores: RankScores) -> dict:
    kept = model.templates_kept()
    return _point(scores, draw=key[0], n=key[1], feature_set=key[2], learner=key[3],
                  seconds=model.info.get("seconds"),
                  templates_kept={g: v["kept"] for g, v in kept.items()},
                  cv_error={g: f.info.get("cv_error") for g, f in model.functions.items()})


def _save(path: Path, config: CurveConfig, lines: dict, points: list[dict], decisions: int
          ) -> dict:
    """Write the curve's results (atomically) and return them."""
    summary = {"format": FORMAT, "version": VERSION, "config": config.to_dict(), "lines": lines,
               "points": points, "test_decisions": decisions}
    write_text_atomic(path, json.dumps(summary, indent=1))
    return summary


def _learn_size(out: Path, config: CurveConfig, keys: list[tuple],
                training: dict[int, list[TrainingDemo]], pool: ProcessPoolExecutor | None,
                log: Callable[[str], None]) -> None:
    """Learn and save the models of ``keys``: in this process, or each in a worker of
    ``pool`` (the same models: each point's learning draws from its own seed)."""
    def done(key: tuple, seconds: float) -> None:
        log(f"  draw {key[0]}, {key[1]} demonstrations, {key[2]}/{key[3]}: learned in "
            f"{seconds:.0f} s")

    if pool is None or len(keys) < 2:
        for key in keys:
            done(key, _learn_point(out, config, key, training[key[0]]))
        return
    for f in as_completed([pool.submit(_learn_in_worker, out, config, k)
                           for k in _work_order(keys)]):
        done(*f.result())


@contextlib.contextmanager
def _pool(processes: int) -> Iterator[ProcessPoolExecutor | None]:
    """Worker processes for the curve's stores and models (None for one process)."""
    if processes <= 1:
        yield None
        return
    with worker_pool(processes) as pool:
        yield pool


@holding_folders
def run_learning_curve(out: Path, config: CurveConfig | None = None,
                       log: Callable[[str], None] = print, processes: int = 1) -> dict:
    """Measure the curve into ``out``: ``results.json``, ``report.md``, ``learning-curve.png``,
    the demonstrations (``test.sqlite``, ``draw<k>.sqlite``) and every model (``models/``).

    A rerun with the same settings resumes: stored demonstrations, saved models and measured
    points are not made again. ``processes`` > 1 collects the draws' demonstrations and learns
    each size's models in that many worker processes (the same stores and models as one
    process: every part draws from its own seed); the measuring stays in this process.
    """
    config = CurveConfig() if config is None else config
    if out.exists() and not out.is_dir():
        raise FootfallError(f"output path is not a directory: {out}")
    out.mkdir(parents=True, exist_ok=True)
    hold_folder(out, "a learning curve")  # a second command into it is refused
    (out / "models").mkdir(exist_ok=True)
    results_path = out / "results.json"
    points, lines = _resumed(results_path, config)
    if points:
        log(f"resuming: {len(points)} points measured")
    done = {(p["draw"], p["n"], p["feature_set"], p["learner"]) for p in points}
    left = {(draw, n, fs, ln) for draw in range(config.draws) for n in config.sizes
            for fs in config.feature_sets for ln in config.learners} - done
    started = time.perf_counter()
    with _pool(processes) as pool:
        if pool is not None:  # the stores filled at once, one task each
            log(f"collecting the held-out decisions and {len({k[0] for k in left})} draws' "
                f"demonstrations in {processes} processes")
            for f in [pool.submit(_prepare_in_worker, out, config, d)
                      for d in [None, *sorted({k[0] for k in left})]]:
                f.result()
        expert = _expert()
        held_out = _held_out(out, config, expert, log)
        if lines is None:  # measured once: a resumed curve keeps them
            lines = {name: _point(scores) for name, scores in held_out.measure(
                {"hand-tuned": EveryLeg(default_reward()),
                 "expert": EveryLeg(ExpertScorer(expert))}).items()}
            _save(results_path, config, lines, points, len(held_out.decisions))
        log(f"{len(held_out.decisions)} held-out decisions; hand-tuned above the margin "
            f"{lines['hand-tuned']['above_margin']:.3f}")

        def save(seconds: float | None = None) -> dict:
            """Results, report and figure of the points measured so far (an interrupted
            curve shows them)."""
            summary = _save(results_path, config, lines, points, len(held_out.decisions))
            if seconds is not None:
                summary["seconds"] = seconds
            write_text_atomic(out / "report.md", curve_report(summary))
            if points:
                save_curve_figure(curve_table(summary), summary["lines"],
                                  out / "learning-curve.png")
            return summary

        training = {draw: _draw_training(out, config, draw, expert, log)
                    for draw in sorted({k[0] for k in left})}
        for n in config.sizes:  # a size's models of every draw, measured in one pass
            todo = sorted(k for k in left if k[1] == n)
            for key in [k for k in todo if n > len(training[k[0]])]:
                log(f"  draw {key[0]}: {len(training[key[0]])} demonstrations, not {n}: "
                    f"{key[2]}/{key[3]} skipped")
            todo = [k for k in todo if n <= len(training[k[0]])]
            if not todo:
                continue
            _learn_size(out, config, [k for k in todo if not point_model_path(out, *k).exists()],
                        training, pool, log)
            log(f"  {n} demonstrations: measuring {len(todo)} models on "
                f"{len(held_out.decisions)} decisions")
            models = {k: FootholdModel.load(point_model_path(out, *k)) for k in todo}
            scores = _measure(held_out, out, config, models, pool, processes)
            points.extend(_model_point(k, m, scores[k]) for k, m in models.items())
            save()
    return save(time.perf_counter() - started)
