"""``footfall offline``, ``learning-curve``, ``reproduce``, ``study``, ``ablation`` and ``demo``: the
experiments end to end, and the picture demo."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import click

from footfall.cli.choices import (
    BUDGET,
    FEATURE_SET,
    LEARNER,
    NO_BUDGET,
    SEED,
    SUPERVISION,
    TEACHER,
    RegistryChoice,
)
from footfall.cli.executors import executor_options, opened_executor
from footfall.cli.output import emit, json_option, progress_log
from footfall.core.compute import usable_cores
from footfall.core.errors import FootfallError
from footfall.experiments.ablation import VARIANTS, AblationConfig, ablation_markdown, run_ablation
from footfall.experiments.curve_report import LINES, compare_points, read_curve
from footfall.experiments.curve_walk import (
    CurveWalkConfig,
    report_name,
    run_curve_walk,
    walk_markdown,
)
from footfall.experiments.learning_curve import CurveConfig, run_learning_curve
from footfall.experiments.offline import OfflineConfig, run_offline
from footfall.experiments.reproduce import ReproduceConfig, run_reproduction
from footfall.experiments.study import run_study
from footfall.experiments.terrain_suite import (
    SUITES,
    SuiteConfig,
    compare_suites,
    comparison_markdown,
    run_suite,
    suite_markdown,
    suite_outcomes,
)
from footfall.learning.ranker import SELECTIONS
from footfall.learning.train import FOLDS
from footfall.plots.showcase import run_demo


@click.command()
@click.option("--out", "out", default="out/offline", show_default=True, help="Report folder.")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--quick", is_flag=True,
              help="A small version (fewer demonstrations, L1 only) for a smoke test.")
@json_option
def offline(out: str, seed: int, quick: bool, as_json: bool) -> None:
    """The offline experiment: learn from demonstrations, rank unseen terrain (Table I)."""
    config = OfflineConfig.quick(seed) if quick else OfflineConfig(seed=seed)
    summary = run_offline(Path(out), config, log=progress_log(as_json))
    emit(as_json, summary, f"wrote {Path(out) / 'report.md'}")


@click.command("learning-curve")
@click.option("--out", "out", default="out/learning-curve", show_default=True,
              help="Report folder (run again with the same settings to resume).")
@click.option("--sizes", default=None, metavar="N[,N...]",
              help="Demonstrations at each point [default: 25,50,100,200,400,800,1600].")
@click.option("--draws", type=click.IntRange(min=1), default=None,
              help="Independent draws of boards and demonstrations per point [default: 3].")
@click.option("--features", "feature_sets", multiple=True, type=FEATURE_SET,
              help="A feature set (repeatable) [default: terrain, templates, both].")
@click.option("--learner", "learners", multiple=True, type=LEARNER,
              help="A learner (repeatable) [default: l1, kernel, lambdarank].")
@click.option("--test-decisions", type=click.IntRange(min=1), default=None,
              help="Held-out decisions every point is measured on [default: 1000].")
@click.option("--folds", type=click.Choice(FOLDS), default=None,
              help="What a cross-validation fold never splits [default: demonstration].")
@click.option("--selection", type=click.Choice(SELECTIONS), default=None,
              help="Where a learner stops on its path: one standard error or the smallest CV "
                   "error [default: min].")
@click.option("--template-budget", type=BUDGET, default=None,
              help="A leg group's function reads at most this share of its demonstrations' "
                   "number of templates, or 'none' [default: none].")
@click.option("--library-size", type=click.IntRange(min=3), default=None,
              help="Templates in the library before selection [default: 1000].")
@click.option("--library-capped/--library-uncapped", default=None,
              help="Never more templates than --library-size (more demonstrations than a "
                   "third of it: a uniform random sample of their footholds), or every "
                   "demonstrated foothold a template as the paper [default: uncapped].")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--quick", is_flag=True, help="A small curve (two sizes, two draws) for a smoke "
                                            "test.")
@click.option("--search-radius", type=click.FloatRange(min=0, min_open=True), default=None,
              metavar="METRES", help="The decisions' F, trained on and held out: the reachable "
              "footholds within this of the gait-nominal foothold, as the walking planner's "
              "(the reproduction walks with 0.03) [default: every reachable foothold].")
@click.option("--path-bias", type=click.FloatRange(min=0), default=None, metavar="REWARD/M",
              help="Rank every scorer as the footstep planner picks: its values less this path "
                   "bias per metre from the gait-nominal foothold, scaled to its spread (the "
                   "reproduction walks 60) [default: each scorer alone].")
@click.option("--processes", type=click.IntRange(1, 1024), default=None,
              help="Worker processes that collect the draws and learn each size's models "
                   "(the same models as one) [default: the available cores].")
@json_option
def learning_curve(out: str, sizes: str | None, draws: int | None,
                   feature_sets: tuple[str, ...], learners: tuple[str, ...],
                   test_decisions: int | None, folds: str | None, selection: str | None,
                   template_budget: float | str | None, library_size: int | None,
                   library_capped: bool | None, seed: int,
                   quick: bool, search_radius: float | None, path_bias: float | None,
                   processes: int | None, as_json: bool) -> None:
    """Learning curves: each feature set and learner from 25 to 1 600 demonstrations, on
    held-out decisions, with the hand-tuned and expert lines."""
    config = CurveConfig.quick(seed) if quick else CurveConfig(seed=seed)
    changes: dict = {}
    if sizes is not None:
        changes["sizes"] = _sizes_option(sizes)
    for key, value in (("draws", draws), ("test_decisions", test_decisions), ("folds", folds),
                       ("selection", selection), ("library_size", library_size),
                       ("library_capped", library_capped),
                       ("feature_sets", feature_sets or None), ("learners", learners or None),
                       ("search_radius", search_radius), ("path_bias", path_bias)):
        if value is not None:
            changes[key] = value
    if template_budget is not None:
        changes["template_budget"] = None if template_budget == NO_BUDGET else template_budget
    config = replace(config, **changes)  # checked: one line for a bad value
    summary = run_learning_curve(Path(out), config, log=progress_log(as_json),
                                 processes=processes or usable_cores())
    emit(as_json, summary, f"wrote {Path(out) / 'report.md'}")


@click.command("curve-compare")
@click.argument("curve")
@click.argument("other", required=False)
@click.option("--size", "n", type=click.IntRange(min=1), required=True,
              help="The demonstrations of the points compared.")
@click.option("--features", "feature_set", default="both", show_default=True,
              help="The feature set of the first point.")
@click.option("--learner", default="l1", show_default=True, help="The first point's learner.")
@click.option("--other-features", default=None, help="The second point's [default: --features].")
@click.option("--other-learner", default=None, help="The second point's [default: --learner].")
@click.option("--other-size", type=click.IntRange(min=1), default=None,
              help="The second point's demonstrations [default: --size].")
@click.option("--other-line", type=click.Choice(LINES), default=None,
              help="Compare with one of the curve's lines instead of a second point.")
@json_option
def curve_compare(curve: str, other: str | None, n: int, feature_set: str, learner: str,
                  other_features: str | None, other_learner: str | None,
                  other_size: int | None, other_line: str | None, as_json: bool) -> None:
    """Two learning-curve points on the same held-out decisions, paired: shares above the
    margin and the exact McNemar test, mean shortfalls and their paired bootstrap interval.

    CURVE is a curve's folder; OTHER a second one whose draws learned from the same
    demonstrations (default: CURVE)."""
    if other_line and (other_size or other_features or other_learner):
        raise FootfallError("--other-line compares with a line: it takes no --other-size, "
                            "--other-features or --other-learner")
    a = read_curve(Path(curve))
    b = a if other is None else read_curve(Path(other))
    r = compare_points(a, b, n, (feature_set, learner),
                       other_line or (other_features or feature_set, other_learner or learner),
                       other_size)
    sizes = f"{n}" if r["b_n"] == n or other_line else f"{n} against {r['b_n']}"
    lines = [f"{sizes} demonstrations, draws {', '.join(map(str, r['draws']))}; share of "
             f"held-out decisions above the margin ({r['margin']:g}):"]
    for side in ("a", "b"):
        q = r[side]
        at = "" if r["b_n"] == n or q["n"] is None else f" at {q['n']}"
        lines.append(f"  {'/'.join(q['point'])}{at}: {q['above_margin']:.3f} (per draw "
                     f"{', '.join(f'{v:.3f}' for v in q['per_draw'])})")
    lines.append(f"  above for the first only {r['a_only_above']}, for the second only "
                 f"{r['b_only_above']}: exact McNemar p = {r['p']:.3g}")
    lo, hi = r["shortfall_difference_ci"]
    lines.append(f"  mean shortfall {r['a']['mean_shortfall']:.2f} against "
                 f"{r['b']['mean_shortfall']:.2f}: first less second {r['shortfall_difference']:+.2f} "
                 f"[{lo:+.2f}, {hi:+.2f}] (95 % paired bootstrap)")
    emit(as_json, r, "\n".join(lines))


@click.command("curve-walk")
@click.argument("curve")
@click.option("--sizes", default=None, metavar="N[,N...]",
              help="The curve's sizes walked [default: 100,1600].")
@click.option("--features", "feature_set", default="both", show_default=True,
              help="The points' feature set.")
@click.option("--learner", type=LEARNER, default="lambdarank", show_default=True,
              help="The points' learner.")
@click.option("--expert", "with_expert", is_flag=True,
              help="Walk the walking expert choosing every foothold too (a reference; its runs "
                   "cost several hand-tuned ones).")
@click.option("--boards", type=click.IntRange(min=1), default=None,
              help="Walking boards rocky:0.7 steps:0.7, never trained on [default: 4].")
@click.option("--runs", type=click.IntRange(min=1), default=None,
              help="Runs on each board, the same seeds for every method [default: 8].")
@executor_options
@json_option
def curve_walk(curve: str, sizes: str | None, feature_set: str, learner: str, with_expert: bool,
               boards: int | None, runs: int | None, processes: int | None, executor_name: str,
               ray_address: str | None, as_json: bool) -> None:
    """Walk a learning curve's points on boards never trained on, paired with the hand-tuned
    reward: crossings beside the curve's offline measure.

    CURVE is the curve's folder; the runs go to CURVE/walk/ (run again to resume)."""
    changes: dict = {"feature_set": feature_set, "learner": learner,
                     "references": ("hand-tuned", "expert") if with_expert else ("hand-tuned",)}
    if sizes is not None:
        changes["sizes"] = _sizes_option(sizes)
    for key, value in (("boards", boards), ("runs", runs)):
        if value is not None:
            changes[key] = value
    config = replace(CurveWalkConfig(), **changes)  # checked: one line for a bad value
    with opened_executor(executor_name, processes, ray_address) as executor:
        summary = run_curve_walk(Path(curve), config, log=progress_log(as_json),
                                 executor=executor)
    emit(as_json, summary, walk_markdown(summary)
         + f"wrote {Path(curve) / 'walk' / report_name(config)}.md and .json")


