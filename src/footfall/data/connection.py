"""The store's SQLite connection: opening a file (new, current or older schema), its transactions
and the translation of SQLite's errors into one-line :class:`FootfallError` messages.

The queries (:mod:`footfall.data.store` and the modules it composes) build on this class.
"""

from __future__ import annotations

import contextlib
import numbers
import os
import secrets
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Self

from footfall import __version__
from footfall.core.errors import FootfallError
from footfall.data import schema

DEFAULT_BUSY_TIMEOUT = 30.0  # [s] how long a write waits for another writer's lock


class StoreConnection:
    """An open demonstration store file: lifecycle, transactions, SQLite errors.

    Parameters are those of :class:`footfall.data.store.DemoStore`.
    """

    def __init__(self, path: str | os.PathLike, create: bool = False,
                 busy_timeout: float = DEFAULT_BUSY_TIMEOUT, read_only: bool = False,
                 any_thread: bool = False) -> None:
        self.path = Path(path)
        self._any_thread = bool(any_thread)
        self.read_only = bool(read_only)
        self.schema_version = schema.SCHEMA_VERSION  # of the open file, set by _check_meta
        self._con: sqlite3.Connection | None = None
        if not (isinstance(busy_timeout, numbers.Real) and busy_timeout >= 0):
            raise FootfallError(f"busy timeout must be >= 0 s, got {busy_timeout!r}")
        if create and read_only:
            raise FootfallError("a store opened read-only cannot be created")
        self._check_path(create)
        self._con = self._connect(float(busy_timeout))
        try:
            with self._errors():
                self._con.execute("PRAGMA foreign_keys = ON")
                if not schema.has_table(self._con, "meta"):
                    self._initialise(create)
                self._check_meta()
                # Persistent: WAL lets readers and one writer work at the same time.
                if not self.read_only and \
                        self._con.execute("PRAGMA journal_mode").fetchone()[0].lower() != "wal":
                    self._con.execute("PRAGMA journal_mode = WAL")
        except BaseException:
            self.close()
            raise

    def _check_path(self, create: bool) -> None:
        """Refuse a missing file (unless ``create``), a directory, or a file that is not SQLite."""
        exists = self.path.exists()
        if exists and not self.path.is_file():
            raise FootfallError(f"{self.path}: not a file")
        if not exists:
            if not create:
                raise FootfallError(f"no such file: {self.path}")
            if not self.path.parent.is_dir():
                raise FootfallError(f"output directory does not exist: {self.path.parent}")
            _create_store(self.path)
        else:
            schema.check_header(self.path)

    def _connect(self, busy_timeout: float) -> sqlite3.Connection:
        """The SQLite connection: read-write, or read-only (:func:`read_only_uri`)."""
        try:
            # isolation_level=None: no implicit transactions; each write opens its own.
            if self.read_only:
                con = sqlite3.connect(read_only_uri(self.path), uri=True, timeout=busy_timeout,
                                      isolation_level=None, check_same_thread=not self._any_thread)
            else:
                con = sqlite3.connect(self.path, timeout=busy_timeout, isolation_level=None,
                                      check_same_thread=not self._any_thread)
        except sqlite3.Error as exc:
            raise FootfallError(f"{self.path}: cannot open ({one_line(exc)})") from None
        con.text_factory = decode_text
        return con

    # -------------------------------------------------------------- lifecycle
    def close(self) -> None:
        """Close the connection (idempotent)."""
        if self._con is not None:
            self._con.close()
            self._con = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"{type(self).__name__}({str(self.path)!r})"

    def check(self) -> None:
        """Check the whole file's structure (SQLite ``quick_check``); reads every page.

        Raises
        ------
        FootfallError
            If SQLite finds the file damaged.
        """
        with self._errors():
            schema.check_pages(self._connection, self.path)

    # ---------------------------------------------------------- opening a file
    def _initialise(self, create: bool) -> None:
        """Create the schema in a new (empty) database, in one transaction."""
        con = self._connection
        if not create or not schema.is_empty(con):
            raise FootfallError(f"{self.path}: not a footfall demonstration store "
                                f"(no footfall metadata)")
        con.execute("PRAGMA journal_mode = WAL")  # before the first write: no journal swap
        with self._write():
            if schema.has_table(con, "meta"):  # another process initialised it meanwhile
                return
            schema.create(con, f"footfall {__version__}")

    def _check_meta(self) -> None:
        """Refuse a foreign or newer file, or one with objects footfall does not make (a trigger,
        a view, an unknown table); bring an older one to the current schema (read-write only)."""
        version = schema.stored_version(self._connection, self.path)
        problems = schema.schema_problems(self._connection, version)
        if problems:
            raise FootfallError(f"{self.path}: {problems[0]}")
        if self.read_only:
            self.schema_version = version  # read as it is: its queries know the older tables
            return
        for old in range(version, schema.SCHEMA_VERSION):
            with self._write() as con:  # one version per transaction; data untouched
                schema.migrate(con, old)
        self.schema_version = schema.SCHEMA_VERSION  # an older file was just migrated

    # ------------------------------------------------------------ transactions
    @contextlib.contextmanager
    def _errors(self) -> Iterator[None]:
        """Turn SQLite errors into one-line :class:`FootfallError` messages."""
        try:
            yield
        except (sqlite3.OperationalError, sqlite3.IntegrityError) as exc:  # locked, read-only, ...
            raise FootfallError(f"{self.path}: {one_line(exc)}") from None
        except sqlite3.DatabaseError as exc:  # malformed image, not a database, ...
            raise FootfallError(f"{self.path}: corrupt demonstration store "
                                f"({one_line(exc)})") from None
        except UnicodeDecodeError:  # a damaged page where SQLite keeps the schema's text
            raise FootfallError(f"{self.path}: corrupt demonstration store "
                                f"(its schema holds text that is not UTF-8)") from None

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

    def _has_table(self, name: str) -> bool:
        """Whether the open file has table ``name`` (an older store read as it is may not)."""
        with self._errors():
            return schema.has_table(self._connection, name)

    @staticmethod
    def _check_id(i: Any) -> int:
        """A row id given by a caller: an integer (a bool is refused)."""
        if isinstance(i, bool) or not isinstance(i, numbers.Integral):
            raise FootfallError(f"demonstration ids are integers, got {i!r}")
        return int(i)


