"""The store's label queries: people's verdicts on the steps of logged runs (paper §II-B).

A person shown a run step either labels the foothold of F they think is the
best greedy choice (verdict ``"foothold"``) or says the robot's own choice
was fine (``"fine"``). A foothold label *is* a demonstration: it is stored as
one, with the step's state and candidate set, source
``human:run:<id>:step:<k>`` and the labeler's name in its settings, in the
same transaction as the label row that records its provenance (run, step,
labeler, time). The learner reads it like any other demonstration
(``footfall learn STORE --source human``). A "fine" verdict makes no
demonstration: the paper labels only sub-optimal choices; it records that
the step was reviewed, and whether labelers agree.

Each labeler keeps one label per step (a new one replaces their old one,
which is kept aside in ``replaced_labels``: undoing the new label restores
it, so a labeler's undo walks back through their history of that step);
two labelers who disagree on a step both keep theirs. A label may carry
the client's request id: a request sent again (a retry after a lost answer)
returns the label it made the first time instead of adding another. A labeler's label never
names a candidate they marked "never here" on the step (:mod:`footfall.data.mark_queries`): they
undo the mark first.
"""

from __future__ import annotations

import json
import math
import sqlite3
import time
from collections.abc import Callable
from typing import Any

from footfall.core.errors import FootfallError, NotFound
from footfall.data import rows, schema
from footfall.data.demonstration import Demonstration
from footfall.data.label import (
    HUMAN_SOURCE,
    LABEL_COLUMNS,
    VERDICTS,
    Label,
    check_index,
    check_labeler,
    check_request,
    checked_label,
    human_source,
)
from footfall.data.run_queries import RunQueries


class LabelConflict(FootfallError):
    """A request id already used for another label, or a label of a candidate its labeler
    marked "never here"."""


