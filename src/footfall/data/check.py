"""The whole-store check (``footfall store check``, ``footfall demos info``): is a file a sound
demonstration store, every row of it?

The file is opened read-only and never changed. In order: SQLite's own integrity check of
every page; the schema (exactly footfall's tables and indexes, no trigger, no view); then every
row of every table, decoded as the queries decode it (:mod:`footfall.data.rows`), the
references between tables (a demonstration's terrain, a step's run) and the counts stored
beside them (a run's ``n_steps``). Each problem is one line naming the table and the row's key,
so a damaged store is reported whole, not refused at its first bad row.
"""

from __future__ import annotations

import contextlib
import os
import sqlite3
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from footfall.core.errors import FootfallError
from footfall.data import rows, schema
from footfall.data.connection import decode_text, one_line, read_only_uri
from footfall.data.demonstration import checked_values, checked_verdict
from footfall.data.label import LABEL_COLUMNS, MARK_COLUMNS, checked_label, checked_mark

SHOWN_PROBLEMS = 20  # problems listed in a one-line-each report; the rest are counted


@dataclass
class StoreReport:
    """What :func:`check_store` found: the problems (one line each) and what the store holds."""

    store: str  # the store's path, as given
    problems: list[str] = field(default_factory=list)
    demonstrations: int = 0  # rows in each table (counted, whether sound or not)
    terrains: int = 0
    runs: int = 0
    run_steps: int = 0
    labels: int = 0
    schema_version: int | None = None  # as the file declares it (None: unreadable)

    @property
    def ok(self) -> bool:
        """Whether no problem was found."""
        return not self.problems

    def lines(self, limit: int = SHOWN_PROBLEMS) -> list[str]:
        """One line per problem, at most ``limit`` and then ``... and N more``; or the verdict."""
        if self.ok:
            return [f"{self.store}: ok ({self.demonstrations} demonstrations, "
                    f"{self.terrains} terrains, {self.runs} runs)"]
        shown = [f"{self.store}: {p}" for p in self.problems[:limit]]
        if len(self.problems) > limit:
            shown.append(f"... and {len(self.problems) - limit} more")
        return shown

    def error(self) -> FootfallError:
        """The one-line error of a store with problems: its first, and how many more."""
        more = len(self.problems) - 1
        return FootfallError(f"{self.store}: {self.problems[0]}" + (
            f" (and {more} more {'problem' if more == 1 else 'problems'}: "
            f"footfall store check {self.store})" if more else ""))

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON."""
        return {"store": self.store, "ok": self.ok, "problems": list(self.problems),
                "schema_version": self.schema_version, "demonstrations": self.demonstrations,
                "terrains": self.terrains, "runs": self.runs, "run_steps": self.run_steps,
                "labels": self.labels}


def check_store(path: str | os.PathLike) -> StoreReport:
    """Check a store file without changing it; every problem found is in the report.

    Raises
    ------
    FootfallError
        Only for a path that is not a file at all (missing, a directory).
    """
    p = Path(path)
    report = StoreReport(str(path))
    if not p.exists():
        raise FootfallError(f"no such file: {p}")
    if not p.is_file():
        raise FootfallError(f"{p}: not a file")
    try:
        schema.check_header(p)
        con = sqlite3.connect(read_only_uri(p), uri=True, isolation_level=None)
        con.text_factory = decode_text
    except FootfallError as exc:
        report.problems.append(str(exc).removeprefix(f"{p}: "))
        return report
    except sqlite3.Error as exc:
        report.problems.append(f"cannot open ({one_line(exc)})")
        return report
    try:
        _check_open(con, report)
    finally:
        con.close()
    return report


def _check_open(con: sqlite3.Connection, report: StoreReport) -> None:
    """The checks of an open file, each stopping at damage that makes the next meaningless."""
    with _sqlite_errors(report, "the file"):
        damaged = [r[0] for r in con.execute("PRAGMA integrity_check(100)")]
        if damaged != ["ok"]:
            report.problems += [f"corrupt demonstration store ({' '.join(str(d).split())})"
                                for d in damaged]
            return
        if not schema.has_table(con, "meta"):
            report.problems.append("not a footfall demonstration store (no footfall metadata)")
            return
        try:
            version = schema.stored_version(con, Path(report.store))
        except FootfallError as exc:
            report.problems.append(str(exc).removeprefix(f"{report.store}: "))
            return
        report.schema_version = version
        problems = schema.schema_problems(con, version)
        report.problems += problems
        if problems:
            return  # its rows may not have the columns read below
        _check_rows(con, report, version)


@contextlib.contextmanager
def _sqlite_errors(report: StoreReport, what: str) -> Iterator[None]:
    """An SQLite error while reading ``what`` becomes one problem (a damaged page, ...)."""
    try:
        yield
    except sqlite3.Error as exc:
        report.problems.append(f"corrupt demonstration store (reading {what}: {one_line(exc)})")
    except UnicodeDecodeError:  # SQLite's own message about the damage holds bytes of it
        report.problems.append(f"corrupt demonstration store (reading {what}: SQLite's error "
                               "message is not UTF-8)")


def _check_rows(con: sqlite3.Connection, report: StoreReport, version: int) -> None:
    """Every row of every table, and the references between them."""
    for key, value in con.execute("SELECT key, value FROM meta"):
        for v, column in ((key, "key"), (value, "value")):
            if not isinstance(v, str):
                report.problems.append(f"meta row {key!r}: {column} is not text")
    hashes: set[Any] = set()
    demo_ids: set[Any] = set()
    sound: dict[Any, Any] = {}  # demonstration id -> the demonstration, where its row is sound
    sources: list[tuple[Any, Any]] = []  # (demonstration id, source)
    with _sqlite_errors(report, "table terrains"):
        for row in con.execute(f"SELECT {rows.TERRAIN_COLUMNS} FROM terrains ORDER BY rowid"):
            report.terrains += 1
            hashes.add(row[0])
            _row(report, "terrains", repr(row[0]), rows.terrain, row)
    with _sqlite_errors(report, "table demonstrations"):
        for row in con.execute(f"SELECT {rows.DEMONSTRATION_COLUMNS} FROM demonstrations "
                               "ORDER BY id"):
            report.demonstrations += 1
            demo_ids.add(row[0])
            demo = _row(report, "demonstrations", repr(row[0]), rows.demonstration, row)
            if demo is not None:
                sound[row[0]] = demo
                _reference(report, "demonstrations", row[0], row[1], hashes)
                sources.append((row[0], row[11]))
    steps: dict[tuple[Any, Any], int | None] = {}
    keys: dict[Any, Any] = {}
    if version >= 2:
        steps, keys = _check_runs(con, report, hashes)
        _check_sources(report, sources, steps, keys)
    if version >= 3:
        _check_labels(con, report, steps, demo_ids)
    if version >= 5:
        _check_verdicts(con, report, demo_ids, sound)
        _check_marks(con, report, steps)


def _check_verdicts(con: sqlite3.Connection, report: StoreReport, demo_ids: set[Any],
                    sound: dict[Any, Any]) -> None:
    """The teachers' verdicts: each row sound, of a stored demonstration, one value and one
    refusal per candidate, the chosen candidate not refused."""
    with _sqlite_errors(report, "table verdicts"):
        for row in con.execute(f"SELECT {rows.VERDICT_COLUMNS} FROM verdicts "
                               "ORDER BY demonstration_id"):
            found = _row(report, "verdicts", repr(row[0]), rows.verdict, row)
            if found is None:
                continue
            demo_id, values, refused, judged = found
            if demo_id not in demo_ids:
                report.problems.append(f"verdicts row {demo_id!r}: demonstration {demo_id} is "
                                       f"not in the store")
            elif demo_id in sound:
                d = sound[demo_id]
                try:
                    checked_verdict(values, refused, d.n_candidates, d.chosen)
                    checked_values(judged, d.n_candidates, "the judged values")
                except FootfallError as exc:
                    report.problems.append(f"verdicts row {demo_id!r}: {exc}")


def _check_marks(con: sqlite3.Connection, report: StoreReport,
                 steps: dict[tuple[Any, Any], int | None]) -> None:
    """People's "never here" marks: each row sound, on a stored run step, on a candidate of its
    F, never the candidate its labeler's own label of the step names."""
    with _sqlite_errors(report, "table marks"):
        labelled = set(con.execute("SELECT run_id, k, labeler, chosen FROM labels"))
        for row in con.execute(f"SELECT {MARK_COLUMNS} FROM marks ORDER BY id"):
            mark = _row(report, "marks", repr(row[0]), checked_mark, row)
            if mark is None:
                continue
            step = (mark.run_id, mark.k)
            if step not in steps:
                report.problems.append(f"marks row {mark.id}: run {mark.run_id} has no step "
                                       f"{mark.k} in the store")
            elif steps[step] is not None and not mark.candidate < steps[step]:
                report.problems.append(f"marks row {mark.id}: candidate {mark.candidate} is not "
                                       f"one of its step's {steps[step]} candidates")
            if (*step, mark.labeler, mark.candidate) in labelled:
                report.problems.append(f"marks row {mark.id}: candidate {mark.candidate} is its "
                                       f"labeler's own label of the step")


