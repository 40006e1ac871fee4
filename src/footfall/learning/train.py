"""Learning a foothold model from stored demonstrations, end to end.

Builds the template library from the training demonstrations, computes
bandwidth-free features once, and for the front and the hind legs chooses
the RBF bandwidth of each scale and the regularisation lambda by the same
cross-validation (folds grouped by demonstration), then fits the ranking
function and keeps only templates with non-zero weight (paper §III-B).
The paper tuned the bandwidths by hand; here they are searched: first one
shared RMS height difference for all scales, then each scale on its own.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from footfall.learning.dataset import (DEFAULT_LIBRARY_SIZE, DEFAULT_TRAINING_CANDIDATES, Example,
                              build_library, check_feature_set, column_names, make_example,
                              stack, training_rows)
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.learning.ranker import LEARNERS, FootholdRanker
from footfall.learning.model import LEG_GROUPS, FootholdModel, RankingFunction
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.features.config import FeatureConfig
from footfall.features.templates import TemplateLibrary, bandwidth_for_rms

BANDWIDTH_RMS_GRID = (0.002, 0.004, 0.008, 0.016)  # [m] shared RMS differences tried first


@dataclass(frozen=True)
class TrainingDemo:
    """What the learner sees of a demonstration: terrain, state, candidates, choice."""

    hmap: HeightMap
    state: object  # RobotState
    candidates: np.ndarray  # (n, 3) [m]
    chosen: int


def _bandwidths(rms: Sequence[float], config: FeatureConfig) -> tuple[float, ...]:
    return tuple(bandwidth_for_rms(r, g) for r, g in zip(rms, config.grids))


def _fit(examples: list[Example], feature_set: str, rms: Sequence[float] | None,
         config: FeatureConfig, learner: str, Cs, cv: int, selection: str = "1se"
         ) -> FootholdRanker:
    bw = None if rms is None else _bandwidths(rms, config)
    X, y, groups = stack(examples, feature_set, bw)
    return FootholdRanker(learner=learner, Cs=Cs, cv=cv, selection=selection).fit(X, y, groups)


def select_bandwidths(examples: list[Example], feature_set: str, config: FeatureConfig,
                      learner: str, Cs, cv: int, log: Callable[[str], None] = lambda s: None
                      ) -> tuple[tuple[float, ...], list[dict]]:
    """RMS height differences [m] per scale with the smallest cross-validation error."""
    n_scales = len(config.scales)
    tried: dict[tuple, float] = {}

    def error(rms: tuple) -> float:
        if rms not in tried:
            tried[rms] = _fit(examples, feature_set, rms, config, learner, Cs, cv).cv_error_
            log(f"  bandwidth rms {tuple(round(r * 1000, 1) for r in rms)} mm: "
                f"cv error {tried[rms]:.4f}")
        return tried[rms]

    best = min((tuple([r] * n_scales) for r in BANDWIDTH_RMS_GRID), key=error)
    for s in range(n_scales):  # then each scale on its own, halving and doubling
        for factor in (0.5, 2.0):
            trial = tuple(r * factor if k == s else r for k, r in enumerate(best))
            if error(trial) < error(best):
                best = trial
    record = [{"rms_m": list(k), "cv_error": v} for k, v in tried.items()]
    return best, record


def learn_model(demos: Sequence[TrainingDemo], feature_set: str, learner: str = "l1", *,
                config: FeatureConfig | None = None, robot: RobotDescription = LITTLEDOG,
                library_size: int = DEFAULT_LIBRARY_SIZE,
                training_candidates: int = DEFAULT_TRAINING_CANDIDATES,
                bandwidth_rms: Sequence[float] | None = None, Cs=10, cv: int = 5, seed: int = 0,
                selection: str = "1se",
                log: Callable[[str], None] = lambda s: None) -> FootholdModel:
    """Learn front- and hind-leg ranking functions from demonstrations.

    ``bandwidth_rms`` fixes the RBF bandwidths (as RMS height differences [m]
    per scale) instead of choosing them by cross-validation. ``selection``
    picks lambda on the path (see :class:`footfall.learning.ranker.FootholdRanker`).
    """
    feature_set = check_feature_set(feature_set)
    if learner not in LEARNERS:
        raise FootfallError(f"unknown learner {learner!r}; use one of {', '.join(LEARNERS)}")
    config = config or FeatureConfig()
    if not demos:
        raise FootfallError("no demonstrations to learn from")
    resolutions = {d.hmap.resolution for d in demos}
    started = time.perf_counter()
    rng = np.random.default_rng(seed)
    uses_templates = feature_set in ("templates", "both")
    library: TemplateLibrary | None = None
    if uses_templates:
        library = build_library([d.hmap for d in demos], [d.state for d in demos],
                                [d.candidates for d in demos], [d.chosen for d in demos],
                                config, rng, size=library_size, robot=robot)
        log(f"template library: {sum(library.counts)} templates {library.counts}")
    examples = []
    for d in demos:  # one demonstration at a time: each is vectorised over its candidates
        rows = training_rows(d.candidates.shape[0], d.chosen, training_candidates, rng)
        examples.append(make_example(d.hmap, d.state, d.candidates, d.chosen, library, config,
                                     rows, robot))
    names = column_names(feature_set, library, config)
    functions = {}
    for group in LEG_GROUPS:
        chosen = [e for e in examples if e.front == (group == "front")]
        if len(chosen) < cv:
            raise FootfallError(f"{group} legs have {len(chosen)} demonstrations; "
                                f"{cv}-fold cross-validation needs at least {cv}")
        log(f"{group} legs: {len(chosen)} demonstrations")
        search: list[dict] = []
        rms = None
        if uses_templates:
            if bandwidth_rms is not None:
                rms = tuple(float(r) for r in bandwidth_rms)
            else:
                rms, search = select_bandwidths(chosen, feature_set, config, learner, Cs, cv, log)
        ranker = _fit(chosen, feature_set, rms, config, learner, Cs, cv, selection)
        coef, scale = ranker.coef_, ranker.scale_
        keep = np.ones(len(names), dtype=bool)
        kept_library = None
        bandwidths: tuple[float, ...] = ()
        if uses_templates:
            start = 27 if feature_set == "both" else 0
            per_scale = []
            for c in library.counts:
                nz = np.flatnonzero(coef[start:start + c] != 0)
                per_scale.append(nz)
                keep[start:start + c] = coef[start:start + c] != 0
                start += c
            kept_library = library.subset(tuple(per_scale))
            bandwidths = _bandwidths(rms, config)
        info = {"lambda": ranker.lambda_, "C": ranker.C_, "cv_error": ranker.cv_error_,
                "path": [vars(p) for p in ranker.path_], "n_demonstrations": len(chosen),
                "library_counts": list(library.counts) if library is not None else [0, 0, 0],
                "kept_counts": list(kept_library.counts) if kept_library is not None else [0, 0, 0],
                "bandwidth_rms_m": list(rms) if rms is not None else None,
                "bandwidth_search": search, "n_nonzero": int(np.count_nonzero(coef))}
        kept_names = tuple(n for n, k in zip(names, keep) if k)
        if kept_library is not None:  # the kept templates are renumbered within their library
            n_terrain = 27 if feature_set == "both" else 0
            kept_names = (kept_names[:n_terrain] + kept_library.names()
                          + kept_names[n_terrain + sum(kept_library.counts):])
        functions[group] = RankingFunction(kept_names, coef[keep], scale[keep], kept_library,
                                           bandwidths, info)
        log(f"  lambda {ranker.lambda_:.4g}, cv error {ranker.cv_error_:.4f}, "
            f"{info['n_nonzero']} non-zero weights, templates kept {info['kept_counts']}")
    return FootholdModel(feature_set, learner, functions, config, robot,
                         map_resolution=max(resolutions),
                         info={"n_demonstrations": len(demos), "seed": seed,
                               "library_size": library_size,
                               "training_candidates": training_candidates,
                               "selection": selection,
                               "seconds": time.perf_counter() - started})
