"""The store's SQLite connection: opening a file (new, current or older schema), its transactions
and the translation of SQLite's errors into one-line :class:`FootfallError` messages.

The queries (:mod:`footfall.data.store` and the modules it composes) build on this class.
"""

from __future__ import annotations

import contextlib
import numbers
import os
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Self

from footfall.core.errors import FootfallError
from footfall.data import schema

DEFAULT_BUSY_TIMEOUT = 30.0  # [s] how long a write waits for another writer's lock


class StoreConnection:
    """An open demonstration store file: lifecycle, transactions, SQLite errors.

    Parameters are those of :class:`footfall.data.store.DemoStore`.
    """

    def __init__(self, path: str | os.PathLike, create: bool = False,
                 busy_timeout: float = DEFAULT_BUSY_TIMEOUT) -> None:
        self.path = Path(path)
        self.schema_version = schema.SCHEMA_VERSION  # of the open file, set by _check_meta
        self._con: sqlite3.Connection | None = None
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
            schema.check_header(self.path)
        try:
            # isolation_level=None: no implicit transactions; each write opens its own.
            self._con = sqlite3.connect(self.path, timeout=float(busy_timeout),
                                        isolation_level=None)
        except sqlite3.Error as exc:
            raise FootfallError(f"{self.path}: cannot open ({exc})") from None
        try:
            with self._errors():
                self._con.execute("PRAGMA foreign_keys = ON")
                if not schema.has_table(self._con, "meta"):
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
        from footfall import __version__

        with self._write():
            if schema.has_table(con, "meta"):  # another process initialised it meanwhile
                return
            schema.create(con, f"footfall {__version__}")

    def _check_meta(self) -> None:
        """Refuse a foreign or newer file; bring an older one to the current schema."""
        version = schema.stored_version(self._connection, self.path)
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
    def _check_id(i: Any) -> int:
        """A row id given by a caller: an integer (a bool is refused)."""
        if isinstance(i, bool) or not isinstance(i, numbers.Integral):
            raise FootfallError(f"demonstration ids are integers, got {i!r}")
        return int(i)
