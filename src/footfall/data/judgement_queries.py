"""The store's judgements: the synthetic expert's verdict on every step of a logged run, kept so
that the teaching page judges a run once per store, not once per server start.

A judgement is keyed by the run and by the expert that judged (a hash of its
settings and of footfall's version: another expert, or another footfall,
judges anew). It holds, per step, the index of the expert's best candidate
in the step's F and the expert's shortfall of the robot's choice [value units].
"""

from __future__ import annotations

import json
import time

import numpy as np

from footfall.core.errors import FootfallError
from footfall.data.connection import StoreConnection


class JudgementQueries(StoreConnection):
    """Read and keep judgements (part of :class:`footfall.data.store.DemoStore`)."""

    def judgement(self, run_id: int, expert: str) -> tuple[np.ndarray, np.ndarray] | None:
        """The kept judgement of run ``run_id`` by ``expert`` (its key): (best index per step,
        shortfall per step [value units], NaN where not defined); None if none is kept."""
        if not self._has_table("judgements"):
            return None  # an older store read as it is
        with self._errors():
            row = self._connection.execute(
                "SELECT best, shortfall FROM judgements WHERE run_id = ? AND expert = ?",
                (int(run_id), str(expert))).fetchone()
        if row is None:
            return None
        try:
            best = np.asarray(json.loads(row[0]), dtype=np.int64)
            shortfall = np.asarray([np.nan if v is None else v for v in json.loads(row[1])],
                                   dtype=np.float64)
        except (ValueError, TypeError):
            raise FootfallError(f"{self.path}: corrupt judgement of run {run_id}") from None
        if best.ndim != 1 or best.shape != shortfall.shape:
            raise FootfallError(f"{self.path}: corrupt judgement of run {run_id}")
        return best, shortfall

    def keep_judgement(self, run_id: int, expert: str, best: np.ndarray,
                       shortfall: np.ndarray) -> None:
        """Keep (or replace) the judgement of run ``run_id`` by ``expert``, in one transaction."""
        best = np.asarray(best, dtype=np.int64).reshape(-1)
        shortfall = np.asarray(shortfall, dtype=np.float64).reshape(-1)
        if best.shape != shortfall.shape:
            raise FootfallError("a judgement has one best index and one shortfall per step")
        if not self._has_table("judgements"):
            raise FootfallError(f"{self.path}: this store was opened read-only at schema "
                                f"version {self.schema_version}; judgements need version 4")
        short = [None if not np.isfinite(v) else float(v) for v in shortfall]
        with self._errors(), self._write() as con:
            con.execute("INSERT OR REPLACE INTO judgements (run_id, expert, best, shortfall, "
                        "created) VALUES (?, ?, ?, ?, ?)",
                        (int(run_id), str(expert), json.dumps(best.tolist()), json.dumps(short),
                         time.time()))
