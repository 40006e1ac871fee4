"""What a demonstration store file is: its SQLite tables, its schema version and the migrations
between versions, and the checks that tell a footfall store from a foreign or damaged file.

The functions take an open connection and leave transactions to the caller
(:class:`footfall.data.connection.StoreConnection`), so each change lands whole.
"""

from __future__ import annotations

import functools
import sqlite3
from collections.abc import Callable
from pathlib import Path

from footfall.core.errors import FootfallError

FORMAT = "footfall.demostore"
SCHEMA_VERSION = 5  # 1: terrains and demonstrations; 2: + runs and run_steps; 3: + labels;
# 4: + replaced labels (undo history) and the expert's judgements of runs (the teaching page);
# 5: + the teacher's verdicts on the other candidates of a demonstration, people's "never here"
# marks on the candidates of run steps
SUFFIXES = (".sqlite", ".sqlite3", ".db")  # the file names of a store footfall writes
STATE_LAYOUT = ("feet LF, RF, LH, RH x y z [m] (12), body position x y z [m] (3), "
                "body roll pitch yaw [rad] (3), goal x y [m] (2)")
UNITS = "positions [m], angles [rad], resolution [m/cell]"
_SQLITE_MAGIC = b"SQLite format 3\x00"

# SQLite keeps each CREATE statement's text in the file: changing a character changes every new
# store. A demonstration and a run step hold the same decision (swing leg, state, candidates F).
_DECISION = """\
    swing_leg TEXT NOT NULL,
    state BLOB NOT NULL,               -- RobotState.to_vector(), see meta state_layout
    state_shape TEXT NOT NULL,
    state_dtype TEXT NOT NULL,
    candidates BLOB NOT NULL,          -- (n, 3) x, y, terrain height z [m]
    candidates_shape TEXT NOT NULL,
    candidates_dtype TEXT NOT NULL,"""

DEMONSTRATION_TABLES = (  # one statement each: executescript would COMMIT mid-transaction
    """
CREATE TABLE meta (
    key TEXT PRIMARY KEY,
    value TEXT NOT NULL
)""",
    """
CREATE TABLE terrains (
    hash TEXT PRIMARY KEY,             -- HeightMap.content_hash()
    heights BLOB NOT NULL,             -- raw little-endian array, row-major
    shape TEXT NOT NULL,               -- JSON [nx, ny] [cells]
    dtype TEXT NOT NULL,               -- numpy dtype string, '<f8'
    resolution REAL NOT NULL,          -- [m/cell]
    origin_x REAL NOT NULL,            -- [m] centre of cell (0, 0)
    origin_y REAL NOT NULL,            -- [m]
    frame TEXT NOT NULL,
    metadata TEXT NOT NULL             -- JSON provenance
)""",
    f"""
CREATE TABLE demonstrations (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- creation order, never reused
    terrain_hash TEXT NOT NULL REFERENCES terrains(hash),
{_DECISION}
    n_candidates INTEGER NOT NULL CHECK (n_candidates >= 2),
    chosen INTEGER NOT NULL CHECK (chosen >= 0 AND chosen < n_candidates),
    source TEXT NOT NULL,              -- 'walker', 'run:<id>:step:<k>', 'teacher', ...
    expert TEXT NOT NULL               -- JSON settings of whoever chose
)""",
    "CREATE INDEX demonstrations_terrain ON demonstrations (terrain_hash)",
    "CREATE INDEX demonstrations_source ON demonstrations (source)",
)

RUN_LOG_TABLES = (  # schema version 2: the run logs (added to a version-1 store when opened)
    """
CREATE TABLE runs (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- creation order, never reused
    key TEXT UNIQUE,                   -- optional unique name (resuming experiments), or NULL
    terrain_hash TEXT NOT NULL REFERENCES terrains(hash),
    seed INTEGER NOT NULL,
    settings TEXT NOT NULL,            -- JSON: reward, controller, perturbation settings
    result TEXT NOT NULL,              -- JSON: success, reason, distance [m], time [s], slip [m], ...
    n_steps INTEGER NOT NULL
)""",
    f"""
CREATE TABLE run_steps (
    run_id INTEGER NOT NULL REFERENCES runs(id),
    k INTEGER NOT NULL,                -- step number in the run, from 0
{_DECISION}
    rewards BLOB NOT NULL,             -- (n,) reward of each candidate (-inf: invalid)
    rewards_shape TEXT NOT NULL,
    rewards_dtype TEXT NOT NULL,
    chosen INTEGER NOT NULL,           -- index of the planned foothold
    t_liftoff REAL NOT NULL,           -- [s]
    t_touchdown REAL,                  -- [s], NULL: never touched down
    touchdown BLOB NOT NULL,           -- (3,) foot-centre position at touch-down [m] (NaN: none)
    touchdown_shape TEXT NOT NULL,
    touchdown_dtype TEXT NOT NULL,
    slip REAL,                         -- [m], NULL: the foot did not swing again
    PRIMARY KEY (run_id, k)
)""",
)

