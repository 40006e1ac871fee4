"""Stage 4 of the reproduction: walking terrain never trained on (paper §V, Table II).

1. **The test difficulty by a rule** (:func:`calibrate`): the synthetic expert
   choosing every foothold walks ``calibration_boards`` boards of the test
   kinds at every difficulty of the grid, ``calibration_runs`` runs each, and
   more boards of the levels the rule's choice rests on until each holds
   ``calibration_level_runs`` runs; the rule chooses the hardest level up
   to which it still crosses 90 % of its runs, and that choice is confirmed
   on fresh boards (:func:`confirm`, ``confirmation_runs`` runs; the next
   easier level where it does not stand) (:mod:`footfall.experiments.difficulty`).
2. **Table II on several unseen boards** (:func:`evaluate`): the three
   learned functions, the synthetic expert and the hand-tuned reward walk
   ``test_boards`` fresh boards at that difficulty with the same run seeds
   (paired runs), and the templates + features function walks the flat board
   (the paper's slip baseline). Table II per board and pooled, with Wilson
   intervals, the distance walked, and for every pair of methods the exact
   McNemar test and paired bootstrap intervals of the differences in success
   and slip (:mod:`footfall.experiments.paired`). The first board's table is
   the paper's one-board table.
3. **Success against difficulty** (:func:`sweep`): every method on one board
   per grid difficulty, ``sweep_runs`` runs each, always.

Run keys: ``calibrate/D/I/sSEED``, ``confirm/D/I/sSEED``, ``eval/BOARD/METHOD/sSEED``
(BOARD ``test0``, ``test1``, ... or ``flat``), ``sweep/D/METHOD/sSEED``; a stopped stage resumes
where it stopped (:class:`footfall.experiments.runs.Runner`).
"""

from __future__ import annotations

from dataclasses import dataclass

from footfall.data.store import DemoStore
from footfall.experiments.batch import summarise
from footfall.experiments.difficulty import (
    DifficultyChoice,
    choose_difficulty,
    confirm_choice,
    deciding_levels,
    next_to_confirm,
)
from footfall.experiments.paired import RunOutcome, compare_all, distance_summary
from footfall.experiments.runs import RunJob, Runner
from footfall.experiments.workspace import (
    ROBOT_FEATURE_SET,
    Workspace,
    calibration_boards,
    calibration_seeds,
    confirmation_board_count,
    confirmation_boards,
    confirmation_seeds,
    evaluation_seeds,
    most_calibration_boards,
    sweep_seeds,
    test_boards,
)
from footfall.features.family import PAPER_FEATURE_SETS

REFERENCES = ("expert", "default")  # the teacher choosing every foothold; the
# hand-tuned reward (the robot before learning)
METHODS = (*PAPER_FEATURE_SETS, *REFERENCES)  # what walks every test and sweep board
COMPARED = ("both", "templates", "terrain", *REFERENCES)  # pairs (a, b) in this order: the
# paper's claimed better method first, so a "held" verdict is the paper's ordering
FLAT = "flat"  # Table II's row of the templates + features function on the flat board


def method_job(ws: Workspace, key: str, board: str, method: str, seed: int) -> RunJob:
    """The run of ``method`` (a feature set, "expert" or "default") on ``board`` with ``seed``."""
    config = ws.config
    path = str(ws.paths[board])
    if method == "expert":
        return RunJob(key, path, None, seed, config.walk, expert=config.expert, judge=True,
                      teacher=config.teacher, rollout=config.rollout)
    if method == "default":
        return RunJob(key, path, None, seed, config.walk)
    return RunJob(key, path, str(ws.model_path(method)), seed, config.walk)