def _sizes_option(sizes: str) -> tuple[int, ...]:
    """--sizes N[,N...] as a tuple of whole numbers (one line for anything else)."""
    try:
        return tuple(int(v) for v in sizes.split(","))
    except ValueError:
        raise FootfallError(f"--sizes must be whole numbers separated by commas, got "
                            f"{sizes!r}") from None


def test_kinds_option(f):
    """Add --test-kinds: the modules of the calibration, test and sweep boards."""
    return click.option(
        "--test-kinds", default=None, metavar="KIND[,KIND...]",
        help="Terrain kinds of every calibration, test and sweep board, 'rocky' among them "
             "[default: rocky,steps]; e.g. rocky,logs to test on kinds never trained on.")(f)


def learner_options(f):
    """Add --teacher, --learner, --folds and --template-budget: who teaches the reproduction and
    how it learns its ranking functions."""
    f = click.option("--teacher", type=TEACHER, default=None,
                     help="Who corrects the runs and walks as the reference line [default: "
                          "the reproduction's, docs/learning/teacher.md]: expert, guarded, "
                          "accepted, or rollout (candidates tried in branches of every run: "
                          "hours, not minutes).")(f)
    f = click.option("--supervision", type=SUPERVISION, default=None,
                     help="What the learners read of a correction [default: the reproduction's, "
                          "docs/learning/student.md]: choice, refusals or graded.")(f)
    f = click.option("--template-budget", type=BUDGET, default=None,
                     help="A leg group's function reads at most this share of its "
                          "demonstrations' number of templates, or 'none' [default: 0.5].")(f)
    f = click.option("--folds", type=click.Choice(FOLDS), default=None,
                     help="What a cross-validation fold never splits [default: "
                          "demonstration].")(f)
    return click.option("--learner", type=LEARNER, default=None,
                        help="The learner of every ranking function [default: lambdarank].")(f)


