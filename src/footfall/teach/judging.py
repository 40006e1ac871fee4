"""The synthetic expert's judgement of a logged run, kept in the store: a run is judged once
per store and expert (seconds the first time), then read back at once -- by every later start
of the teaching server and by ``footfall demos info``; and its refusals on the steps people
marked "never here", to set their marks against."""

from __future__ import annotations

import hashlib
import json

import numpy as np

from footfall import __version__
from footfall.control.footstep import FootstepConfig
from footfall.core.errors import FootfallError
from footfall.data.runlog import RunRecord
from footfall.data.store import DemoStore
from footfall.expert.corrections import step_verdicts
from footfall.expert.protocol import REFUSED_SHORTFALL, teacher_verdict
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert, walking_expert
from footfall.teach.agreement import agreement, expert_verdicts, marks_agreement


def default_expert() -> ExpertConfig:
    """The synthetic expert that judges labelled steps: the one that corrects the reproduction's
    runs (the walking expert at the default gait's foot lead, :func:`walking_expert`)."""
    return walking_expert(FootstepConfig().lead)


def expert_key(expert: SyntheticExpert) -> str:
    """The key a judgement is kept under: a hash of the expert's settings and footfall's
    version (another expert, or another footfall, judges anew)."""
    text = json.dumps({"expert": expert.config.to_dict(), "footfall": __version__},
                      sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def judged_run(store: DemoStore, run: RunRecord, expert: SyntheticExpert,
               key: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The expert's best index and the robot's shortfall [value units] at every step of ``run``
    (:func:`footfall.expert.corrections.step_verdicts`): read from ``store`` if kept, else
    judged and kept (when the store can be written)."""
    key = key or expert_key(expert)
    kept = store.judgement(run.id, key)
    if kept is not None and kept[0].shape[0] == len(run.steps):
        return kept
    best, shortfall = step_verdicts(run, store.terrain(run.terrain_hash), expert)
    if not store.read_only:
        try:
            store.keep_judgement(run.id, key, best, shortfall)
        except FootfallError:  # a store another process holds locked: judged, not kept
            pass
    return best, shortfall


def labels_agreement(store: DemoStore, expert: SyntheticExpert, margin: float) -> dict:
    """:func:`footfall.teach.agreement.agreement` of a store's labels: each labelled run judged
    by ``expert`` (kept judgements read back), its verdicts at ``margin`` [value units]."""
    labels = store.labels()
    key = expert_key(expert)
    runs = {run_id: store.run(run_id) for run_id in sorted({label.run_id for label in labels})}
    verdicts = {run_id: expert_verdicts(*judged_run(store, run, expert, key), margin)
                for run_id, run in runs.items()}
    return agreement(labels, lambda run, k: int(verdicts[run][k]),
                     lambda run, k: runs[run].steps[k].candidates) | {"margin": float(margin)}


def store_agreement(store: DemoStore, expert: SyntheticExpert, margin: float,
                    refusals: dict | None = None) -> dict:
    """Every agreement figure of a store: its labels' (:func:`labels_agreement`) and, under
    ``marks``, its "never here" marks' (:func:`marks_agreement_of`)."""
    return labels_agreement(store, expert, margin) | {
        "marks": marks_agreement_of(store, expert, refusals)}


def marks_agreement_of(store: DemoStore, expert: SyntheticExpert,
                       refusals: dict | None = None) -> dict:
    """:func:`footfall.teach.agreement.marks_agreement` of a store's marks: ``expert`` judges
    every marked step (:func:`footfall.expert.protocol.teacher_verdict`: the candidates it
    refuses). ``refusals``, {(run id, k): (n,) bool}, keeps its verdicts between calls (the
    same expert's: a server's)."""
    marks = store.marks()
    kept = {} if refusals is None else refusals
    runs = {run_id: store.run(run_id) for run_id in sorted({m.run_id for m in marks})}
    maps: dict = {}

    def refused(run_id: int, k: int) -> np.ndarray:
        if (run_id, k) not in kept:
            run = runs[run_id]
            if run.terrain_hash not in maps:
                maps[run.terrain_hash] = store.terrain(run.terrain_hash)
            step = run.steps[k]
            kept[run_id, k] = teacher_verdict(expert, maps[run.terrain_hash], step.state,
                                              step.candidates)[1]
        return kept[run_id, k]

    return marks_agreement(marks, refused, lambda run, k: runs[run].steps[k].candidates) | {
        "refused_shortfall": REFUSED_SHORTFALL}