LABEL_TABLES = (  # schema version 3: people's labels of run steps (the teaching interface)
    """
CREATE TABLE labels (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- creation order, never reused
    run_id INTEGER NOT NULL REFERENCES runs(id),
    k INTEGER NOT NULL,                -- the labelled step of the run
    labeler TEXT NOT NULL,             -- who labelled (a name the labeler gave)
    verdict TEXT NOT NULL CHECK (verdict IN ('foothold', 'fine')),
    chosen INTEGER,                    -- index in the step's F of the labelled foothold ('fine':
                                       -- the robot's own choice)
    demonstration_id INTEGER UNIQUE REFERENCES demonstrations(id),  -- 'foothold': the
                                       -- demonstration the label made; 'fine': NULL
    created REAL NOT NULL,             -- [s] Unix time the label was stored
    request TEXT UNIQUE,               -- the client's id of the request: a retry is not doubled
    FOREIGN KEY (run_id, k) REFERENCES run_steps(run_id, k)
)""",
    "CREATE INDEX labels_step ON labels (run_id, k)",
)

REVIEW_TABLES = (  # schema version 4: what the teaching page keeps besides the labels
    """
CREATE TABLE replaced_labels (
    id INTEGER PRIMARY KEY,            -- the replaced label's id (restored under it on undo)
    run_id INTEGER NOT NULL REFERENCES runs(id),
    k INTEGER NOT NULL,                -- the labelled step of the run
    labeler TEXT NOT NULL,
    verdict TEXT NOT NULL CHECK (verdict IN ('foothold', 'fine')),
    chosen INTEGER,                    -- index in the step's F (as in labels)
    created REAL NOT NULL,             -- [s] Unix time the label was first stored
    request TEXT UNIQUE,               -- the client's id of the request that made it
    replaced_by INTEGER NOT NULL UNIQUE,  -- the label of the same labeler and step that
                                       -- replaced it: undoing that one restores this one
    FOREIGN KEY (run_id, k) REFERENCES run_steps(run_id, k)
)""",
    """
CREATE TABLE judgements (
    run_id INTEGER NOT NULL REFERENCES runs(id),
    expert TEXT NOT NULL,              -- sha256 of the judging expert's settings and footfall's
                                       -- version: another expert judges anew
    best TEXT NOT NULL,                -- JSON list: the expert's best index in each step's F
    shortfall TEXT NOT NULL,           -- JSON list: the expert's value of its best less that
                                       -- of the robot's choice, per step [value units]
    created REAL NOT NULL,             -- [s] Unix time of the judgement
    PRIMARY KEY (run_id, expert)
)""",
)

VERDICT_TABLES = (  # schema version 5: what a teacher said of the candidates it did not choose
    """
CREATE TABLE verdicts (
    demonstration_id INTEGER PRIMARY KEY REFERENCES demonstrations(id),
    teacher_values BLOB,               -- (n,) the teacher's value of each candidate of F [its
                                       -- value units, higher better]; NULL: it gave none
    values_shape TEXT,
    values_dtype TEXT,
    refused BLOB,                      -- (n,) 1 where the teacher refuses the candidate outright
                                       -- ("never here"), else 0; NULL: it said nothing of them
    refused_shape TEXT,
    refused_dtype TEXT,
    judged BLOB,                       -- (n,) the values the refusals are relative to [value
                                       -- units]: refused where more than the teacher's margin
                                       -- below their best; NULL: not given
    judged_shape TEXT,
    judged_dtype TEXT
)""",
)

