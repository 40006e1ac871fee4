"""Expert corrections of run logs (paper §II-B): the demonstrations the robot learns from.

The expert is shown a logged run. At every step it judges the candidate set
F the robot chose from; where the robot's choice falls short of the expert's
own best by more than a margin, it labels the foothold it would have chosen
among the same F, and that label becomes a demonstration -- with the state
the robot was in, the whole F, and its source (the run's key and the step).
Steps where the robot chose well enough teach nothing new and are left
alone, exactly as a human expert skims the good parts of a run.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import distinct_inputs, writable_path
from footfall.core.heightmap import HeightMap
from footfall.data.runlog import RunRecord
from footfall.data.schema import FORMAT as STORE_FORMAT
from footfall.data.schema import SUFFIXES
from footfall.data.store import Demonstration, DemoStore
from footfall.expert.protocol import Expert, expert_settings, kept_verdict, teacher_verdict

DEFAULT_MARGIN = 1.0  # [value units; 1 unit = 1 cm of progress for the synthetic expert] a choice
# this much worse than the expert's best is corrected: about the value spread of footholds a few
# millimetres apart on smooth ground, so near-ties are not labelled as mistakes
REPRODUCTION_MARGIN = 2.0  # [value units] the reproduction's correction margin (its config's
# default), and the veto of the teacher that accepts only what the expert does ("accepted")
SEVERE_SHORTFALL = 10.0  # [value units; 1 cm off the gait-nominal foothold] a choice this much
# worse than the expert's best: a foothold on a slanted face, a pit's rim or a riser's edge


@dataclass(frozen=True)
class Correction:
    """The expert's verdict on one logged step."""

    k: int  # step number in the run
    chosen: int  # index in F of the robot's choice
    best: int  # index in F of the expert's (noiseless) best
    shortfall: float  # [value units] expert value of its best minus of the robot's choice (>= 0)
    label: int | None  # index in F the expert demonstrates (None: not corrected)
    values: np.ndarray | None = None  # (n,) the teacher's value of every candidate [value units]
    refused: np.ndarray | None = None  # (n,) bool: the candidates it refuses outright
    judged: np.ndarray | None = None  # (n,) [value units] what its refusals are relative to


def source_of(run_key: str, k: int) -> str:
    """The demonstration source of a correction at step ``k`` of the run stored as ``run_key``."""
    return f"run:{run_key}:step:{k}"


def step_verdicts(run: RunRecord, hmap: HeightMap, expert: Expert) -> tuple[np.ndarray, np.ndarray]:
    """The expert's noiseless best index in F and the robot's shortfall, for every step of ``run``.

    Returns ``(best, shortfall)``, each of shape (n_steps,): ``best`` indexes the
    step's candidates; ``shortfall`` [value units] is the expert's value of its
    best minus its value of the robot's choice (>= 0). ``hmap`` must be the
    map the run was logged on.
    """
    if not isinstance(run, RunRecord):
        raise FootfallError(f"inspecting a run needs a RunRecord, got {type(run).__name__}")
    if hmap.content_hash() != run.terrain_hash:
        raise FootfallError("the run was logged on another terrain than the map given")
    best = np.zeros(len(run.steps), dtype=np.intp)
    shortfall = np.zeros(len(run.steps))
    for i, step in enumerate(run.steps):  # steps of one run (dozens), each vectorised over F
        values = np.asarray(expert.values(hmap, step.state, step.candidates), dtype=np.float64)
        best[i] = int(np.argmax(values))
        shortfall[i] = float(values[best[i]] - values[step.chosen])
    return best, shortfall


def inspect_run(run: RunRecord, hmap: HeightMap, expert: Expert, margin: float = DEFAULT_MARGIN,
                rng: np.random.Generator | int = 0, every_step: bool = False) -> list[Correction]:
    """The expert's verdict on every step of ``run`` (on the map ``hmap`` the planner saw).

    A step is corrected when ``max(values) - values[chosen] > margin``, or,
    with ``every_step``, always (the teacher labels every state the robot
    visited, its choice where the robot chose as it would: the DAgger labels);
    its label is ``expert.choose`` among the step's candidates (the noiseless
    best for a perfect expert; an imperfect one may pick another). Every
    verdict keeps the teacher's values of the step's candidates and those it
    refuses (:func:`~footfall.expert.protocol.teacher_verdict`). ``rng`` draws
    the imperfection, step by step in order, so the same run and seed give the
    same labels.
    """
    if not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 0):
        raise FootfallError(f"the correction margin must be a number >= 0, got {margin!r}")
    if not isinstance(run, RunRecord):
        raise FootfallError(f"inspecting a run needs a RunRecord, got {type(run).__name__}")
    if hmap.content_hash() != run.terrain_hash:
        raise FootfallError("the run was logged on another terrain than the map given")
    rng = np.random.default_rng(rng)
    out = []
    for step in run.steps:  # steps of one run (dozens), each vectorised over F
        values, refused, judged = teacher_verdict(expert, hmap, step.state, step.candidates)
        best = int(np.argmax(values))
        sf = float(values[best] - values[step.chosen])
        label = None
        if (every_step or sf > margin) and step.candidates.shape[0] >= 2:
            label = int(expert.choose(hmap, step.state, step.candidates, rng))
        out.append(Correction(step.k, step.chosen, best, sf, label, values, refused, judged))
    return out


