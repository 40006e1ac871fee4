"""``footfall demos``: collect demonstrated footholds into a store, and count what a store holds."""

from __future__ import annotations

import click

from footfall.cli.choices import RECORDED_STEP, SEED, TEACHER, Finite, count_range
from footfall.cli.executors import executor_options, opened_executor
from footfall.cli.output import emit, json_option, progress_bar
from footfall.control.footstep import FootstepConfig
from footfall.core.errors import FootfallError
from footfall.data.inventory import store_inventory
from footfall.data.store import DemoStore
from footfall.experiments.relabel import relabel_runs
from footfall.expert.collect import collect_into_store
from footfall.expert.corrections import DEFAULT_MARGIN, correct_stored_runs
from footfall.expert.settings_file import load_expert
from footfall.expert.synthetic import SyntheticExpert, walking_expert
from footfall.expert.teachers import TEACHERS
from footfall.teach.agreement import agreement_lines
from footfall.teach.judging import default_expert, store_agreement


@click.group()
def demos() -> None:
    """Collect and inspect demonstrated footholds (a demonstration store, .sqlite)."""


def _plural(n: int, noun: str) -> str:
    return f"{noun}{'s' if n != 1 else ''}"


@demos.command("collect")
@click.option("--terrain", "terrains", multiple=True, required=True, metavar="FILE.npz",
              help="Terrain height map to walk on; more files may follow it.")
@click.argument("more_terrains", nargs=-1, metavar="[FILE.npz]...")
@click.option("-n", "--n", "n", type=count_range(1), required=True,
              help="Number of demonstrations to add.")
@click.option("--seed", type=SEED, required=True, help="Random seed.")
@click.option("-o", "--output", required=True,
              help="Demonstration store (.sqlite): appended to, created if missing.")
@click.option("--noise", type=Finite(min=0.0), default=None,
              help="Noise of the expert's foothold values (default: the expert's).")
@click.option("--second-best", type=Finite(0.0, 1.0), default=None,
              help="Probability that the expert picks its second-best foothold "
                   "(default: the expert's).")
@click.option("--steps", type=RECORDED_STEP, default="rough", show_default=True,
              help="Record footholds on a board's non-flat modules only, or every step.")
@json_option
def demos_collect(terrains: tuple[str, ...], more_terrains: tuple[str, ...], n: int, seed: int,
                  output: str, noise: float | None, second_best: float | None, steps: str,
                  as_json: bool) -> None:
    """Add the synthetic expert's foothold choices on terrains to a store.

    The kinematic walker crosses each terrain along a few lateral paths in the
    crawl gait; the N demonstrations are spread over terrains and paths. The
    store is written in one transaction at the end: a failed or interrupted
    command leaves it as it was.
    """
    with progress_bar(n, "collect", "demo", quiet=as_json) as step:
        added = collect_into_store(terrains + more_terrains, output, n, seed, noise=noise,
                                   second_best=second_best, steps=steps, progress=step)
    text = (f"added {added.added} demonstrations (ids {added.first_id}..{added.last_id}) to "
            f"{added.store}: now {added.total} on {added.terrains} "
            f"{_plural(added.terrains, 'terrain')}")
    if added.added < n:
        text += f" (only {added.added} of the {n} requested fit on these terrains)"
    emit(as_json, added.as_dict(), text)


@demos.command("correct")
@click.argument("run_paths", nargs=-1, required=True, metavar="RUNS.sqlite...")
@click.option("-o", "--output", required=True, metavar="DEMOS.sqlite",
              help="Store the corrections are added to (created if missing).")
@click.option("--margin", type=Finite(min=0.0), default=2.0, show_default=True,
              help="A step is corrected when the robot's choice falls short of the expert's "
                   "best by more than this [value units] (the reproduction's margin).")
@click.option("--per-run", type=count_range(1), default=None,
              help="Label at most this many steps of a run, the worst [default: 6, the "
                   "reproduction's; with --every-step, all].")
@click.option("--every-step", is_flag=True,
              help="Label every step of a run, not only those short of the teacher's best by "
                   "more than the margin: the teacher's choice on every state the robot visited "
                   "(DAgger), each with its verdict on every candidate.")
@click.option("--teacher", type=TEACHER, default="expert", show_default=True,
              help="Who corrects: the synthetic expert, the hand-tuned reward with its veto "
                   "(guarded, accepted), or the simulator trying the accepted teacher's best "
                   "candidates in branches of each run walked again (rollout; "
                   "docs/learning/teacher.md).")
@click.option("--run-key", default=None, metavar="PREFIX",
              help="Only the runs whose key starts with this.")
@click.option("--expert-config", default=None, metavar="EXPERT.json",
              help="Correct with these expert settings; default: the walking expert.")
@click.option("--seed", type=SEED, default=0, show_default=True,
              help="Seed of an imperfect expert's labels.")
@click.option("--model", "model_path", default=None, metavar="MODEL.npz",
              help="With a teacher that walks the runs again (rollout): the function that "
                   "walked them [default: the hand-tuned reward]; a run it does not walk again "
                   "as logged is refused.")
