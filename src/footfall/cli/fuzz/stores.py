"""The fuzz target of demonstration stores: rows of the wrong type, foreign schema objects,
dropped tables and damaged bytes, then a read, ``store check``, ``demos info`` or a write."""

from __future__ import annotations

import shutil
import sqlite3
from collections.abc import Callable
from pathlib import Path

from hypothesis import strategies as st

from footfall.cli.fuzz import craft, values
from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import cli_work
from footfall.cli.fuzz.oracles import check_demonstrations, check_runs
from footfall.cli.fuzz.targets import Target, register_target

_TABLES = ("meta", "terrains", "demonstrations", "runs", "run_steps")
FOREIGN_DDL = {
    "trigger": "CREATE TRIGGER fuzz_t AFTER INSERT ON demonstrations BEGIN "
               "DELETE FROM demonstrations; END",
    "view": "CREATE VIEW fuzz_v AS SELECT 1",
    "table": "CREATE TABLE fuzz_table (x)",
    "index": "CREATE INDEX fuzz_i ON demonstrations (chosen)",
}
_store_mutation = st.one_of(
    st.tuples(st.just("cell"), st.sampled_from(_TABLES), st.integers(0, 10 ** 6),
              st.integers(0, 10 ** 6), values.sql_value),
    st.tuples(st.just("ddl"), st.sampled_from(sorted(FOREIGN_DDL))),
    st.tuples(st.just("drop"), st.sampled_from(_TABLES)),
    st.tuples(st.just("bytes"), st.sampled_from(["flip", "truncate", "zero_run"]),
              st.integers(0, 2 ** 31 - 1)),
)
store_cases = st.tuples(st.lists(_store_mutation, min_size=1, max_size=3),
                        st.sampled_from(["read", "check", "info", "collect"]))


def _edit_store(path: Path, mutations: list) -> bool:
    """Apply the SQL mutations to the store at ``path``; whether a foreign object was added."""
    foreign = False
    con = sqlite3.connect(path, isolation_level=None)
    try:
        for m in mutations:
            if m[0] == "cell":
                _, table, row, column, value = m
                cols = [r[1] for r in con.execute(f"PRAGMA table_info({table})")]
                ids = [r[0] for r in con.execute(f"SELECT rowid FROM {table}")]
                if cols and ids:
                    con.execute(f"UPDATE {table} SET {cols[column % len(cols)]} = ? "
                                f"WHERE rowid = ?", (value, ids[row % len(ids)]))
            elif m[0] == "ddl":
                con.execute(FOREIGN_DDL[m[1]])
                foreign = True
            elif m[0] == "drop":
                con.execute("PRAGMA foreign_keys = OFF")
                con.execute(f"DROP TABLE IF EXISTS {m[1]}")
    except (sqlite3.Error, OverflowError):
        pass  # a mutation SQLite refuses is simply not made
    finally:
        con.close()
    return foreign


def _store_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    mutations, action = case

    def work() -> None:
        path = scratch / "store.sqlite"
        shutil.copyfile(bases.store, path)
        foreign = _edit_store(path, [m for m in mutations if m[0] != "bytes"])
        for _, edit, k in (m for m in mutations if m[0] == "bytes"):
            path.write_bytes(craft.patch_zip(path.read_bytes(), edit, k))
        if action == "read":
            check_demonstrations(path)
            check_runs(path)
        elif action == "check":  # a store the check passes must read as valid
            cli_work(["store", "check", str(path)], must_refuse=foreign)()
            check_demonstrations(path)
            check_runs(path)
        elif action == "info":
            cli_work(["demos", "info", str(path)], must_refuse=False)()
        else:
            cli_work(["demos", "collect", "--terrain", str(bases.map), "-n", "1", "--seed", "3",
                      "-o", str(path)], must_refuse=foreign)()
    return work


register_target(Target("store", store_cases, _store_work, seconds=20.0))
