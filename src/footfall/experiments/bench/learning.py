"""Benchmark of learning at the paper's scale: the L1 path against scikit-learn's own.

``bench_learning``: one ranking function learned from 100 of the synthetic
expert's demonstrations on a ~1000-template library, footfall's L1 path with
grouped cross-validation against ``LogisticRegressionCV`` on the same pairs,
folds and regularisation values; seconds and peak memory of each.
"""

from __future__ import annotations

import time
import tracemalloc
import warnings
from typing import Callable, TypeVar

import numpy as np
from sklearn.exceptions import ConvergenceWarning
from sklearn.linear_model import LogisticRegressionCV

from footfall.expert.collect import collect_demonstrations
from footfall.expert.synthetic import SyntheticExpert
from footfall.features.config import FeatureConfig
from footfall.features.template_library import TemplateLibrary
from footfall.learning.dataset import create_families, make_example, stack, training_rows
from footfall.learning.ranker import FootholdRanker, grouped_folds, pairwise_transform
from footfall.learning.screening import l1_objective
from footfall.terrain import make_board

_Result = TypeVar("_Result")  # what a timed piece of work returns


def bench_learning(n_demos: int = 100, library_size: int = 1000, seed: int = 0) -> dict:
    """Paper-scale learning: the L1 path with 5-fold grouped CV, against LogisticRegressionCV.

    Demonstrations come from the synthetic expert on rocky, steps, barrier
    and slope boards (not timed); the timed part is the learning of one
    ranking function (front and hind legs together, as one problem) on the
    templates + features set with a ~1000-template library.
    """
    n, library, (X, y, groups), collect, features = _learning_problem(n_demos, library_size, seed)
    ours, ours_s, ours_peak = _timed(
        lambda: FootholdRanker(learner="l1", Cs=10, cv=5).fit(X, y, groups))
    every, every_s, _ = _timed(  # the same path, every fit given all columns
        lambda: FootholdRanker(learner="l1", Cs=10, cv=5, screening=False).fit(X, y, groups))
    ref, ref_s, ref_peak, n_pairs = _sklearn_baseline(X, y, groups, ours)
    return {
        "demonstrations": n, "library": list(library.counts),
        "features": int(X.shape[1]), "candidate_rows": int(X.shape[0]),
        "pairs_mirrored": n_pairs,
        "collect_seconds_untimed_part": collect, "feature_seconds": features,
        "learn_seconds": ours_s, "target_seconds": 8.0,
        "unscreened_seconds": every_s, "screening_speedup": every_s / ours_s,
        "same_lambda_unscreened": bool(every.C_ == ours.C_),
        "objective": _objective(ours, X, y, groups),
        "objective_unscreened": _objective(every, X, y, groups, ours.C_),
        "non_zero_unscreened": int(np.count_nonzero(every.coef_)),
        "path_points_evaluated": len(ours.path_), "lambda": ours.lambda_,
        "cv_error": ours.cv_error_, "non_zero": int(np.count_nonzero(ours.coef_)),
        "learn_peak_memory_mib": ours_peak / 2 ** 20,
        "baseline": "sklearn LogisticRegressionCV(l1, liblinear) on the same mirrored pairs, "
                    "folds and C values",
        "baseline_seconds": ref_s, "baseline_peak_memory_mib": ref_peak / 2 ** 20,
        "baseline_non_zero": int(np.count_nonzero(ref.coef_)),
        "speedup_vs_baseline": ref_s / ours_s,
    }


def _learning_problem(n_demos: int, library_size: int, seed: int
                      ) -> tuple[int, TemplateLibrary, tuple[np.ndarray, ...], float, float]:
    """The benchmark's learning problem: demonstrations on five boards, the templates + features
    families fitted to them and their candidate rows.

    Returns the number of demonstrations, the template library, the stacked (X, y, groups), and
    the seconds spent collecting and computing the features.
    """
    rng = np.random.default_rng(seed)
    config = FeatureConfig()
    boards = [make_board([(k, d)], seed + i) for i, (k, d) in
              enumerate([("rocky", 0.5), ("rocky", 0.8), ("steps", 0.6), ("barrier", 0.6),
                          ("slope", 0.6)])]
    maps = {b.content_hash(): b for b in boards}
    t0 = time.perf_counter()
    demos = collect_demonstrations(boards, SyntheticExpert(), n_demos, seed)
    collect = time.perf_counter() - t0
    hmaps = [maps[d.terrain_hash] for d in demos]
    t0 = time.perf_counter()
    families = tuple(f.fit(hmaps, [d.state for d in demos], [d.candidates for d in demos],
                           [d.chosen for d in demos], rng, library_size=library_size,
                           bandwidth_rms=(0.004,) * len(config.scales))
                     for f in create_families("both", config))
    examples = [make_example(h, d.state, d.candidates, d.chosen, families, config,
                             training_rows(d.candidates.shape[0], d.chosen, 100, rng))
                for h, d in zip(hmaps, demos)]
    rows = stack(examples, families)
    return len(demos), families[1].library, rows, collect, time.perf_counter() - t0