def worst_corrections(corrections: list[Correction], margin: float, cap: int | None,
                      every_step: bool = False) -> list[Correction]:
    """The corrections the expert labels: every shortfall above ``margin`` (value units) --
    with ``every_step``, every labelled step -- or the worst ``cap`` of them (ties: the earlier
    step); the others keep their verdict, unlabelled."""
    chosen = [c for c in corrections
              if c.label is not None and (every_step or c.shortfall > margin)]
    if cap is not None and len(chosen) > cap:
        chosen = sorted(chosen, key=lambda c: (-c.shortfall, c.k))[:cap]
    keep = {c.k for c in chosen}
    return [c if c.k in keep else replace(c, label=None) for c in corrections]


def corrections_to_demonstrations(run: RunRecord, run_key: str, corrections: list[Correction],
                                  expert: Expert) -> list[Demonstration]:
    """One demonstration per corrected step, sourced ``run:<run_key>:step:<k>``, with the
    teacher's verdict on the step's other candidates (its values, its refusals)."""
    settings = expert_settings(expert)
    steps = {s.k: s for s in run.steps}
    out = []
    for c in corrections:
        if c.label is None:
            continue
        values, refused, judged = _stored_verdict(c)
        out.append(Demonstration(run.terrain_hash, steps[c.k].state, steps[c.k].candidates,
                                 c.label, source=source_of(run_key, c.k), expert=settings,
                                 values=values, refused=refused, judged=judged))
    return out


def _stored_verdict(c: Correction) -> tuple[np.ndarray | None, ...]:
    """A labelled step's verdict as a demonstration keeps it (:func:`kept_verdict`)."""
    if c.values is None or c.refused is None:
        return c.values, c.refused, c.judged
    return kept_verdict(c.values, c.refused, c.judged, c.label)


@dataclass(frozen=True)
class StoredCorrections:
    """What correcting a store's runs added to a demonstration store."""

    store: str  # the output store's path
    runs: int  # runs inspected
    steps: int  # their steps (decisions)
    above_margin: int  # steps whose shortfall exceeded the margin
    added: int  # corrections stored (at most ``per_run`` a run)
    margin: float  # [value units]
    per_run: int | None  # labels a run at most (None: every step above the margin)
    seed: int
    every_step: bool = False  # every step labelled, not only those above the margin
    skipped: int = 0  # corrections the store already held (the same step, the same teacher)

    def as_dict(self) -> dict:
        """Plain data for JSON, in field order."""
        return dict(vars(self))


def correct_stored_runs(run_paths: Sequence[str | os.PathLike], out: str | os.PathLike,
                        expert: Expert, margin: float, per_run: int | None, seed: int,
                        key_prefix: str | None = None, every_step: bool = False
                        ) -> StoredCorrections:
    """The expert's corrections of the run logs in ``run_paths``, added to the store ``out``
    (created if missing) in one transaction, as the reproduction's correction rounds make
    them: each run's steps judged, the worst ``per_run`` above ``margin`` labelled (with
    ``every_step``, the worst ``per_run`` of all steps: DAgger's labels).

    The labels of run ``i`` (in store and creation order) draw their imperfection from
    ``numpy.random.default_rng([seed, i])``: the same stores and seed give the same store.

    Raises
    ------
    FootfallError
        For a bad output path, an unreadable store, or stores without runs.
    """
    run_paths = distinct_inputs(run_paths, "run store")
    target = writable_path(out, SUFFIXES, what="store", kind="store", writes=STORE_FORMAT)
    demos, terrains, runs, steps, above = [], {}, 0, 0, 0
    for path in run_paths:
        with DemoStore(path, read_only=True) as store:
            for head in store.runs(key_prefix=key_prefix):
                run = store.run(head["id"])
                if run.terrain_hash not in terrains:
                    terrains[run.terrain_hash] = store.terrain(run.terrain_hash)
                found = inspect_run(run, terrains[run.terrain_hash], expert, margin,
                                    rng=np.random.default_rng([seed, runs]),
                                    every_step=every_step)
                steps += len(found)
                above += sum(c.shortfall > margin for c in found)
                found = worst_corrections(found, margin, per_run, every_step)
                demos += corrections_to_demonstrations(run, head["key"] or f"{path}#{head['id']}",
                                                       found, expert)
                runs += 1
    if runs == 0:
        raise FootfallError("the stores hold no run logs to correct")
    used = {d.terrain_hash for d in demos}
    with DemoStore(target, create=True) as store:
        ids, skipped = store.add_new_demonstrations(
            demos, terrains=[h for k, h in terrains.items() if k in used])
    return StoredCorrections(str(target), runs, steps, above, len(ids), float(margin), per_run,
                             seed, every_step, skipped)
