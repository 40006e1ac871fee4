"""Kinds of supervision: what a teacher's verdict on one decision tells a learner.

A demonstration names the foothold the teacher chose among the candidates F (paper §II-B). A
teacher may say more: which candidates it refuses outright ("never here": the synthetic
expert's veto, a person's mark on the teaching page) and how much it values every candidate
(a synthetic teacher's own values). A supervision kind turns what a demonstration carries into
relevance levels of its candidates, one whole number each, the chosen foothold alone at the
top; every learner reads levels (:mod:`footfall.learning.ranker`: pairs between levels; the
boosted ranker: LightGBM's relevance labels). Where a demonstration carries less than a kind
reads, the kind uses what it has: a choice alone gives 1 for the chosen candidate, 0 else.

==========  =============================================================================
kind        levels
==========  =============================================================================
choice      the chosen 1, every other 0 (the paper's Eq. 2)
refusals    the chosen 2, an acceptable candidate 1, a refused one 0
graded      the chosen 3; within ``margin`` of the teacher's best value 2; within ``severe``
            of it 1; further below, or refused, 0
==========  =============================================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.registry import Registry

GRADED_MARGIN = 2.0  # [teacher's value units] a candidate this close to the teacher's best is
# as good as its choice: the reproduction's correction margin (expert.corrections), 2 cm of
# the synthetic expert's path preference
GRADED_SEVERE = 10.0  # [teacher's value units] a candidate this far below the teacher's best is
# as bad as a refused one: the severe shortfall of expert.corrections (a slanted face, an edge)


@dataclass(frozen=True)
class Supervision:
    """A kind of supervision: ``levels(n, chosen, values, refused)`` -> (n,) int relevance."""

    name: str  # registry key (``footfall learn --supervision``)
    description: str  # one line for --help and reports
    levels: Callable[[int, int, np.ndarray | None, np.ndarray | None], np.ndarray]
    reads: str  # what it reads beyond the choice: "", "refusals" or "values and refusals"


SUPERVISIONS: Registry[Supervision] = Registry("supervision")


def choice_levels(n: int, chosen: int, values: np.ndarray | None = None,
                  refused: np.ndarray | None = None) -> np.ndarray:
    """(n,) int: 1 for the chosen candidate, 0 for every other."""
    return np.eye(1, n, chosen, dtype=int)[0]


def refusal_levels(n: int, chosen: int, values: np.ndarray | None = None,
                   refused: np.ndarray | None = None) -> np.ndarray:
    """(n,) int: the chosen 2, a refused candidate 0, any other 1 (a choice without refusals:
    :func:`choice_levels`)."""
    if refused is None:
        return choice_levels(n, chosen)
    out = np.where(np.asarray(refused, dtype=bool), 0, 1)
    out[chosen] = 2
    return out


def graded_levels(n: int, chosen: int, values: np.ndarray | None = None,
                  refused: np.ndarray | None = None, margin: float = GRADED_MARGIN,
                  severe: float = GRADED_SEVERE) -> np.ndarray:
    """(n,) int from the teacher's ``values`` (n,) [its value units] and ``refused`` (n,): the
    chosen 3; a candidate within ``margin`` of the best value 2, within ``severe`` 1, else 0;
    a refused one 0 (no values: :func:`refusal_levels`)."""
    if values is None:
        return refusal_levels(n, chosen, None, refused)
    v = np.asarray(values, dtype=np.float64)
    short = v.max() - v
    out = np.where(short <= margin, 2, np.where(short <= severe, 1, 0))
    if refused is not None:
        out[np.asarray(refused, dtype=bool)] = 0
    out[chosen] = 3
    return out


SUPERVISIONS.register("choice", Supervision(
    "choice", "the chosen foothold above every other candidate (the paper's)", choice_levels, ""))
SUPERVISIONS.register("refusals", Supervision(
    "refusals", "the chosen foothold above the acceptable ones, those above the refused ones",
    refusal_levels, "refusals"))
SUPERVISIONS.register("graded", Supervision(
    "graded", f"levels by the teacher's values: the chosen, within {GRADED_MARGIN:g} of its "
              f"best, within {GRADED_SEVERE:g}, the rest and the refused",
    graded_levels, "values and refusals"))


def get_supervision(name: str) -> Supervision:
    """The registered kind called ``name``, or a clear error."""
    if not isinstance(name, str):
        raise FootfallError(f"a supervision kind is named by a string, got {name!r}")
    return SUPERVISIONS.get(name)
