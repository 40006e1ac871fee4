"""What a demonstration store holds: counts by terrain, leg and source, and each terrain's label.

The store's whole file is checked first -- every page, the schema and every row
(:func:`footfall.data.check.check_store`) -- so an inventory is also a health check
(``footfall demos info``); the file is only read.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

from footfall.data.check import checked_store
from footfall.data.store import DemoStore


@dataclass(frozen=True)
class StoreInventory:
    """A store's counts (:meth:`DemoStore.summary`) and its terrains, each with a label."""

    store: str  # the store's path, as given
    summary: dict[str, Any]  # DemoStore.summary(): format, counts by terrain, leg, source, ...
    terrains: dict[str, dict[str, Any]]  # {hash: geometry (no metadata) and "label"}

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON: the store, its summary's keys, then ``terrain_info``."""
        return {"store": self.store, **self.summary, "terrain_info": self.terrains}


def terrain_label(info: dict[str, Any]) -> str:
    """A short label of a stored terrain: its modules (``flat, rocky:0.6, scan.npz``) or its size.

    ``info`` is one entry of :meth:`DemoStore.terrain_info`: shape [cells],
    resolution [m/cell] and metadata. A module made from a file shows as its file name.
    """
    modules = info.get("metadata", {}).get("modules")
    if isinstance(modules, list) and modules and all(isinstance(m, dict) for m in modules):
        return ", ".join(_module_label(m) for m in modules)
    shape = info.get("shape", ["?", "?"])
    return f"{shape[0]} x {shape[1]} cells at {info.get('resolution', 0) * 1000:g} mm"


def _module_label(module: dict[str, Any]) -> str:
    """``rocky:0.6``, ``flat``, or a file module's file name (a record without difficulty)."""
    if module.get("kind") == "file" and "file" in module:
        return str(module["file"])
    if module.get("kind") == "flat" or module.get("difficulty") is None:
        return str(module.get("kind"))
    return f"{module.get('kind')}:{module.get('difficulty')}"


def store_inventory(path: str | os.PathLike) -> StoreInventory:
    """Check a store's file and count what it holds.

    Raises
    ------
    FootfallError
        If ``path`` is missing, not a store, or damaged (a page, the schema or
        a row: the first problem, and how many more).
    """
    checked_store(path)
    with DemoStore(path, read_only=True) as store:
        summary = store.summary()
        terrains = store.terrain_info()
    labelled = {h: {k: v for k, v in t.items() if k != "metadata"} | {"label": terrain_label(t)}
                for h, t in terrains.items()}
    return StoreInventory(str(path), summary, labelled)
