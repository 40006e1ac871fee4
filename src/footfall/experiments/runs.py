"""Batches of stored runs: a job per run, run where it is not yet stored, each kept on arrival.

An experiment that walks many runs (the reproduction, the walking ablation)
describes each as a :class:`RunJob` -- a unique key, the board file, the
reward (a model file or the hand-tuned default, or the walking expert
choosing every foothold), the seed and the walking settings -- and hands the
list to a :class:`Runner`. The runner skips the keys its store already
holds, walks the rest in parallel worker processes (one core each) and
stores every run, with the expert's corrections of it if asked for, in one
transaction as it arrives: an experiment stopped at any point and started
again walks only what is missing, and the result does not depend on the
order in which the workers finish. Where the runs are walked -- a local
process pool or a Ray cluster -- is the runner's executor
(:mod:`footfall.experiments.executors`); only the runner writes the store.
"""

from __future__ import annotations

import json
import os
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from threadpoolctl import threadpool_limits

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError
from footfall.core.folders import hold_folder
from footfall.core.heightmap import HeightMap
from footfall.core.progress import BatchProgress
from footfall.core.robot import LITTLEDOG
from footfall.data.runlog import RunRecord
from footfall.data.store import DemoStore
from footfall.expert.corrections import (
    corrections_to_demonstrations,
    inspect_run,
    worst_corrections,
)
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert
from footfall.expert.teachers import TEACHERS, state_judge
from footfall.features.scorer import SCORERS
from footfall.learning.model import FootholdModel
from footfall.sim.episode import Frames, Walk, WalkConfig
from footfall.sim.rollout import RolloutConfig, RolloutWalk, verdict_demonstrations
from footfall.terrain import make_board

if TYPE_CHECKING:
    from footfall.experiments.executors import Executor

RunOutput = tuple[RunRecord, list]  # a walked run and the expert's corrections of it (demos)


@dataclass(frozen=True)
class RunJob:
    """One run of an experiment; everything a worker process needs (paths, not maps)."""

    key: str | None  # unique run key in the store (None: a run not for a store)
    terrain: str  # board file
    model: str | None  # model file (None: the hand-tuned default reward)
    seed: int  # the run's seed (start pose, registration, friction, sensors)
    walk: WalkConfig
    correct: bool = False  # the expert inspects the run
    margin: float = 0.0  # [value units] shortfall the expert corrects (with ``correct``)
    cap: int | None = None  # most corrections labelled per run (the worst ones)
    expert: ExpertConfig = field(default_factory=ExpertConfig)
    judge: bool = False  # the teacher chooses every foothold itself (model unused)
    inspect_seed: int = 0  # the expert's randomness while it inspects the run
    teacher: str = "expert"  # who judges and corrects (footfall.expert.teachers.TEACHERS)
    every_step: bool = False  # the teacher labels every step (DAgger), not only those short
    # of its best by more than ``margin`` (``cap`` still bounds them)
    rollout: RolloutConfig = field(default_factory=RolloutConfig)  # the rollout teacher's
    # settings, where the teacher is "rollout"


def reward_source(model_path: str | os.PathLike | None, hmap: HeightMap):
    """The reward ``reward_for(leg)`` of a model file, or the hand-tuned default (None).

    Raises
    ------
    FootfallError
        If the model is for another robot or another map resolution.
    """
    if model_path is None:
        reward = SCORERS.get("hand-tuned")(None)
        return lambda leg: reward
    model = FootholdModel.load(model_path)
    model.check_compatible(robot=LITTLEDOG, map_resolution=hmap.resolution)
    return model.reward_for


