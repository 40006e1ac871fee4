"""The store's "never here" marks: a person refuses candidates of a logged run's step outright.

Beside the foothold a person labels (:mod:`footfall.data.label_queries`), they may mark any
candidate of the step's F as one the robot must never take. A mark is a row of its own (run,
step, labeler, candidate, time, the client's request id), one per labeler and candidate of a
step, written in one transaction. It never names the candidate the same labeler's current label
names -- their foothold, or the robot's choice they called fine -- a person undoes the mark
before labelling that candidate, or the label before marking it.

A labeler's marks on a step they labelled with a foothold join that label's demonstration as
its refused candidates (:attr:`footfall.data.demonstration.Demonstration.refused`, read by
``footfall learn --supervision refusals``); marks on a step they called fine, or did not label,
make no demonstration (the paper labels only sub-optimal choices).
"""

from __future__ import annotations

import json
import math
import sqlite3
import time
from collections.abc import Callable
from typing import Any

from footfall.core.errors import FootfallError, NotFound
from footfall.data.label import (
    MARK_COLUMNS,
    Mark,
    check_index,
    check_labeler,
    check_request,
    checked_mark,
)
from footfall.data.run_queries import RunQueries


class MarkConflict(FootfallError):
    """A mark on the labeler's own label of the step, or a request id already used for another
    mark."""