class LabelQueries(RunQueries):
    """Add, read and undo labels (part of :class:`footfall.data.store.DemoStore`)."""

    # DemoStore's: one demonstration row, in the caller's transaction
    _insert_demonstration: Callable[[sqlite3.Connection, Demonstration], int]

    def add_label(self, run_id: int, k: int, labeler: str, verdict: str,
                  chosen: int | None = None, request: str | None = None,
                  created: float | None = None) -> tuple[Label, bool]:
        """Store a person's verdict on step ``k`` of run ``run_id`` in ONE transaction.

        Parameters
        ----------
        verdict : str
            ``"foothold"``: ``chosen`` (an index into the step's F) is the
            labelled foothold, stored as a demonstration; ``"fine"``: the
            robot's choice was fine (``chosen`` must be None or the robot's).
        request : str, optional
            The client's id of this request: if a label with this id is
            stored, it is returned and nothing is written.
        created : float, optional
            [s] Unix time; now if not given.

        Returns
        -------
        (Label, bool)
            The label, and whether it was newly stored (False: a repeated request).

        Raises
        ------
        NotFound
            For a run or step that is not in the store.
        LabelConflict
            For a request id used by another label, or a candidate the labeler marked "never here".
        FootfallError
            For a bad labeler name, verdict or index; nothing is written then.
        """
        run_id, k = check_index(run_id, "a run id"), check_index(k, "a step number")
        labeler, request = check_labeler(labeler), check_request(request)
        if verdict not in VERDICTS:
            raise FootfallError(f"a verdict is one of {', '.join(VERDICTS)}, got {verdict!r}")
        chosen = None if chosen is None else check_index(chosen, "a candidate index")
        if verdict == "foothold" and chosen is None:
            raise FootfallError("a foothold label needs the index of the candidate chosen")
        when = time.time() if created is None else float(created)
        if not math.isfinite(when):
            raise FootfallError("a label's time is a finite number of seconds")
        self._require_labels()
        with self._errors(), self._write() as con:
            if request is not None:
                old = con.execute(f"SELECT {LABEL_COLUMNS} FROM labels WHERE request = ?",
                                  (request,)).fetchone() or self._replaced_request(con, request)
                if old is not None:
                    label = _label(old)
                    same = (label.run_id, label.k, label.labeler, label.verdict) == \
                        (run_id, k, labeler, verdict) and (chosen is None or chosen == label.chosen)
                    if not same:
                        raise LabelConflict(f"request id {request!r} was used for another label")
                    return label, False
            step = self._step(con, run_id, k)
            n = len(step["candidates"])
            if verdict == "fine":
                if chosen is not None and chosen != step["chosen"]:
                    raise FootfallError("a 'fine' verdict is on the robot's own choice "
                                        f"(candidate {step['chosen']}), not candidate {chosen}")
                chosen = step["chosen"]
            elif not 0 <= chosen < n:
                raise FootfallError(f"candidate {chosen} is not in F (the step has {n} candidates)")
            if verdict == "foothold" and n < 2:
                raise FootfallError("the step's F has one candidate: there is nothing to choose")
            current = con.execute(f"SELECT {LABEL_COLUMNS} FROM labels WHERE run_id = ? AND k = ? "
                                  "AND labeler = ?", (run_id, k, labeler)).fetchone()
            if current is not None and (current[4], current[5]) == (verdict, chosen):
                return _label(current), False  # the same verdict again: nothing changes
            _refuse_marked(con, run_id, k, labeler, chosen, verdict)
            if current is not None:
                self._delete_labels(con, "id = ?", (current[0],))
            new_id = self._insert_label(con, step, (None, run_id, k, labeler, verdict, chosen,
                                                    None, when, request))
            if current is not None:  # kept aside: undoing the new label restores it
                con.execute("INSERT INTO replaced_labels (id, run_id, k, labeler, verdict, chosen, "
                            "created, request, replaced_by) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                            (*current[:6], current[7], current[8], new_id))
            row = con.execute(f"SELECT {LABEL_COLUMNS} FROM labels WHERE id = ?",
                              (new_id,)).fetchone()
        return _label(row), True

    def remove_label(self, label_id: int, labeler: str | None = None) -> Label:
        """Undo a label (:meth:`undo_label`) and return the label removed."""
        return self.undo_label(label_id, labeler)[0]

    def undo_label(self, label_id: int, labeler: str | None = None) -> tuple[Label, Label | None]:
        """Undo a label in one transaction: delete it and the demonstration it made, and restore
        the label it replaced (with its id and a new demonstration), if it replaced one.

        ``labeler``: only a label of this labeler is undone (a page undoes its
        own labels, never another person's).

        Returns
        -------
        (Label, Label or None)
            The label removed, and the one restored in its place (None: none).

        Raises
        ------
        NotFound
            For a label that is not stored (or is another labeler's).
        LabelConflict
            When the label it would restore names a candidate the labeler has since marked
            "never here" (they undo the mark first).
        """
        label_id = check_index(label_id, "a label id")
        labeler = None if labeler is None else check_labeler(labeler)
        self._require_labels()
        with self._errors(), self._write() as con:
            row = con.execute(f"SELECT {LABEL_COLUMNS} FROM labels WHERE id = ?",
                              (label_id,)).fetchone()
            if row is None or (labeler is not None and _label(row).labeler != labeler):
                raise NotFound(f"label {label_id} is not in the store"
                               + ("" if labeler is None else f" (of labeler {labeler!r})"))
            self._delete_labels(con, "id = ?", (label_id,))
            restored = None
            if self._has_table("replaced_labels"):
                old = con.execute("SELECT id, run_id, k, labeler, verdict, chosen, created, request "
                                  "FROM replaced_labels WHERE replaced_by = ?",
                                  (label_id,)).fetchone()
                if old is not None:
                    _refuse_marked(con, old[1], old[2], old[3], old[5], old[4], undo=True)
                    con.execute("DELETE FROM replaced_labels WHERE id = ?", (old[0],))
                    step = self._step(con, old[1], old[2])
                    self._insert_label(con, step, (*old[:6], None, old[6], old[7]))
                    restored = _label(con.execute(f"SELECT {LABEL_COLUMNS} FROM labels WHERE id = ?",
                                                  (old[0],)).fetchone())
        return _label(row), restored

    def labels(self, run_id: int | None = None, k: int | None = None,
               labeler: str | None = None) -> list[Label]:
        """Stored labels (of a run, a step, a labeler), in creation order."""
        if not self._has_table("labels"):
            return []  # an older store read as it is
        clauses, params = [], []
        for column, value in (("run_id", run_id), ("k", k), ("labeler", labeler)):
            if value is not None:
                clauses.append(f"{column} = ?")
                params.append(value)
        where = (" WHERE " + " AND ".join(clauses)) if clauses else ""
        with self._errors():
            found = self._connection.execute(
                f"SELECT {LABEL_COLUMNS} FROM labels{where} ORDER BY id", params).fetchall()
        return [_label(row) for row in found]

    def step_labels(self, run_id: int, k: int) -> list[Label]:
        """The labels of step ``k`` of run ``run_id``, in creation order.

        Raises
        ------
        NotFound
            For a run or step that is not in the store.
        """
        run_id, k = check_index(run_id, "a run id"), check_index(k, "a step number")
        with self._errors(), self._read() as con:
            head = con.execute("SELECT n_steps FROM runs WHERE id = ?", (run_id,)).fetchone()
            if head is None:
                raise NotFound(f"run {run_id} is not in the store")
            if not 0 <= k < head[0]:
                raise NotFound(f"run {run_id} has no step {k} (it has {head[0]} steps)")
        return self.labels(run_id, k)

    def label_counts(self) -> dict[str, Any]:
        """Labels by labeler and verdict: ``{labeler: {"foothold": n, "fine": m}}``, and the
        steps two labelers disagree on (``disagreements``: labelled different footholds)."""
        if not self._has_table("labels"):
            return {"by_labeler": {}, "disagreements": 0}
        with self._errors(), self._read() as con:
            found = con.execute("SELECT labeler, verdict, count(*) FROM labels "
                                "GROUP BY labeler, verdict ORDER BY labeler").fetchall()
            split = con.execute("SELECT count(*) FROM (SELECT run_id, k FROM labels "
                                "GROUP BY run_id, k HAVING count(DISTINCT chosen) > 1)"
                                ).fetchone()[0]
        by_labeler: dict[str, dict[str, int]] = {}
        for name, verdict, n in found:
            by_labeler.setdefault(name, dict.fromkeys(VERDICTS, 0))[verdict] = int(n)
        return {"by_labeler": by_labeler, "disagreements": int(split)}

    # ----------------------------------------------------------------- helpers
    def _require_labels(self) -> None:
        if not self._has_table("labels"):
            raise FootfallError(f"{self.path}: this store was opened read-only at schema "
                                f"version {self.schema_version}; labels need version 3")

    @staticmethod
    def _step(con: sqlite3.Connection, run_id: int, k: int) -> dict[str, Any]:
        """The run's terrain and step ``k``'s state, candidates and choice (in ``con``'s transaction)."""
        head = con.execute("SELECT terrain_hash, n_steps FROM runs WHERE id = ?",
                           (run_id,)).fetchone()
        if head is None:
            raise NotFound(f"run {run_id} is not in the store")
        row = con.execute(f"SELECT {rows.STEP_COLUMNS} FROM run_steps WHERE run_id = ? AND k = ?",
                          (run_id, k)).fetchone()
        if row is None:
            raise NotFound(f"run {run_id} has no step {k} (it has {head[1]} steps)")
        step = rows.run_step(row)
        return {"terrain_hash": head[0], "state": step.state, "candidates": step.candidates,
                "chosen": step.chosen}

    def _insert_label(self, con: sqlite3.Connection, step: dict[str, Any], row: tuple) -> int:
        """Insert a label row (LABEL_COLUMNS order; id None: a new one) with the demonstration a
        foothold label makes, in the caller's transaction; returns the label's id."""
        id_, run_id, k, labeler, verdict, chosen, _, when, request = row
        demo_id = None
        if verdict == "foothold":
            demo_id = self._insert_demonstration(con, Demonstration(
                step["terrain_hash"], step["state"], step["candidates"], chosen,
                source=human_source(run_id, k), expert={"kind": HUMAN_SOURCE, "labeler": labeler}))
        cur = con.execute(
            "INSERT INTO labels (id, run_id, k, labeler, verdict, chosen, demonstration_id, "
            "created, request) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (id_, run_id, k, labeler, verdict, chosen, demo_id, when, request))
        return int(cur.lastrowid)

    def _replaced_request(self, con: sqlite3.Connection, request: str) -> tuple | None:
        """A replaced label made by request ``request``, as a labels row (or None)."""
        if not self._has_table("replaced_labels"):
            return None
        old = con.execute("SELECT id, run_id, k, labeler, verdict, chosen, created, request "
                          "FROM replaced_labels WHERE request = ?", (request,)).fetchone()
        return None if old is None else (*old[:6], None, old[6], old[7])

    @staticmethod
    def _delete_labels(con: sqlite3.Connection, where: str, params: tuple) -> None:
        """Delete labels and the demonstrations they made (in the caller's transaction)."""
        demos = [d for (d,) in con.execute(
            f"SELECT demonstration_id FROM labels WHERE {where} AND demonstration_id IS NOT NULL",
            params)]
        con.execute(f"DELETE FROM labels WHERE {where}", params)
        con.execute("DELETE FROM demonstrations WHERE id IN (SELECT value FROM json_each(?))",
                    (json.dumps(demos),))


def _refuse_marked(con: sqlite3.Connection, run_id: int, k: int, labeler: str, chosen: int,
                   verdict: str, undo: bool = False) -> None:
    """Refuse (LabelConflict) a label of a candidate ``labeler`` marked "never here" on the
    step (``undo``: the label an undo would restore), in the caller's transaction."""
    if not schema.has_table(con, "marks") or con.execute(
            "SELECT 1 FROM marks WHERE run_id = ? AND k = ? AND labeler = ? AND candidate = ?",
            (run_id, k, labeler, chosen)).fetchone() is None:
        return
    what = f"candidate {chosen}" if verdict == "foothold" else \
        f"the robot's choice (candidate {chosen})"
    if undo:
        raise LabelConflict(f"undoing this label would bring back {labeler}'s label of {what}, "
                            f"which they marked 'never here' on this step: undo that mark first")
    raise LabelConflict(f"{labeler} marked {what} 'never here' on this step: undo that mark "
                        f"first")


def _label(row: tuple) -> Label:
    try:
        return checked_label(row)
    except FootfallError as exc:
        raise FootfallError(f"label {row[0]!r} is corrupt ({exc})") from None