def teacher_walk(hmap: HeightMap, reward_for, seed: int, config: WalkConfig, teacher: str,
                 expert: ExpertConfig, frames: Frames | None = None,
                 rollout: RolloutConfig = RolloutConfig()) -> Walk:
    """The walk in which ``teacher`` (:data:`~footfall.expert.teachers.TEACHERS`, with the
    expert of ``expert``) chooses every foothold: the judged planner, the planner of a reward
    it guards, or the rollout teacher over that (:class:`~footfall.sim.rollout.RolloutWalk`).
    ``reward_for`` plans the body path where the teacher is a judge; ``rollout``: the rollout
    teacher's settings."""
    step = config.footstep
    walker = TEACHERS.get(teacher).walker(expert, step.bias_weight, step.lead)
    if walker.reward is not None:
        reward_for = lambda leg: walker.reward  # noqa: E731
    if walker.rollout:
        return RolloutWalk(hmap, reward_for, seed, config, frames=frames, judge=walker.judge,
                           rollout=rollout, expert=SyntheticExpert(expert))
    return Walk(hmap, reward_for, seed, config, frames=frames, judge=walker.judge)


def execute(job: RunJob) -> RunOutput:
    """One run (in a worker process): walk, and the expert's corrections if asked for."""
    hmap = _board(job.terrain)
    # One core per run: the stack's small matrix products only lose to BLAS threads
    # fighting over the cores the other runs use.
    teacher = TEACHERS.get(job.teacher)
    footstep = job.walk.footstep
    walker = teacher.walker(job.expert, footstep.bias_weight, footstep.lead)
    rollout = walker.rollout
    with threadpool_limits(limits=1):
        reward_for = reward_source(job.model, hmap)
        if job.judge:
            run = teacher_walk(hmap, reward_for, job.seed, job.walk, job.teacher, job.expert,
                               rollout=job.rollout)
        elif job.correct and rollout:  # it labels the run's own states as the run goes,
            # improving on the teacher's base chooser, or on the walking function itself
            base = walker.reward if job.rollout.base == "teacher" else None
            run = RolloutWalk(hmap, reward_for, job.seed, job.walk, rollout=job.rollout,
                              expert=SyntheticExpert(job.expert), take=False,
                              base=None if base is None else (lambda leg: base))
        else:
            run = Walk(hmap, reward_for, job.seed, job.walk)
        record = run.run()
        record = replace(record, key=job.key)
        demos = []
        if job.correct and rollout and not job.judge:
            untried = (state_judge(job.teacher, job.expert, footstep.bias_weight, footstep.lead)
                       if job.rollout.base == "teacher" else None)  # the base's word, if it has one
            demos = verdict_demonstrations(run, record, job.key, job.every_step, job.cap,
                                           untried=untried)
        elif job.correct:
            expert = teacher.expert(job.expert, footstep.bias_weight, footstep.lead)
            found = inspect_run(record, hmap, expert, job.margin, rng=job.inspect_seed,
                                every_step=job.every_step)
            found = worst_corrections(found, job.margin, job.cap, job.every_step)
            demos = corrections_to_demonstrations(record, job.key, found, expert)
    return record, demos


BOARDS_KEPT = 4  # [-] boards a worker process keeps loaded between runs
_BOARDS: OrderedDict = OrderedDict()  # (path, size, mtime) -> HeightMap, most recent last


def _board(path: str) -> HeightMap:
    """The board at ``path``, loaded once per worker process while the file is unchanged.

    Runs of a batch on one board then share one map object, and with it what
    is computed once per map: the reward grids
    (:func:`footfall.control.body_path.terrain_grids`) and the expert's sphere
    surface (:mod:`footfall.core.sphere_surface`).
    """
    st = os.stat(path)
    key = (os.path.realpath(path), st.st_size, st.st_mtime_ns)
    if key in _BOARDS:
        _BOARDS.move_to_end(key)
    else:
        _BOARDS[key] = HeightMap.load(path)
        if len(_BOARDS) > BOARDS_KEPT:
            _BOARDS.popitem(last=False)
    return _BOARDS[key]


