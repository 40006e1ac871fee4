"""``footfall bench``: benchmarks that print figures, each against a baseline run in the same
process (:mod:`footfall.experiments.bench`)."""

from __future__ import annotations

import click

from footfall.cli.choices import SEED
from footfall.cli.output import emit, json_option, progress_log
from footfall.core.errors import FootfallError
from footfall.experiments.bench.branch import bench_branch, format_branch
from footfall.experiments.bench.executors import bench_executors, format_executors
from footfall.experiments.bench.expert import bench_expert, format_expert
from footfall.experiments.bench.learning import bench_learning, format_learning
from footfall.experiments.bench.pose import bench_pose, format_pose
from footfall.experiments.bench.rankers import bench_rankers, format_rankers
from footfall.experiments.bench.sampling import bench_sampling, format_sampling
from footfall.experiments.bench.scoring import bench_scoring, format_scoring
from footfall.experiments.bench.sim import bench_sim, format_sim
from footfall.teach.bench import bench_teach, format_teach


@click.group()
def bench() -> None:
    """Benchmarks: print figures, compared with a baseline run in the same process."""


@bench.command("scoring")
@click.option("--repeats", type=click.IntRange(1, 100), default=7, show_default=True)
@click.option("--baseline-sample", type=click.IntRange(10, 100000), default=300,
              show_default=True, help="Candidates timed with the per-candidate loop.")
@json_option
def bench_scoring_cmd(repeats: int, baseline_sample: int, as_json: bool) -> None:
    """Dense scoring of a 3-module board at 5 mm with 60 templates and 27 features."""
    result = bench_scoring(repeats=repeats, baseline_sample=baseline_sample)
    emit(as_json, result, format_scoring(result))


@bench.command("learning")
@click.option("--demos", "n_demos", type=click.IntRange(10, 10000), default=100, show_default=True)
@click.option("--library-size", type=click.IntRange(3, 100000), default=1000, show_default=True)
@json_option
def bench_learning_cmd(n_demos: int, library_size: int, as_json: bool) -> None:
    """Paper-scale learning against scikit-learn's LogisticRegressionCV."""
    result = bench_learning(n_demos=n_demos, library_size=library_size)
    emit(as_json, result, format_learning(result))


@bench.command("pose")
@click.option("--states", type=click.IntRange(1, 100), default=8, show_default=True)
@json_option
def bench_pose_cmd(states: int, as_json: bool) -> None:
    """Pose features of a planning step: compiled support features against NumPy."""
    result = bench_pose(states=states)
    emit(as_json, result, format_pose(result))


@bench.command("rankers")
@click.option("--demos", "n_demos", type=click.IntRange(10, 10000), default=100, show_default=True)
@click.option("--library-size", type=click.IntRange(3, 100000), default=1000, show_default=True)
@json_option
def bench_rankers_cmd(n_demos: int, library_size: int, as_json: bool) -> None:
    """Each learner's learning time and its scoring of 45 000 candidates, against linear."""
    result = bench_rankers(n_demos=n_demos, library_size=library_size)
    emit(as_json, result, format_rankers(result))


@bench.command("sampling")
@click.option("--states", type=click.IntRange(1, 100), default=8, show_default=True)
@json_option
def bench_sampling_cmd(states: int, as_json: bool) -> None:
    """Compiled bilinear sampling (patches, the expert's rays) against the NumPy rules."""
    result = bench_sampling(states=states)
    emit(as_json, result, format_sampling(result))


@bench.command("sim")
@click.option("--seed", type=SEED, default=0, show_default=True)
@click.option("--runs", type=click.IntRange(1, 100), default=1, show_default=True,
              help="Rocky runs (seeds SEED, SEED+1, ...).")
@click.option("--physics", "physics", multiple=True, metavar="OPTION=VALUE",
              help="Walk and measure with a MuJoCo <option> changed (repeatable), e.g. "
                   "cone=pyramidal, impratio=10, tolerance=1e-5: what another physics costs "
                   "in fidelity and gives in speed.")
@click.option("--hfield-spacing", type=click.FloatRange(0.0005, 0.02), default=None,
              help="Coarsest height-field vertex spacing [m] to measure (default 0.002).")
@click.option("--foot-contact", type=click.Choice(["terrain", "pads"]), default="terrain",
              show_default=True,
              help="pads: each ball foot meets only its own pad on the tangent plane under it "
                   "(one contact per foot; footfall.sim.foot_pads), to measure.")
@json_option
def bench_sim_cmd(seed: int, runs: int, physics: tuple[str, ...], hfield_spacing: float | None,
                  foot_contact: str, as_json: bool) -> None:
    """Real-time factor of the walking stack against bare MuJoCo stepping, with the physics'
    fidelity."""
    options = {}
    for item in physics:
        key, sep, value = item.partition("=")
        if not sep or not key or not value:
            raise FootfallError(f"--physics takes OPTION=VALUE, got {item!r}")
        options[key] = value
    result = bench_sim(seed=seed, runs=runs, physics=options, hfield_spacing=hfield_spacing,
                       foot_contact=foot_contact)
    emit(as_json, result, format_sim(result))


