"""Relevance levels of stacked demonstrations: what they assert, and how a scorer is measured.

Every learner reads a demonstration as relevance levels of its candidates, one whole number
each, the chosen candidate alone at the top (a choice: 1 for it, 0 else; graded supervision:
more levels, :mod:`footfall.learning.supervision`). The pairs those levels assert are what the
linear and kernel learners are fitted on (:func:`footfall.learning.ranker.pairwise_transform`)
and what every learner's held-out error counts (:func:`pairwise_error`).
"""

from __future__ import annotations

import numpy as np

from footfall.core.errors import FootfallError

MAX_LEVEL = 30  # the highest relevance level a candidate may have (LightGBM's label gains)


def level_pairs(y: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (better, worse) row pairs (m,), (m,) that relevance levels ``y`` (n,) assert.

    Every candidate below its demonstration's top is paired with one candidate of each higher
    level of its demonstration: the chosen candidate for the top level, the first row of the
    level for any other. A candidate k levels down is thus below k others, so a larger gap in
    the teacher's preference weighs more, and a demonstration of n candidates gives at most
    n x (levels - 1) pairs instead of the n^2 of all ordered pairs. For a choice (levels 0 and
    1) these are exactly (chosen, other) for every other candidate. Pairs are ordered by
    demonstration (its ``groups`` value, ascending), then by the worse row, then from the
    highest partner level down.
    """
    y = np.asarray(y).astype(np.intp)
    uniq, inverse = np.unique(np.asarray(groups), return_inverse=True)
    n_levels = int(y.max(initial=0)) + 1
    key = inverse * n_levels + y
    first = np.full(uniq.size * n_levels, -1, dtype=np.intp)
    rows = np.arange(y.size, dtype=np.intp)
    first[key[::-1]] = rows[::-1]  # the last write wins: each (demonstration, level)'s first row
    levels = np.arange(n_levels)
    partner = first[inverse[:, None] * n_levels + levels[None, :]]  # (n, levels)
    worse, level = np.nonzero((levels[None, :] > y[:, None]) & (partner >= 0))
    order = np.lexsort((-level, worse, inverse[worse]))
    return partner[worse[order], level[order]], worse[order]


def _check_demonstrations(X: np.ndarray, y: np.ndarray, groups: np.ndarray) -> None:
    if X.ndim != 2 or y.shape != (X.shape[0],) or groups.shape != (X.shape[0],):
        raise FootfallError("need X (n, d), y (n,) and groups (n,) of the same length")
    if not np.isfinite(X).all():
        raise FootfallError("features contain NaN or infinite values")
    if not (np.issubdtype(y.dtype, np.number) and not np.issubdtype(y.dtype, np.complexfloating)
            and np.all((y >= 0) & (y <= MAX_LEVEL) & (y == np.round(y)))):
        raise FootfallError(f"y must be whole relevance levels in [0, {MAX_LEVEL}]: 1 for the "
                            f"chosen candidate and 0 for the others, or graded")
    uniq, inverse = np.unique(groups, return_inverse=True)
    top = np.zeros(uniq.size)
    np.maximum.at(top, inverse, y)
    n_chosen = np.bincount(inverse, weights=(y == top[inverse]), minlength=uniq.size)
    n_all = np.bincount(inverse, minlength=uniq.size)
    if np.any((n_chosen != 1) | (top < 1)):
        bad = uniq[np.flatnonzero((n_chosen != 1) | (top < 1))[0]]
        raise FootfallError(f"demonstration {bad} must have exactly one chosen candidate (alone "
                            f"at its highest level, at least 1)")
    if np.any(n_all < 2):
        raise FootfallError("every demonstration needs at least two candidates")


def chosen_rows(y: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """(n,) bool: each demonstration's chosen candidate, the one at its highest level."""
    y = np.asarray(y)
    uniq, inverse = np.unique(np.asarray(groups), return_inverse=True)
    top = np.full(uniq.size, -np.inf)
    np.maximum.at(top, inverse, y)
    return y == top[inverse]


def pairwise_error(scores: np.ndarray, y: np.ndarray, groups: np.ndarray) -> float:
    """The share of the pairs the levels ``y`` assert (:func:`level_pairs`; for a choice, the
    (chosen, other) pairs of every demonstration) that ``scores`` does not order strictly right
    (a tie is an error): the linear learners' held-out error, for any scorer."""
    better, worse = level_pairs(y, groups)
    scores = np.asarray(scores)
    return float(np.mean(scores[worse] >= scores[better]))