def _sklearn_baseline(X: np.ndarray, y: np.ndarray, groups: np.ndarray, ours
                      ) -> tuple[object, float, int, int]:
    """scikit-learn's own cross-validated L1 logistic regression on the same standardised
    mirrored pairs, folds and C values as the fitted ranker ``ours``, without early stop.

    Returns the fitted estimator, its seconds and peak memory [bytes], and the number of pairs.
    """
    pairs, labels, pair_groups = pairwise_transform(X, y, groups)
    scale = pairs.std(axis=0)
    scale[scale < 1e-12] = 1.0
    Cs = np.array([p.C for p in ours.path_])
    Cs = np.concatenate([Cs, Cs[-1] * np.logspace(0.41, 0.41 * (10 - Cs.size), 10 - Cs.size)]) \
        if Cs.size < 10 else Cs

    def fit():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            warnings.simplefilter("ignore", FutureWarning)
            return LogisticRegressionCV(Cs=Cs, cv=grouped_folds(pair_groups, 5), l1_ratios=(1.0,),
                                        solver="liblinear", fit_intercept=False, tol=1e-4,
                                        max_iter=2000, random_state=0).fit(pairs / scale, labels)

    ref, seconds, peak = _timed(fit)
    return ref, seconds, peak, int(pairs.shape[0])


def _objective(fitted: FootholdRanker, X: np.ndarray, y: np.ndarray, groups: np.ndarray,
               C: float | None = None) -> float:
    """The L1 objective of the ranker's final fit at ``C`` (default its own C): ||w||_1 on the
    standardised pairs plus 2 C times their logistic loss (the mirrored problem's C)."""
    pairs, _, _ = pairwise_transform(X, y, groups, mirrored=False)
    w = fitted.coef_ * fitted.scale_
    return l1_objective(pairs / fitted.scale_, np.ones(pairs.shape[0]), w,
                        2.0 * (fitted.C_ if C is None else C))


def _timed(work: Callable[[], _Result]) -> tuple[_Result, float, int]:
    """Run ``work``: its result, its wall-clock time [s] and its peak traced memory [bytes]."""
    tracemalloc.start()
    t0 = time.perf_counter()
    out = work()
    seconds = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return out, seconds, peak


def format_learning(r: dict) -> str:
    """Human-readable summary of :func:`bench_learning`."""
    return "\n".join([
        f"learning: {r['demonstrations']} demonstrations, library {sum(r['library'])} "
        f"{tuple(r['library'])}, {r['features']} features, {r['pairs_mirrored']} mirrored pairs",
        f"  features: {r['feature_seconds']:7.1f} s (patches, template distances, pose)",
        f"  footfall: {r['learn_seconds']:7.1f} s for the L1 path ({r['path_points_evaluated']} "
        f"values x 5 grouped folds; target {r['target_seconds']:.0f} s), lambda "
        f"{r['lambda']:.3g}, {r['non_zero']} non-zero, peak {r['learn_peak_memory_mib']:.0f} MiB",
        f"  unscreened: {r['unscreened_seconds']:5.1f} s for the same path, every fit on all "
        f"columns -> screening x{r['screening_speedup']:.2f}; same lambda: "
        f"{'yes' if r['same_lambda_unscreened'] else 'NO'}; objective at that lambda "
        f"{r['objective']:.4f} screened, {r['objective_unscreened']:.4f} all columns "
        f"({r['non_zero']} / {r['non_zero_unscreened']} non-zero)",
        f"  sklearn:  {r['baseline_seconds']:7.1f} s LogisticRegressionCV, "
        f"peak {r['baseline_peak_memory_mib']:.0f} MiB -> speed-up {r['speedup_vs_baseline']:.1f} x",
    ])
