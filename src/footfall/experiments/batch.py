"""Many walking runs of one configuration, in parallel processes, and their statistics.

Run i of ``walk_many(..., seed=S)`` has seed S + i, so ``footfall walk --seed
S+i`` repeats any one of them exactly. The summary follows the paper's
Table II: success rate (with a 95 % Wilson interval) and slip averaged over
the successful runs only.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import matplotlib
import numpy as np

from footfall.core.atomic import atomic_path
from footfall.core.compute import usable_cores
from footfall.core.errors import FootfallError
from footfall.core.files import plain_json, writable_path
from footfall.core.heightmap import HeightMap, board_records
from footfall.core.seeds import check_seed_span
from footfall.core.stats import wilson_interval
from footfall.data.runlog import RunRecord
from footfall.data.schema import FORMAT as STORE_FORMAT
from footfall.data.schema import SUFFIXES as STORE_SUFFIXES
from footfall.data.store import DemoStore
from footfall.experiments.executors import Executor, LocalPool
from footfall.experiments.runs import RunJob, reward_source, teacher_walk
from footfall.experiments.variants import VARIANTS
from footfall.expert.scorer import ExpertScorer, judge_name, settings_hash
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert, walking_expert
from footfall.expert.teachers import TEACHERS
from footfall.plots.explain import save_explain_plot
from footfall.sim.branch import TapedWalk
from footfall.sim.episode import Frames, Walk, WalkConfig


def chooser_expert(config: WalkConfig, expert: bool,
                   expert_config: ExpertConfig | None = None) -> ExpertConfig:
    """The settings of the expert that chooses when ``expert``: ``expert_config``, or the
    walking expert (:func:`footfall.expert.synthetic.walking_expert`) of the walk's gait.

    Raises
    ------
    FootfallError
        For expert settings without ``expert`` (a reward chooses then).
    """
    if expert_config is not None and not expert:
        raise FootfallError("expert settings are for runs the expert chooses (--expert)")
    return expert_config or walking_expert(config.footstep.lead)


def variant_expert(config: WalkConfig, expert: bool, expert_config: ExpertConfig | None,
                   variant: str) -> ExpertConfig | None:
    """``expert_config``, or where none is given and ``variant`` changes the walking expert
    (:attr:`~footfall.experiments.variants.Variant.expert`), that expert of the walk's gait."""
    changed = VARIANTS.get(variant)
    if expert and expert_config is None and changed.changes_expert:
        return changed.expert(walking_expert(config.footstep.lead))
    return expert_config


def expert_judge(settings: ExpertConfig) -> ExpertScorer:
    """The expert of ``settings`` as a foothold judge, named as its runs are logged."""
    return ExpertScorer(SyntheticExpert(settings), name=judge_name(settings))


def walk_many(terrain_path: str | os.PathLike, model_path: str | os.PathLike | None, runs: int,
              seed: int, config: WalkConfig = WalkConfig(), processes: int | None = None,
              progress: Callable[[RunRecord], None] | None = None,
              expert: bool = False, executor: Executor | None = None,
              expert_config: ExpertConfig | None = None, teacher: str = "expert"
              ) -> list[RunRecord]:
    """``runs`` runs with seeds ``seed .. seed + runs - 1``, in parallel; returned in seed order.

    Each worker loads the terrain and the model itself (nothing is shipped
    but paths or file bytes, seeds and the frozen config). ``expert``: the
    teacher chooses the footholds (the walking expert: :func:`expert_judge`), not a reward.
    The runs are walked on ``executor`` [default: a local pool of
    ``processes`` workers, one per run at most]. ``expert_config``: the settings of the
    expert that chooses [default: the walking expert]; ``teacher``: which teacher chooses with
    ``expert`` (:data:`footfall.expert.teachers.TEACHERS`).
    """
    jobs = batch_jobs(terrain_path, model_path, runs, seed, config, expert,
                      expert_config=expert_config, teacher=teacher)
    executor = executor or LocalPool(min(processes or usable_cores(), runs))
    out = {job.seed: record for job, record in _walked(executor, jobs, progress)}
    return [out[job.seed] for job in jobs]