MARK_TABLES = (  # schema version 5: people's "never here" marks on run steps' candidates
    """
CREATE TABLE marks (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- creation order, never reused
    run_id INTEGER NOT NULL REFERENCES runs(id),
    k INTEGER NOT NULL,                -- the marked step of the run
    labeler TEXT NOT NULL,             -- who marked (a name the labeler gave)
    candidate INTEGER NOT NULL,        -- index in the step's F of the candidate refused outright
    created REAL NOT NULL,             -- [s] Unix time the mark was stored
    request TEXT UNIQUE,               -- the client's id of the request: a retry is not doubled
    UNIQUE (run_id, k, labeler, candidate),  -- one mark per labeler and candidate of a step
    FOREIGN KEY (run_id, k) REFERENCES run_steps(run_id, k)
)""",
)


# ---------------------------------------------------------------- a new store
def create(con: sqlite3.Connection, created_by: str) -> None:
    """Create every table of the current schema and its ``meta`` rows (inside the caller's write)."""
    for statement in (DEMONSTRATION_TABLES + RUN_LOG_TABLES + LABEL_TABLES + REVIEW_TABLES
                      + VERDICT_TABLES + MARK_TABLES):
        con.execute(statement)
    con.executemany("INSERT INTO meta (key, value) VALUES (?, ?)",
                    [("format", FORMAT), ("schema_version", str(SCHEMA_VERSION)),
                     ("created_by", created_by), ("state_layout", STATE_LAYOUT),
                     ("units", UNITS)])


# ----------------------------------------------------------------- migrations
def _add_run_log(con: sqlite3.Connection) -> None:
    """Version 1 -> 2: the run-log tables; the demonstrations are untouched."""
    if not has_table(con, "runs"):
        for statement in RUN_LOG_TABLES:
            con.execute(statement)


def _add_labels(con: sqlite3.Connection) -> None:
    """Version 2 -> 3: the labels table; demonstrations and runs are untouched."""
    if not has_table(con, "labels"):
        for statement in LABEL_TABLES:
            con.execute(statement)


def _add_review(con: sqlite3.Connection) -> None:
    """Version 3 -> 4: replaced labels and judgements; every other table is untouched."""
    if not has_table(con, "judgements"):
        for statement in REVIEW_TABLES:
            con.execute(statement)


def _add_verdicts(con: sqlite3.Connection) -> None:
    """Version 4 -> 5: the verdicts and marks tables; every other table is untouched."""
    if not has_table(con, "verdicts"):
        for statement in VERDICT_TABLES:
            con.execute(statement)
    if not has_table(con, "marks"):
        for statement in MARK_TABLES:
            con.execute(statement)


# version v -> the step that makes a version-v store a version-(v + 1) store
MIGRATIONS: dict[int, Callable[[sqlite3.Connection], None]] = {1: _add_run_log, 2: _add_labels,
                                                               3: _add_review, 4: _add_verdicts}


def migrate(con: sqlite3.Connection, version: int) -> None:
    """Upgrade a version-``version`` store by one version (inside the caller's write transaction).

    Another process may have upgraded the file since its version was read: the
    stored version is read again under the write lock, and only a store still
    at ``version`` is changed.
    """
    row = con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
    if row is not None and row[0] == str(version):
        MIGRATIONS[version](con)
        con.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'", (str(version + 1),))


# --------------------------------------------------------------------- checks
def check_header(path: Path) -> None:
    """Refuse a file that is not an SQLite database before SQLite touches it.

    Raises
    ------
    FootfallError
        For an unreadable or empty file, or one without the SQLite header.
    """
    try:
        with open(path, "rb") as fh:
            head = fh.read(len(_SQLITE_MAGIC))
    except OSError as exc:
        raise FootfallError(f"{path}: cannot read ({exc.strerror})") from None
    if not head:
        raise FootfallError(f"{path}: empty file, not a footfall demonstration store")
    if head != _SQLITE_MAGIC:
        raise FootfallError(f"{path}: not a footfall demonstration store "
                            f"(not an SQLite database)")


def has_table(con: sqlite3.Connection, name: str) -> bool:
    """Whether the database holds a table called ``name``."""
    return con.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?",
                       (name,)).fetchone() is not None


def is_empty(con: sqlite3.Connection) -> bool:
    """Whether the database holds no object at all (a new file, or one SQLite just made)."""
    return not con.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]