def _reproduce_config(seed: int, quick: bool, test_kinds: str | None,
                      learner: str | None = None, folds: str | None = None,
                      template_budget: float | str | None = None, teacher: str | None = None,
                      supervision: str | None = None):
    """The reproduction's settings for ``seed``: the default or quick ones, with other kinds,
    learner, folds, template budget, teacher or supervision."""
    config = ReproduceConfig.quick(seed) if quick else ReproduceConfig(seed=seed)
    changes: dict = {"learner": learner, "folds": folds, "teacher": teacher,
                     "supervision": supervision}
    if test_kinds is not None:
        changes["test_kinds"] = tuple(k.strip() for k in test_kinds.split(","))
    changes = {k: v for k, v in changes.items() if v is not None}
    if template_budget is not None:
        changes["template_budget"] = None if template_budget == NO_BUDGET else template_budget
    return replace(config, **changes)


def _table2_line(name: str, row: dict) -> str:
    """One row of Table II: successes of runs, and slip [mm]."""
    slip = ("-" if row["slip_mean_mm"] is None
            else f"{row['slip_mean_mm']:.1f} +- {row['slip_std_mm']:.1f} mm")
    return f"{name}: {row['successes']} / {row['runs']} succeeded, slip {slip}"


@click.command()
@click.option("--out", "out", default="out/reproduce", show_default=True, help="Report folder "
              "(and the store of every run; run again with the same arguments to resume).")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--quick", is_flag=True, help="A small version (a few minutes) for a smoke test.")