def batch_jobs(terrain_path: str | os.PathLike, model_path: str | os.PathLike | None, runs: int,
               seed: int, config: WalkConfig = WalkConfig(), expert: bool = False,
               hmap: HeightMap | None = None, expert_config: ExpertConfig | None = None,
               teacher: str = "expert") -> list[RunJob]:
    """The jobs of :func:`walk_many`, in seed order, without run keys.

    ``hmap``: the board at ``terrain_path`` if already loaded (it is read otherwise, to
    check the model against it). ``expert_config``: the judging expert's settings
    [default: the walking expert's].

    Raises
    ------
    FootfallError
        For the expert with a model, a bad run count, or a model the board cannot use.
    """
    if expert and model_path is not None:
        raise FootfallError("the expert chooses the footholds itself: give no model with it")
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 1:
        raise FootfallError(f"runs must be an integer >= 1, got {runs!r}")
    check_seed_span(seed, runs)
    hmap = HeightMap.load(terrain_path) if hmap is None else hmap
    reward_source(model_path, hmap)  # fail early, in this process, on a bad model
    model = None if model_path is None else str(model_path)
    judge = chooser_expert(config, expert, expert_config)
    TEACHERS.get(teacher).walker(judge, config.footstep.bias_weight, config.footstep.lead)
    return [RunJob(None, str(terrain_path), model, s, config, expert=judge, judge=expert,
                   teacher=teacher) for s in range(seed, seed + runs)]


def _walked(executor: Executor, jobs: list[RunJob],
            progress: Callable[[RunRecord], None] | None) -> Iterator[tuple[RunJob, RunRecord]]:
    """Each job with its record as it finishes; an interrupted batch cancels the rest."""
    runs = executor.map(jobs)
    try:
        for job, (record, _) in runs:
            yield job, record
            if progress:
                progress(record)
    finally:
        runs.close()


def batch_run_keys(hmap: HeightMap, model_path: str | os.PathLike | None, expert: bool,
                   config: WalkConfig, seeds: list[int],
                   expert_config: ExpertConfig | None = None, teacher: str = "expert"
                   ) -> dict[int, str]:
    """Each seed's run key in a log store: board, chooser, settings and seed decide a run.

    ``walk-many/<board hash>/<hand | teacher | model-<file hash>>/<settings hash>/s<seed>``:
    the same run walked again has the same key, so a batch logged to a store and
    interrupted walks only what is missing when run again.
    """
    if expert:
        judge = chooser_expert(config, expert, expert_config)
        chooser = (teacher if judge == walking_expert(config.footstep.lead)
                   else f"{teacher}-{settings_hash(judge)}")
    elif model_path is None:
        chooser = "hand"
    else:
        chooser = "model-" + hashlib.sha256(Path(model_path).read_bytes()).hexdigest()[:16]
    settings = json.dumps(plain_json(config.to_dict(), nonfinite="null"), sort_keys=True)
    digest = hashlib.sha256(settings.encode()).hexdigest()[:16]
    return {s: f"walk-many/{hmap.content_hash()[:16]}/{chooser}/{digest}/s{s}" for s in seeds}


@dataclass(frozen=True)
class RunSummary:
    """Table II's measures of a set of runs."""

    runs: int
    successes: int
    success_rate: float  # [-]
    success_ci: tuple[float, float]  # 95 % Wilson interval of the success rate
    slip_mean_mm: float | None  # [mm] mean over every foothold of the successful runs
    slip_std_mm: float | None  # [mm] standard deviation of the same
    slip_count: int  # footholds measured
    speed_cm_s: float | None  # [cm/s] mean speed of the successful runs
    speed_body_lengths_s: float | None  # [body lengths / s]
    reasons: dict  # how the runs ended: {reason: count}
    causes: dict  # what the failed runs are put down to: {cause: count} (footfall.sim.explain)

    def as_dict(self) -> dict:
        d = dict(vars(self))
        d["success_ci"] = list(self.success_ci)
        return d


def summarise(records: list[RunRecord]) -> RunSummary:
    """Success rate, slip over the successful runs (as the paper), speed."""
    if not records:
        raise FootfallError("no runs to summarise")
    ok = [r for r in records if r.result.get("success")]
    slips = np.concatenate([r.slips() for r in ok]) if ok else np.zeros(0)
    reasons: dict[str, int] = {}
    for r in records:
        reasons[r.result.get("reason", "?")] = reasons.get(r.result.get("reason", "?"), 0) + 1
    causes: dict[str, int] = {}
    for r in records:
        cause = (r.result.get("explanation") or {}).get("cause")
        if cause is not None:
            causes[cause] = causes.get(cause, 0) + 1
    speeds = [r.result["speed_cm_s"] for r in ok]
    bl = [r.result["speed_body_lengths_s"] for r in ok]
    return RunSummary(len(records), len(ok), len(ok) / len(records),
                      wilson_interval(len(ok), len(records)),
                      1e3 * float(slips.mean()) if slips.size else None,
                      1e3 * float(slips.std()) if slips.size else None, int(slips.size),
                      float(np.mean(speeds)) if speeds else None,
                      float(np.mean(bl)) if bl else None, reasons, causes)