def _create_store(path: Path) -> None:
    """Make a new store at ``path`` whole or not at all: its schema is written to a temporary
    file beside it, which is then hard-linked to ``path``. A link never replaces a file, so
    of processes creating the same store at once one links its file and the others find a
    complete store there (never an empty or half-made file) and open it. Where the file
    system has no hard links, the store is made in place (one creator at a time)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.new")
    try:
        try:
            con = sqlite3.connect(tmp, isolation_level=None)
        except sqlite3.Error as exc:
            raise FootfallError(f"{path}: cannot create ({one_line(exc)})") from None
        try:
            con.execute("PRAGMA journal_mode = WAL")  # recorded in the file's header
            con.execute("BEGIN IMMEDIATE")
            schema.create(con, f"footfall {__version__}")
            con.execute("COMMIT")
        except sqlite3.Error as exc:
            raise FootfallError(f"{path}: cannot create ({one_line(exc)})") from None
        finally:
            con.close()
        try:
            os.link(tmp, path)
        except FileExistsError:
            pass  # another process made it first: opened as it stands
        except OSError:
            if not path.exists():  # no hard links here: in place, as a single creator would
                os.replace(tmp, path)
    finally:
        for leftover in (tmp, Path(f"{tmp}-wal"), Path(f"{tmp}-shm")):
            leftover.unlink(missing_ok=True)


def one_line(exc: BaseException) -> str:
    """An exception's message on one line (SQLite quotes multi-line SQL and constraints)."""
    return " ".join(str(exc).split())


def read_only_uri(path: Path) -> str:
    """The SQLite URI that opens ``path`` without writing to it.

    ``mode=ro`` reads a store that another process may be writing (it shares
    the WAL index, the ``-shm`` file, which it creates if missing). In a
    folder the user cannot write, that file cannot be made: there, and only
    when no write-ahead log holds committed pages (no ``-wal`` file, or an
    empty one), the file is opened ``immutable``: read as it is on disk.
    """
    uri = path.resolve().as_uri()
    wal = Path(f"{path}-wal")
    wal_empty = not wal.exists() or wal.stat().st_size == 0
    if wal_empty and not os.access(path.resolve().parent, os.W_OK):
        return uri + "?immutable=1"
    return uri + "?mode=ro"


class UndecodableText:
    """A TEXT value that is not UTF-8 (a damaged row): neither text nor bytes, so every check
    of a column's type refuses it, naming the column."""

    def __init__(self, raw: bytes) -> None:
        self.raw = raw

    def __repr__(self) -> str:
        return f"<{len(self.raw)} bytes of text that is not UTF-8>"


def decode_text(raw: bytes) -> str | UndecodableText:
    """SQLite's TEXT values as ``str``; one that is not UTF-8 as :class:`UndecodableText`
    (instead of an error that would stop a whole query at one bad row)."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return UndecodableText(raw)