@test_kinds_option
@learner_options
@executor_options
@json_option
def reproduce(out: str, seed: int, quick: bool, test_kinds: str | None, learner: str | None,
              folds: str | None, template_budget: float | str | None,
              supervision: str | None, teacher: str | None, processes: int | None,
              executor_name: str, ray_address: str | None, as_json: bool) -> None:
    """The paper's walking experiment end to end: corrections, learning, Tables I and II."""
    config = _reproduce_config(seed, quick, test_kinds, learner, folds, template_budget, teacher,
                               supervision)
    with opened_executor(executor_name, processes, ray_address) as executor:
        results = run_reproduction(Path(out), config, log=progress_log(as_json),
                                   executor=executor)
    boards = len(results["table2_boards"])
    met = results["calibration"]["met"]
    lines = [f"test difficulty {results['test_difficulty']:g}"
             + ("" if met else " (NOT MET: the teacher missed the threshold even at the easiest "
                               "level, which is used)")
             + f"; rule: {results['calibration']['rule']}",
             "the first test board (the paper's one-board table):"]
    shown = {"expert": "teacher", "default": "hand-tuned"}  # the references' rows
    lines += ["  " + _table2_line(shown.get(k, k), v) for k, v in results["table2"].items()]
    lines += [f"pooled over {boards} test boards:"]
    lines += ["  " + _table2_line(shown.get(k, k), v)
              for k, v in results["table2_pooled"].items()]
    emit(as_json, results, "\n".join(lines + [f"wrote {Path(out) / 'report.md'} and report.html"]))


@click.command()
@click.option("--seeds", "first_seed", type=SEED, required=True, metavar="SEED [SEED ...]",
              help="The reproduction seeds, e.g. --seeds 0 1 2: each a whole reproduction with "
                   "its own boards, runs and demonstrations.")
@click.argument("more_seeds", nargs=-1, type=SEED, metavar="")
@click.option("--out", "out", default="out/study", show_default=True, help="Study folder: "
              "a reproduction folder per seed (seedN/) and the summary; run again to resume.")