class MarkQueries(RunQueries):
    """Add, read and remove "never here" marks (part of :class:`footfall.data.store.DemoStore`)."""

    # LabelQueries's: the run's terrain and step k's state, candidates and choice (NotFound for
    # an unknown run or step), in the caller's transaction
    _step: Callable[[sqlite3.Connection, int, int], dict[str, Any]]

    def add_mark(self, run_id: int, k: int, labeler: str, candidate: int,
                 request: str | None = None, created: float | None = None) -> tuple[Mark, bool]:
        """Mark candidate ``candidate`` of step ``k`` of run ``run_id`` "never here" for
        ``labeler``, in ONE transaction.

        Parameters
        ----------
        candidate : int
            Index into the step's F.
        request : str, optional
            The client's id of this request: if a mark with this id is stored, it is
            returned and nothing is written.
        created : float, optional
            [s] Unix time; now if not given.

        Returns
        -------
        (Mark, bool)
            The mark, and whether it was newly stored (False: a repeated request, or the
            labeler had marked that candidate already).

        Raises
        ------
        NotFound
            For a run or step that is not in the store.
        MarkConflict
            For the candidate the labeler's current label of the step names, or a request id
            used for another mark.
        FootfallError
            For a candidate outside F or a bad name, id or time; nothing is written then.
        """
        run_id, k = check_index(run_id, "a run id"), check_index(k, "a step number")
        labeler, request = check_labeler(labeler), check_request(request)
        candidate = check_index(candidate, "a candidate index")
        when = time.time() if created is None else float(created)
        if not math.isfinite(when):
            raise FootfallError("a mark's time is a finite number of seconds")
        self._require_marks()
        with self._errors(), self._write() as con:
            if request is not None:
                old = con.execute(f"SELECT {MARK_COLUMNS} FROM marks WHERE request = ?",
                                  (request,)).fetchone()
                if old is not None:
                    mark = _mark(old)
                    if (mark.run_id, mark.k, mark.labeler, mark.candidate) != \
                            (run_id, k, labeler, candidate):
                        raise MarkConflict(f"request id {request!r} was used for another mark")
                    return mark, False
            n = len(self._step(con, run_id, k)["candidates"])
            if not 0 <= candidate < n:
                raise FootfallError(f"candidate {candidate} is not in F (the step has {n} "
                                    f"candidates)")
            held = con.execute(f"SELECT {MARK_COLUMNS} FROM marks WHERE run_id = ? AND k = ? AND "
                               "labeler = ? AND candidate = ?",
                               (run_id, k, labeler, candidate)).fetchone()
            if held is not None:
                return _mark(held), False  # marked already: nothing changes
            _refuse_own_label(con, run_id, k, labeler, candidate)
            cur = con.execute("INSERT INTO marks (run_id, k, labeler, candidate, created, request) "
                              "VALUES (?, ?, ?, ?, ?, ?)",
                              (run_id, k, labeler, candidate, when, request))
            row = con.execute(f"SELECT {MARK_COLUMNS} FROM marks WHERE id = ?",
                              (cur.lastrowid,)).fetchone()
        return _mark(row), True

    def remove_mark(self, mark_id: int, labeler: str) -> Mark:
        """Remove one of ``labeler``'s marks (one transaction) and return it.

        Raises
        ------
        NotFound
            For a mark that is not stored, or is another labeler's.
        """
        mark_id = check_index(mark_id, "a mark id")
        labeler = check_labeler(labeler)
        self._require_marks()
        with self._errors(), self._write() as con:
            row = con.execute(f"SELECT {MARK_COLUMNS} FROM marks WHERE id = ?",
                              (mark_id,)).fetchone()
            if row is None or _mark(row).labeler != labeler:
                raise NotFound(f"mark {mark_id} is not in the store (of labeler {labeler!r})")
            con.execute("DELETE FROM marks WHERE id = ?", (mark_id,))
        return _mark(row)

    def marks(self, run_id: int | None = None, k: int | None = None,
              labeler: str | None = None) -> list[Mark]:
        """Stored marks (all, of a run, of a step, of a labeler), in creation order."""
        if not self._has_table("marks"):
            return []  # an older store read as it is
        clauses, params = [], []
        for column, value in (("run_id", run_id), ("k", k), ("labeler", labeler)):
            if value is not None:
                clauses.append(f"{column} = ?")
                params.append(value)
        where = (" WHERE " + " AND ".join(clauses)) if clauses else ""
        with self._errors():
            found = self._connection.execute(
                f"SELECT {MARK_COLUMNS} FROM marks{where} ORDER BY id", params).fetchall()
        return [_mark(row) for row in found]

    def mark_counts(self) -> dict[str, int]:
        """Marks by labeler: ``{labeler: n}``, by name."""
        if not self._has_table("marks"):
            return {}
        with self._errors():
            found = self._connection.execute("SELECT labeler, count(*) FROM marks "
                                             "GROUP BY labeler ORDER BY labeler").fetchall()
        return {str(name): int(n) for name, n in found}

    def _marked_candidates(self, demo_ids: list) -> dict[int, list[int]]:
        """{demonstration id: the candidates its labeler marked "never here" on its step} for
        the demonstrations of ``demo_ids`` that people's foothold labels made and that have
        marks."""
        if not demo_ids or not self._has_table("marks"):
            return {}
        with self._errors():
            found = self._connection.execute(
                "SELECT l.demonstration_id, m.candidate FROM labels l JOIN marks m ON "
                "m.run_id = l.run_id AND m.k = l.k AND m.labeler = l.labeler WHERE "
                "l.demonstration_id IN (SELECT value FROM json_each(?)) ORDER BY m.id",
                [json.dumps(demo_ids)]).fetchall()
        out: dict[int, list[int]] = {}
        for demo_id, candidate in found:
            if isinstance(candidate, bool) or not isinstance(candidate, int):
                raise FootfallError(f"{self.path}: a mark on the step of demonstration "
                                    f"{demo_id!r} is corrupt (candidate is not an integer)")
            out.setdefault(demo_id, []).append(candidate)
        return out

    def _require_marks(self) -> None:
        if not self._has_table("marks"):
            raise FootfallError(f"{self.path}: this store was opened read-only at schema "
                                f"version {self.schema_version}; marks need version 5")


def _refuse_own_label(con: sqlite3.Connection, run_id: int, k: int, labeler: str,
                      candidate: int) -> None:
    """Refuse (MarkConflict) a mark on the candidate ``labeler``'s current label of the step
    names: their foothold, or the robot's choice they called fine."""
    own = con.execute("SELECT verdict FROM labels WHERE run_id = ? AND k = ? AND labeler = ? "
                      "AND chosen = ?", (run_id, k, labeler, candidate)).fetchone()
    if own is None:
        return
    what = f"{labeler}'s own foothold label" if own[0] == "foothold" else \
        f"the robot's choice, which {labeler} called fine"
    raise MarkConflict(f"candidate {candidate} is {what} on this step: undo that label before "
                       f"marking it 'never here'")


def _mark(row: tuple) -> Mark:
    try:
        return checked_mark(row)
    except FootfallError as exc:
        raise FootfallError(f"mark {row[0]!r} is corrupt ({exc})") from None