SNAPSHOT_SUFFIXES = (".png",)  # what save_strip writes
VIDEO_SUFFIXES = (".mp4",)  # what save_video writes (H.264 in an MP4 container)


def save_strip(frames: list, path: str | os.PathLike, title: str | None = None) -> None:
    """A strip of snapshot frames [(time [s], image)] side by side (as the paper's Fig. 4)."""
    matplotlib.use("Agg")  # headless: pyplot picks its backend when it is imported
    import matplotlib.pyplot as plt

    if not frames:
        raise FootfallError("no frames to draw")
    fig, axes = plt.subplots(1, len(frames), figsize=(2.6 * len(frames), 2.4), squeeze=False)
    for ax, (t, img) in zip(axes[0], frames):
        ax.imshow(img)
        ax.set_title(f"t = {t:.1f} s", fontsize=9)
        ax.axis("off")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    with atomic_path(Path(path)) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def save_video(images: list, path: str | os.PathLike, fps: float) -> None:
    """Write frames (h, w, 3) uint8 as an H.264 MP4 (imageio's bundled ffmpeg)."""
    import imageio.v2 as imageio  # with its ffmpeg: only for a video

    if not images:
        raise FootfallError("no frames to write")
    with atomic_path(Path(path)) as tmp:
        with imageio.get_writer(tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                                macro_block_size=8, ffmpeg_log_level="error") as writer:
            for img in images:
                writer.append_data(img)


# ------------------------------------------------ runs from files (footfall walk, walk-many)
def load_board(path: str | os.PathLike) -> HeightMap:
    """The board height map at ``path``; a missing file is refused by name."""
    if not Path(path).exists():
        raise FootfallError(f"no such terrain file: {path}")
    hmap = HeightMap.load(path)
    board_records(hmap, str(path))  # what a walk relies on: by field, and against the map
    return hmap


def walk_config(model_path: str | os.PathLike | None = None, expert: bool = False,
                search_radius: float | None = None, friction_safety: float | None = None,
                path_bias: float | None = None, variant: str = "defaults") -> WalkConfig:
    """The default walk, with the candidate set F limited to ``search_radius`` [m], the
    footstep planner's friction check at ``friction_safety`` [-] and its path bias at
    ``path_bias`` [hand-tuned reward/m] if given
    (:class:`~footfall.control.footstep.FootstepConfig`), then changed as the controller
    variant ``variant`` changes it (:data:`footfall.experiments.variants.VARIANTS`).

    Raises
    ------
    FootfallError
        For the expert together with a model, or a bad search radius, safety factor, bias or
        variant.
    """
    if expert and model_path is not None:
        raise FootfallError("--expert chooses the footholds itself: give no --model with it")
    base = WalkConfig()
    changes = {k: v for k, v in (("search_radius", search_radius),
                                 ("friction_safety", friction_safety),
                                 ("bias_weight", path_bias)) if v is not None}
    config = replace(base, footstep=replace(base.footstep, **changes)) if changes else base
    return VARIANTS.get(variant).change(config)


@dataclass(frozen=True)
class WalkOutcome:
    """One run across a board: who chose the footholds, and the run's record."""

    terrain: str  # the board file, as given
    model: str | None  # the model file, None for the hand-tuned reward
    expert: bool  # the walking expert chose every foothold
    seed: int  # the run seed
    record: RunRecord  # the run: result (success, slip, speed, ...) and every step
    run_id: int | None = None  # the run's id in the log store, if logged
    teacher: str | None = None  # with ``expert``: which teacher chose

    def as_dict(self) -> dict:
        """Plain data for JSON: the settings, the run's result, then its log id if logged."""
        data = {"terrain": self.terrain, "model": self.model, "expert": self.expert,
                "teacher": self.teacher, "seed": self.seed, **self.record.result}
        if self.run_id is not None:
            data["run_id"] = self.run_id
        return data