def _run_step_of(source: str) -> tuple[str, str, str] | None:
    """(kind, run, step) of a demonstration source that names a run's step --
    ``run:<run key or id>:step:<k>`` (an expert's correction, a rank-eval decision) or
    ``human:run:<run id>:step:<k>`` (a person's label) -- as text; None for every other
    source (the walker's, a collection's: they name no run)."""
    for kind, prefix in (("run", "run:"), ("human", "human:run:")):
        if source.startswith(prefix) and ":step:" in source:
            run, step = source[len(prefix):].rsplit(":step:", 1)
            return kind, run, step
    return None


def _check_sources(report: StoreReport, sources: list[tuple[Any, Any]],
                   steps: dict[tuple[Any, Any], int | None], keys: dict[Any, Any]) -> None:
    """Every demonstration whose source names a run's step names one that is stored."""
    for demo_id, source in sources:
        named = _run_step_of(source)
        if named is None:
            continue
        kind, run, step = named
        number = int(run) if run.isdigit() else None  # a run's id
        run_id = number if kind == "human" else keys.get(run, number)  # or its key
        if run_id is None or not step.isdigit() or (run_id, int(step)) not in steps:
            report.problems.append(f"demonstrations row {demo_id!r}: its source {source!r} "
                                   f"names a run step that is not in the store")


