"""How often people agree with the synthetic expert, and with each other (paper §II-B).

The teaching page stores who chose what; these pure functions say how far
to trust it. On a step, the expert's verdict is the one its corrections
give (:func:`footfall.expert.corrections.inspect_run`): "fine" when the
robot's choice falls short of its best by at most the margin, otherwise its
best candidate. A person agrees with the expert when both say "fine", or
both name a foothold within :data:`SAME_FOOTHOLD` of each other. Two people
agree on a step both labelled by the same rule.

People's "never here" marks are compared the same way: a person's mark agrees with the
synthetic expert when the expert also refuses that candidate (its value more than
:data:`footfall.expert.protocol.REFUSED_SHORTFALL` below its best in the step's F:
:func:`footfall.expert.protocol.teacher_verdict`), and with another person when they marked the
same candidate, or one within :data:`SAME_FOOTHOLD` of it.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable

import numpy as np

from footfall.data.label import Label, Mark

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


def marks_agreement(marks: Iterable[Mark], refusals: Callable[[int, int], np.ndarray | None],
                    candidates: Callable[[int, int], np.ndarray]) -> dict:
    """Agreement figures of stored "never here" marks.

    Parameters
    ----------
    marks : iterable of Mark
        The stored marks (one per labeler and candidate of a step).
    refusals : callable (run id, k) -> array (n,) of bool, or None
        The candidates of the step's F the expert refuses (None: the step is not judged).
    candidates : callable (run id, k) -> array (n, 3) [m]
        The step's candidate set F.

    Returns
    -------
    dict
        ``with_expert``: per labeler ``{"steps", "marks", "refused", "share"}`` (steps with
        their marks that the expert judged, their marks there, how many of those the expert
        also refuses, and that share); ``between``: per pair ``"a | b"`` ``{"steps", "marks",
        "shared", "share"}`` over the steps both marked: the marks either gave there, how
        many of them the other also marked (the same candidate or one within
        :data:`SAME_FOOTHOLD`), and that share.
    """
    by_step: dict[tuple[int, int], dict[str, list[int]]] = {}
    for mark in marks:
        by_step.setdefault((mark.run_id, mark.k), {}).setdefault(mark.labeler, []).append(
            mark.candidate)
    with_expert: dict[str, list[int]] = {}
    between: dict[str, list[int]] = {}
    for (run, k), given in sorted(by_step.items()):
        refused = refusals(run, k)
        if refused is not None:
            for name, marked in given.items():
                tally = with_expert.setdefault(name, [0, 0, 0])
                tally[0] += 1
                tally[1] += len(marked)
                tally[2] += int(np.asarray(refused, dtype=bool)[marked].sum())
        if len(given) < 2:
            continue
        xy = np.asarray(candidates(run, k), dtype=np.float64)[:, :2]
        for (a, ma), (b, mb) in itertools.combinations(sorted(given.items()), 2):
            tally = between.setdefault(f"{a} | {b}", [0, 0, 0])
            tally[0] += 1
            tally[1] += len(ma) + len(mb)
            tally[2] += _also_marked(xy, ma, mb) + _also_marked(xy, mb, ma)
    return {"with_expert": {n: _mark_shares(t, "refused") for n, t in sorted(with_expert.items())},
            "between": {n: _mark_shares(t, "shared") for n, t in sorted(between.items())},
            "same_foothold_m": SAME_FOOTHOLD}


def _also_marked(xy: np.ndarray, mine: list[int], theirs: list[int]) -> int:
    """How many of the candidates ``mine`` lie within :data:`SAME_FOOTHOLD` (horizontally, of
    the candidates' x, y ``xy`` (n, 2) [m]) of one of ``theirs``."""
    d = np.hypot(*(xy[mine][:, None, :] - xy[theirs][None, :, :]).transpose(2, 0, 1))
    return int((d.min(axis=1) <= SAME_FOOTHOLD).sum())


def _mark_shares(tally: list[int], agreeing: str) -> dict:
    steps, marks, agree = tally
    return {"steps": steps, "marks": marks, agreeing: agree,
            "share": agree / marks if marks else None}


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
    marks = figures.get("marks") or {"with_expert": {}, "between": {}}
    lines += [f"  {name}'s 'never here' marks: the synthetic expert also refuses {t['refused']} "
              f"of {t['marks']} ({share(t)})" for name, t in marks["with_expert"].items()]
    lines += [f"  {pair} mark the same candidates: {t['shared']} of {t['marks']} marks on "
              f"{t['steps']} steps ({share(t)})" for pair, t in marks["between"].items()]
    return lines