def _checked_log(log_path: str | os.PathLike | None, inputs: tuple = ()) -> Path | None:
    """The log store's path, checked before a run without creating it: an existing store must
    open, a new one is made only when the run is stored (a refused run leaves no file)."""
    if log_path is None:
        return None
    path = writable_path(log_path, STORE_SUFFIXES, what="--log", kind="store", inputs=inputs,
                         writes=STORE_FORMAT)
    if path.exists():
        with DemoStore(path):
            pass
    return path


def _path_or_none(path: str | os.PathLike | None) -> str | None:
    return None if path is None else str(path)


def check_picture_outputs(snapshots: str | os.PathLike | None, video: str | os.PathLike | None,
                          explain_plot: str | os.PathLike | None = None, *,
                          as_options: bool = False, inputs: tuple = ()) -> None:
    """Refuse a snapshots, video or explain-plot path that could not be written, before a run:
    one of ``inputs`` (the board, the model, the log store) or another of these outputs.

    With ``as_options`` the error names them as the command line does (``--snapshots``).
    """
    written: list = []
    for path, suffixes, option, name, kind in (
            (snapshots, SNAPSHOT_SUFFIXES, "--snapshots", "snapshots", "picture"),
            (video, VIDEO_SUFFIXES, "--video", "video", "video"),
            (explain_plot, SNAPSHOT_SUFFIXES, "--explain-plot", "explain plot", "picture")):
        if path is not None:
            writable_path(path, suffixes, what=option if as_options else name, kind=kind,
                          inputs=(*inputs, *written))
            written.append(path)


def walk_once(terrain_path: str | os.PathLike, seed: int, *,
              model_path: str | os.PathLike | None = None, expert: bool = False,
              search_radius: float | None = None, friction_safety: float | None = None,
              path_bias: float | None = None, variant: str = "defaults",
              snapshots: str | os.PathLike | None = None, frames: int = 6, video: str | os.PathLike | None = None,
              log_path: str | os.PathLike | None = None,
              explain_plot: str | os.PathLike | None = None,
              expert_config: ExpertConfig | None = None, teacher: str = "expert") -> WalkOutcome:
    """One run across the board at ``terrain_path`` with the reward of ``model_path``.

    Without a model the hand-tuned reward chooses the footholds; with
    ``expert`` the teacher ``teacher`` does (:data:`footfall.expert.teachers.TEACHERS`: the
    walking expert, or the hand-tuned reward it guards), with the expert of ``expert_config``
    if given (:func:`chooser_expert`). ``search_radius`` [m] limits the candidate set F and
    ``friction_safety`` [-] sets the friction check, ``path_bias`` [hand-tuned reward/m]
    the footstep planner's path bias and ``variant`` the controller variant
    (:func:`walk_config`).
    ``snapshots`` writes a strip of ``frames`` pictures (.png), ``video`` an
    .mp4 at 25 frames/s, ``log_path`` appends the run to a store,
    ``explain_plot`` draws the run's last seconds (.png,
    :func:`footfall.plots.explain.save_explain_plot`).

    Raises
    ------
    FootfallError
        For bad settings, a missing board, a model for another robot or map,
        or a bad output path: all before the run.
    """
    config = walk_config(model_path, expert, search_radius, friction_safety, path_bias,
                         variant)
    expert_config = variant_expert(config, expert, expert_config, variant)
    judge = chooser_expert(config, expert, expert_config)
    hmap = load_board(terrain_path)
    reward_for = reward_source(model_path, hmap)
    log = _checked_log(log_path, inputs=(terrain_path, model_path))
    check_picture_outputs(snapshots, video, explain_plot, inputs=(terrain_path, model_path, log))
    pictures = None
    if snapshots or video:
        pictures = Frames(snapshot_count=frames if snapshots else 0,
                          video_fps=25.0 if video else 0.0)
    run = (teacher_walk(hmap, reward_for, seed, config, teacher, judge, pictures) if expert
           else Walk(hmap, reward_for, seed, config, frames=pictures))
    if isinstance(run, TapedWalk):  # one run: its branches on every core this process may use
        run.branch_processes = usable_cores()
    record = run.run()
    run_id = None
    if log is not None:  # stored before any picture: a picture that fails loses no run
        with DemoStore(log, create=True) as store:
            run_id = store.add_run(record, terrains=[hmap])
    if explain_plot is not None:
        save_explain_plot(run.trace.series(), record.result.get("explanation"), run.robot,
                          explain_plot, title=f"{Path(terrain_path).name}, seed {seed}: "
                                              f"{record.result['reason']}")
    if snapshots:
        save_strip(pictures.snapshots, snapshots)
    if video:
        save_video(pictures.video, video, pictures.video_fps)
    return WalkOutcome(str(terrain_path), _path_or_none(model_path), expert, seed, record, run_id,
                       teacher if expert else None)


