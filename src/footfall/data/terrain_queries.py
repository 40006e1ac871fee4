"""The store's terrain queries: each terrain is kept once, by its content hash, and verified
against that hash when it is read back.

Demonstrations and runs refer to a terrain by its hash; the helpers here let their queries
add terrains in the same transaction and refuse a row whose terrain is missing.
"""

from __future__ import annotations

import contextlib
import json
import os
import sqlite3
from collections.abc import Iterator, Sequence
from typing import Any

from footfall.core.errors import FootfallError, NotFound
from footfall.core.heightmap import HeightMap
from footfall.data import codec, rows
from footfall.data.connection import DEFAULT_BUSY_TIMEOUT, StoreConnection


class TerrainQueries(StoreConnection):
    """Add and read the terrains of a store (part of :class:`footfall.data.store.DemoStore`)."""

    def __init__(self, path: str | os.PathLike, create: bool = False,
                 busy_timeout: float = DEFAULT_BUSY_TIMEOUT, read_only: bool = False,
                 any_thread: bool = False) -> None:
        self._terrains: dict[str, HeightMap] = {}  # verified terrains, by hash: hashed once
        super().__init__(path, create, busy_timeout, read_only, any_thread)

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
            row = self._connection.execute(f"SELECT {rows.TERRAIN_COLUMNS} FROM terrains "
                                           "WHERE hash = ?", (terrain_hash,)).fetchone()
        if row is None:
            raise NotFound(f"terrain {terrain_hash} is not in the store")
        try:
            hmap = rows.terrain(row)
        except FootfallError as exc:
            raise FootfallError(f"{self.path}: terrain {terrain_hash} is corrupt ({exc})") \
                from None
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
            found = self._connection.execute(
                "SELECT hash, shape, resolution, origin_x, origin_y, frame, metadata "
                "FROM terrains ORDER BY rowid").fetchall()
        info = {}
        for digest, shape, resolution, ox, oy, frame, metadata in found:
            try:
                info[digest] = {"shape": json.loads(codec.text(shape, "shape")),
                                "resolution": rows.real(resolution, "resolution"),
                                "origin": [rows.real(ox, "origin_x"), rows.real(oy, "origin_y")],
                                "frame": codec.text(frame, "frame"),
                                "metadata": rows.json_object(metadata, "metadata")}
            except (FootfallError, ValueError) as exc:
                raise FootfallError(f"{self.path}: terrain {digest!r} is corrupt ({exc})") \
                    from None
        return info

    # ------------------------------------------------ for the other queries
    @contextlib.contextmanager
    def _write_after_terrains(self, terrains: Sequence[HeightMap]
                              ) -> Iterator[sqlite3.Connection]:
        """One write transaction that first adds ``terrains`` (those its rows will refer to)."""
        with self._errors(), self._write() as con:
            for hmap in terrains:
                self._insert_terrain(con, hmap)
            yield con

    @staticmethod
    def _require_terrain(con: sqlite3.Connection, terrain_hash: str, users: str) -> None:
        """Refuse a row on a terrain that is not stored; ``users`` names such rows in the message."""
        if not _has_terrain(con, terrain_hash):
            raise FootfallError(f"terrain {terrain_hash} is not in the store; "
                                f"add it before its {users}")

    def _insert_terrain(self, con: sqlite3.Connection, hmap: HeightMap) -> str:
        if not isinstance(hmap, HeightMap):
            raise FootfallError(f"a terrain must be a HeightMap, got {type(hmap).__name__}")
        digest = hmap.content_hash()
        if not _has_terrain(con, digest):
            blob, shape, dtype = codec.encode(hmap.heights)
            try:
                metadata = json.dumps(hmap.metadata, sort_keys=True)
            except (TypeError, ValueError) as exc:
                raise FootfallError(f"terrain metadata must be JSON-serialisable ({exc})") from None
            con.execute("INSERT INTO terrains (hash, heights, shape, dtype, resolution, origin_x, "
                        "origin_y, frame, metadata) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                        (digest, blob, shape, dtype, hmap.resolution, hmap.origin[0],
                         hmap.origin[1], hmap.frame, metadata))
        return digest


def _has_terrain(con: sqlite3.Connection, terrain_hash: str) -> bool:
    return con.execute("SELECT 1 FROM terrains WHERE hash = ?",
                       (terrain_hash,)).fetchone() is not None
