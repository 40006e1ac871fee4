"""Terrain straight to a height-map file: make a module or a board, or import a scan, save it.

Each function checks the output path before the work, writes the map atomically and returns a
:class:`MapSummary` of the file written (what ``footfall terrain make/board/import`` print).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from footfall.core.files import writable_path
from footfall.core.heightmap import FORMAT as MAP_FORMAT
from footfall.core.heightmap import HeightMap
from footfall.terrain.modules import make_board, make_module, parse_board_spec
from footfall.terrain.scans import import_terrain

MAP_SUFFIXES = (".npz",)  # what HeightMap.save writes


@dataclass(frozen=True)
class MapSummary:
    """What a height-map file holds: geometry, height range, completeness, content hash."""

    file: str  # the file written
    shape: tuple[int, int]  # [cells] along x and y
    resolution: float  # [m/cell]
    origin: tuple[float, float]  # [m] centre of cell (0, 0)
    bounds: tuple[float, float, float, float]  # [m] x_min, x_max, y_min, y_max of the cells
    height_min: float  # [m] lowest height with data
    height_max: float  # [m] highest height with data
    no_data_fraction: float  # [-] share of cells without data (NaN)
    hash: str  # content hash (HeightMap.content_hash)
    metadata: dict[str, Any]  # the map's metadata (e.g. its modules)

    @property
    def length(self) -> tuple[float, float]:
        """Extent of the map along x and y [m]."""
        return self.shape[0] * self.resolution, self.shape[1] * self.resolution

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON, in field order."""
        return {"file": self.file, "shape": list(self.shape), "resolution": self.resolution,
                "origin": list(self.origin), "bounds": list(self.bounds),
                "height_min": self.height_min, "height_max": self.height_max,
                "no_data_fraction": self.no_data_fraction, "hash": self.hash,
                "metadata": self.metadata}


def summarise_map(hmap: HeightMap, path: str | os.PathLike) -> MapSummary:
    """The summary of ``hmap`` as written to ``path``."""
    h = hmap.heights
    return MapSummary(str(path), tuple(hmap.shape), hmap.resolution, tuple(hmap.origin),
                      tuple(hmap.bounds), float(np.nanmin(h)), float(np.nanmax(h)),
                      float(np.isnan(h).mean()), hmap.content_hash(), hmap.metadata)


def _save(hmap: HeightMap, out: Path) -> MapSummary:
    hmap.save(out)
    return summarise_map(hmap, out)


def save_module(kind: str, difficulty: float, seed: int, path: str | os.PathLike) -> MapSummary:
    """Make one terrain module (:func:`~footfall.terrain.modules.make_module`) into ``path``.

    Raises
    ------
    FootfallError
        For a bad output path (or one not ending in .npz), an unknown kind, a difficulty outside [0, 1] or a bad seed.
    """
    out = writable_path(path, MAP_SUFFIXES, kind="height map", writes=MAP_FORMAT)
    return _save(make_module(kind, difficulty, seed), out)


def save_board(specs: Sequence[str], seed: int, path: str | os.PathLike,
               flat_ends: bool = True) -> MapSummary:
    """Make a board of modules in a row along x into ``path``.

    Each spec is ``"kind[:difficulty]"`` or a height-map file (``.npz``) laid in as a
    module (:func:`~footfall.terrain.modules.parse_board_spec`). ``flat_ends`` adds a
    flat start and end module unless the row has them
    (:func:`~footfall.terrain.modules.make_board`).

    Raises
    ------
    FootfallError
        For a bad output path (or one not ending in .npz), a malformed spec, a module
        file that is missing, not a height map, without data or too large, a board
        above the ``max_map_cells`` limit, or a bad seed.
    """
    out = writable_path(path, MAP_SUFFIXES, kind="height map", writes=MAP_FORMAT, inputs=specs)
    return _save(make_board([parse_board_spec(s) for s in specs], seed, flat_ends=flat_ends), out)


def save_imported(source: str | os.PathLike, path: str | os.PathLike,
                  resolution: float | None = None, z_scale: float | None = None,
                  nodata: float | None = None, **formats) -> MapSummary:
    """Import a scan (:func:`~footfall.terrain.scans.import_terrain`) into ``path``.

    ``resolution`` [m/cell], ``z_scale`` [m per raw unit] and ``nodata`` (the
    raw value meaning no data) as for the import; ``formats``: the options of one
    format alone (a bag's ``topic``, ``layer``, ``message``, ``time``; a point cloud's
    ``classes``, ``statistic``; a raster's ``band``, ``bounds``).

    Raises
    ------
    FootfallError
        For a bad output path or a source the import refuses.
    """
    out = writable_path(path, MAP_SUFFIXES, kind="height map", writes=MAP_FORMAT, inputs=(source,))
    return _save(import_terrain(source, resolution=resolution, z_scale=z_scale, nodata=nodata,
                                **formats), out)
