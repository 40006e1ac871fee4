"""How often people agree with the synthetic expert, and with each other (paper §II-B).

The teaching page stores who chose what; these pure functions say how far
to trust it. On a step, the expert's verdict is the one its corrections
give (:func:`footfall.expert.corrections.inspect_run`): "fine" when the
robot's choice falls short of its best by at most the margin, otherwise its
best candidate. A person agrees with the expert when both say "fine", or
both name a foothold within :data:`SAME_FOOTHOLD` of each other. Two people
agree on a step both labelled by the same rule.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable

import numpy as np

from footfall.data.label import Label

SAME_FOOTHOLD = 0.01  # [m] two footholds this close (horizontally) are the same choice


def expert_verdicts(best: np.ndarray, shortfall: np.ndarray, margin: float
                    ) -> np.ndarray:
    """Per step, the expert's label as a candidate index, or -1 for "fine" (the robot's
    shortfall [value units] at most ``margin``, or not defined)."""
    best = np.asarray(best, dtype=np.int64)
    shortfall = np.asarray(shortfall, dtype=np.float64)
    return np.where(np.nan_to_num(shortfall, nan=0.0) > margin, best, -1)


def same_choice(a: Label | int, b: Label | int, candidates: np.ndarray) -> bool:
    """Whether two verdicts on one step agree: both "fine", or footholds (indices into the step's
    ``candidates`` (n, 3) [m]) within :data:`SAME_FOOTHOLD`. An int is a verdict as
    :func:`expert_verdicts` gives it (-1: fine)."""
    ia, ib = (_index(v) for v in (a, b))
    if ia < 0 or ib < 0:
        return ia == ib
    d = np.asarray(candidates, dtype=np.float64)[[ia, ib], :2]
    return bool(np.hypot(*(d[0] - d[1])) <= SAME_FOOTHOLD)


def _index(verdict: Label | int) -> int:
    if isinstance(verdict, Label):
        return -1 if verdict.verdict == "fine" else verdict.chosen
    return int(verdict)


def agreement(labels: Iterable[Label], expert: Callable[[int, int], int | None],
              candidates: Callable[[int, int], np.ndarray]) -> dict:
    """Agreement figures of stored labels.

    Parameters
    ----------
    labels : iterable of Label
        The current labels (one per labeler and step).
    expert : callable (run id, k) -> int or None
        The expert's verdict on a step (:func:`expert_verdicts`; None: not judged).
    candidates : callable (run id, k) -> array (n, 3) [m]
        The step's candidate set F.

    Returns
    -------
    dict
        ``with_expert``: per labeler ``{"steps", "agree", "share", "exact"}`` (steps judged,
        steps agreeing, their share, and the share naming the expert's very candidate or
        "fine" alike); ``between``: per pair ``"a | b"`` the same over steps both labelled.
    """
    by_step: dict[tuple[int, int], dict[str, Label]] = {}
    for label in labels:
        by_step.setdefault((label.run_id, label.k), {})[label.labeler] = label
    with_expert: dict[str, list[int]] = {}
    between: dict[str, list[int]] = {}
    for (run, k), given in sorted(by_step.items()):
        f = candidates(run, k)
        verdict = expert(run, k)
        for name, label in given.items():
            if verdict is not None:
                tally = with_expert.setdefault(name, [0, 0, 0])
                tally[0] += 1
                tally[1] += same_choice(label, verdict, f)
                tally[2] += _index(label) == verdict
        for (a, la), (b, lb) in itertools.combinations(sorted(given.items()), 2):
            tally = between.setdefault(f"{a} | {b}", [0, 0, 0])
            tally[0] += 1
            tally[1] += same_choice(la, lb, f)
            tally[2] += _index(la) == _index(lb)
    return {"with_expert": {n: _shares(t) for n, t in sorted(with_expert.items())},
            "between": {n: _shares(t) for n, t in sorted(between.items())},
            "same_foothold_m": SAME_FOOTHOLD}


def _shares(tally: list[int]) -> dict:
    steps, agree, exact = tally
    return {"steps": steps, "agree": agree, "share": agree / steps if steps else None,
            "exact": exact / steps if steps else None}


def agreement_lines(figures: dict) -> list[str]:
    """:func:`agreement`'s figures as lines of text (``footfall demos info``)."""
    def share(t: dict) -> str:
        return "-" if t["share"] is None else f"{100 * t['share']:.0f} %"
    lines = [f"  {name} agrees with the synthetic expert on {t['agree']} of {t['steps']} steps "
             f"({share(t)})" for name, t in figures["with_expert"].items()]
    lines += [f"  {pair} agree on {t['agree']} of {t['steps']} steps ({share(t)})"
              for pair, t in figures["between"].items()]
    return lines