@click.option("--quick", is_flag=True, help="Each reproduction's small version (a smoke test).")
@test_kinds_option
@learner_options
@executor_options
@json_option
def study(first_seed: int, more_seeds: tuple[int, ...], out: str, quick: bool,
          test_kinds: str | None, learner: str | None, folds: str | None,
          template_budget: float | str | None, supervision: str | None, teacher: str | None,
          processes: int | None, executor_name: str, ray_address: str | None,
          as_json: bool) -> None:
    """Several whole reproductions and a verdict on each of the paper's orderings."""
    seeds = [first_seed, *more_seeds]

    def config_for(seed: int):
        return _reproduce_config(seed, quick, test_kinds, learner, folds, template_budget,
                                 teacher, supervision)

    config_for(0)  # bad settings: one line before anything is walked
    with opened_executor(executor_name, processes, ray_address) as executor:
        summary = run_study(Path(out), seeds, executor=executor, log=progress_log(as_json),
                            config_for=config_for)
    lines = [f"{v['ordering']}: success {v['success_verdict']} (p = {v['p_value']:.3g}, "
             f"{v['a_only']} against {v['b_only']} paired runs), slip {v['slip_verdict']}"
             for v in summary["verdicts"]]
    emit(as_json, summary, "\n".join(lines + [f"wrote {Path(out) / 'summary.md'}"]))


def _variant_names() -> list[str]:
    return list(VARIANTS)


@click.command()
@click.option("--out", "out", default="out/ablation", show_default=True, help="Report folder "
              "(and the store of every run; run again with the same arguments to resume).")
@click.option("--variant", "variants", multiple=True, type=RegistryChoice(_variant_names),
              help="A controller variant to walk (repeatable) [default: all of them]; the "
                   "defaults are always walked, as the baseline.")
@click.option("--who", "who", multiple=True, type=click.Choice(["expert", "hand"]),
              help="Who chooses the footholds (repeatable) [default: both]: the walking expert "
                   "or the hand-tuned reward.")
@click.option("--hard/--no-hard", default=True, show_default=True,
              help="Walk the four hard boards too (rocky:0.85 steps:0.85, 64 runs per variant "
                   "and chooser); --no-hard walks the test and calibration boards only. A folder keeps its "
                   "choice.")
@click.option("--training-suite/--no-training-suite", "training_suite", default=True,
              show_default=True,
              help="Walk the training suite too (four boards KIND:0.7 KIND:0.7 of each of "
                   "the training kinds -- steps, barrier, slope, logs, rocky, ridges, pitted, rockyscan, pavers: "
                   "288 "
                   "runs per variant and chooser; "
                   "the training-suite rule judges on it). A folder keeps its choice.")
@click.option("--seeds-round", "seeds_round", type=click.IntRange(0, 1000), default=0,
              show_default=True,
              help="Walk round K's run seeds: every board's first run seed moved by 1000 K, so "
                   "that a new judgement's runs, the defaults' among them, were never used to "
                   "judge before (docs/terrain-suite.md).")
@click.option("--quick", is_flag=True, help="A small version (about a minute) for a smoke test.")
@executor_options
@json_option
def ablation(out: str, variants: tuple[str, ...], who: tuple[str, ...], hard: bool,
             training_suite: bool, seeds_round: int, quick: bool, processes: int | None,
             executor_name: str, ray_address: str | None, as_json: bool) -> None:
    """The walking controller's ablation: each part switched off alone, paired runs."""
    config = (AblationConfig.quick() if quick else AblationConfig()).seeds_round(seeds_round)
    if not hard:
        config = replace(config, hard_runs=0)
    if not training_suite:
        config = replace(config, suite_runs=0)
    if variants:
        config = replace(config, variants=variants)
    if who:
        config = replace(config, who=tuple(dict.fromkeys(who)))
    with opened_executor(executor_name, processes, ray_address) as executor:
        summary = run_ablation(Path(out), config, log=progress_log(as_json), executor=executor)
    emit(as_json, summary, ablation_markdown(config, summary)
         + f"wrote {Path(out) / 'ablation.md'} and ablation.json")


@click.command("benchmark-terrain")
@click.option("--suite", type=click.Choice(tuple(SUITES)), default="held-out", show_default=True,
              help="The held-out kinds (never tuned on) or the training kinds.")
@click.option("--out", "out", default=None,
              help="Report folder and store of every run (run again to resume) "
                   "[default: out/suite-SUITE].")
@click.option("--kind", "kinds", multiple=True,
              help="A kind of the suite to walk (repeatable) [default: all of them].")
@click.option("--who", "who", multiple=True, type=click.Choice(["expert", "hand", "teacher"]),
              help="Who chooses the footholds (repeatable) [default: expert and hand]: the "
                   "walking expert, the hand-tuned reward, or the reproduction's teacher (the "
                   "hand-tuned reward among the footholds the expert accepts), paired with the "
                   "hand-tuned reward.")