# ---------------------------------------------------------------- 1. the rule
def calibrate(ws: Workspace, runner: Runner) -> DifficultyChoice:
    """The test difficulty: ``config.test_difficulty`` if set, else by the rule.

    Every grid level first gets ``calibration_boards`` boards; then the levels
    the rule's choice rests on get more boards (fresh board and run seeds)
    until each holds ``calibration_level_runs`` runs, and the rule decides
    again, until its deciding levels hold that many.
    """
    config = ws.config
    if config.test_difficulty is not None:
        d = float(config.test_difficulty)
        return DifficultyChoice(d, True, config.calibration_success, {},
                                "fixed by the setting test_difficulty (no calibration)")
    per_level = {d: config.calibration_boards for d in config.difficulties}
    while True:
        jobs = {d: [method_job(ws, f"calibrate/{d:g}/{i}/s{s}", f"cal{d:g}-{i}", "expert", s)
                    for i in range(per_level[d]) for s in calibration_seeds(config, j, i)]
                for j, d in enumerate(config.difficulties)}
        runner.run([j for level in jobs.values() for j in level], "calibration runs (the teacher)")
        stored = {r["key"]: r["result"] for r in runner.store.runs(key_prefix="calibrate/")}
        outcomes = {d: (sum(bool(stored[j.key]["success"]) for j in level), len(level))
                    for d, level in jobs.items()}
        more = deciding_levels(outcomes, config.calibration_success,
                               config.calibration_level_runs)
        if not more:
            break
        for d in more:  # enough boards of the level for the runs the rule needs
            j = config.difficulties.index(d)
            per_level[d] = most_calibration_boards(config)
            ws.add_boards(calibration_boards(config, j, range(per_level[d])))
        runner.log("calibration: " + ", ".join(f"{d:g}" for d in more) + " decide the rule; "
                   f"walking them to {config.calibration_level_runs} runs")
    choice = choose_difficulty(outcomes, config.calibration_success)
    runner.log("calibration: the rule chose " + f"{choice.difficulty:g}" + (
        "" if choice.met else " (the teacher missed the threshold even at the easiest level)")
        + ": the teacher crossed " + ", ".join(
            f"{v['successes']}/{v['runs']} at {k}" for k, v in choice.levels.items()))
    if config.confirmation_runs:
        choice = confirm(ws, runner, choice)
    return choice


def confirm(ws: Workspace, runner: Runner, choice: DifficultyChoice) -> DifficultyChoice:
    """The rule's choice confirmed on fresh boards, stepping down the grid where it is not
    (:func:`footfall.experiments.difficulty.next_to_confirm`); run keys
    ``confirm/D/I/sSEED`` on boards ``confirm<D>-<I>``."""
    config = ws.config
    boards = range(confirmation_board_count(config))
    walked: dict[float, tuple[int, int]] = {}
    while (d := next_to_confirm(choice, config.difficulties, walked)) is not None:
        j = config.difficulties.index(d)
        ws.add_boards(confirmation_boards(config, j, boards))
        jobs = [method_job(ws, f"confirm/{d:g}/{i}/s{s}", f"confirm{d:g}-{i}", "expert", s)
                for i in boards for s in confirmation_seeds(config, j, i)]
        runner.run(jobs, f"confirmation runs at {d:g} (the teacher, fresh boards)")
        stored = {r["key"]: r["result"] for r in runner.store.runs(key_prefix=f"confirm/{d:g}/")}
        walked[d] = (sum(bool(stored[job.key]["success"]) for job in jobs), len(jobs))
        runner.log(f"confirmation at {d:g}: the teacher crossed {walked[d][0]}/{walked[d][1]}")
    choice = confirm_choice(choice, walked)
    runner.log("test difficulty " + f"{choice.difficulty:g}"
               + ("" if choice.met else " (the rule is not met)"))
    return choice


# ---------------------------------------------------------------- 2. Table II
@dataclass(frozen=True)
class Evaluation:
    """Table II on several unseen boards, every method with the same run seeds (paired runs)."""

    difficulty: DifficultyChoice  # the test difficulty and how it was chosen
    seeds: list[int]  # the run seeds, the same on every board
    boards: list[str]  # the test boards: test0 (the paper's one-board table), test1, ...
    per_board: dict  # board -> method -> Table II row (batch.summarise + distance)
    pooled: dict  # method (and "flat") -> the row over every test board
    pairs: list[dict]  # paired comparisons over every test board (paired.compare)
    slips_mm: dict  # method -> slip [mm] of every foothold of its successful runs, pooled
    strip_seed: int  # the report's Fig. 4: the first templates + features run that crossed on test0