@executor_options
@json_option
def demos_correct(run_paths: tuple[str, ...], output: str, margin: float,
                  per_run: int | None, every_step: bool, teacher: str, run_key: str | None,
                  expert_config: str | None, seed: int, model_path: str | None,
                  processes: int | None, executor_name: str, ray_address: str | None,
                  as_json: bool) -> None:
    """The teacher's corrections of logged runs (walk-many --log, a reproduction's store), as
    the reproduction's correction rounds make them, added to a demonstration store with its
    verdict on every candidate of each corrected step. The rollout teacher labels a run by
    walking it again from its log, trying candidates in branches (minutes a run); runs the
    store already holds labels of are skipped."""
    footstep = FootstepConfig()
    config = load_expert(expert_config) if expert_config else walking_expert(footstep.lead)
    if TEACHERS.get(teacher).walker(config, footstep.bias_weight, footstep.lead).rollout:
        _correct_by_walking(run_paths, output, per_run, every_step, teacher, run_key, config,
                            model_path, processes, executor_name, ray_address, as_json)
        return
    if model_path is not None:
        raise FootfallError("--model names the function that walked the runs, for a teacher "
                            "that walks them again (--teacher rollout)")
    judge = TEACHERS.get(teacher).expert(config, footstep.bias_weight, footstep.lead)
    done = correct_stored_runs(run_paths, output, judge, margin,
                               per_run if per_run is not None else (None if every_step else 6),
                               seed, key_prefix=run_key, every_step=every_step)
    emit(as_json, done.as_dict(),
         f"added {done.added} corrections to {done.store}: {done.runs} "
         f"{_plural(done.runs, 'run')}, {done.steps} steps, {done.above_margin} short of the "
         f"expert's best by more than {done.margin:g}"
         + (f"; {done.skipped} already there, skipped" if done.skipped else ""))


def _correct_by_walking(run_paths, output, per_run, every_step, teacher, run_key, config,
                        model_path, processes, executor_name, ray_address, as_json) -> None:
    """``demos correct`` by a teacher that walks the runs again (footfall.experiments.relabel)."""
    todo = {"runs": 0}
    with (opened_executor(executor_name, processes, ray_address) as executor,
          progress_bar(lambda: todo["runs"], "runs labelled", "run", quiet=False,
                       log_lines=True) as step):
        done = relabel_runs(run_paths, output, model_path, teacher, config, per_run=per_run,
                            every_step=every_step, key_prefix=run_key, executor=executor,
                            progress=step, todo=lambda n: todo.update(runs=n))
    skipped = (f"; {done.skipped} {_plural(done.skipped, 'run')} already labelled there, "
               f"skipped" if done.skipped else "")
    if done.repeated:
        skipped += f"; {done.repeated} labels already there, skipped"
    emit(as_json, done.as_dict(),
         f"added {done.added} labels to {done.store}: {done.runs} {_plural(done.runs, 'run')} "
         f"walked again, {done.steps} steps{skipped}")


@demos.command("info")
@click.argument("store_path", metavar="DEMOS.sqlite")
@json_option
def demos_info(store_path: str, as_json: bool) -> None:
    """Count a store's demonstrations by terrain, swing leg, source and labeler; check the file."""
    inventory = store_inventory(store_path)
    summary = inventory.summary
    agreement = None
    with DemoStore(store_path, read_only=True) as store:  # people's labels and "never here"
        if summary["labels"]["by_labeler"] or store.mark_counts():  # marks against the expert
            agreement = store_agreement(store, SyntheticExpert(default_expert()), DEFAULT_MARGIN)
    lines = [(f"{store_path}: {summary['demonstrations']} demonstrations on "
              f"{summary['terrains']} {_plural(summary['terrains'], 'terrain')} "
              f"({summary['format']} v{summary['schema_version']})")]
    for digest, count in summary["by_terrain"].items():
        lines.append(f"  terrain {digest[:12]}  {count:6d}  {inventory.terrains[digest]['label']}")
    lines.append("  legs:    " + ", ".join(f"{k} {v}" for k, v in summary["by_leg"].items()))
    lines.append("  sources: " + (", ".join(f"{k} {v}" for k, v in summary["by_source"].items())
                                  or "none"))
    for name, verdicts in summary["labels"]["by_labeler"].items():
        lines.append(f"  labeler {name}: {verdicts['foothold']} footholds labelled, "
                     f"{verdicts['fine']} choices marked fine")
    if summary["labels"]["disagreements"]:
        lines.append(f"  labelers disagree on {summary['labels']['disagreements']} "
                     f"{_plural(summary['labels']['disagreements'], 'step')}")
    lines += agreement_lines(agreement) if agreement else []
    if summary["candidates"]:
        c = summary["candidates"]
        lines.append(f"  candidates per demonstration: {c['min']} .. {c['max']} "
                     f"(mean {c['mean']:.0f})")
    emit(as_json, inventory.as_dict() | ({"agreement": agreement} if agreement else {}),
         "\n".join(lines))
