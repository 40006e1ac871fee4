"""A person's label of a run step (paper §II-B): the foothold they think is the best greedy
choice among the step's candidate set F, or their verdict that the robot's choice was fine;
and a person's "never here" mark on one candidate of a step's F (a candidate they refuse
outright). Stored by :class:`footfall.data.store.DemoStore` (:mod:`footfall.data.label_queries`,
:mod:`footfall.data.mark_queries`), made by the teaching interface (:mod:`footfall.teach`).
"""

from __future__ import annotations

import numbers
import re
from dataclasses import dataclass
from typing import Any

from footfall.core.errors import FootfallError
from footfall.data import rows

VERDICTS = ("foothold", "fine")  # a labelled foothold of F; the robot's choice was fine
HUMAN_SOURCE = "human"  # the source prefix of every demonstration a person labelled
MAX_LABELER = 64  # [characters] the longest labeler name
MAX_REQUEST = 64  # [characters] the longest request id
_NAME_RE = re.compile(r"^[\w][\w .@+-]*$")  # letters, digits, _ and a few separators
_REQUEST_RE = re.compile(r"^[A-Za-z0-9_-]+$")
LABEL_COLUMNS = "id, run_id, k, labeler, verdict, chosen, demonstration_id, created, request"
MARK_COLUMNS = "id, run_id, k, labeler, candidate, created, request"


@dataclass(frozen=True)
class Label:
    """One stored label of a run step."""

    id: int  # row id (creation order)
    run_id: int  # the labelled run
    k: int  # the labelled step of that run
    labeler: str  # who labelled
    verdict: str  # one of VERDICTS
    chosen: int  # index in the step's F of the labelled foothold ("fine": the robot's choice)
    demonstration_id: int | None  # the demonstration a "foothold" label made; None for "fine"
    created: float  # [s] Unix time the label was stored
    request: str | None  # the client's request id, if it gave one

    def to_dict(self) -> dict[str, Any]:
        """The label as plain JSON types."""
        return dict(self.__dict__)


@dataclass(frozen=True)
class Mark:
    """One stored "never here" mark: a person refuses one candidate of a run step's F outright."""

    id: int  # row id (creation order)
    run_id: int  # the marked run
    k: int  # the marked step of that run
    labeler: str  # who marked
    candidate: int  # index in the step's F of the refused candidate
    created: float  # [s] Unix time the mark was stored
    request: str | None  # the client's request id, if it gave one

    def to_dict(self) -> dict[str, Any]:
        """The mark as plain JSON types."""
        return dict(self.__dict__)


def human_source(run_id: int, k: int) -> str:
    """The demonstration source of a person's label of step ``k`` of run ``run_id``."""
    return f"{HUMAN_SOURCE}:run:{int(run_id)}:step:{int(k)}"


def check_labeler(name: Any) -> str:
    """A labeler's name, stripped: 1-64 letters, digits, spaces and ``_ . @ + -``."""
    if not isinstance(name, str) or not name.strip():
        raise FootfallError("a labeler name is a non-empty string")
    name = name.strip()
    if len(name) > MAX_LABELER or not _NAME_RE.match(name):
        raise FootfallError(f"a labeler name has at most {MAX_LABELER} letters, digits, spaces "
                            f"and _ . @ + - (got {name[:MAX_LABELER]!r})")
    return name


def check_request(request: Any) -> str | None:
    """A client's request id (None: none given): 1-64 of A-Z a-z 0-9 _ -."""
    if request is None:
        return None
    if not isinstance(request, str) or not 0 < len(request) <= MAX_REQUEST \
            or not _REQUEST_RE.match(request):
        raise FootfallError(f"a request id is 1-{MAX_REQUEST} characters of A-Z a-z 0-9 _ -")
    return request


def check_index(value: Any, what: str) -> int:
    """An index or id given by a caller: an integer (a bool is refused)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise FootfallError(f"{what} is an integer, got {value!r}")
    return int(value)


def checked_label(row: tuple) -> Label:
    """A label from its row (LABEL_COLUMNS), every field checked."""
    id_, run_id, k, labeler, verdict, chosen, demo, created, request = row
    if verdict not in VERDICTS:
        raise FootfallError(f"verdict {verdict!r} is not one of {', '.join(VERDICTS)}")
    return Label(rows.integer(id_, "id"), rows.integer(run_id, "run_id"), rows.integer(k, "k"),
                 check_labeler(labeler), verdict, rows.integer(chosen, "chosen"),
                 None if demo is None else rows.integer(demo, "demonstration_id"),
                 rows.real(created, "created"), check_request(request))


def checked_mark(row: tuple) -> Mark:
    """A mark from its row (MARK_COLUMNS), every field checked."""
    id_, run_id, k, labeler, candidate, created, request = row
    candidate = rows.integer(candidate, "candidate")
    if candidate < 0:
        raise FootfallError(f"candidate {candidate} is negative")
    return Mark(rows.integer(id_, "id"), rows.integer(run_id, "run_id"), rows.integer(k, "k"),
                check_labeler(labeler), candidate, rows.real(created, "created"),
                check_request(request))