@bench.command("executors")
@click.option("--runs", type=click.IntRange(2, 1000), default=8, show_default=True)
@click.option("--processes", type=click.IntRange(1, 1024), default=2, show_default=True)
@json_option
def bench_executors_cmd(runs: int, processes: int, as_json: bool) -> None:
    """Runs per minute of a batch on the local process pool against a Ray cluster."""
    result = bench_executors(runs=runs, processes=processes)
    emit(as_json, result, format_executors(result))


@bench.command("expert")
@click.option("--runs", type=click.IntRange(1, 50), default=2, show_default=True,
              help="Seeds walked by each chooser.")
@click.option("--sets", type=click.IntRange(1, 10000), default=60, show_default=True,
              help="Candidate sets whose terrain terms are timed, compiled against NumPy.")
@json_option
def bench_expert_cmd(runs: int, sets: int, as_json: bool) -> None:
    """A run with the walking expert choosing every foothold against a hand-tuned run (CPU
    time), and its terrain terms compiled against the NumPy rules."""
    result = bench_expert(runs=runs, sets=sets)
    emit(as_json, result, format_expert(result))


@bench.command("branch")
@click.option("--seed", type=click.IntRange(0), default=5000, show_default=True,
              help="The run's seed.")
@click.option("--decisions", type=click.IntRange(1, 100), default=4, show_default=True,
              help="Decisions, spread over the run, whose candidates are tried.")
@click.option("--tries", type=click.IntRange(1, 20), default=3, show_default=True,
              help="Candidates tried at each of them (the planner's best).")
@json_option
def bench_branch_cmd(seed: int, decisions: int, tries: int, as_json: bool) -> None:
    """A branch of a run forked at a decision and one replayed after it, against the physics
    of its own steps (CPU time)."""
    result = bench_branch(seed=seed, decisions=decisions, tries=tries)
    emit(as_json, result, format_branch(result))


@bench.command("teach")
@click.option("--walks", type=click.IntRange(1, 20), default=2, show_default=True,
              help="Runs walked with the hand-tuned reward.")
@click.option("--copies", type=click.IntRange(1, 100), default=10, show_default=True,
              help="Times each walked run is stored (the store holds walks x copies runs).")
@click.option("--runs", type=click.IntRange(1, 50), default=3, show_default=True,
              help="Runs opened in the page.")
@click.option("--steps", type=click.IntRange(1, 200), default=10, show_default=True,
              help="Arrow presses in each opened run.")
@click.option("--labels", type=click.IntRange(0, 1000), default=9, show_default=True,
              help="Labels clicked in the top view, over all opened runs.")
@json_option
def bench_teach_cmd(walks: int, copies: int, runs: int, steps: int, labels: int,
                    as_json: bool) -> None:
    """The teaching page in Chromium: step view, label and a new run's first step [ms] against
    their targets, and opening a run as the expert judges it (the baseline). Needs Chromium and
    Playwright."""
    result = bench_teach(walks=walks, copies=copies, runs=runs, steps=steps, labels=labels)
    emit(as_json, result, format_teach(result))


FUZZ_TARGETS = ("map-file", "model-file", "store", "scan-import", "survey-import", "cli", "lying-file",
                "concurrency", "classes")
"""The fuzz targets by name (footfall.cli.fuzz.targets.TARGETS, which needs Hypothesis)."""


@bench.command("fuzz")
@click.option("--minutes", type=click.FloatRange(min=0.05, max=24 * 60), default=10.0,
              show_default=True, help="Time budget [min] (the base files are made first).")
@click.option("--seed", type=click.IntRange(0, 2 ** 31 - 1), default=0, show_default=True)
@click.option("--target", "targets", multiple=True,
              type=click.Choice(FUZZ_TARGETS),
              help="Fuzz only these targets (default: all).")
@json_option
def bench_fuzz_cmd(minutes: float, seed: int, targets: tuple[str, ...], as_json: bool) -> None:
    """Hostile files and arguments at every loader and command: inputs tried, failures found."""
    # The fuzz suite is built on Hypothesis, a test extra: imported only when it runs.
    try:
        from footfall.cli.fuzz.campaign import format_campaign, run_campaign
    except ModuleNotFoundError as exc:
        if exc.name != "hypothesis":
            raise
        raise FootfallError("the fuzz campaign needs Hypothesis: pip install "
                            "'footfall[test]'") from None

    result = run_campaign(minutes, seed, targets or None, log=progress_log(as_json))
    emit(as_json, result, format_campaign(result))