@dataclass(frozen=True)
class BatchOutcome:
    """Runs with seeds ``seed``, ``seed + 1``, ... across a board, and their Table II measures."""

    terrain: str  # the board file, as given
    model: str | None  # the model file, None for the hand-tuned reward
    expert: bool  # the walking expert chose every foothold
    seed: int  # seed of the first run
    summary: RunSummary  # success rate, slip, speed, ...
    records: tuple[RunRecord, ...]  # the runs, in seed order
    teacher: str | None = None  # with ``expert``: which teacher chose

    def as_dict(self) -> dict:
        """Plain data for JSON: the settings, the summary's keys, then each run's result."""
        return {"terrain": self.terrain, "model": self.model, "expert": self.expert,
                "teacher": self.teacher, "seed": self.seed, **self.summary.as_dict(),
                "runs_detail": [{"seed": self.seed + i, **r.result}
                                for i, r in enumerate(self.records)]}


def walk_batch(terrain_path: str | os.PathLike, runs: int, seed: int, *,
               model_path: str | os.PathLike | None = None, expert: bool = False,
               search_radius: float | None = None, friction_safety: float | None = None,
               path_bias: float | None = None, variant: str = "defaults",
               log_path: str | os.PathLike | None = None,
               progress: Callable[[RunRecord], None] | None = None,
               executor: Executor | None = None,
               reused: Callable[[int], None] | None = None,
               expert_config: ExpertConfig | None = None, teacher: str = "expert"
               ) -> BatchOutcome:
    """``runs`` runs in parallel (:func:`walk_many`), each logged to ``log_path`` as it ends.

    Settings as for :func:`walk_once`; ``progress`` is called with each
    walked run (in the order they finish). With a log store, each run is
    keyed (:func:`batch_run_keys`) and a run the store holds already is read
    from it, not walked again (``reused(count)`` is told how many, before any
    run): an interrupted batch run again walks only what is missing. The runs
    are walked on ``executor`` [default: a local pool].

    Raises
    ------
    FootfallError
        As :func:`walk_once` and :func:`walk_many`.
    """
    config = walk_config(model_path, expert, search_radius, friction_safety, path_bias,
                         variant)
    expert_config = variant_expert(config, expert, expert_config, variant)
    hmap = load_board(terrain_path)
    log = _checked_log(log_path, inputs=(terrain_path, model_path))
    jobs = batch_jobs(terrain_path, model_path, runs, seed, config, expert, hmap,
                      expert_config=expert_config, teacher=teacher)
    store = DemoStore(log) if log is not None and log.exists() else None  # a new one is made
    try:  # with the first run kept: a batch refused before any run leaves no file
        records: dict[int, RunRecord] = {}
        if log is not None:
            keys = batch_run_keys(hmap, model_path, expert, config, [j.seed for j in jobs],
                                  expert_config, teacher)
            jobs = [replace(j, key=keys[j.seed]) for j in jobs]
        if store is not None:
            held = {r["key"]: r["id"] for r in store.runs(key_prefix="walk-many/")}
            records = {j.seed: store.run(held[j.key]) for j in jobs if j.key in held}
        if reused is not None:
            reused(len(records))
        todo = [j for j in jobs if j.seed not in records]
        executor = executor or LocalPool(min(usable_cores(), max(1, len(todo))))
        for job, record in _walked(executor, todo, None):
            if log is not None:  # each finished run is kept at once
                store = store or DemoStore(log, create=True)
                run_id, added = store.add_run_if_new(record, terrains=[hmap])
                if not added:  # another batch on the store walked it meanwhile: theirs
                    record = store.run(run_id)
            records[job.seed] = record
            if progress is not None:
                progress(record)
    finally:
        if store is not None:
            store.close()
    ordered = [records[j.seed] for j in jobs]
    return BatchOutcome(str(terrain_path), _path_or_none(model_path), expert, seed,
                        summarise(ordered), tuple(ordered), teacher if expert else None)
