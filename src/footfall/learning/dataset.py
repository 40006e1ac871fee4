"""Demonstrations as learning data: the feature families' columns of each candidate set.

Turns demonstrations (a terrain, a state, the candidate set F, the chosen
index) into the design matrices a ranking function is learned on, for a
feature set -- the paper's terrain features, templates, or both, each with
the pose features (§V), or any combination of registered families
(:mod:`footfall.features.family`). Each family keeps what does not depend on
its tunable parameters (templates: squared patch distances, free of the RBF
bandwidth), so that those parameters can be chosen by cross-validation
without recomputing patches.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.data.demonstration import decision_hash
from footfall.features.config import FeatureConfig
from footfall.features.family import (
    FEATURE_SETS,
    Candidates,
    FeatureFamily,
    family_class,
    feature_set_families,
)

DEFAULT_TRAINING_CANDIDATES = 100  # other candidates per demonstration used for training pairs

__all__ = ["FEATURE_SETS", "Example", "check_feature_set", "column_names", "create_families",
           "design_matrix", "distinct_examples", "make_example", "pair_example", "stack", "stack_units",
           "training_rows"]


def check_feature_set(feature_set: str) -> str:
    """Validate a feature-set name (registered, or family names joined by ``+``)."""
    feature_set_families(feature_set)
    return feature_set


def create_families(feature_set: str, config: FeatureConfig,
                    robot: RobotDescription = LITTLEDOG) -> tuple[FeatureFamily, ...]:
    """The families of a feature set before learning, in column order."""
    return tuple(family_class(name).create(config, robot)
                 for name in feature_set_families(feature_set))


@dataclass(frozen=True)
class Example:
    """One demonstration's candidates with what each family keeps of them."""

    prepared: tuple[Any, ...]  # per family: FeatureFamily.prepare of the candidates
    n: int  # candidates (rows)
    chosen: int  # index of the demonstrated foothold among the n rows
    front: bool  # a front-leg demonstration
    rows: np.ndarray  # (n,) indices of these rows in the demonstration's full candidate set
    key: str = ""  # the demonstration's decision_hash (state, all candidates, choice): examples
    # with the same key are the same demonstration, stacked once; "" = unique
    unit: str = ""  # its fold unit (a run, a board): folds never split one; "" = its own
    parts: tuple[Example, ...] = ()  # a comparison across decisions: its rows are these
    # examples' rows in order (each prepared in its own state); ``prepared`` is then empty
    levels: np.ndarray | None = None  # (n,) relevance level of each row (the chosen one alone
    # at the top: footfall.learning.supervision); None: a choice, 1 for the chosen row, 0 else
    refused: np.ndarray | None = None  # (n,) bool: rows the teacher refused outright (None:
    # it said nothing of them)
    judged: np.ndarray | None = None  # (n,) [value units] what the refusals are relative to
    judged_best: float = float("nan")  # [value units] the best judged value of the whole F

    def relevance(self) -> np.ndarray:
        """(n,) int: each row's relevance level (a choice: 1 for the chosen row, 0 else)."""
        if self.levels is None:
            return np.eye(1, self.n, self.chosen, dtype=int)[0]
        return np.asarray(self.levels, dtype=int)


def stack_units(examples: Sequence[Example]) -> np.ndarray | None:
    """The fold unit (N,) of every row :func:`stack` gives, or None when every example is its
    own unit (folds grouped by demonstration)."""
    examples = distinct_examples(examples)
    if not any(e.unit for e in examples):
        return None
    return np.concatenate([np.full(e.n, e.unit or f"demonstration {k}", dtype=object)
                           for k, e in enumerate(examples)]).astype(str)


def make_example(hmap: HeightMap, state: RobotState, candidates: np.ndarray, chosen: int,
                 families: Sequence[FeatureFamily], config: FeatureConfig,
                 rows: np.ndarray | None = None, robot: RobotDescription = LITTLEDOG,
                 levels: np.ndarray | None = None, refused: np.ndarray | None = None,
                 judged: np.ndarray | None = None) -> Example:
    """What every family keeps of (a subset ``rows`` of) a demonstration's candidates, with the
    relevance ``levels`` (n_all,) of all its candidates if graded (None: a choice), the
    teacher's refusals (n_all,) bool and the values they are relative to (n_all,) [value
    units], if it gave them."""
    rows = np.arange(candidates.shape[0]) if rows is None else np.asarray(rows)
    if not 0 <= chosen < candidates.shape[0] or chosen not in rows:
        raise FootfallError("the chosen candidate must be among the rows")
    c = Candidates.of_state(hmap, state, candidates[rows], config, robot)
    if not c.patches.valid.all():
        raise FootfallError("a candidate has too little terrain data for its features")
    return Example(tuple(f.prepare(c) for f in families), int(rows.size),
                   int(np.flatnonzero(rows == chosen)[0]), robot.leg(state.swing_leg).front, rows,
                   decision_hash(state, candidates, chosen),
                   levels=None if levels is None else np.asarray(levels, dtype=int)[rows],
                   refused=None if refused is None else np.asarray(refused, dtype=bool)[rows],
                   judged=None if judged is None else np.asarray(judged, dtype=float)[rows],
                   judged_best=float("nan") if judged is None else float(np.max(judged)))


