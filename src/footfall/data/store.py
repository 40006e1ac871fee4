"""The demonstration store: expert-chosen footholds in one embedded SQLite file.

Walkers, walking runs and the teaching interface add demonstrations (paper
§II-B) to the same store while learners read it; every write is one SQLite
transaction in WAL mode, so readers never see half a demonstration. The
same file keeps the terrains and the run logs of the simulated robot
(:mod:`footfall.data.runlog`): a whole run, with all its steps, is one transaction.

:class:`DemoStore` holds the demonstration queries and composes the rest: the
file's schema, version and migrations (:mod:`~footfall.data.schema`), the array
codec (:mod:`~footfall.data.codec`), the connection and its transactions
(:mod:`~footfall.data.connection`), the terrain and run-log queries
(:mod:`~footfall.data.terrain_queries`, :mod:`~footfall.data.run_queries`), people's labels
of run steps (:mod:`~footfall.data.label_queries`) and their "never here" marks
(:mod:`~footfall.data.mark_queries`).
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Iterable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES
from footfall.data import codec, rows, schema
from footfall.data.connection import DEFAULT_BUSY_TIMEOUT
from footfall.data.demonstration import Demonstration, as_demonstrations
from footfall.data.judgement_queries import JudgementQueries
from footfall.data.label_queries import LabelQueries
from footfall.data.mark_queries import MarkQueries
from footfall.data.runlog import RunRecord, RunStep
from footfall.data.schema import FORMAT, SCHEMA_VERSION, STATE_LAYOUT
from footfall.data.terrain_queries import TerrainQueries

__all__ = ["DEFAULT_BUSY_TIMEOUT", "FORMAT", "SCHEMA_VERSION", "STATE_LAYOUT", "DemoStore",
           "Demonstration", "RunRecord", "RunStep", "teacher_key"]


def teacher_key(expert: dict) -> str:
    """Who labelled, as a demonstration's settings say (canonical JSON), without what they say
    of the one step (a rollout verdict): two labels of a step with the same key are the same
    label given twice."""
    return json.dumps({k: v for k, v in expert.items() if k != "verdict"}, sort_keys=True)


class DemoStore(MarkQueries, LabelQueries, JudgementQueries, TerrainQueries):
    """An SQLite file of terrains and demonstrations, safe to share between processes.

    Use as a context manager. Every write is one transaction (``BEGIN
    IMMEDIATE`` ... ``COMMIT``): it lands whole or not at all, even if the
    process dies. The journal is in WAL mode, so readers keep reading while a
    writer writes and see each write once it is committed.

    Parameters
    ----------
    path : str or os.PathLike
        The store file (e.g. ``demos.sqlite``).
    create : bool
        If true, make a new store when ``path`` does not exist. Otherwise a
        missing file is an error.
    busy_timeout : float
        How long [s] an operation waits for another process's lock before failing.
    read_only : bool
        Open the file without writing to it, not even to upgrade an older
        schema (:func:`footfall.data.connection.read_only_uri`): for commands
        that only read. A write then fails.
    any_thread : bool
        Let another thread than the one that opened it use (or close) the
        connection. The caller must still never use it from two threads at
        once (a server's per-thread connections, closed when it stops).

    Raises
    ------
    FootfallError
        For a missing file (without ``create``), a file that is not a footfall
        demonstration store, a corrupt one, or one of a newer schema version.
    """

    def __len__(self) -> int:
        return self.count()

    # --------------------------------------------------------- demonstrations
    def add_demonstration(self, demo: Demonstration) -> int:
        """Store one demonstration (one transaction); return its id.

        Its terrain must be in the store already (:meth:`add_terrain`).
        """
        return self.add_demonstrations([demo])[0]

    def add_demonstrations(self, demos: Iterable[Demonstration],
                           terrains: Iterable[HeightMap] = ()) -> list[int]:
        """Store terrains and demonstrations in ONE transaction: all of them or none.

        Parameters
        ----------
        demos : iterable of Demonstration
            Their ``id`` is ignored; the store assigns new ones in order.
        terrains : iterable of HeightMap
            Terrains to add first (in the same transaction), e.g. those the
            demonstrations were made on.

        Returns
        -------
        list of int
            The new ids, increasing, in the order of ``demos``.

        Raises
        ------
        FootfallError
            If an item is not a Demonstration or its terrain is not stored;
            nothing is written then.
        """
        demos = as_demonstrations(demos)
        with self._write_after_terrains(list(terrains)) as con:
            return [self._insert_demonstration(con, d) for d in demos]

    def add_new_demonstrations(self, demos: Iterable[Demonstration],
                               terrains: Iterable[HeightMap] = ()) -> tuple[list[int], int]:
        """As :meth:`add_demonstrations`, but a label the store already holds is not added
        again: a demonstration of the same source (a run's step) by the same teacher
        (:func:`teacher_key`), or one repeated in ``demos``. The check and the writes are
        one transaction, so two writers at once add each label once.

        Returns
        -------
        (list of int, int)
            The new ids in the order of the demonstrations added, and how many were skipped.
        """
        demos = as_demonstrations(demos)
        with self._write_after_terrains(list(terrains)) as con:
            held = set()
            sources = sorted({d.source for d in demos})
            for i in range(0, len(sources), 500):
                chunk = sources[i:i + 500]
                rows = con.execute("SELECT source, expert FROM demonstrations WHERE source IN "
                                   f"({', '.join('?' * len(chunk))})", chunk)
                held |= {(source, teacher_key(json.loads(expert))) for source, expert in rows}
            ids = []
            for d in demos:
                key = (d.source, teacher_key(d.expert))
                if key not in held:
                    held.add(key)
                    ids.append(self._insert_demonstration(con, d))
            return ids, len(demos) - len(ids)

    def _insert_demonstration(self, con: sqlite3.Connection, demo: Demonstration) -> int:
        self._require_terrain(con, demo.terrain_hash, "demonstrations")
        state = codec.encode(demo.state.to_vector())
        cand = codec.encode(demo.candidates)
        cur = con.execute(
            "INSERT INTO demonstrations (terrain_hash, swing_leg, state, state_shape, state_dtype, "
            "candidates, candidates_shape, candidates_dtype, n_candidates, chosen, source, expert) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (demo.terrain_hash, demo.swing_leg, *state, *cand, demo.n_candidates, demo.chosen,
             demo.source, json.dumps(demo.expert, sort_keys=True)))
        demo_id = int(cur.lastrowid)
        if demo.has_verdict:
            self._insert_verdict(con, demo_id, demo)
        return demo_id

    def _insert_verdict(self, con: sqlite3.Connection, demo_id: int, demo: Demonstration) -> None:
        none = (None, None, None)
        values = none if demo.values is None else codec.encode(demo.values)
        refused = none if demo.refused is None else codec.encode(demo.refused)
        judged = none if demo.judged is None else codec.encode(demo.judged)
        con.execute(f"INSERT INTO verdicts ({rows.VERDICT_COLUMNS}) VALUES "
                    f"(?, ?, ?, ?, ?, ?, ?, ?, ?, ?)", (demo_id, *values, *refused, *judged))

    def demonstrations(self, ids: Sequence[int] | None = None, terrain_hash: str | None = None,
                       source_prefix: str | Sequence[str] | None = None) -> list[Demonstration]:
        """Read demonstrations, each validated.

        Parameters
        ----------
        ids : sequence of int, optional
            Exactly these, in this order (a missing id is an error).
            Otherwise all that match the filters, in creation order.
        terrain_hash : str, optional
            Only those on this terrain.
        source_prefix : str or sequence of str, optional
            Only those whose source starts with this (case-sensitive), e.g.
            ``"run:"``, or with any of these (``["human", "run:"]``).

        Raises
        ------
        FootfallError
            For a missing id, or a stored row that is not a valid
            demonstration (the message names its id).
        """
        where, params = _where(terrain_hash, source_prefix)
        columns = f"SELECT {rows.DEMONSTRATION_COLUMNS} FROM demonstrations"
        with self._errors():
            if ids is None:
                found = self._connection.execute(columns + where + " ORDER BY id",
                                                 params).fetchall()
            else:
                wanted = [self._check_id(i) for i in ids]
                extra = where.replace(" WHERE ", " AND ", 1)
                found = self._connection.execute(
                    columns + " WHERE id IN (SELECT value FROM json_each(?))" + extra,
                    [json.dumps(wanted), *params]).fetchall()
        verdicts = self._verdicts([row[0] for row in found])
        marked = self._marked_candidates([row[0] for row in found])  # a person's "never here"
        demos = [self._row_to_demo(row, verdicts.get(row[0]), marked.get(row[0]))
                 for row in found]
        if ids is None:
            return demos
        by_id = {d.id: d for d in demos}
        missing = [i for i in wanted if i not in by_id]
        if missing:
            raise FootfallError(f"demonstration {missing[0]} is not in the store"
                                + (" (or does not match the filters)" if where else ""))
        return [by_id[i] for i in wanted]

    def _verdicts(self, ids: list) -> dict:
        """{demonstration id: (values, refused, judged)} of the demonstrations ``ids`` that have
        one."""
        if not ids or self.schema_version < 5:
            return {}
        with self._errors():
            found = self._connection.execute(
                f"SELECT {rows.VERDICT_COLUMNS} FROM verdicts WHERE demonstration_id IN "
                f"(SELECT value FROM json_each(?))", [json.dumps(ids)]).fetchall()
        out = {}
        for row in found:
            try:
                demo_id, *verdict = rows.verdict(row)
            except FootfallError as exc:
                raise FootfallError(f"{self.path}: the verdict of demonstration {row[0]!r} is "
                                    f"corrupt ({exc})") from None
            out[demo_id] = tuple(verdict)
        return out

    def _row_to_demo(self, row: tuple, verdict: tuple | None = None,
                     marked: list[int] | None = None) -> Demonstration:
        """A demonstration from its row (:func:`footfall.data.rows.demonstration`) with its
        teacher's ``verdict`` (values, refused, judged), if it has one, and the candidates its labeler
        marked "never here" on its step (``marked``: indices into F) among the refused."""
        try:
            demo = rows.demonstration(row)
            if verdict is not None:
                demo = replace(demo, values=verdict[0], refused=verdict[1], judged=verdict[2])
            if marked:
                demo = replace(demo, refused=_with_marks(demo, marked))
            return demo
        except FootfallError as exc:
            raise FootfallError(f"{self.path}: demonstration {row[0]!r} is corrupt ({exc})") \
                from None

    def count(self, terrain_hash: str | None = None,
              source_prefix: str | Sequence[str] | None = None) -> int:
        """Number of stored demonstrations (matching the filters of :meth:`demonstrations`)."""
        where, params = _where(terrain_hash, source_prefix)
        with self._errors():
            return int(self._connection.execute("SELECT count(*) FROM demonstrations" + where,
                                                params).fetchone()[0])

    def summary(self) -> dict[str, Any]:
        """Counts of the store, from one consistent snapshot.

        Returns
        -------
        dict
            ``format``, ``schema_version``, ``demonstrations`` (total),
            ``terrains`` (number stored), ``by_terrain`` {hash: count, 0 for a
            terrain without demonstrations}, ``by_leg`` {leg: count} in
            LEG_NAMES order, ``by_source`` {kind: count} where the kind is the
            source up to its first ``:`` (``"run:3:step:7"`` counts as
            ``"run"``), ``candidates`` {min, mean, max} per demonstration
            (None when empty), ``first_id``/``last_id``, ``runs`` (run logs stored)
            and ``labels`` (people's labels by labeler, :meth:`label_counts`).
        """
        with self._errors(), self._read() as con:
            total, first, last, cmin, cmean, cmax = con.execute(
                "SELECT count(*), min(id), max(id), min(n_candidates), avg(n_candidates), "
                "max(n_candidates) FROM demonstrations").fetchone()
            if total and not all(isinstance(v, (int, float)) for v in (cmin, cmean, cmax)):
                raise FootfallError(f"{self.path}: corrupt demonstration store (a candidate "
                                    f"count that is not a number; run footfall store check)")
            by_terrain = dict(con.execute(
                "SELECT t.hash, count(d.id) FROM terrains t LEFT JOIN demonstrations d "
                "ON d.terrain_hash = t.hash GROUP BY t.hash ORDER BY t.rowid"))
            legs = dict(con.execute(
                "SELECT swing_leg, count(*) FROM demonstrations GROUP BY swing_leg"))
            n_runs = (int(con.execute("SELECT count(*) FROM runs").fetchone()[0])
                      if schema.has_table(con, "runs") else 0)  # a version-1 store read as it is
            by_source = dict(con.execute(
                "SELECT substr(source, 1, instr(source || ':', ':') - 1) AS kind, count(*) "
                "FROM demonstrations GROUP BY kind ORDER BY kind"))
        by_leg = {leg: int(legs.pop(leg, 0)) for leg in LEG_NAMES}
        by_leg.update(legs)  # a corrupt leg name still shows up in the counts
        return {"format": FORMAT, "schema_version": self.schema_version,
                "demonstrations": int(total), "terrains": len(by_terrain),
                "by_terrain": by_terrain, "by_leg": by_leg, "by_source": by_source,
                "candidates": None if not total else {"min": int(cmin), "mean": float(cmean),
                                                      "max": int(cmax)},
                "first_id": first, "last_id": last, "runs": n_runs,
                "labels": self.label_counts()}


def _with_marks(demo: Demonstration, marked: list[int]) -> np.ndarray:
    """The demonstration's refused candidates (n,) bool united with those ``marked``."""
    n = demo.n_candidates
    outside = [c for c in marked if not 0 <= c < n]
    if outside:
        raise FootfallError(f"its labeler's mark on candidate {outside[0]} is outside its {n} "
                            f"candidates")
    refused = np.zeros(n, dtype=bool) if demo.refused is None else demo.refused.copy()
    refused[marked] = True
    return refused


def _where(terrain_hash: str | None, source_prefix: str | Sequence[str] | None
           ) -> tuple[str, list[Any]]:
    """The WHERE clause (or "") and its parameters for the demonstration filters."""
    clauses, params = [], []
    if terrain_hash is not None:
        clauses.append("terrain_hash = ?")
        params.append(terrain_hash)
    if source_prefix is not None:  # not LIKE: '_' and '%' are ordinary characters here
        prefixes = [source_prefix] if isinstance(source_prefix, str) else list(source_prefix)
        if not prefixes or not all(isinstance(p, str) for p in prefixes):
            raise FootfallError(f"a source filter is a string or a non-empty list of strings, "
                                f"got {source_prefix!r}")
        clauses.append("(" + " OR ".join(["substr(source, 1, length(?)) = ?"] * len(prefixes))
                       + ")")
        params += [p for prefix in prefixes for p in (prefix, prefix)]
    return (" WHERE " + " AND ".join(clauses)) if clauses else "", params
