"""The paper's walking experiment end to end (§II-B, §V, Tables I and II): ``footfall reproduce``.

1. Terrain: training boards of several kinds and difficulties, a flat board,
   and boards of the test kinds (a rocky module among them; fresh seeds
   each) on a difficulty grid: calibration boards and sweep boards.
2. Corrections (§II-B): the robot crosses every training board with its
   current reward function (the hand-tuned default first); the teacher
   (:mod:`footfall.expert.teachers`) inspects each run log and labels a better
   foothold wherever the robot's choice fell short of its best by more than a
   margin (:mod:`footfall.expert.corrections`). footfall learns from all corrections so far
   and the robot walks again, for a few rounds, until about 100
   demonstrations are collected (and, for a few extra rounds, while the
   front or the hind legs have too few to learn from).
3. Learning: the paper's three ranking functions -- terrain features,
   templates, templates + features, each with the pose features -- from the
   same corrections, L1-regularised with lambda at the smallest
   cross-validation error (the paper's rule); Table I.
4. Unseen terrain (Table II; :mod:`footfall.experiments.unseen`): the test
   difficulty chosen by a rule on the calibration boards (the hardest grid
   level at which the teacher choosing every foothold still crosses 90 % of
   its runs, its success fitted non-increasing over the grid); the three functions, the expert and the hand-tuned reward on
   several fresh test boards at that difficulty with the same 21 run seeds
   (paired runs), the templates + features function on the flat board (the
   slip baseline): Table II per board and pooled, with Wilson intervals,
   the distance walked, exact McNemar tests and paired bootstrap intervals
   between every two methods; every method's success against difficulty on
   the sweep boards. The offline ranking of the three functions on expert
   demonstrations over the first test board is reported beside it.
5. A report, Markdown and a self-contained HTML page (:mod:`footfall.experiments.report`).

Everything lives in one store (``reproduce.sqlite``): every finished run is
written with its corrections in one transaction under a unique key, so a
reproduction stopped at any point and started again with the same arguments
skips what is stored and loses nothing. Runs are seeded and independent of
the order in which parallel workers finish; demonstrations are used in the
order of their source (run key, step), never of their arrival. Every seed --
of a board, a run, the expert's inspection, its demonstrations, the learner
-- comes from a named stream of :class:`footfall.core.seeds.SeedStreams`, so
two reproduction seeds share no randomness.

Each stage is a function with a typed result: :func:`open_workspace` (1),
:func:`correction_rounds` (2), :func:`learn_functions` (3),
:mod:`footfall.experiments.unseen`'s ``calibrate``, ``evaluate`` and ``sweep``
(4); :func:`run_reproduction`
runs them in order and writes the report (5).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from footfall.core.compute import usable_cores
from footfall.core.errors import FootfallError
from footfall.core.folders import holding_folders
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, above, at_least, param, within
from footfall.core.robot import LITTLEDOG
from footfall.data.store import DemoStore
from footfall.experiments.difficulty import calibration_held
from footfall.experiments.executors import Executor, LocalPool
from footfall.experiments.judged_runs import choice_quality, imitation_gaps
from footfall.experiments.report import write_report
from footfall.experiments.reproduce_learning import learn_functions, learn_saved
from footfall.experiments.runs import RunJob, Runner
from footfall.experiments.unseen import FLAT, calibrate, evaluate, sweep
from footfall.experiments.workspace import (
    ROBOT_FEATURE_SET,
    Spec,
    Workspace,
    boards,
    calibration_boards,
    confirmation_board_count,
    confirmation_boards,
    correction_seeds,
    open_workspace,
    test_boards,
)
from footfall.expert.collect import collect_demonstrations
from footfall.expert.corrections import REPRODUCTION_MARGIN
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert, walking_expert
from footfall.expert.teachers import TEACHERS, state_judge
from footfall.learning.evaluation import expert_values, rank_scores
from footfall.learning.learner import LEARNERS, get_learner
from footfall.learning.model import LEG_GROUPS
from footfall.learning.ranker import SELECTIONS
from footfall.learning.supervision import SUPERVISIONS
from footfall.learning.train import FOLDS, check_budget
from footfall.sim.episode import WalkConfig
from footfall.sim.rollout import RolloutConfig
from footfall.terrain import KINDS

STORE_NAME = "reproduce.sqlite"


def is_board_spec(value: object) -> bool:
    """A board: a non-empty tuple of (kind, difficulty) with a known kind and 0 <= d <= 1."""
    return isinstance(value, tuple) and len(value) > 0 and all(
        isinstance(m, tuple) and len(m) == 2 and m[0] in KINDS
        and isinstance(m[1], (int, float)) and not isinstance(m[1], bool) and 0 <= m[1] <= 1
        for m in value)


def _test_kinds(value: object) -> bool:
    return (isinstance(value, tuple) and "rocky" in value
            and all(isinstance(k, str) and k in KINDS and k != "flat" for k in value))


def _difficulties(value: object) -> bool:
    return isinstance(value, tuple) and len(value) > 0 and all(
        isinstance(d, (int, float)) and not isinstance(d, bool) and 0 <= d <= 1 for d in value)


@dataclass(frozen=True)
class ReproduceConfig(Params):
    """Everything the reproduction runs; written next to its results (docs/configuration.md)."""

    seed: int = param(0, range=at_least(0), doc="the experiment's seed: every board, run and "
                      "demonstration seed is drawn from its named streams (core.seeds)")
    train_boards: tuple[Spec, ...] = param(
        ((("rocky", 0.4),), (("rocky", 0.6),), (("steps", 0.5),), (("barrier", 0.5),),
         (("slope", 0.5),), (("logs", 0.5),)),
        check=lambda v: isinstance(v, tuple) and len(v) > 0 and all(map(is_board_spec, v)),
        must="a non-empty tuple of boards, each a tuple of (kind, difficulty in [0, 1])",
        doc="the training boards the robot is corrected on")
    test_kinds: tuple[str, ...] = param(
        ("rocky", "steps"), check=_test_kinds,
        must="a tuple of terrain kinds other than flat ('footfall terrain make --help' lists "
             "them), 'rocky' among them",
        doc="the modules of every calibration, test and sweep board (fresh seeds each)")
    difficulties: tuple[float, ...] = param(
        (0.5, 0.6, 0.7, 0.8, 0.9, 1.0), unit="-", check=_difficulties,
        must="a non-empty tuple of numbers in [0, 1]",
        doc="the difficulty grid: calibrated on, and every method's success against difficulty")
    test_difficulty: float | None = param(
        None, unit="-", range=within(0.0, 1.0),
        doc="the test boards' difficulty; None: by the rule (experiments.difficulty) on the "
            "calibration boards")
    calibration_boards: int = param(5, range=at_least(1),
                                    doc="calibration boards per grid difficulty (boards differ "
                                        "more than runs on one board: many boards, few runs)")
    calibration_runs: int = param(2, range=at_least(1),
                                  doc="the expert's runs on each calibration board (each board "
                                      "has run seeds of its own)")
    calibration_level_runs: int = param(
        30, range=at_least(1),
        doc="the expert's runs the levels the difficulty rule's choice rests on (the chosen "
            "level and the next harder one) must hold before it decides: more calibration "
            "boards of those levels are walked until they do")
    confirmation_runs: int = param(
        30, range=at_least(0),
        doc="the teacher's runs on fresh boards (calibration_runs a board) that confirm the "
            "chosen test difficulty, and each easier level walked after one that does not "
            "(experiments.difficulty); 0: not confirmed")
    calibration_success: float = param(
        0.9, unit="-", range=within(0.0, 1.0, low_open=True),
        doc="the expert's success rate the rule requires at the test difficulty")
    test_boards: int = param(3, range=at_least(1),
                             doc="unseen test boards at the test difficulty (Table II per "
                                 "board and pooled; the first is the paper's one-board table)")
    rounds: int = param(5, range=at_least(1), doc="most correction rounds (walk, correct, learn)")
    target_demos: int | None = param(
        None, range=at_least(1), doc="rounds stop once this many corrections are collected; "
                                     "None: every round is walked")
    extra_rounds: int = param(3, range=at_least(0),
                              doc="further rounds, walked only while the front or the hind legs "
                                  "have fewer corrections than the cv folds need")
    corrections_per_run: int | None = param(
        None, range=at_least(1), doc="the teacher labels at most the worst this many steps of "
                                     "a run (None: all of them)")
    every_step: bool = param(
        True, doc="the teacher labels every step of the robot's runs, not only those short of "
                   "its best by more than the margin (DAgger: the student's own states); "
                   "corrections_per_run still bounds them")
    round_runs: int = param(2, range=at_least(1),
                            doc="runs on each training board in every correction round")
    supervision: str = param(
        "graded", check=lambda v: v in SUPERVISIONS, must="a registered supervision kind",
        doc="what the learners read of a correction (learning.supervision): the teacher's "
            "choice (the paper's), its refusals too, or every candidate graded by its values")
    veto: bool = param(
        True, doc="beside each ranking function, learn which candidates the teacher refuses "
                   "outright (learning.veto: relative to the best of a candidate set, from the "
                   "values its veto judges by) and take a penalty from them when walking")
    library_capped: bool = param(
        True, doc="the template library holds at most library_size templates however many "
                   "corrections there are (a sample of their footholds); False: every "
                   "corrected foothold is a template (the paper's)")
    margin: float = param(REPRODUCTION_MARGIN, unit="value", range=at_least(0),
                          doc="shortfall against the expert's best that counts (the walking "
                              "expert's unit: 1 cm off the gait-nominal foothold)")
    library_size: int = param(1000, range=at_least(1),
                              doc="templates in the library before L1 selection")
    training_candidates: int = param(30, range=at_least(1),
                                     doc="candidates per demonstration in the pairwise training set")
    selection: str = param("min", choices=SELECTIONS,
                           doc="lambda: at the smallest cross-validation error (paper §V) or by "
                               "the one-standard-error rule")
    cv: int = param(5, range=at_least(1), doc="cross-validation folds")
    learner: str = param("lambdarank", check=lambda v: v in LEARNERS,
                         must="a registered learner", doc="the learner of every ranking "
                         "function (l1: the paper's; lambdarank: picked by the rule of "
                         "docs/learning/model-selection.md)")
    folds: str = param("demonstration", choices=FOLDS,
                       doc="what a cross-validation fold never splits")
    template_budget: float | None = param(
        0.5, unit="-", range=above(0),
        doc="a leg group's function reads at most this share of its demonstrations' number "
            "of templates (docs/learning/model-selection.md); None: no budget (the paper's)")
    round_bandwidth_rms: float = param(
        0.004, unit="m", range=above(0), doc="RBF bandwidth (as RMS height difference) of the "
                                             "functions the robot walks with between rounds")
    final_bandwidth_rms: float | None = param(
        None, unit="m", range=above(0),
        doc="fixed bandwidth of the final functions; None: chosen by cross-validation (for "
            "a learner that reads only each column's order, the trees, set to 16 mm: "
            "features.templates.ORDER_ONLY_RMS)")
    eval_runs: int = param(21, range=at_least(1),
                           doc="runs per method on each test board, the same seeds on every "
                               "board (the paper's 21)")
    sweep_runs: int = param(3, range=at_least(1),
                            doc="runs per method at each difficulty of the grid (one board each)")
    offline_demos: int = param(40, range=at_least(1), doc="the teacher's demonstrations on the "
                                                          "test board for the ranking table")
    walk: WalkConfig = param(factory=lambda: reproduction_walk(),
                             doc="every run's settings (F within REPRODUCTION_SEARCH_RADIUS)")
    expert: ExpertConfig | None = param(
        None, doc="the synthetic expert who judges (and, as or within the teacher, corrects "
                  "and demonstrates); None: walking_expert(walk.footstep.lead), filled in so "
                  "that config.json states it")
    teacher: str = param("accepted", check=lambda v: v in TEACHERS, must="a registered teacher",
                         doc="who corrects the runs and walks as the reference: 'accepted' (the "
                             "hand-tuned reward among the footholds the expert accepts; picked "
                             "by the rule of docs/learning/teacher.md), 'guarded', 'expert' or "
                             "'rollout' (the accepted teacher's best candidates tried in "
                             "branches of each run; on a state alone -- the offline ranking, "
                             "the verdicts on test runs -- its base, the accepted teacher, "
                             "answers)")
    rollout: RolloutConfig = param(
        factory=RolloutConfig, doc="the rollout teacher's settings, where the teacher is "
                                   "'rollout' (sim.rollout; docs/learning/teacher.md)")

    def __post_init__(self) -> None:
        if self.expert is None and isinstance(self.walk, WalkConfig):
            object.__setattr__(self, "expert", walking_expert(self.walk.footstep.lead))
        super().__post_init__()
        check_budget(get_learner(self.learner), self.template_budget)
        if self.veto and not get_learner(self.learner).vetoes:
            raise FootfallError(f"learner {self.learner!r} cannot carry a learned veto; use "
                                f"lambdarank or veto=False")
        step = self.walk.footstep  # a teacher these settings cannot make fails here, not mid-run
        state_judge(self.teacher, self.expert, step.bias_weight, step.lead)

    @classmethod
    def quick(cls, seed: int = 0) -> ReproduceConfig:
        """A small version (a few minutes on two cores): fewer boards, runs and templates."""
        return cls(seed=seed, train_boards=((("rocky", 0.5),), (("steps", 0.5),)),
                   test_kinds=("rocky",), difficulties=(0.5, 0.9), calibration_boards=1,
                   calibration_runs=2, calibration_level_runs=4, confirmation_runs=2,
                   test_boards=2, rounds=2, corrections_per_run=6,
                   library_size=200, training_candidates=40, cv=3, final_bandwidth_rms=0.004,
                   eval_runs=3, sweep_runs=1, offline_demos=12)


REPRODUCTION_SEARCH_RADIUS = 0.03  # [m] the candidate set F of a step in the reproduction: the
# reachable footholds within this distance of the gait-nominal position (or all reachable ones
# where none of those is usable); docs/configuration.md gives the runs behind the number


def reproduction_walk() -> WalkConfig:
    """The walking settings of the reproduction: the defaults, F within REPRODUCTION_SEARCH_RADIUS."""
    base = WalkConfig()
    return replace(base, footstep=replace(base.footstep, search_radius=REPRODUCTION_SEARCH_RADIUS))


def _short_groups(demos: list, cv: int) -> list[str]:
    """The leg groups (front, hind) with fewer than ``cv`` demonstrations: they cannot be learned."""
    front = sum(LITTLEDOG.leg(d.state.swing_leg).front for d in demos)
    counts = {"front": front, "hind": len(demos) - front}
    return [g for g in LEG_GROUPS if counts[g] < cv]


def round_labels(store: DemoStore, rounds: int) -> list:
    """The corrections of rounds 0 .. rounds - 1, in source order.

    A resumed reproduction may already hold later rounds' corrections: a
    round's function learns from the earlier rounds only, as it did the first time.
    """
    demos = []
    for r in range(rounds):
        demos += store.demonstrations(source_prefix=f"run:correct/r{r}/")
    return sorted(demos, key=lambda d: _source_order(d.source))


def _source_order(source: str) -> tuple:
    head, _, k = source.rpartition(":step:")
    return head, int(k)


# ---------------------------------------------------------------- stage 2
@dataclass(frozen=True)
class Corrections:
    """What the correction rounds gave (paper §II-B): the rounds and every correction."""

    rounds: list[dict]  # per round: its reward, runs, crossings, corrections so far
    demos: list  # the corrections of every round, in source order (run key, step)


def _learning_threads(runner: Runner) -> int:
    """A round's learning has this machine to itself (no run is walked meanwhile): the local
    pool's processes as its threads, at most the cores this process may use."""
    return max(1, min(getattr(runner.executor, "processes", None) or 1, usable_cores()))