def training_rows(n: int, chosen: int, k: int, rng: np.random.Generator) -> np.ndarray:
    """The chosen row and up to ``k`` other rows drawn at random, sorted."""
    others = np.delete(np.arange(n), chosen)
    if others.size > k:
        others = rng.choice(others, size=k, replace=False)
    return np.sort(np.append(others, chosen))


def pair_example(better: Example, worse: Example, unit: str = "") -> Example:
    """A comparison of two footholds from different decisions -- e.g. a trial's foothold that
    went well and one that went wrong (:mod:`footfall.learning.trials`) --, the first
    preferred: a two-row example whose rows are the one-row examples ``better`` and ``worse``."""
    if better.n != 1 or worse.n != 1:
        raise FootfallError("a comparison is of two one-foothold examples")
    return Example((), 2, 0, better.front, np.arange(2), unit=unit, parts=(better, worse))


def design_matrix(example: Example, families: Sequence[FeatureFamily]) -> np.ndarray:
    """The feature matrix (n, d) of an example, the families' columns side by side."""
    if example.parts:
        return np.concatenate([design_matrix(p, families) for p in example.parts])
    return np.concatenate([f.from_prepared(p) for f, p in zip(families, example.prepared)],
                          axis=1)


def column_names(families: Sequence[FeatureFamily]) -> tuple[str, ...]:
    """Full names (``family.column``) of the design matrix's columns."""
    return tuple(f"{f.name}.{c}" for f in families for c in f.columns())


def stack(examples: Sequence[Example], families: Sequence[FeatureFamily]
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stacked X (N, d), y (N,) (relevance levels: 1 = chosen, 0 = other for a choice) and
    groups (N,) of distinct examples.

    The groups number the demonstrations: the units of the pairwise
    transform (one chosen row each) and of the cross-validation folds. A
    store may hold one demonstration twice (collected twice, or copied by
    hand): its copies are stacked once (:func:`distinct_examples`), so that no
    fold tests on a demonstration it also trained on.
    """
    examples = distinct_examples(examples)
    if not examples:
        raise FootfallError("no demonstrations to learn from")
    # filled in place, one example at a time: at 1 600 demonstrations of 4 800 columns the
    # matrix is 6 GB, and a list of the examples' matrices joined afterwards would be another
    first = design_matrix(examples[0], families)
    X = np.empty((sum(e.n for e in examples), first.shape[1]), dtype=first.dtype)
    start = 0
    for k, e in enumerate(examples):
        block = first if k == 0 else design_matrix(e, families)
        X[start:start + e.n] = block
        start += e.n
    del first
    y = np.concatenate([e.relevance() for e in examples])
    groups = np.concatenate([np.full(e.n, k) for k, e in enumerate(examples)])
    return X, y, groups


def distinct_examples(examples: Sequence[Example]) -> list[Example]:
    """The examples without repeats: the first of those with the same ``key`` (one
    demonstration's copies; an example without a key is always kept)."""
    seen: set[str] = set()
    out = []
    for e in examples:
        if not e.key or e.key not in seen:
            seen.add(e.key)
            out.append(e)
    return out



def check_informative(candidates: Sequence[np.ndarray], went_wrong: Sequence[bool]) -> None:
    """Refuse what says nothing to learn from: demonstrations alone whose candidate sets (each
    (n, 3) [m]) are every one a single foothold (there was nothing to choose), or trial
    footholds (``went_wrong``: each one's outcome) of which none went wrong (nothing to rank
    below the others).

    Raises
    ------
    FootfallError
        Saying which, in the words of the input.
    """
    if went_wrong and not any(went_wrong):
        raise FootfallError(f"none of the {len(went_wrong)} footholds of the trial runs went "
                            f"wrong (slid, missed or fell): nothing to rank below the others")
    if candidates and not went_wrong and all(np.ptp(c, axis=0).max() == 0 for c in candidates):
        raise FootfallError(f"each of the {len(candidates)} demonstrations' candidates are one "
                            f"foothold: a choice among them says nothing to learn from")
