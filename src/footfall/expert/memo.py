"""Values remembered per foothold: a walk judges the same footholds again and again.

A walk's look-ahead judges the footholds around each coming step from every
step before it: on a rocky board an expert run computes the terrain terms of
about 230 000 footholds, of which 43 000 are distinct. Where the values of a
row are a function of that row alone (the terrain terms, sampled from the
whole map's surface: :func:`footfall.core.sphere_surface.board_sphere`), a memo
returns what was computed before and computes only the rows it has not seen:
the same bits as computing them all.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np

MEMO_ROWS = 200_000  # [-] rows a memo keeps before it starts again (~30 MB with its index)


class RowMemo:
    """Values of rows of a float array, remembered by the rows' bits.

    ``compute(rows)`` maps an (m, d) float64 array to a dict of (m,) arrays, and must give each
    row the same values whatever the other rows are. Calls from several threads take turns.
    """

    def __init__(self, compute: Callable[[np.ndarray], dict[str, np.ndarray]],
                 capacity: int = MEMO_ROWS):
        self._compute = compute
        self._capacity = int(capacity)
        self._index: dict[bytes, int] = {}
        self._values: dict[str, np.ndarray] = {}
        self._size = 0
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return self._size

    def __call__(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """The values of ``rows`` (n, d), computed where not remembered; fresh arrays."""
        rows = np.ascontiguousarray(rows, dtype=np.float64)
        with self._lock:
            return self._lookup(rows)

    def _lookup(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        keys = [r.tobytes() for r in rows]
        where = np.fromiter((self._index.get(k, -1) for k in keys), dtype=np.int64,
                            count=len(keys))
        todo = np.flatnonzero(where < 0)
        if todo.size:
            if self._size + todo.size > self._capacity:  # full: start again with these rows
                self._index, self._values, self._size = {}, {}, 0
                todo = np.arange(len(keys))
            fresh: dict[bytes, int] = {}  # rows repeated within this call computed once
            for i in todo:
                fresh.setdefault(keys[i], int(i))
            first = np.fromiter(fresh.values(), dtype=np.int64, count=len(fresh))
            new = self._compute(rows[first])
            self._store(new, [keys[i] for i in first])
            where = np.fromiter((self._index[k] for k in keys), dtype=np.int64, count=len(keys))
        return {name: v[where] for name, v in self._values.items()}

    def _store(self, new: dict[str, np.ndarray], keys: list[bytes]) -> None:
        m, start = len(keys), self._size
        for name, v in new.items():
            have = self._values.get(name)
            if have is None or have.shape[0] < start + m:
                grown = np.empty((max(2 * (start + m), 1024),) + v.shape[1:], dtype=v.dtype)
                if have is not None:
                    grown[:start] = have[:start]
                self._values[name] = grown
            self._values[name][start:start + m] = v
        for j, k in enumerate(keys):
            self._index[k] = start + j
        self._size = start + m