def evaluate(ws: Workspace, runner: Runner, choice: DifficultyChoice) -> Evaluation:
    """Every method on every test board at ``choice``'s difficulty, the flat baseline, the pairs."""
    config = ws.config
    ws.add_boards(test_boards(config, choice.difficulty))
    names = [f"test{b}" for b in range(config.test_boards)]
    seeds = evaluation_seeds(config)
    jobs = [method_job(ws, f"eval/{board}/{m}/s{s}", board, m, s)
            for board in names for m in METHODS for s in seeds]
    jobs += [method_job(ws, f"eval/flat/{ROBOT_FEATURE_SET}/s{s}", "flat", ROBOT_FEATURE_SET, s)
             for s in seeds]
    runner.run(jobs, "evaluation runs")
    runs = load_runs(runner.store, "eval/")
    per_board = {board: {m: _row(runs, f"eval/{board}/{m}/") for m in METHODS}
                 for board in names}
    pooled = {m: _row(runs, *(f"eval/{board}/{m}/" for board in names)) for m in METHODS}
    pooled[FLAT] = _row(runs, f"eval/flat/{ROBOT_FEATURE_SET}/")
    outcomes = test_outcomes(runs, names, seeds)
    slips = {m: _slips(runs, *(f"eval/{board}/{m}/" for board in names)) for m in METHODS}
    slips[FLAT] = _slips(runs, f"eval/flat/{ROBOT_FEATURE_SET}/")
    crossed = [s for s in seeds if runs[f"eval/{names[0]}/{ROBOT_FEATURE_SET}/s{s}"].result[
        "success"]]
    return Evaluation(choice, seeds, names, per_board, pooled,
                      compare_all(outcomes, COMPARED, seed=ws.streams.seed_for("learning")),
                      slips, crossed[0] if crossed else seeds[0])


# ---------------------------------------------------------------- 3. the curves
def sweep(ws: Workspace, runner: Runner) -> dict:
    """Every method on one board per grid difficulty: difficulty -> method -> Table II row."""
    config = ws.config
    seeds = sweep_seeds(config)  # paired over difficulties too
    jobs = [method_job(ws, f"sweep/{d:g}/{m}/s{s}", f"sweep{d:g}", m, s)
            for d in config.difficulties for m in METHODS for s in seeds]
    runner.run(jobs, "sweep runs (success against difficulty)")
    runs = load_runs(runner.store, "sweep/")
    return {f"{d:g}": {m: _row(runs, f"sweep/{d:g}/{m}/") for m in METHODS}
            for d in config.difficulties}


# ---------------------------------------------------------------- the store
def _records(runs: dict, prefixes: tuple[str, ...]) -> list:
    """The runs under ``prefixes``, in key order (not in the order parallel workers finished)."""
    return [runs[k] for k in sorted(runs) if k.startswith(prefixes)]


def _row(runs: dict, *prefixes: str) -> dict:
    """Table II's row of the runs under ``prefixes``, with the distance walked."""
    records = _records(runs, prefixes)
    return {**summarise(records).as_dict(),
            **distance_summary([_outcome(r) for r in records])}


def test_outcomes(runs: dict, boards: list[str], seeds: list[int], tag: str = "") -> dict:
    """Every method's test-board runs as paired units: method -> (``tag`` + board, run seed) ->
    :class:`~footfall.experiments.paired.RunOutcome` (``runs``: key -> record, ``eval/...``)."""
    return {m: {(tag + board, s): _outcome(runs[f"eval/{board}/{m}/s{s}"])
                for board in boards for s in seeds} for m in METHODS}


def load_runs(store: DemoStore, prefix: str) -> dict:
    """Run key -> run record of every stored run under ``prefix``."""
    return {r["key"]: store.run(r["id"]) for r in store.runs(key_prefix=prefix)}


def _outcome(record) -> RunOutcome:
    return RunOutcome.of(record.result, record.slips())


def _slips(runs: dict, *prefixes: str) -> list[float]:
    return [1e3 * float(s) for r in _records(runs, prefixes) if r.result.get("success")
            for s in r.slips()]