@dataclass
class Runner:
    """Runs jobs not yet in the store on an executor; each run is stored with its demos on arrival."""

    store: DemoStore
    terrains: dict[str, HeightMap]  # content hash -> board (stored with the first run on it)
    executor: Executor  # where the runs are walked (footfall.experiments.executors)
    on_run: Callable[[str], None] | None  # called with each stored run's key
    log: Callable[[str], None]

    def run(self, jobs: list[RunJob], desc: str) -> None:
        """Walk the jobs whose keys are not stored yet, their progress named ``desc`` (a bar on a
        terminal, a line every few runs in a log: :class:`footfall.core.progress.BatchProgress`)."""
        done = {r["key"] for r in self.store.runs()}
        todo = [j for j in jobs if j.key not in done]
        if len(todo) < len(jobs):
            self.log(f"{desc}: {len(jobs) - len(todo)} of {len(jobs)} runs already stored")
        if not todo:
            return
        bar = BatchProgress(len(todo), desc, "run")
        runs = self.executor.map(todo)
        try:
            for _, (record, demos) in runs:
                self._keep(record, demos, bar)
        finally:
            runs.close()  # an interrupted batch cancels the runs not yet finished
            bar.close()

    def _keep(self, record: RunRecord, demos: list, bar) -> None:
        self.store.add_run(record, terrains=[self.terrains[record.terrain_hash]],
                           demonstrations=demos)
        bar.update(failed=not record.result["success"])
        if self.on_run is not None:
            self.on_run(record.key)


def claim_folder(out: Path, settings: dict, what: str, free: tuple[str, ...] = (),
                 hold: bool = True) -> None:
    """Make the folder ``out`` an experiment's, with ``settings`` in its ``config.json``.

    A folder that holds ``what`` (e.g. "a reproduction") with other settings is refused,
    so that a resumed experiment never mixes runs of two settings, and so is one another
    process holds (:func:`footfall.core.folders.hold_folder`: two runs at once); ``hold``
    False: a worker process of the command that holds it. Settings named in
    ``free`` may differ: they choose which runs are walked, not how (their run keys tell
    the runs apart).
    """
    if out.exists() and not out.is_dir():
        raise FootfallError(f"output path is not a directory: {out}")
    out.mkdir(parents=True, exist_ok=True)
    if hold:  # for this process's run: a second command is refused
        hold_folder(out, what)
    path = out / "config.json"
    if path.exists():
        try:
            held = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise FootfallError(f"{path}: unreadable settings ({exc})") from None
        mine = json.loads(json.dumps(settings))  # as it would read back
        if not isinstance(held, dict) or ({k: v for k, v in held.items() if k not in free}
                                          != {k: v for k, v in mine.items() if k not in free}):
            raise FootfallError(f"{out} holds {what} with other settings; use another --out")
    write_text_atomic(path, json.dumps(settings, sort_keys=True, indent=1))


def _holds(hmap: HeightMap, spec: tuple, seed: int) -> bool:
    """Whether a board file's metadata says it is ``spec`` (flat ends aside) made with ``seed``."""
    meta = hmap.metadata
    modules = [(m.get("kind"), m.get("difficulty")) for m in meta.get("modules", [])]
    inner = [m for m in modules if m[0] != "flat"] or modules
    wanted = [(k, float(d)) for k, d in spec if k != "flat"] or [(k, float(d)) for k, d in spec]
    return meta.get("board_seed") == seed and (inner == wanted or modules == wanted)


def board_files(out: Path, boards: dict[str, tuple[tuple, int, bool]]) -> dict[str, Path]:
    """The experiment's boards as files ``out/terrain/NAME.npz``, each made once from its seed.

    ``boards``: name -> (modules as (kind, difficulty) pairs, board seed, flat ends). A board
    is saved atomically, so a file left by a stopped experiment is whole.
    """
    folder = out / "terrain"
    folder.mkdir(parents=True, exist_ok=True)
    paths = {}
    for name, (spec, seed, flat_ends) in boards.items():
        path = folder / f"{name}.npz"
        if not path.exists():
            make_board(list(spec), seed=seed, flat_ends=flat_ends).save(path)
        elif not _holds(HeightMap.load(path), spec, seed):
            # (a board chosen by a stage, e.g. the test boards at the calibrated difficulty)
            raise FootfallError(f"{path} holds another board than {name} "
                                f"({', '.join(f'{k} {d:g}' for k, d in spec)}, seed {seed}); "
                                f"use another --out")
        paths[name] = path
    return paths
