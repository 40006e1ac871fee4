"""``footfall walk`` and ``footfall walk-many``: the simulated robot across a board, once or
many times in parallel."""

from __future__ import annotations

import click

from footfall.cli.choices import SEED, TEACHER, VARIANT, count_range
from footfall.cli.executors import executor_options, opened_executor
from footfall.cli.output import emit, json_option, progress_bar
from footfall.experiments.batch import check_picture_outputs, walk_batch, walk_once
from footfall.expert.settings_file import load_expert
from footfall.sim.explain import explanation_lines

TERRAIN_OPTION = click.option("--terrain", "terrain_path", required=True,
                              help="Board height map (.npz).")
MODEL_OPTION = click.option("--model", "model_path", default=None,
                            help="Learned model (.npz); default: the hand-tuned reward.")


def _chooser_options(f):
    """--expert, --search-radius, --friction-safety, --path-bias and --variant: who chooses
    the footholds, among which, and with which controller."""
    f = click.option("--variant", type=VARIANT, default="defaults", show_default=True,
                     help="The controller variant that walks (as `footfall ablation` names "
                          "them, e.g. no-load-hold, with-friction-check).")(f)
    f = click.option("--path-bias", type=click.FloatRange(min=0), default=None,
                     metavar="REWARD/M",
                     help="The footstep planner's pull toward the path: a candidate loses this "
                          "much hand-tuned reward per metre from its path-nominal position, "
                          "scaled to the reward's spread; 0: none, as the expert walks "
                          "[default: the walk's own, 60].")(f)
    f = click.option("--friction-safety", type=float, default=None,
                     help="Drop the footholds where the ball foot's contact tilts past "
                          "atan(friction / this) within 5 mm (the friction check, e.g. 1.5); "
                          "default: no check.")(f)
    f = click.option("--search-radius", type=float, default=None,
                     help="Candidate set F of a step: the footholds within this many metres of "
                          "the gait-nominal position (the reproduction uses 0.03); "
                          "default: every reachable one.")(f)
    f = click.option("--expert-config", "expert_config", default=None, metavar="EXPERT.json",
                     help="With --expert or --teacher: the expert of these settings (e.g. the "
                          "one `footfall outcomes --fit` grounded); default: the walking "
                          "expert.")(f)
    f = click.option("--teacher", type=TEACHER, default=None,
                     help="This teacher chooses every foothold (no --model): 'expert', the "
                          "synthetic expert (as --expert); 'guarded', the hand-tuned reward "
                          "with the expert's veto of severe footholds; 'accepted', with its "
                          "veto at the correction margin (the reproduction's teacher); "
                          "'rollout', the accepted teacher's best candidates and the expert's "
                          "tried in branches of the run, the one that walked best taken "
                          "(about 4 s a step).")(f)
    return click.option("--expert", is_flag=True,
                        help="The synthetic walking expert chooses every foothold (no --model): "
                             "what learning from its demonstrations can reach at best.")(f)


def _teacher(expert: bool, teacher: str | None) -> tuple[bool, str]:
    """Whether a teacher chooses, and which: ``--teacher``, or the expert for ``--expert``."""
    return expert or teacher is not None, teacher or "expert"


def _expert_settings(path: str | None):
    """The expert settings of ``--expert-config``, or None."""
    if path is None:
        return None
    return load_expert(path)


def _run_text(result: dict) -> str:
    """One line of a run's result: success, distance, time, steps, speed, slip."""
    slip = ("" if result.get("slip_mean_mm") is None else
            f", slip {result['slip_mean_mm']:.1f} +- {result['slip_std_mm']:.1f} mm "
            f"({result['slip_count']} footholds)")
    return (f"{'success' if result['success'] else 'failure'} ({result['reason']}): "
            f"{result['distance']:.3f} m in {result['time']:.1f} s, {result['steps']} steps, "
            f"{result['speed_cm_s']:.1f} cm/s{slip}; real-time factor "
            f"{result['real_time_factor']:.1f}")


@click.command("walk")
@TERRAIN_OPTION
@MODEL_OPTION
@click.option("--seed", type=SEED, required=True,
              help="Run seed: start pose, terrain registration, friction, sensor noise.")
@click.option("--snapshots", default=None, help="Write a strip of frames (.png).")
@click.option("--frames", type=click.IntRange(2, 12), default=6, show_default=True,
              help="Frames in the snapshot strip.")