def stored_version(con: sqlite3.Connection, path: Path) -> int:
    """The schema version a footfall store declares in its ``meta`` table, checked.

    Raises
    ------
    FootfallError
        For another format, a version that is not a number >= 1, or one newer
        than :data:`SCHEMA_VERSION` (this footfall cannot read it).
    """
    rows = dict(con.execute("SELECT key, value FROM meta").fetchall())
    if rows.get("format") != FORMAT:
        raise FootfallError(f"{path}: not a footfall demonstration store "
                            f"(format {rows.get('format')!r})")
    try:
        version = int(rows.get("schema_version", ""))
    except ValueError:
        raise FootfallError(f"{path}: corrupt demonstration store "
                            f"(schema version {rows.get('schema_version')!r})") from None
    if version > SCHEMA_VERSION:
        raise FootfallError(f"{path}: demonstration store schema version {version} is "
                            f"newer than this footfall reads ({SCHEMA_VERSION}); "
                            f"upgrade footfall")
    if version < 1:
        raise FootfallError(f"{path}: corrupt demonstration store "
                            f"(schema version {version})")
    return version


def check_pages(con: sqlite3.Connection, path: Path) -> None:
    """SQLite's ``quick_check`` of every page of the file.

    Raises
    ------
    FootfallError
        If SQLite finds the file damaged.
    """
    problems = [r[0] for r in con.execute("PRAGMA quick_check")]
    if problems != ["ok"]:
        raise FootfallError(f"{path}: corrupt demonstration store ({problems[0]})")


# ---------------------------------------------------------- the schema's objects
def _tables(version: int) -> tuple[str, ...]:
    """The CREATE statements of a version-``version`` store."""
    return (DEMONSTRATION_TABLES + (RUN_LOG_TABLES if version >= 2 else ())
            + (LABEL_TABLES if version >= 3 else ()) + (REVIEW_TABLES if version >= 4 else ())
            + (VERDICT_TABLES + MARK_TABLES if version >= 5 else ()))


def _objects(con: sqlite3.Connection) -> dict[tuple[str, str], tuple]:
    """Every object of a database as {(type, name): its shape}: a table's columns (name,
    declared type, NOT NULL, default, primary-key position) and foreign keys, an index's table
    and columns; a trigger's or view's table."""
    out: dict[tuple[str, str], tuple] = {}
    for kind, name, table in con.execute("SELECT type, name, tbl_name FROM sqlite_master"):
        if kind == "table":
            columns = tuple(con.execute('SELECT name, upper(type), "notnull", dflt_value, pk '
                                        "FROM pragma_table_info(?)", (name,)))
            keys = tuple(con.execute('SELECT "table", "from", "to" FROM pragma_foreign_key_list(?)',
                                     (name,)))
            out[(kind, name)] = (columns, keys)
        elif kind == "index":
            out[(kind, name)] = (table, tuple(c for (c,) in con.execute(
                "SELECT name FROM pragma_index_info(?) ORDER BY seqno", (name,))))
        else:
            out[(kind, name)] = (table,)
    return out


@functools.lru_cache(maxsize=None)
def expected_objects(version: int) -> dict[tuple[str, str], tuple]:
    """The objects (:func:`_objects`) footfall makes in a store of schema ``version``."""
    con = sqlite3.connect(":memory:")
    try:
        for statement in _tables(version):
            con.execute(statement)
        return _objects(con)
    finally:
        con.close()


def schema_problems(con: sqlite3.Connection, version: int) -> list[str]:
    """What differs from the schema footfall makes: one message per object, naming it.

    A trigger or a view is never part of a store (a trigger could delete or
    rewrite rows behind a writer's back); neither is any table or index
    footfall did not make, and each of footfall's must have its columns.
    """
    expected, found = expected_objects(version), _objects(con)
    problems = []
    for (kind, name), shape in found.items():
        if kind in ("trigger", "view"):
            on = f" on table {shape[0]!r}" if kind == "trigger" else ""
            problems.append(f"{kind} {name!r}{on} is not part of a footfall store "
                            f"(remove it: DROP {kind.upper()} \"{name}\")")
        elif (kind, name) not in expected:
            problems.append(f"unknown {kind} {name!r} is not part of a footfall store")
        elif shape != expected[(kind, name)]:
            problems.append(f"{kind} {name!r} does not have the columns footfall makes")
    problems += [f"{kind} {name!r} is missing" for kind, name in expected
                 if (kind, name) not in found]
    return problems