def correction_rounds(ws: Workspace, runner: Runner) -> Corrections:
    """Walk, correct, learn, for up to ``rounds + extra_rounds`` rounds (see the module)."""
    config, log = ws.config, runner.log
    train = [n for n in ws.paths if n.startswith("train")]
    model_path: str | None = None
    rounds: list[dict] = []
    short: list[str] = []
    for r in range(config.rounds + config.extra_rounds):
        jobs = [RunJob(f"correct/r{r}/{name}" + (f"/s{k}" if k else ""), str(ws.paths[name]),
                       model_path, seed, config.walk, True, config.margin,
                       config.corrections_per_run, config.expert, inspect_seed=inspect,
                       teacher=config.teacher, every_step=config.every_step,
                       rollout=config.rollout)
                for name, runs in zip(train, correction_seeds(config, r))
                for k, (seed, inspect) in enumerate(runs)]
        runner.run(jobs, f"round {r} runs")
        demos = round_labels(runner.store, r + 1)
        runs = [runner.store.runs(key_prefix=j.key)[0] for j in jobs]
        rounds.append({"round": r, "reward": (f"models/{Path(model_path).name}" if model_path
                                              else "hand-tuned default"),
                       "runs": len(runs), "successes": sum(x["result"]["success"] for x in runs),
                       "demonstrations_total": len(demos)})
        log(f"round {r}: {rounds[-1]['successes']} / {len(runs)} crossings, "
            f"{len(demos)} corrections so far")
        short = _short_groups(demos, config.cv)
        if ((config.target_demos is not None and len(demos) >= config.target_demos)
                or r >= config.rounds - 1) and not short:
            break
        if short:  # too few to learn from: walk the next round with the same reward
            log(f"  too few corrections of the {' and '.join(short)} legs to learn from "
                f"({config.cv}-fold CV); the next round walks with the same reward"
                + (" (an extra round)" if r + 1 >= config.rounds else ""))
            continue
        learn_saved(ws, f"round{r + 1}", demos, ROBOT_FEATURE_SET, config.round_bandwidth_rms,
                    log, _learning_threads(runner))
        model_path = str(ws.model_path(f"round{r + 1}"))
    if short:
        raise FootfallError(
            f"after {len(rounds)} correction rounds the {' and '.join(short)} legs have fewer "
            f"than {config.cv} corrections, too few to learn from: the robot's choices seldom "
            f"fell short of the expert's by the margin ({config.margin:g} units)")
    return Corrections(rounds, round_labels(runner.store, len(rounds)))