@click.option("--video", default=None, help="Write a video (.mp4).")
@click.option("--log", "log_path", default=None, help="Append the run log to this store (.sqlite).")
@click.option("--explain", is_flag=True,
              help="Say how a failed run ended: the stance foot that moved, the support "
                   "margin, roll and pitch, contact forces, joints at their limits.")
@click.option("--explain-plot", default=None,
              help="Draw those time series over the run's last seconds (.png).")
@_chooser_options
@json_option
def walk_cmd(terrain_path: str, model_path: str | None, seed: int, snapshots: str | None,
             frames: int, video: str | None, log_path: str | None, explain: bool,
             explain_plot: str | None, expert: bool, expert_config: str | None,
             teacher: str | None, search_radius: float | None, friction_safety: float | None,
             path_bias: float | None, variant: str, as_json: bool) -> None:
    """One run of the simulated robot across a board (success, slip, speed)."""
    check_picture_outputs(snapshots, video, explain_plot, as_options=True,
                          inputs=(terrain_path, model_path, log_path, expert_config))
    expert, teacher = _teacher(expert, teacher)
    outcome = walk_once(terrain_path, seed, model_path=model_path, expert=expert,
                        search_radius=search_radius, friction_safety=friction_safety,
                        path_bias=path_bias, variant=variant, snapshots=snapshots,
                        frames=frames,
                        video=video, log_path=log_path, explain_plot=explain_plot,
                        expert_config=_expert_settings(expert_config), teacher=teacher)
    text = _run_text(outcome.record.result)
    explanation = outcome.record.result.get("explanation")
    if explain and explanation is not None:
        text += "".join(f"\n  {line}" for line in explanation_lines(explanation))
    emit(as_json, outcome.as_dict(), text)


@click.command("walk-many")
@TERRAIN_OPTION
@MODEL_OPTION
@click.option("--runs", type=count_range(1), default=21, show_default=True)
@click.option("--seed", type=SEED, required=True,
              help="Run i has seed SEED + i.")
@click.option("--log", "log_path", default=None,
              help="Keep every run in this store (.sqlite) as it ends; run again with the same "
                   "store to walk only the runs it does not hold yet.")
@_chooser_options
@executor_options
@json_option
def walk_many_cmd(terrain_path: str, model_path: str | None, runs: int, seed: int,
                  log_path: str | None, expert: bool, expert_config: str | None,
                  teacher: str | None,
                  search_radius: float | None, friction_safety: float | None,
                  path_bias: float | None, variant: str, processes: int | None,
                  executor_name: str,
                  ray_address: str | None, as_json: bool) -> None:
    """N runs in parallel: success rate (Wilson 95 % CI), slip, speed."""
    expert, teacher = _teacher(expert, teacher)
    todo = {"runs": runs}

    def reused(count: int) -> None:
        todo["runs"] = runs - count
        if count:
            click.echo(f"runs: {count} of {runs} already in {log_path}", err=True)

    with (opened_executor(executor_name, processes, ray_address) as executor,
          progress_bar(lambda: todo["runs"], "runs", "run", quiet=False,  # also with --json
                       failed=lambda record: not record.result["success"],
                       log_lines=True) as step):
        batch = walk_batch(terrain_path, runs, seed, model_path=model_path, expert=expert,
                           search_radius=search_radius, friction_safety=friction_safety,
                           path_bias=path_bias, variant=variant, log_path=log_path,
                           progress=step,
                           executor=executor, reused=reused,
                           expert_config=_expert_settings(expert_config), teacher=teacher)
    s = batch.summary
    slip = ("no successful run" if s.slip_mean_mm is None else
            f"slip {s.slip_mean_mm:.1f} +- {s.slip_std_mm:.1f} mm over "
            f"{s.slip_count} footholds, {s.speed_cm_s:.1f} cm/s")
    causes = "".join(f"\n  {count} x {cause}" for cause, count in
                     sorted(s.causes.items(), key=lambda item: -item[1]))
    emit(as_json, batch.as_dict(), f"{s.successes} / {s.runs} succeeded "
         f"({100 * s.success_rate:.1f} %, 95 % CI {100 * s.success_ci[0]:.1f}-"
         f"{100 * s.success_ci[1]:.1f} %); {slip}" + (f"\nfailures:{causes}" if causes else ""))
