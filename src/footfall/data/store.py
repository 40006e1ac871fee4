"""The demonstration store: expert-chosen footholds in one embedded SQLite file.

Walkers, walking runs and the teaching interface add demonstrations (paper
§II-B) to the same store while learners read it; every write is one SQLite
transaction in WAL mode, so readers never see half a demonstration. The
same file keeps the run logs of the simulated robot (:mod:`footfall.data.runlog`):
a whole run, with all its steps, is one transaction.
"""

from __future__ import annotations

import contextlib
import json
import math
import numbers
import os
import re
import sqlite3
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import checked_json
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES
from footfall.core.state import RobotState
from footfall.data.runlog import RunRecord, RunStep

FORMAT = "footfall.demostore"
SCHEMA_VERSION = 2  # 1: terrains and demonstrations; 2: + runs and run_steps
DEFAULT_BUSY_TIMEOUT = 30.0  # [s] how long a write waits for another writer's lock
_SQLITE_MAGIC = b"SQLite format 3\x00"
_DTYPE = "<f8"  # every array is stored as little-endian float64, nothing else is read
_HASH_RE = re.compile(r"^[0-9a-f]{64}$")
STATE_LAYOUT = ("feet LF, RF, LH, RH x y z [m] (12), body position x y z [m] (3), "
                "body roll pitch yaw [rad] (3), goal x y [m] (2)")

_SCHEMA = (  # one statement each: executescript would COMMIT mid-transaction
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
    """
CREATE TABLE demonstrations (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- creation order, never reused
    terrain_hash TEXT NOT NULL REFERENCES terrains(hash),
    swing_leg TEXT NOT NULL,
    state BLOB NOT NULL,               -- RobotState.to_vector(), see meta state_layout
    state_shape TEXT NOT NULL,
    state_dtype TEXT NOT NULL,
    candidates BLOB NOT NULL,          -- (n, 3) x, y, terrain height z [m]
    candidates_shape TEXT NOT NULL,
    candidates_dtype TEXT NOT NULL,
    n_candidates INTEGER NOT NULL CHECK (n_candidates >= 2),
    chosen INTEGER NOT NULL CHECK (chosen >= 0 AND chosen < n_candidates),
    source TEXT NOT NULL,              -- 'walker', 'run:<id>:step:<k>', 'teacher', ...
    expert TEXT NOT NULL               -- JSON settings of whoever chose
)""",
    "CREATE INDEX demonstrations_terrain ON demonstrations (terrain_hash)",
    "CREATE INDEX demonstrations_source ON demonstrations (source)",
)

