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

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES
from footfall.core.state import RobotState
from footfall.data import codec
from footfall.data.demonstration import Demonstration, as_demonstrations
from footfall.data.runlog import RunRecord, RunStep
from footfall.data.terrain_queries import TerrainQueries

_STEP_COLUMNS = ("k, swing_leg, state, state_shape, state_dtype, candidates, candidates_shape, "
                 "candidates_dtype, rewards, rewards_shape, rewards_dtype, chosen, t_liftoff, "
                 "t_touchdown, touchdown, touchdown_shape, touchdown_dtype, slip")


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
        if not isinstance(run, RunRecord):
            raise FootfallError(f"expected a RunRecord, got {type(run).__name__}")
        terrains = list(terrains)
        demos = as_demonstrations(demonstrations)
        with self._write_after_terrains(terrains) as con:
            self._require_terrain(con, run.terrain_hash, "runs")
            if run.key is not None and con.execute("SELECT 1 FROM runs WHERE key = ?",
                                                   (run.key,)).fetchone() is not None:
                raise FootfallError(f"a run with key {run.key!r} is already in the store")
            run_id = _insert_run(con, run)
            for d in demos:
                self._insert_demonstration(con, d)
        return run_id

    def runs(self, key_prefix: str | None = None) -> list[dict[str, Any]]:
        """Every stored run without its steps: id, key, terrain_hash, seed, settings, result, n_steps.

        ``key_prefix`` keeps only runs whose key starts with it. In creation order.
        """
        sql = "SELECT id, key, terrain_hash, seed, settings, result, n_steps FROM runs"
        params: list[Any] = []
        if key_prefix is not None:
            sql += " WHERE key IS NOT NULL AND substr(key, 1, length(?)) = ?"
            params = [key_prefix, key_prefix]
        with self._errors():
            rows = self._connection.execute(sql + " ORDER BY id", params).fetchall()
        out = []
        for id_, key, th, seed, settings, result, n in rows:
            try:
                out.append({"id": int(id_), "key": key, "terrain_hash": th, "seed": int(seed),
                            "settings": json.loads(settings), "result": json.loads(result),
                            "n_steps": int(n)})
            except (TypeError, ValueError) as exc:
                raise FootfallError(f"{self.path}: run {id_} is corrupt ({exc})") from None
        return out

    def run(self, run_id: int) -> RunRecord:
        """The stored run ``run_id`` with all its steps, validated."""
        run_id = self._check_id(run_id)
        with self._errors(), self._read() as con:
            head = con.execute("SELECT key, terrain_hash, seed, settings, result FROM runs "
                               "WHERE id = ?", (run_id,)).fetchone()
            rows = con.execute(f"SELECT {_STEP_COLUMNS} FROM run_steps WHERE run_id = ? "
                               "ORDER BY k", (run_id,)).fetchall()
        if head is None:
            raise FootfallError(f"run {run_id} is not in the store")
        try:
            steps = tuple(_step_from_row(row) for row in rows)
            key, th, seed, settings, result = head
            return RunRecord(th, int(seed), json.loads(settings), json.loads(result), steps,
                             key, run_id)
        except (FootfallError, TypeError, ValueError) as exc:
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
        f"INSERT INTO run_steps (run_id, {_STEP_COLUMNS}) VALUES ({', '.join(['?'] * 19)})",
        [(run_id, st.k, st.swing_leg, *codec.encode(st.state.to_vector()),
          *codec.encode(st.candidates), *codec.encode(st.rewards), st.chosen,
          float(st.t_liftoff), None if math.isnan(st.t_touchdown) else float(st.t_touchdown),
          *codec.encode(st.touchdown), None if math.isnan(st.slip) else float(st.slip))
         for st in run.steps])
    return run_id


def _step_from_row(row: tuple) -> RunStep:
    """A run step from its ``run_steps`` row (the columns of ``_STEP_COLUMNS``)."""
    k, leg, st, st_s, st_d, c, c_s, c_d, r, r_s, r_d, chosen, t0, t1, td, td_s, td_d, slip = row
    if leg not in LEG_NAMES:
        raise FootfallError(f"unknown swing leg {leg!r}")
    state = RobotState.from_vector(codec.decode(st, st_s, st_d, "a state"), leg)
    return RunStep(int(k), state, codec.decode(c, c_s, c_d, "candidates"),
                   codec.decode(r, r_s, r_d, "rewards"), int(chosen), float(t0),
                   math.nan if t1 is None else float(t1),
                   codec.decode(td, td_s, td_d, "a touch-down"),
                   math.nan if slip is None else float(slip))