def _check_labels(con: sqlite3.Connection, report: StoreReport,
                  steps: dict[tuple[Any, Any], int | None], demo_ids: set[Any]) -> None:
    """People's labels: each row sound, on a stored run step, a foothold label with its
    demonstration (a "fine" verdict has none)."""
    with _sqlite_errors(report, "table labels"):
        for row in con.execute(f"SELECT {LABEL_COLUMNS} FROM labels ORDER BY id"):
            report.labels += 1
            label = _row(report, "labels", repr(row[0]), checked_label, row)
            if label is None:
                continue
            if (label.run_id, label.k) not in steps:
                report.problems.append(f"labels row {label.id}: run {label.run_id} has no step "
                                       f"{label.k} in the store")
            elif not 0 <= label.chosen < (steps[label.run_id, label.k] or 0):
                report.problems.append(f"labels row {label.id}: chosen {label.chosen} is not "
                                       f"one of its step's {steps[label.run_id, label.k]} "
                                       f"candidates")
            if (label.verdict == "foothold") != (label.demonstration_id in demo_ids):
                report.problems.append(f"labels row {label.id}: a {label.verdict!r} label "
                                       + ("without its demonstration" if label.verdict ==
                                          "foothold" else "with a demonstration"))


def _check_runs(con: sqlite3.Connection, report: StoreReport, hashes: set[Any]
                ) -> tuple[dict[tuple[Any, Any], int | None], dict[Any, Any]]:
    """The run logs: each run's row, its terrain, its steps numbered 0 .. n_steps - 1.
    Returns the stored steps, (run id, k) -> its number of candidates (None: unreadable),
    and the runs' ids by key."""
    n_steps: dict[Any, Any] = {}
    keys: dict[Any, Any] = {}
    with _sqlite_errors(report, "table runs"):
        for row in con.execute(f"SELECT {rows.RUN_COLUMNS} FROM runs ORDER BY id"):
            report.runs += 1
            n_steps[row[0]] = row[6]
            if row[1] is not None:
                keys[row[1]] = row[0]
            if _row(report, "runs", repr(row[0]), rows.run_head, row) is not None:
                _reference(report, "runs", row[0], row[2], hashes)
    found: dict[Any, list[Any]] = {}
    stored: dict[tuple[Any, Any], int | None] = {}
    with _sqlite_errors(report, "table run_steps"):
        for row in con.execute(f"SELECT run_id, {rows.STEP_COLUMNS} FROM run_steps "
                               "ORDER BY run_id, k"):
            report.run_steps += 1
            run_id, step = row[0], row[1:]
            where = f"(run {run_id!r}, k {step[0]!r})"
            sound = _row(report, "run_steps", where, rows.run_step, step)
            if run_id not in n_steps:
                report.problems.append(f"run_steps row {where}: run {run_id!r} is not in "
                                       f"the store")
            found.setdefault(run_id, []).append(step[0])
            stored[run_id, step[0]] = None if sound is None else sound.candidates.shape[0]
    for run_id, n in n_steps.items():
        ks = found.get(run_id, [])
        if isinstance(n, int) and ks != list(range(n)):
            report.problems.append(f"runs row {run_id!r}: n_steps is {n} but its steps are "
                                   f"numbered {_range(ks)}")
    return stored, keys


def _row(report: StoreReport, table: str, key: str, decode: Callable[[tuple], Any],
         row: tuple) -> Any:
    """The decoded row; None and a problem naming the table and the row's key if it is not
    sound."""
    try:
        return decode(row)
    except FootfallError as exc:
        report.problems.append(f"{table} row {key}: {exc}")
        return None


def _reference(report: StoreReport, table: str, key: Any, terrain_hash: Any,
               hashes: set[Any]) -> None:
    if terrain_hash not in hashes:
        report.problems.append(f"{table} row {key!r}: its terrain {terrain_hash!r} is not in "
                               f"the store")


def _range(ks: list[Any]) -> str:
    """The step numbers of a run, shortly: ``none``, ``0..4`` or the list."""
    if not ks:
        return "none"
    if ks == list(range(len(ks))):
        return f"0..{len(ks) - 1}"
    return ", ".join(map(repr, ks[:10])) + (" ..." if len(ks) > 10 else "")


def checked_store(path: str | os.PathLike) -> StoreReport:
    """:func:`check_store`, raising the first problem as one line if there is any.

    Raises
    ------
    FootfallError
        If the store has a problem: the first, and how many more.
    """
    report = check_store(path)
    if not report.ok:
        raise report.error()
    return report
