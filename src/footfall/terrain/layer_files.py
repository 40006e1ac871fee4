"""A map's layers written out for other tools: footfall's ``.npz``, a GeoTIFF, a ROS 2 bag.

A *layer* is an array of the map's shape (``[i, j]`` along +x and +y, NaN where
undefined): the elevation itself and, for example, a scorer's values
(:mod:`footfall.features.map_scores`). By the output's suffix:

``.npz``
    ``footfall.map_layers`` version 1: one float array per layer beside JSON meta
    (resolution [m/cell], origin [m] of cell (0, 0)'s centre, frame, the map's own
    metadata and what the caller describes).
``.tif`` / ``.tiff``
    a float32 GeoTIFF, one band per layer described by its name, with the map's
    georeference (the input's CRS and transform where it came from one) --
    :func:`footfall.terrain.geotiff.write_geotiff`.
``.mcap`` / ``.db3``
    a ROS 2 bag (MCAP or SQLite 3 storage) of one ``grid_map_msgs/GridMap`` with a
    layer each, in the map's frame -- :func:`footfall.terrain.bags.write_grid_map`.

Every file is written to a temporary name and renamed into place.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import save_npz
from footfall.core.heightmap import HeightMap

FORMAT = "footfall.map_layers"
VERSION = 1
LAYER_SUFFIXES = (".npz", ".tif", ".tiff", ".mcap", ".db3")


def write_layers(path: str | os.PathLike, layers: dict[str, np.ndarray], hmap: HeightMap,
                 describe: dict | None = None) -> Path:
    """Write ``layers`` (name -> array of ``hmap.shape``) on ``hmap``'s grid to ``path``, in
    the format its suffix names; ``describe`` (JSON) goes into an ``.npz``'s meta."""
    p = Path(path)
    for name, values in layers.items():
        if np.shape(values) != hmap.shape:
            raise FootfallError(f"layer {name!r} has shape {np.shape(values)}, not the map's "
                                f"{hmap.shape}")
    suffix = p.suffix.lower()
    if suffix == ".npz":
        save_npz(p, FORMAT, VERSION,
                 {name: np.asarray(v, dtype=np.float64) for name, v in layers.items()},
                 {"layers": list(layers), "resolution": hmap.resolution,
                  "origin": list(hmap.origin), "frame": hmap.frame,
                  "units": {"resolution": "m/cell", "origin": "m"},
                  "index": "layer[i, j] at origin + (i, j) * resolution; NaN = undefined",
                  "metadata": hmap.metadata, "describe": describe or {}})
        return p
    if suffix in (".tif", ".tiff"):
        from footfall.terrain.geotiff import write_geotiff

        return write_geotiff(p, layers, hmap)
    if suffix in (".mcap", ".db3"):
        from footfall.terrain.bags import write_grid_map

        return write_grid_map(p, layers, hmap, storage="mcap" if suffix == ".mcap" else
                              "sqlite3")
    raise FootfallError(f"{p}: unknown layer file format {suffix or '(no suffix)'!r} (use "
                        f"{' or '.join(LAYER_SUFFIXES)})")
