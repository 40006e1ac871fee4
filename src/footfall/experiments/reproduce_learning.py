"""The reproduction's learning: a model per function, saved in the workspace and reused.

:func:`learn_saved` learns one model from the corrections (a correction
round's function, or one of the paper's three) and saves it under
``models/``, keyed by everything it was learned from, so that a resumed
reproduction reuses it. :func:`learn_functions` learns the paper's three
functions (terrain features, templates, templates + features) from the same
corrections -- each in a worker process of its own when the reproduction
has more than one: they are independent, each draws from its own seed, and
a worker reads the corrections from the store by id, so the models are the
same bits however many processes learn them.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from footfall.core.compute import worker_pool
from footfall.core.errors import FootfallError
from footfall.data.store import DemoStore
from footfall.experiments.workspace import Workspace, open_workspace
from footfall.features.family import PAPER_FEATURE_SETS
from footfall.learning.model import FootholdModel
from footfall.learning.train import TrainingDemo, learn_model


def _training_key(demos: list, feature_set: str, settings: dict) -> str:
    h = hashlib.sha256()
    h.update(json.dumps({"fs": feature_set, **settings}, sort_keys=True).encode())
    for d in demos:
        h.update(f"{d.source}:{d.chosen}:{d.terrain_hash}".encode())
    return h.hexdigest()


def _key(ws: Workspace, demos: list, feature_set: str, rms: float | None) -> tuple[str, int]:
    """The key of a model learned from ``demos`` with the workspace's settings, and its seed."""
    config = ws.config
    seed = ws.streams.seed_for("learning")
    settings = {"library_size": config.library_size, "selection": config.selection,
                "cv": config.cv, "rms": rms, "seed": seed,
                "training_candidates": config.training_candidates}
    if (config.learner, config.folds) != ("l1", "demonstration"):  # keys of the paper's stay
        settings.update(learner=config.learner, folds=config.folds)
    if config.template_budget is not None:
        settings.update(template_budget=config.template_budget)
    if config.supervision != "choice":  # keys of the paper's supervision stay
        settings.update(supervision=config.supervision)
    if config.veto:
        settings.update(veto=True)
    if config.library_capped:
        settings.update(library_capped=True)
    return _training_key(demos, feature_set, settings), seed


def _saved(path: Path, key: str) -> FootholdModel | None:
    """The model saved at ``path`` if it was learned under ``key``; None otherwise."""
    if not path.exists():
        return None
    try:
        model = FootholdModel.load(path)
    except FootfallError:
        return None  # unreadable or stale: learn again
    return model if model.info.get("training_key") == key else None


def learn_saved(ws: Workspace, name: str, demos: list, feature_set: str, rms: float | None,
                log: Callable[[str], None], threads: int = 1) -> FootholdModel:
    """The model learned from ``demos`` (ordered by source), reused from its file if it matches.

    ``rms`` [m]: the RBF bandwidths fixed as that RMS height difference on
    every scale; None: chosen by cross-validation. ``threads``: each fit's threads
    (:func:`~footfall.learning.train.learn_model`; the same model whatever the number).
    """
    config, path = ws.config, ws.model_path(name)
    key, seed = _key(ws, demos, feature_set, rms)
    model = _saved(path, key)
    if model is not None:
        return model
    terrains = ws.by_hash
    training = [TrainingDemo.of(d, terrains[d.terrain_hash]) for d in demos]
    t0 = time.perf_counter()
    model = learn_model(training, feature_set, config.learner,
                        library_size=config.library_size,
                        training_candidates=config.training_candidates,
                        bandwidth_rms=None if rms is None else (rms,) * 3, cv=config.cv,
                        seed=seed, selection=config.selection, folds=config.folds,
                        template_budget=config.template_budget,
                        supervision=config.supervision, veto=config.veto,
                        library_capped=config.library_capped, threads=threads,
                        log=lambda s: log("    " + s))
    model = replace(model, info={**model.info, "training_key": key,
                                 "sources": [d.source for d in demos]})
    model.save(path)
    log(f"  learned {feature_set} from {len(demos)} demonstrations in "
        f"{time.perf_counter() - t0:.0f} s")
    return model


@dataclass(frozen=True)
class Functions:
    """The paper's three ranking functions, learned from the same corrections (Table I)."""

    models: dict[str, FootholdModel]  # feature set -> model

    def table1(self) -> dict:
        """Templates kept per scale and leg group, for the sets with templates."""
        return {fs: m.templates_kept() for fs, m in self.models.items() if fs != "terrain"}

    def summary(self) -> dict:
        """Per set and leg group: lambda (a linear learner's) or trees (a boosted one's), CV
        error, non-zero weights (columns a tree reads), template bandwidths."""
        return {fs: {g: {"lambda": f.info.get("lambda"), "trees": f.info.get("trees"),
                         "cv_error": f.info["cv_error"], "n_nonzero": f.info["n_nonzero"],
                         "bandwidth_rms_m": f.info.get("bandwidth_rms_m")}
                     for g, f in m.functions.items()} for fs, m in self.models.items()}


# The paper's sets, slowest to learn first, so that the last worker to finish has a short one.
_SLOWEST_FIRST = {"both": 0, "templates": 1, "terrain": 2}


def _heading(ws: Workspace, feature_set: str) -> str:
    c = ws.config
    return (f"learning {feature_set} (learner {c.learner}, {c.selection} on its path, folds by "
            f"{c.folds})")


def _learn_in_worker(out: Path, config, feature_set: str, store_path: Path,
                     ids: list[int]) -> list[str]:
    """A worker's part: one of the paper's functions learned from the corrections ``ids`` (read
    from the store, in this order) and saved; the lines it would have logged."""
    ws = open_workspace(out, config, hold=False)  # the command's folder, held by its process
    with DemoStore(store_path, read_only=True) as store:
        demos = store.demonstrations(ids=ids)
    lines = [_heading(ws, feature_set)]
    learn_saved(ws, feature_set, demos, feature_set, config.final_bandwidth_rms, lines.append)
    return lines


def learn_functions(ws: Workspace, demos: list, log: Callable[[str], None],
                    processes: int = 1, store_path: Path | None = None) -> Functions:
    """Terrain features, templates, templates + features, by the configured learner and model
    selection (:class:`~footfall.experiments.reproduce.ReproduceConfig`: learner, selection,
    folds): with ``processes`` > 1 and the corrections stored (``store_path``), those not
    saved yet are learned in that many worker processes at once, their logs in the sets'
    order; one left to learn takes ``processes`` threads."""
    rms = ws.config.final_bandwidth_rms
    todo = [fs for fs in PAPER_FEATURE_SETS
            if _saved(ws.model_path(fs), _key(ws, demos, fs, rms)[0]) is None]
    ids = [d.id for d in demos]
    pooled = processes > 1 and len(todo) > 1 and store_path is not None and None not in ids
    if pooled:
        with worker_pool(min(processes, len(todo))) as pool:
            futures = {fs: pool.submit(_learn_in_worker, ws.out, ws.config, fs, store_path, ids)
                       for fs in sorted(todo, key=lambda f: _SLOWEST_FIRST.get(f, 3))}
            for fs in todo:  # the sets' order, whichever finished first
                for line in futures[fs].result():
                    log(line)
    models = {}
    for fs in PAPER_FEATURE_SETS:
        if not (pooled and fs in todo):
            log(_heading(ws, fs))
        models[fs] = learn_saved(ws, fs, demos, fs, rms, log, 1 if pooled else processes)
    return Functions(models)