@click.option("--model", "models", multiple=True, metavar="NAME=MODEL.npz",
              help="A learned function walked as a chooser too, named NAME (repeatable); "
                   "paired with the hand-tuned reward.")
@click.option("--boards", type=click.IntRange(min=1), default=None,
              help="Boards per kind [default: 2].")
@click.option("--first-board", "first_board", type=click.IntRange(min=0), default=None,
              help="The first board walked, from 0 [default: 0]: --boards 6 --first-board 4 "
                   "walks boards 5 and 6 only.")
@click.option("--runs", type=click.IntRange(min=1), default=None,
              help="Runs on each board [default: 8].")
@click.option("--difficulty", type=click.FloatRange(0, 1), default=None,
              help="Difficulty D of every board KIND:D KIND:D, 0-1 [default: 0.7, the "
                   "reproduction's test difficulty]; walk each into its own --out.")
@click.option("--variant", type=RegistryChoice(_variant_names), default="defaults",
              show_default=True, help="The controller variant walked (as the ablation's); "
              "walk each into its own --out.")
@click.option("--against", "against", default=None, metavar="FOLDER",
              help="Pair these runs with those of another suite folder (the same boards and "
                   "run seeds, another variant or code): per kind, won / lost and p.")
@click.option("--quick", is_flag=True, help="One board and two hand-tuned runs a kind.")
@executor_options
@json_option
def benchmark_terrain(suite: str, out: str | None, kinds: tuple[str, ...], who: tuple[str, ...],
                      models: tuple[str, ...], boards: int | None, first_board: int | None, runs: int | None,
                      difficulty: float | None, variant: str, against: str | None,
                      quick: bool, processes: int | None, executor_name: str,
                      ray_address: str | None, as_json: bool) -> None:
    """A terrain suite: the expert and the hand-tuned reward on every kind, success with
    Wilson intervals, slip and the failure taxonomy per kind."""
    config = SuiteConfig.quick(suite) if quick else SuiteConfig(suite=suite)
    named = tuple(_model_option(m) for m in models)
    changes: dict = {"models": named} if named else {}
    who = tuple(dict.fromkeys(who or config.who)) + tuple(f"model:{n}" for n, _ in named) \
        if named else tuple(dict.fromkeys(who))
    for key, value in (("kinds", kinds or None), ("who", who or None),
                       ("boards", boards), ("first_board", first_board), ("runs", runs),
                       ("difficulty", difficulty), ("variant", variant)):
        if value is not None:
            changes[key] = value
    config = replace(config, **changes)  # checked: one line for a bad value
    folder = Path(out or f"out/suite-{suite}" + ("" if variant == "defaults" else f"-{variant}")
                  + ("" if difficulty is None else f"-d{difficulty:g}"))
    those = None if against is None else suite_outcomes(against)  # a bad folder: before walking
    with opened_executor(executor_name, processes, ray_address) as executor:
        summary = run_suite(folder, config, log=progress_log(as_json), executor=executor)
    text = suite_markdown(summary)
    if those is not None:
        comparison = compare_suites(suite_outcomes(folder), those, config.walked_kinds(),
                                    config.who)
        summary = {**summary, "against": {"folder": str(against), "paired": comparison}}
        text += "\n" + comparison_markdown(comparison, str(against))
    emit(as_json, summary, text + f"wrote {folder / 'suite.md'}")


def _model_option(text: str) -> tuple[str, str]:
    """``NAME=MODEL.npz`` as (name, path); one line for anything else."""
    name, sep, path = text.partition("=")
    if not sep or not name or not path or "/" in name:
        raise FootfallError(f"--model takes NAME=MODEL.npz (a name without '/'), got {text!r}")
    return name, path


@click.command()
@click.option("--out", "out", default="out/demo", show_default=True, help="Output folder.")
@click.option("--seed", type=SEED, default=0, show_default=True)
@json_option
def demo(out: str, seed: int, as_json: bool) -> None:
    """Build a board, score it densely and draw the terrain, features and templates."""
    result = run_demo(Path(out), seed=seed)
    emit(as_json, result, "\n".join(f"wrote {p}" for p in result["files"]))
