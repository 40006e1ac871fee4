"""The imitation gap: where a student that failed left the teacher that crossed, run by run.

For every pair of runs on the same board with the same seed -- one walked by a learned
function (the student), one by its teacher choosing every foothold -- in which the student
failed and the teacher crossed, the teacher judges every step of the student's run: its
values of the step's candidates, those it refuses outright, and its own choice
(:func:`~footfall.expert.protocol.teacher_verdict`). A foothold is *unacceptable* where the
teacher refuses it or values it short of its best by more than the margin. The run is an
**imitation error at the end** when the student stood on an unacceptable foothold in the
last gait cycle before it failed (its last :data:`END_STEPS` steps: each foot once), an
**imitation error earlier** when its unacceptable footholds all lie before that, and
**accepted throughout** when the teacher accepted every foothold it chose: a failure the
teacher's own choices could have met on the student's way. The first step where the
student's foothold is not the teacher's choice is reported too: where the two runs parted.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.data.runlog import RunRecord
from footfall.expert.protocol import Expert, teacher_verdict

CAUSES = ("imitation error at the end", "imitation error earlier", "accepted throughout")
END_STEPS = 4  # [steps] the last gait cycle before a failure: each foot of the crawl once


@dataclass(frozen=True)
class GapRun:
    """One run the student failed and its teacher crossed (same board, same seed)."""

    key: str  # the student's run
    reason: str  # why the student's run failed
    steps: int  # the student's steps
    parted: int | None  # the first step whose foothold is not the teacher's choice (None: none)
    parted_shortfall: float | None  # [value units] the teacher's best less its value of that
    # foothold (None: never parted)
    unacceptable: int | None  # the first step whose foothold the teacher refuses or values
    # short of its best by more than the margin (None: none)
    unacceptable_shortfall: float | None  # [value units] at that step (None: none)
    refused: bool  # the teacher refuses that foothold outright
    last_unacceptable: int | None  # the last such step (None: none)
    unacceptable_steps: int  # how many of the run's steps stood on such a foothold
    cause: str  # one of CAUSES

    def as_dict(self) -> dict:
        """Plain data for JSON."""
        return dict(vars(self))


def judge_gap_run(student: RunRecord, hmap: HeightMap, teacher: Expert, margin: float
                  ) -> GapRun:
    """The teacher's verdict on every step of a failed ``student`` run on ``hmap``."""
    parted = unacceptable = last = None
    parted_short: float | None = None
    unacceptable_short: float | None = None
    refused_there = False
    count = 0
    rng = np.random.default_rng(0)  # a noiseless teacher draws nothing
    for step in student.steps:  # one run's steps (dozens), each vectorised over F
        values, refused, _ = teacher_verdict(teacher, hmap, step.state, step.candidates)
        short = float(np.max(values) - values[step.chosen])
        if parted is None and int(teacher.choose(hmap, step.state, step.candidates,
                                                 rng)) != step.chosen:
            parted, parted_short = step.k, short
        if bool(refused[step.chosen]) or short > margin:
            count += 1
            last = step.k
            if unacceptable is None:
                unacceptable, unacceptable_short = step.k, short
                refused_there = bool(refused[step.chosen])
    end = student.steps[-1].k if student.steps else 0
    cause = (CAUSES[2] if last is None else CAUSES[0] if end - last < END_STEPS
             else CAUSES[1])
    return GapRun(student.key or "", str(student.result.get("reason", "")), len(student.steps),
                  parted, parted_short, unacceptable, unacceptable_short, refused_there, last,
                  count, cause)


def imitation_gap(pairs: Sequence[tuple[RunRecord, RunRecord]], maps: dict[str, HeightMap],
                  teacher: Expert, margin: float) -> dict:
    """The gap between a student and its teacher over paired runs (student, teacher).

    Returns the paired runs, the runs only one of the two crossed, and for each run the
    student failed and the teacher crossed its :class:`GapRun`, with the count by cause.
    """
    gap = [judge_gap_run(s, maps[s.terrain_hash], teacher, margin)
           for s, t in pairs if not s.result["success"] and t.result["success"]]
    return {"pairs": len(pairs),
            "student_only": sum(s.result["success"] and not t.result["success"]
                                for s, t in pairs),
            "teacher_only": len(gap),
            "by_cause": {c: sum(g.cause == c for g in gap) for c in CAUSES},
            "refused": sum(g.refused for g in gap),
            "runs": [g.as_dict() for g in gap]}