_RUN_SCHEMA = (  # schema version 2: the run logs (added to a version-1 store when opened)
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
    """
CREATE TABLE run_steps (
    run_id INTEGER NOT NULL REFERENCES runs(id),
    k INTEGER NOT NULL,                -- step number in the run, from 0
    swing_leg TEXT NOT NULL,
    state BLOB NOT NULL,               -- RobotState.to_vector(), see meta state_layout
    state_shape TEXT NOT NULL,
    state_dtype TEXT NOT NULL,
    candidates BLOB NOT NULL,          -- (n, 3) x, y, terrain height z [m]
    candidates_shape TEXT NOT NULL,
    candidates_dtype TEXT NOT NULL,
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


@dataclass(frozen=True, eq=False)
class Demonstration:
    """One demonstrated foothold: in ``state`` on terrain ``terrain_hash``, ``chosen`` of F.

    Parameters
    ----------
    terrain_hash : str
        :meth:`HeightMap.content_hash` of the terrain (64 hex digits).
    state : RobotState
        The robot's state at the decision; ``state.swing_leg`` is the leg that moves.
    candidates : array of shape (n, 3)
        The candidate set F: x, y and terrain height z [m] of each reachable
        foothold, n >= 2, finite.
    chosen : int
        Index in ``candidates`` of the foothold the expert chose, in [0, n).
    source : str
        Where it came from: ``"walker"``, ``"run:<id>:step:<k>"``, ``"teacher"``.
    expert : dict
        JSON-serialisable settings of the expert that chose (a private copy is kept).
    id : int or None
        Row id in a :class:`DemoStore` (creation order); None until stored.
    """

    terrain_hash: str
    state: RobotState
    candidates: np.ndarray  # (n, 3) [m] x, y, terrain height
    chosen: int  # index into candidates
    source: str = "walker"
    expert: dict = field(default_factory=dict)
    id: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.terrain_hash, str) or not _HASH_RE.match(self.terrain_hash):
            raise FootfallError(f"terrain hash must be 64 lowercase hex digits, "
                                f"got {self.terrain_hash!r}")
        if not isinstance(self.state, RobotState):
            raise FootfallError(f"state must be a RobotState, got {type(self.state).__name__}")
        try:
            cand = np.array(self.candidates, dtype=np.float64)
        except (TypeError, ValueError):
            raise FootfallError("candidates must be an (n, 3) array of numbers") from None
        if cand.ndim != 2 or cand.shape[1] != 3 or cand.shape[0] < 2:
            raise FootfallError(f"candidates must have shape (n, 3) with n >= 2, got {cand.shape}")
        if not np.isfinite(cand).all():
            raise FootfallError("candidates must be finite")
        chosen = self.chosen
        if isinstance(chosen, bool) or not isinstance(chosen, numbers.Integral):
            raise FootfallError(f"chosen must be an integer index, got {chosen!r}")
        if not 0 <= int(chosen) < cand.shape[0]:
            raise FootfallError(f"chosen index {chosen} is outside the {cand.shape[0]} candidates")
        if not isinstance(self.source, str) or not self.source.strip():
            raise FootfallError(f"source must be a non-empty string, got {self.source!r}")
        if not isinstance(self.expert, dict):
            raise FootfallError(f"expert settings must be a dict, got {type(self.expert).__name__}")
        if self.id is not None and (isinstance(self.id, bool)
                                    or not isinstance(self.id, numbers.Integral)):
            raise FootfallError(f"id must be an integer or None, got {self.id!r}")
        cand.setflags(write=False)
        object.__setattr__(self, "candidates", cand)
        object.__setattr__(self, "chosen", int(chosen))
        object.__setattr__(self, "expert", checked_json(self.expert, "expert settings"))
        object.__setattr__(self, "id", None if self.id is None else int(self.id))

    @property
    def swing_leg(self) -> str:
        """The leg that moves (``state.swing_leg``)."""
        return self.state.swing_leg

    @property
    def n_candidates(self) -> int:
        """Number of candidate footholds n."""
        return int(self.candidates.shape[0])

    @property
    def foothold(self) -> np.ndarray:
        """The chosen foothold, shape (3,): x, y, terrain height [m]."""
        return self.candidates[self.chosen]


# ------------------------------------------------------------------ encoding
def _encode(array: np.ndarray) -> tuple[bytes, str, str]:
    a = np.ascontiguousarray(array, dtype=_DTYPE)
    return a.tobytes(), json.dumps(list(a.shape)), _DTYPE


def _decode(blob: bytes, shape_json: str, dtype: str, what: str) -> np.ndarray:
    """Rebuild an array from its blob; any inconsistency is a corrupt store."""
    if dtype != _DTYPE:
        raise FootfallError(f"{what} has unsupported dtype {dtype!r}")
    try:
        shape = json.loads(shape_json)
    except (TypeError, ValueError):
        raise FootfallError(f"{what} has a malformed shape {shape_json!r}") from None
    if (not isinstance(shape, list) or not all(isinstance(s, int) and not isinstance(s, bool)
                                               and s >= 0 for s in shape)):
        raise FootfallError(f"{what} has a malformed shape {shape_json!r}")
    if not isinstance(blob, bytes) or len(blob) != math.prod(shape) * np.dtype(dtype).itemsize:
        raise FootfallError(f"{what} holds {len(blob) if isinstance(blob, bytes) else 'no'} "
                            f"bytes, not the {math.prod(shape)} numbers of shape {tuple(shape)}")
    return np.frombuffer(blob, dtype=dtype).reshape(shape)


def _sql_text(value: Any, what: str) -> str:
    if not isinstance(value, str):
        raise FootfallError(f"{what} is not text")
    return value


# --------------------------------------------------------------------- store
class DemoStore:
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

    Raises
    ------
    FootfallError
        For a missing file (without ``create``), a file that is not a footfall
        demonstration store, a corrupt one, or one of a newer schema version.
    """

    def __init__(self, path: str | os.PathLike, create: bool = False,
                 busy_timeout: float = DEFAULT_BUSY_TIMEOUT) -> None:
        self.path = Path(path)
        self.schema_version = SCHEMA_VERSION  # of the open file, set by _check_meta
        self._con: sqlite3.Connection | None = None
        self._terrains: dict[str, HeightMap] = {}  # verified terrains, by hash
        if not (isinstance(busy_timeout, numbers.Real) and busy_timeout >= 0):
            raise FootfallError(f"busy timeout must be >= 0 s, got {busy_timeout!r}")
        exists = self.path.exists()
        if exists and not self.path.is_file():
            raise FootfallError(f"{self.path}: not a file")
        if not exists:
            if not create:
                raise FootfallError(f"no such file: {self.path}")
            if not self.path.parent.is_dir():
                raise FootfallError(f"output directory does not exist: {self.path.parent}")
        else:
            self._check_header()
        try:
            # isolation_level=None: no implicit transactions; each write opens its own.
            self._con = sqlite3.connect(self.path, timeout=float(busy_timeout),
                                        isolation_level=None)
        except sqlite3.Error as exc:
            raise FootfallError(f"{self.path}: cannot open ({exc})") from None
        try:
            with self._errors():
                self._con.execute("PRAGMA foreign_keys = ON")
                if not self._has_table(self._con, "meta"):
                    self._initialise(create)
                self._check_meta()
                # Persistent: WAL lets readers and one writer work at the same time.
                if self._con.execute("PRAGMA journal_mode").fetchone()[0].lower() != "wal":
                    self._con.execute("PRAGMA journal_mode = WAL")
        except BaseException:
            self.close()
            raise

    # -------------------------------------------------------------- lifecycle
    def close(self) -> None:
        """Close the connection (idempotent)."""
        if self._con is not None:
            self._con.close()
            self._con = None

    def __enter__(self) -> DemoStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __len__(self) -> int:
        return self.count()

    def __repr__(self) -> str:
        return f"DemoStore({str(self.path)!r})"

    # --------------------------------------------------------------- plumbing
    def _check_header(self) -> None:
        try:
            with open(self.path, "rb") as fh:
                head = fh.read(len(_SQLITE_MAGIC))
        except OSError as exc:
            raise FootfallError(f"{self.path}: cannot read ({exc.strerror})") from None
        if not head:
            raise FootfallError(f"{self.path}: empty file, not a footfall demonstration store")
        if head != _SQLITE_MAGIC:
            raise FootfallError(f"{self.path}: not a footfall demonstration store "
                                f"(not an SQLite database)")

    @contextlib.contextmanager
    def _errors(self) -> Iterator[None]:
        """Turn SQLite errors into one-line :class:`FootfallError` messages."""
        try:
            yield
        except (sqlite3.OperationalError, sqlite3.IntegrityError) as exc:  # locked, read-only, ...
            raise FootfallError(f"{self.path}: {exc}") from None
        except sqlite3.DatabaseError as exc:  # malformed image, not a database, ...
            raise FootfallError(f"{self.path}: corrupt demonstration store ({exc})") from None

    @property
    def _connection(self) -> sqlite3.Connection:
        if self._con is None:
            raise FootfallError(f"demonstration store {self.path} is closed")
        return self._con

    @contextlib.contextmanager
    def _write(self) -> Iterator[sqlite3.Connection]:
        """One write transaction: commit on success, roll back on any exception."""
        con = self._connection
        con.execute("BEGIN IMMEDIATE")  # take the write lock now: no upgrade deadlocks
        try:
            yield con
        except BaseException:
            if con.in_transaction:
                con.execute("ROLLBACK")
            raise
        else:
            try:
                con.execute("COMMIT")
            except BaseException:
                if con.in_transaction:
                    con.execute("ROLLBACK")
                raise

    @contextlib.contextmanager
    def _read(self) -> Iterator[sqlite3.Connection]:
        """One read transaction: several queries see the same snapshot."""
        con = self._connection
        con.execute("BEGIN")
        try:
            yield con
        finally:
            if con.in_transaction:
                con.execute("COMMIT")

    @staticmethod
    def _has_table(con: sqlite3.Connection, name: str) -> bool:
        return con.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?",
                           (name,)).fetchone() is not None

    def _initialise(self, create: bool) -> None:
        """Create the schema in a new (empty) database, in one transaction."""
        con = self._connection
        if not create or con.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]:
            raise FootfallError(f"{self.path}: not a footfall demonstration store "
                                f"(no footfall metadata)")
        con.execute("PRAGMA journal_mode = WAL")  # before the first write: no journal swap
        from footfall import __version__

        with self._write():
            if self._has_table(con, "meta"):  # another process initialised it meanwhile
                return
            for statement in _SCHEMA + _RUN_SCHEMA:
                con.execute(statement)
            con.executemany("INSERT INTO meta (key, value) VALUES (?, ?)",
                            [("format", FORMAT), ("schema_version", str(SCHEMA_VERSION)),
                             ("created_by", f"footfall {__version__}"),
                             ("state_layout", STATE_LAYOUT),
                             ("units", "positions [m], angles [rad], resolution [m/cell]")])

    def _check_meta(self) -> None:
        rows = dict(self._connection.execute("SELECT key, value FROM meta").fetchall())
        if rows.get("format") != FORMAT:
            raise FootfallError(f"{self.path}: not a footfall demonstration store "
                                f"(format {rows.get('format')!r})")
        try:
            version = int(rows.get("schema_version", ""))
        except ValueError:
            raise FootfallError(f"{self.path}: corrupt demonstration store "
                                f"(schema version {rows.get('schema_version')!r})") from None
        if version > SCHEMA_VERSION:
            raise FootfallError(f"{self.path}: demonstration store schema version {version} is "
                                f"newer than this footfall reads ({SCHEMA_VERSION}); "
                                f"upgrade footfall")
        if version < 1:
            raise FootfallError(f"{self.path}: corrupt demonstration store "
                                f"(schema version {version})")
        if version == 1:
            self._upgrade_to_2()
            version = 2
        self.schema_version = version

    def _upgrade_to_2(self) -> None:
        """Add the run-log tables to a version-1 store (one transaction; data untouched)."""
        con = self._connection
        with self._write():
            row = con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
            if row is not None and row[0] == "1":  # not upgraded meanwhile by another process
                if not self._has_table(con, "runs"):
                    for statement in _RUN_SCHEMA:
                        con.execute(statement)
                con.execute("UPDATE meta SET value = '2' WHERE key = 'schema_version'")

    # --------------------------------------------------------------- terrains
    def add_terrain(self, hmap: HeightMap) -> str:
        """Store a terrain once (its first metadata wins); return its content hash.

        Parameters
        ----------
        hmap : HeightMap
            The terrain. Adding a map whose content hash is already stored
            changes nothing.

        Returns
        -------
        str
            ``hmap.content_hash()``.
        """
        with self._errors(), self._write() as con:
            return self._insert_terrain(con, hmap)

    def _insert_terrain(self, con: sqlite3.Connection, hmap: HeightMap) -> str:
        if not isinstance(hmap, HeightMap):
            raise FootfallError(f"a terrain must be a HeightMap, got {type(hmap).__name__}")
        digest = hmap.content_hash()
        if con.execute("SELECT 1 FROM terrains WHERE hash = ?", (digest,)).fetchone() is None:
            blob, shape, dtype = _encode(hmap.heights)
            try:
                metadata = json.dumps(hmap.metadata, sort_keys=True)
            except (TypeError, ValueError) as exc:
                raise FootfallError(f"terrain metadata must be JSON-serialisable ({exc})") from None
            con.execute("INSERT INTO terrains (hash, heights, shape, dtype, resolution, origin_x, "
                        "origin_y, frame, metadata) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                        (digest, blob, shape, dtype, hmap.resolution, hmap.origin[0],
                         hmap.origin[1], hmap.frame, metadata))
        return digest

    def terrain(self, terrain_hash: str) -> HeightMap:
        """The stored terrain with this content hash, verified against the hash.

        Raises
        ------
        FootfallError
            If it is not in the store, or its stored heights and geometry no
            longer give ``terrain_hash`` (corrupt).
        """
        if terrain_hash in self._terrains:
            return self._terrains[terrain_hash]
        with self._errors():
            row = self._connection.execute(
                "SELECT heights, shape, dtype, resolution, origin_x, origin_y, frame, metadata "
                "FROM terrains WHERE hash = ?", (terrain_hash,)).fetchone()
        if row is None:
            raise FootfallError(f"terrain {terrain_hash} is not in the store")
        what = f"{self.path}: terrain {terrain_hash}"
        blob, shape, dtype, resolution, ox, oy, frame, metadata = row
        try:
            heights = _decode(blob, shape, dtype, what)
            meta = json.loads(_sql_text(metadata, "its metadata"))
            if not isinstance(meta, dict):
                raise FootfallError("its metadata is not a JSON object")
            hmap = HeightMap(heights, resolution, (ox, oy), _sql_text(frame, "its frame"), meta)
        except (FootfallError, TypeError, ValueError) as exc:
            raise FootfallError(f"{what} is corrupt ({exc})") from None
        if hmap.content_hash() != terrain_hash:
            raise FootfallError(f"{what} is corrupt (its content hash does not match)")
        self._terrains[terrain_hash] = hmap
        return hmap

    def terrain_hashes(self) -> list[str]:
        """Content hashes of every stored terrain, in the order they were added."""
        with self._errors():
            return [h for (h,) in self._connection.execute(
                "SELECT hash FROM terrains ORDER BY rowid")]

    def terrain_info(self) -> dict[str, dict[str, Any]]:
        """Geometry and metadata of every stored terrain, without loading its heights.

        Returns
        -------
        dict
            {hash: {"shape": [nx, ny] [cells], "resolution" [m/cell],
            "origin": [x, y] [m], "frame", "metadata"}}, in the order added.
        """
        with self._errors():
            rows = self._connection.execute(
                "SELECT hash, shape, resolution, origin_x, origin_y, frame, metadata "
                "FROM terrains ORDER BY rowid").fetchall()
        info = {}
        for digest, shape, resolution, ox, oy, frame, metadata in rows:
            try:
                info[digest] = {"shape": json.loads(shape), "resolution": float(resolution),
                                "origin": [float(ox), float(oy)], "frame": str(frame),
                                "metadata": json.loads(metadata)}
            except (TypeError, ValueError) as exc:
                raise FootfallError(f"{self.path}: terrain {digest} is corrupt ({exc})") from None
        return info

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
        demos = list(demos)
        terrains = list(terrains)
        for d in demos:
            if not isinstance(d, Demonstration):
                raise FootfallError(f"expected a Demonstration, got {type(d).__name__}")
        with self._errors(), self._write() as con:
            for hmap in terrains:
                self._insert_terrain(con, hmap)
            return [self._insert_demonstration(con, d) for d in demos]

    def _insert_demonstration(self, con: sqlite3.Connection, demo: Demonstration) -> int:
        if con.execute("SELECT 1 FROM terrains WHERE hash = ?",
                       (demo.terrain_hash,)).fetchone() is None:
            raise FootfallError(f"terrain {demo.terrain_hash} is not in the store; "
                                f"add it before its demonstrations")
        state = _encode(demo.state.to_vector())
        cand = _encode(demo.candidates)
        cur = con.execute(
            "INSERT INTO demonstrations (terrain_hash, swing_leg, state, state_shape, state_dtype, "
            "candidates, candidates_shape, candidates_dtype, n_candidates, chosen, source, expert) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (demo.terrain_hash, demo.swing_leg, *state, *cand, demo.n_candidates, demo.chosen,
             demo.source, json.dumps(demo.expert, sort_keys=True)))
        return int(cur.lastrowid)

    def _where(self, terrain_hash: str | None, source_prefix: str | None
               ) -> tuple[str, list[Any]]:
        clauses, params = [], []
        if terrain_hash is not None:
            clauses.append("terrain_hash = ?")
            params.append(terrain_hash)
        if source_prefix is not None:  # not LIKE: '_' and '%' are ordinary characters here
            clauses.append("substr(source, 1, length(?)) = ?")
            params += [source_prefix, source_prefix]
        return (" WHERE " + " AND ".join(clauses)) if clauses else "", params

    def demonstrations(self, ids: Sequence[int] | None = None, terrain_hash: str | None = None,
                       source_prefix: str | None = None) -> list[Demonstration]:
        """Read demonstrations, each validated.

        Parameters
        ----------
        ids : sequence of int, optional
            Exactly these, in this order (a missing id is an error).
            Otherwise all that match the filters, in creation order.
        terrain_hash : str, optional
            Only those on this terrain.
        source_prefix : str, optional
            Only those whose source starts with this (case-sensitive), e.g.
            ``"run:"``.

        Raises
        ------
        FootfallError
            For a missing id, or a stored row that is not a valid
            demonstration (the message names its id).
        """
        where, params = self._where(terrain_hash, source_prefix)
        columns = ("SELECT id, terrain_hash, swing_leg, state, state_shape, state_dtype, "
                   "candidates, candidates_shape, candidates_dtype, chosen, source, expert "
                   "FROM demonstrations")
        with self._errors():
            if ids is None:
                rows = self._connection.execute(columns + where + " ORDER BY id",
                                                params).fetchall()
            else:
                wanted = [self._check_id(i) for i in ids]
                extra = where.replace(" WHERE ", " AND ", 1)
                rows = self._connection.execute(
                    columns + " WHERE id IN (SELECT value FROM json_each(?))" + extra,
                    [json.dumps(wanted), *params]).fetchall()
        demos = [self._row_to_demo(row) for row in rows]
        if ids is None:
            return demos
        by_id = {d.id: d for d in demos}
        missing = [i for i in wanted if i not in by_id]
        if missing:
            raise FootfallError(f"demonstration {missing[0]} is not in the store"
                                + (" (or does not match the filters)" if where else ""))
        return [by_id[i] for i in wanted]

    @staticmethod
    def _check_id(i: Any) -> int:
        if isinstance(i, bool) or not isinstance(i, numbers.Integral):
            raise FootfallError(f"demonstration ids are integers, got {i!r}")
        return int(i)

    def _row_to_demo(self, row: tuple) -> Demonstration:
        (id_, terrain_hash, leg, state, state_shape, state_dtype, cand, cand_shape, cand_dtype,
         chosen, source, expert) = row
        what = f"{self.path}: demonstration {id_}"
        try:
            if leg not in LEG_NAMES:
                raise FootfallError(f"unknown swing leg {leg!r}")
            vector = _decode(state, state_shape, state_dtype, "its state")
            candidates = _decode(cand, cand_shape, cand_dtype, "its candidates")
            settings = json.loads(_sql_text(expert, "its expert settings"))
            return Demonstration(terrain_hash, RobotState.from_vector(vector, leg), candidates,
                                 chosen, _sql_text(source, "its source"), settings, id_)
        except (FootfallError, TypeError, ValueError) as exc:
            raise FootfallError(f"{what} is corrupt ({exc})") from None

    def count(self, terrain_hash: str | None = None, source_prefix: str | None = None) -> int:
        """Number of stored demonstrations (matching the filters of :meth:`demonstrations`)."""
        where, params = self._where(terrain_hash, source_prefix)
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
            (None when empty), ``first_id``/``last_id`` and ``runs`` (run logs stored).
        """
        with self._errors(), self._read() as con:
            total, first, last, cmin, cmean, cmax = con.execute(
                "SELECT count(*), min(id), max(id), min(n_candidates), avg(n_candidates), "
                "max(n_candidates) FROM demonstrations").fetchone()
            by_terrain = dict(con.execute(
                "SELECT t.hash, count(d.id) FROM terrains t LEFT JOIN demonstrations d "
                "ON d.terrain_hash = t.hash GROUP BY t.hash ORDER BY t.rowid"))
            legs = dict(con.execute(
                "SELECT swing_leg, count(*) FROM demonstrations GROUP BY swing_leg"))
            n_runs = int(con.execute("SELECT count(*) FROM runs").fetchone()[0])
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
                "first_id": first, "last_id": last, "runs": n_runs}

    # ------------------------------------------------------------------- runs
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
        demos = list(demonstrations)
        for d in demos:
            if not isinstance(d, Demonstration):
                raise FootfallError(f"expected a Demonstration, got {type(d).__name__}")
        with self._errors(), self._write() as con:
            for hmap in terrains:
                self._insert_terrain(con, hmap)
            if con.execute("SELECT 1 FROM terrains WHERE hash = ?",
                           (run.terrain_hash,)).fetchone() is None:
                raise FootfallError(f"terrain {run.terrain_hash} is not in the store; "
                                    f"add it before its runs")
            if run.key is not None and con.execute("SELECT 1 FROM runs WHERE key = ?",
                                                   (run.key,)).fetchone() is not None:
                raise FootfallError(f"a run with key {run.key!r} is already in the store")
            cur = con.execute(
                "INSERT INTO runs (key, terrain_hash, seed, settings, result, n_steps) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                (run.key, run.terrain_hash, int(run.seed), json.dumps(run.settings, sort_keys=True),
                 json.dumps(run.result, sort_keys=True), len(run.steps)))
            run_id = int(cur.lastrowid)
            con.executemany(
                "INSERT INTO run_steps (run_id, k, swing_leg, state, state_shape, state_dtype, "
                "candidates, candidates_shape, candidates_dtype, rewards, rewards_shape, "
                "rewards_dtype, chosen, t_liftoff, t_touchdown, touchdown, touchdown_shape, "
                "touchdown_dtype, slip) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, "
                "?, ?, ?)",
                [(run_id, st.k, st.swing_leg, *_encode(st.state.to_vector()),
                  *_encode(st.candidates), *_encode(st.rewards), st.chosen, float(st.t_liftoff),
                  None if math.isnan(st.t_touchdown) else float(st.t_touchdown),
                  *_encode(st.touchdown), None if math.isnan(st.slip) else float(st.slip))
                 for st in run.steps])
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
            rows = con.execute(
                "SELECT k, swing_leg, state, state_shape, state_dtype, candidates, "
                "candidates_shape, candidates_dtype, rewards, rewards_shape, rewards_dtype, "
                "chosen, t_liftoff, t_touchdown, touchdown, touchdown_shape, touchdown_dtype, "
                "slip FROM run_steps WHERE run_id = ? ORDER BY k", (run_id,)).fetchall()
        if head is None:
            raise FootfallError(f"run {run_id} is not in the store")
        what = f"{self.path}: run {run_id}"
        try:
            steps = []
            for (k, leg, st, st_s, st_d, c, c_s, c_d, r, r_s, r_d, chosen, t0, t1, td, td_s,
                 td_d, slip) in rows:
                if leg not in LEG_NAMES:
                    raise FootfallError(f"unknown swing leg {leg!r}")
                state = RobotState.from_vector(_decode(st, st_s, st_d, "a state"), leg)
                steps.append(RunStep(int(k), state, _decode(c, c_s, c_d, "candidates"),
                                     _decode(r, r_s, r_d, "rewards"), int(chosen), float(t0),
                                     math.nan if t1 is None else float(t1),
                                     _decode(td, td_s, td_d, "a touch-down"),
                                     math.nan if slip is None else float(slip)))
            key, th, seed, settings, result = head
            return RunRecord(th, int(seed), json.loads(settings), json.loads(result),
                             tuple(steps), key, run_id)
        except (FootfallError, TypeError, ValueError) as exc:
            raise FootfallError(f"{what} is corrupt ({exc})") from None

    def check(self) -> None:
        """Check the whole file's structure (SQLite ``quick_check``); reads every page.

        Raises
        ------
        FootfallError
            If SQLite finds the file damaged.
        """
        with self._errors():
            problems = [r[0] for r in self._connection.execute("PRAGMA quick_check")]
        if problems != ["ok"]:
            raise FootfallError(f"{self.path}: corrupt demonstration store ({problems[0]})")
