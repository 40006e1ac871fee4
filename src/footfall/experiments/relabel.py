"""Stored runs labelled by a teacher that must walk them: ``footfall demos correct --teacher rollout``.

The rollout teacher (:mod:`footfall.sim.rollout`) judges a step by walking
branches of the run from it, so it cannot label a run log as the state-alone
teachers do (:mod:`footfall.expert.corrections`): the run is walked again.
A stored run names its board (kept in the store), its seed and its walking
settings, and the function that walked it by name only (a learned model's
file is not kept), so the caller names that function. The same board, seed,
settings and function give the same run, so each run is walked again from
its log with the teacher labelling it as it goes (a correcting
:class:`~footfall.experiments.runs.RunJob`), on an executor, and the walk is
checked against the log: a run that walks otherwise -- another function
walked it, or another version of footfall -- is refused, never labelled.

Each run's labels are stored in their own transaction as it finishes, and a
run whose labels the output store already holds is skipped: a stopped
command resumes where it stopped, and the same command run twice adds
nothing twice.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import distinct_inputs, writable_path
from footfall.core.robot import LEG_NAMES
from footfall.data.runlog import RunRecord
from footfall.data.schema import FORMAT as STORE_FORMAT
from footfall.data.schema import SUFFIXES
from footfall.data.store import DemoStore
from footfall.experiments.executors import Executor, LocalPool
from footfall.experiments.runs import RunJob, reward_source
from footfall.expert.synthetic import ExpertConfig
from footfall.sim.episode import WalkConfig
from footfall.sim.rollout import RolloutConfig

__all__ = ["Relabelled", "relabel_runs", "retraces"]


@dataclass(frozen=True)
class Relabelled:
    """What labelling stored runs again added to a demonstration store."""

    store: str  # the output store's path
    runs: int  # runs walked again and labelled now
    skipped: int  # runs the store already held labels of (a resumed or repeated command)
    steps: int  # the steps of the runs labelled now (decisions kept in their logs)
    added: int  # labels stored now
    per_run: int | None  # labels a run at most (None: every one the teacher gave)
    every_step: bool  # every step labelled, not only where the teacher taught another
    repeated: int = 0  # labels of the runs walked now that the store held by then (another
    # command labelling the same runs at once): not added again

    def as_dict(self) -> dict:
        """Plain data for JSON, in field order."""
        return dict(vars(self))


def retraces(walked: RunRecord, logged: RunRecord) -> int | None:
    """The first step [index] at which ``walked`` leaves the run ``logged`` (its F or its
    choice differ, or one has more steps), or None where it walked the same footholds."""
    for a, b in zip(walked.steps, logged.steps):
        if a.chosen != b.chosen or not np.array_equal(a.candidates, b.candidates):
            return a.k
    if len(walked.steps) != len(logged.steps):
        return min(len(walked.steps), len(logged.steps))
    return None


def _labelled(store: Path, key: str, rollout: RolloutConfig) -> bool:
    """Whether the store at ``store`` (if it exists) holds this teacher's labels of the run
    ``key`` (the rollout teacher's with these settings; another teacher's labels of the same
    steps, e.g. a reproduction's own, do not count)."""
    if not store.exists():
        return False
    with DemoStore(store, read_only=True) as held:
        return any(d.expert.get("class", "").endswith(".RolloutVerdict")
                   and d.expert.get("config") == rollout.to_dict()
                   for d in held.demonstrations(source_prefix=f"run:{key}:step:"))


def _reward_names(model: str | None, hmap) -> list[str]:
    """The reward names a run walked by ``model`` (None: the hand-tuned reward) logs."""
    reward_for = reward_source(model, hmap)
    return sorted({str(getattr(reward_for(leg), "name", "reward"))
                   for leg in LEG_NAMES})


def relabel_runs(run_paths: Sequence[str | os.PathLike], out: str | os.PathLike,
                 model: str | None, teacher: str, expert: ExpertConfig,
                 rollout: RolloutConfig = RolloutConfig(), per_run: int | None = None,
                 every_step: bool = True, key_prefix: str | None = None,
                 executor: Executor | None = None,
                 progress: Callable[[RunRecord], None] | None = None,
                 todo: Callable[[int], None] | None = None) -> Relabelled:
    """The stored runs of ``run_paths`` (those whose key starts with ``key_prefix``), each
    walked again with ``model`` (None: the hand-tuned reward; the function that walked it)
    and labelled as it goes by ``teacher`` (a teacher that walks, e.g. "rollout", with the
    expert settings ``expert`` and ``rollout``), the labels added to the store ``out``
    (created if missing) run by run. ``todo(n)`` is told how many runs will be walked before
    the first; ``progress(record)`` is called as each finishes.

    Raises
    ------
    FootfallError
        For a bad output path, stores without runs, a run the model did not walk (its log
        names another reward), or a run that walks again otherwise than its log.
    """
    run_paths = distinct_inputs(run_paths, "run store")
    target = writable_path(out, SUFFIXES, what="store", kind="store", writes=STORE_FORMAT)
    heads = []
    for path in run_paths:
        with DemoStore(path, read_only=True) as store:
            heads += [(str(path), h) for h in store.runs(key_prefix=key_prefix)]
    if not heads:
        raise FootfallError("the stores hold no run logs to correct")
    with tempfile.TemporaryDirectory(prefix="footfall-relabel-") as scratch:
        jobs, logged, terrains, skipped = [], {}, {}, 0
        for path, head in heads:
            key = head["key"] or f"{path}#{head['id']}"
            if _labelled(target, key, rollout):
                skipped += 1
                continue
            with DemoStore(path, read_only=True) as store:
                run = store.run(head["id"])
                if run.terrain_hash not in terrains:
                    hmap = store.terrain(run.terrain_hash)
                    board = Path(scratch) / f"{run.terrain_hash[:16]}.npz"
                    hmap.save(board)
                    terrains[run.terrain_hash] = (hmap, str(board))
            hmap, board = terrains[run.terrain_hash]
            names = _reward_names(model, hmap)
            if sorted(run.settings.get("reward", [])) != names:
                raise FootfallError(
                    f"run {key} was walked by {', '.join(run.settings.get('reward', [])) or '?'}"
                    f", not by {', '.join(names)}: give --model the function that walked it")
            walk = WalkConfig.from_dict(run.settings["walk"])
            jobs.append(RunJob(key, board, model, run.seed, walk, correct=True,
                               cap=per_run, expert=expert, teacher=teacher,
                               every_step=every_step, rollout=rollout))
            logged[key] = run
        if todo is not None:
            todo(len(jobs))
        steps = added = repeated = 0
        if jobs:  # the store is made (or opened) only once every run was found good to walk
            pool = executor or LocalPool(1)
            try:
                with DemoStore(target, create=True) as output:
                    for job, (record, demos) in pool.map(jobs):
                        off = retraces(record, logged[job.key])
                        if off is not None:
                            raise FootfallError(
                                f"run {job.key} walked again leaves its log at step {off}: "
                                f"another function or another version of footfall walked it")
                        used = {d.terrain_hash for d in demos}
                        ids, again = output.add_new_demonstrations(
                            demos, terrains=[terrains[h][0] for h in used])
                        steps += len(record.steps)
                        added += len(ids)
                        repeated += again  # labelled meanwhile by another command
                        if progress is not None:
                            progress(record)
            finally:
                if executor is None:
                    pool.close()
    return Relabelled(str(target), len(jobs), skipped, steps, added, per_run, every_step,
                      repeated)