# ---------------------------------------------------------------- stage 3
def _calibration_boards_walked(config: ReproduceConfig, choice) -> dict:
    """The calibration boards of every grid level the rule walked (more where it needed runs),
    and the confirmation boards of every level confirmed."""
    out = {}
    for j, d in enumerate(config.difficulties):
        level = choice.levels.get(f"{d:g}")
        walked = config.calibration_boards if level is None else -(
            -level["runs"] // config.calibration_runs)
        out.update(calibration_boards(config, j, range(walked)))
        if f"{d:g}" in choice.confirmations:
            out.update(confirmation_boards(config, j, range(confirmation_board_count(config))))
    return {name: {"modules": [list(m) for m in spec], "seed": seed}
            for name, (spec, seed) in out.items()}


# ------------------------------------------------------------------ the job
@holding_folders
def run_reproduction(out: str | os.PathLike, config: ReproduceConfig | None = None,
                     processes: int | None = None, log: Callable[[str], None] = print,
                     on_run: Callable[[str], None] | None = None,
                     executor: Executor | None = None) -> dict:
    """Run (or resume) the whole experiment into ``out``; return the results (also results.json).

    The stages of the module's docstring, one function each. ``on_run(key)``
    is called after each run is stored (e.g. to show progress). The runs are
    walked on ``executor`` [default: a local pool of ``processes`` workers].
    """
    # Built here, not at import: a config's checks ask the registries, which load the
    # plugins (a broken plugin must fail as one line when the command runs, not on import).
    config = ReproduceConfig() if config is None else config
    started = time.perf_counter()
    ws = open_workspace(out, config)
    results: dict = {"config": config.to_dict(),
                     "boards": {name: {"modules": [list(m) for m in spec], "seed": seed}
                                for name, (spec, seed) in boards(config).items()}}
    with DemoStore(ws.out / STORE_NAME, create=True) as store:
        runner = Runner(store, ws.by_hash, executor or LocalPool(processes), on_run, log)
        corrections = correction_rounds(ws, runner)
        results["rounds"] = corrections.rounds
        results["demonstrations"] = _demo_summary(corrections.demos, ws.by_hash)
        functions = learn_functions(ws, corrections.demos, log,
                                    getattr(runner.executor, "processes", None) or 1,
                                    ws.out / STORE_NAME)
        results["table1"] = functions.table1()
        results["models"] = functions.summary()
        difficulty = calibrate(ws, runner)
        results["calibration"] = difficulty.as_dict()
        results["boards"].update(_calibration_boards_walked(config, difficulty))
        results["test_difficulty"] = difficulty.difficulty
        evaluation = evaluate(ws, runner, difficulty)
        results["boards"].update({name: {"modules": [list(m) for m in spec], "seed": seed}
                                  for name, (spec, seed) in
                                  test_boards(config, difficulty.difficulty).items()})
        results["table2"] = {**evaluation.per_board[evaluation.boards[0]],
                             FLAT: evaluation.pooled[FLAT]}  # the paper's one-board table
        results["table2_pooled"] = evaluation.pooled
        expert = evaluation.pooled.get("expert")
        results["calibration"]["held_on_test"] = None if expert is None else calibration_held(
            results["calibration"], expert["successes"], expert["runs"])
        results["table2_boards"] = evaluation.per_board
        results["pairs"] = evaluation.pairs
        results["slips_mm"] = evaluation.slips_mm
        results["sweep"] = sweep(ws, runner)
        results["strip_seed"] = evaluation.strip_seed
        # The offline ranking of the three functions on the expert's demonstrations, and the
        # expert's verdict on every choice the robot made in the test-board runs.
        results["ranking"] = _ranking(ws, store, functions.models, log)
        results["choices"] = choice_quality(store, ws.by_hash, config, evaluation.boards, log)
        results["imitation_gap"] = imitation_gaps(store, ws.by_hash, config, evaluation.boards,
                                                  log)
        results["seconds_this_session"] = time.perf_counter() - started
    write_report(ws.out, results, ws.maps, functions.models, config, log)
    return results


def _demo_summary(demos: list, maps: dict[str, HeightMap]) -> dict:
    kinds: dict[str, int] = {}
    legs: dict[str, int] = {}
    for d in demos:
        mods = maps[d.terrain_hash].metadata.get("modules", [])
        x = d.foothold[0] - maps[d.terrain_hash].bounds[0]
        kind = next((f"{m['kind']} {m['difficulty']:g}" if "difficulty" in m
                     else str(m.get("file", m["kind"])) for m in mods
                     if m["x_start"] <= x < m["x_end"]), "?")
        kinds[kind] = kinds.get(kind, 0) + 1
        legs[d.swing_leg] = legs.get(d.swing_leg, 0) + 1
    return {"n": len(demos), "by_module": dict(sorted(kinds.items())), "by_leg": legs}


def _ranking(ws: Workspace, store: DemoStore, models: dict, log: Callable[[str], None]) -> dict:
    """The three functions ranked on the teacher's test-board demonstrations, by the expert."""
    config, test = ws.config, ws.maps["test0"]
    step = config.walk.footstep
    teacher = state_judge(config.teacher, config.expert, step.bias_weight, step.lead)
    demos = store.demonstrations(source_prefix="walker:test")
    if len(demos) < config.offline_demos:  # collected and stored in one transaction: all or none
        made = collect_demonstrations([test], teacher, config.offline_demos,
                                      seed=ws.streams.seed_for("demonstrations", 0),
                                      source="walker:test")
        store.add_demonstrations(made, terrains=[test])
        demos = store.demonstrations(source_prefix="walker:test")
    log(f"ranking on {len(demos)} of the teacher's demonstrations over the test board")
    terrain = {test.content_hash(): test}.__getitem__
    values = expert_values(demos, terrain, SyntheticExpert(config.expert))
    return {fs: rank_scores(m, demos, terrain, values=values).as_dict() for fs, m in models.items()}
