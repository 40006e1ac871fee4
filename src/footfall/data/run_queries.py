"""The store's run-log queries: a whole run of the simulated robot (:mod:`footfall.data.runlog`),
with all its steps and the corrections made from it, is written in one transaction and read
back validated.
"""

from __future__ import annotations

import json
import math
import sqlite3
from collections.abc import Callable, Iterable
from typing import Any

from footfall.core.errors import FootfallError, NotFound
from footfall.core.heightmap import HeightMap
from footfall.data import codec, rows
from footfall.data.demonstration import Demonstration, as_demonstrations
from footfall.data.runlog import RunRecord
from footfall.data.terrain_queries import TerrainQueries


class RunQueries(TerrainQueries):
    """Add and read the run logs of a store (part of :class:`footfall.data.store.DemoStore`)."""

    # DemoStore's: one demonstration row, in the caller's transaction (a run's corrections)
    _insert_demonstration: Callable[[sqlite3.Connection, Demonstration], int]

    def add_run(self, run: RunRecord, terrains: Iterable[HeightMap] = (),
                demonstrations: Iterable[Demonstration] = ()) -> int:
        """Store a whole run with all its steps in ONE transaction; return its id.

        ``demonstrations`` made from the run (an expert's corrections of it)
        go into the same transaction: a run is never stored without them,
        so an interrupted experiment that finds the run stored knows its
        corrections are too.

        Parameters
        ----------
        run : RunRecord
            Its ``id`` is ignored. Its terrain must be stored, or be among
            ``terrains`` (added in the same transaction).
        terrains : iterable of HeightMap
            Terrains to add first.
        demonstrations : iterable of Demonstration
            Demonstrations to add with the run (their terrains must be stored
            or among ``terrains``).

        Raises
        ------
        FootfallError
            If the terrain is missing or a run with the same key is stored;
            nothing is written then.
        """
        return self._add_run(run, terrains, demonstrations, stored_ok=False)[0]

    def add_run_if_new(self, run: RunRecord, terrains: Iterable[HeightMap] = ()
                       ) -> tuple[int, bool]:
        """Store ``run`` unless a run with its key is stored already -- by another process
        walking the same run at the same time, say: (the stored run's id, whether this call
        stored it). Otherwise as :meth:`add_run`."""
        if not isinstance(run, RunRecord) or run.key is None:
            raise FootfallError("add_run_if_new needs a RunRecord with a key")
        return self._add_run(run, terrains, (), stored_ok=True)

    def _add_run(self, run: RunRecord, terrains: Iterable[HeightMap],
                 demonstrations: Iterable[Demonstration], stored_ok: bool) -> tuple[int, bool]:
        if not isinstance(run, RunRecord):
            raise FootfallError(f"expected a RunRecord, got {type(run).__name__}")
        terrains = list(terrains)
        demos = as_demonstrations(demonstrations)
        with self._write_after_terrains(terrains) as con:
            self._require_terrain(con, run.terrain_hash, "runs")
            held = None if run.key is None else con.execute(
                "SELECT id FROM runs WHERE key = ?", (run.key,)).fetchone()
            if held is not None:
                if stored_ok:
                    return int(held[0]), False
                raise FootfallError(f"a run with key {run.key!r} is already in the store")
            run_id = _insert_run(con, run)
            for d in demos:
                self._insert_demonstration(con, d)
        return run_id, True

    def runs(self, key_prefix: str | None = None) -> list[dict[str, Any]]:
        """Every stored run without its steps: id, key, terrain_hash, seed, settings, result, n_steps.

        ``key_prefix`` keeps only runs whose key starts with it. In creation order.
        """
        if not self._has_table("runs"):
            return []  # a version-1 store, read as it is, has no run logs
        sql = f"SELECT {rows.RUN_COLUMNS} FROM runs"
        params: list[Any] = []
        if key_prefix is not None:
            sql += " WHERE key IS NOT NULL AND substr(key, 1, length(?)) = ?"
            params = [key_prefix, key_prefix]
        with self._errors():
            found = self._connection.execute(sql + " ORDER BY id", params).fetchall()
        out = []
        for row in found:
            try:
                out.append(rows.run_head(row))
            except FootfallError as exc:
                raise FootfallError(f"{self.path}: run {row[0]!r} is corrupt ({exc})") from None
        return out

    def run(self, run_id: int) -> RunRecord:
        """The stored run ``run_id`` with all its steps, validated."""
        run_id = self._check_id(run_id)
        if not self._has_table("runs"):
            raise NotFound(f"run {run_id} is not in the store")
        with self._errors(), self._read() as con:
            head = con.execute(f"SELECT {rows.RUN_COLUMNS} FROM runs WHERE id = ?",
                               (run_id,)).fetchone()
            steps = con.execute(f"SELECT {rows.STEP_COLUMNS} FROM run_steps WHERE run_id = ? "
                                "ORDER BY k", (run_id,)).fetchall()
        if head is None:
            raise NotFound(f"run {run_id} is not in the store")
        try:
            run = rows.run_head(head)
            if run["n_steps"] != len(steps):
                raise FootfallError(f"n_steps is {run['n_steps']} but {len(steps)} steps are "
                                    f"stored; `footfall store check` lists every problem")
            return RunRecord(run["terrain_hash"], run["seed"], run["settings"], run["result"],
                             tuple(rows.run_step(row) for row in steps), run["key"], run_id)
        except FootfallError as exc:
            raise FootfallError(f"{self.path}: run {run_id} is corrupt ({exc})") from None


def _insert_run(con: sqlite3.Connection, run: RunRecord) -> int:
    """Write the run's row and one row per step; return the run's new id."""
    cur = con.execute(
        "INSERT INTO runs (key, terrain_hash, seed, settings, result, n_steps) "
        "VALUES (?, ?, ?, ?, ?, ?)",
        (run.key, run.terrain_hash, int(run.seed), json.dumps(run.settings, sort_keys=True),
         json.dumps(run.result, sort_keys=True), len(run.steps)))
    run_id = int(cur.lastrowid)
    con.executemany(
        f"INSERT INTO run_steps (run_id, {rows.STEP_COLUMNS}) VALUES ({', '.join(['?'] * 19)})",
        [(run_id, st.k, st.swing_leg, *codec.encode(st.state.to_vector()),
          *codec.encode(st.candidates), *codec.encode(st.rewards), st.chosen,
          float(st.t_liftoff), None if math.isnan(st.t_touchdown) else float(st.t_touchdown),
          *codec.encode(st.touchdown), None if math.isnan(st.slip) else float(st.slip))
         for st in run.steps])
    return run_id
