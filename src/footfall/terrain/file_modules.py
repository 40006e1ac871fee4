"""Height-map files as board modules: a user's own scan laid in a row with generated modules.

A file module is a footfall height map (``.npz``, what :meth:`HeightMap.save` and
``footfall terrain import`` write) at any resolution. To join a board it is resampled onto
the board's grid (1 mm cells, 0.61 m wide, see :mod:`footfall.terrain.modules`):

* **resolution**: where the file is coarser than the board, each board cell takes the
  file's height at the cell centre, interpolated bilinearly by
  :meth:`HeightMap.height_at` (the walker's own reading of a map: a board cell whose
  nearest file cell has no data stays NaN, so a hole keeps its extent; elsewhere only
  cells with data are interpolated). Where the file is as fine or finer, each board
  cell takes the area-weighted mean of the file cells' data it covers, NaN if none of
  them has data. Either way no-data is never filled in, and no new no-data appears.
* **length** along x: the file's own extent, rounded to whole board cells (the file is
  centred on them, so its ends shift by at most a quarter of a board cell).
* **width** along y: the board's 0.61 m. A narrower file is padded with NaN (no data),
  a wider one cropped, both centred in y; the record says which (``width_fit``).
* **height**: shifted so that the module's lowest height with data is 0, as the
  generated modules stand on z = 0; the shift [m] is recorded (``z_shift``).

The file's own origin and frame do not matter: the module is placed by its extent.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy import sparse

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.limits import check_cells

FILE_KIND = "file"  # the "kind" of a file module's record in a board's metadata
FILE_SUFFIX = ".npz"  # a module file is a footfall height map
_SAMPLE_POINTS = 1 << 20  # board cells interpolated at a time (bounds the temporaries)
_SLIVER = 1e-9  # [board cells] overlaps shorter than this are rounding, not coverage


@dataclass(frozen=True, eq=False)
class FileModule:
    """A board module read from a height-map file.

    ``name`` is the file's name, recorded in the board's metadata; ``hmap`` the map it
    holds, at its own resolution [m/cell] and extent [m].
    """

    name: str
    hmap: HeightMap

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise FootfallError(f"a file module needs its file's name, got {self.name!r}")
        if not isinstance(self.hmap, HeightMap):
            raise FootfallError(f"{self.name}: a file module holds a HeightMap, got "
                                f"{type(self.hmap).__name__}")

    @classmethod
    def load(cls, path: str | os.PathLike) -> "FileModule":
        """Read a footfall height map (``.npz``) as a module.

        Raises
        ------
        FootfallError
            Naming the file: missing, not a footfall height map, damaged, above the
            ``max_map_cells`` or file-size limits, or without any height data.
        """
        p = Path(path)
        if p.suffix.lower() != FILE_SUFFIX:
            raise FootfallError(f"{p}: a board module file must be a footfall height map "
                                f"({FILE_SUFFIX}); import a scan first with "
                                f"`footfall terrain import {p} ... -o {p.stem}{FILE_SUFFIX}`")
        return cls(p.name, HeightMap.load(p))


@dataclass(frozen=True)
class BoardGrid:
    """The grid a board's modules share: cell size [m/cell] and cells across (along y)."""

    resolution: float  # [m/cell]
    width_cells: int  # [cells] along y


def module_cells(module: FileModule, grid: BoardGrid) -> int:
    """Board cells along x that ``module`` will fill: its extent rounded to whole cells.

    Raises
    ------
    FootfallError
        Naming the file: it is shorter than one board cell, or the module on the board's
        grid would exceed the ``max_map_cells`` limit (checked before anything is made).
    """
    length = module.hmap.length[0]  # [m]
    n = int(round(length / grid.resolution))
    if n < 1:
        raise FootfallError(f"{module.name}: the map is {length * 1000:.3g} mm long, shorter "
                            f"than one board cell ({grid.resolution * 1000:g} mm)")
    check_cells((n, grid.width_cells), f"{module.name}: the module resampled to the board's "
                f"{grid.resolution * 1000:g} mm grid ({length:.3g} m long)")
    return n


def fit_to_board(module: FileModule, grid: BoardGrid) -> tuple[np.ndarray, dict[str, Any]]:
    """The module's heights on the board grid and the fields of its board record.

    Returns
    -------
    heights : ndarray, shape (module_cells(module, grid), grid.width_cells)
        Heights [m], lowest datum 0, NaN where there is no data (see the module docstring).
    record : dict
        ``kind`` ("file"), ``file`` (name), ``content_hash`` (of the source map),
        ``resolution`` [m/cell] and ``width`` [m] of the source, ``width_fit``
        ("exact", "padded" or "cropped") and ``z_shift`` [m] added to its heights;
        the caller adds ``x_start`` and ``x_end`` [m].

    Raises
    ------
    FootfallError
        Naming the file: the module would exceed the ``max_map_cells`` limit, or no data
        lies within the board's width.
    """
    src = module.hmap
    shape = (module_cells(module, grid), grid.width_cells)
    ratio = src.resolution / grid.resolution  # [board cells per source cell]
    offset = tuple((shape[k] - src.shape[k] * ratio) / 2 for k in (0, 1))  # [board cells]
    if ratio > 1.0:
        heights = _bilinear(src, grid.resolution, shape, offset)
    else:
        heights = _area_mean(src.heights, ratio, shape, offset)
    if np.isnan(heights).all():
        raise FootfallError(f"{module.name}: no height data within the board's "
                            f"{grid.width_cells * grid.resolution:g} m width (centred in y)")
    z_shift = 0.0 - float(np.nanmin(heights))  # [m] (0.0 - : never -0.0)
    heights += z_shift
    width = src.length[1]  # [m]
    return heights, {"kind": FILE_KIND, "file": module.name, "content_hash": src.content_hash(),
                     "resolution": src.resolution, "width": width,
                     "width_fit": _width_fit(width, grid), "z_shift": z_shift}


def _width_fit(width: float, grid: BoardGrid) -> str:
    """How a module ``width`` [m] wide meets the board's width: exact, padded or cropped."""
    board = grid.width_cells * grid.resolution  # [m]
    if math.isclose(width, board, rel_tol=0.0, abs_tol=_SLIVER * grid.resolution):
        return "exact"
    return "padded" if width < board else "cropped"


def _bilinear(src: HeightMap, resolution: float, shape: tuple[int, int],
              offset: tuple[float, float]) -> np.ndarray:
    """Heights [m] of ``src`` at the centres of a grid of ``shape`` cells of ``resolution`` [m].

    The grid's cell (0, 0) has its lower corner ``offset`` [grid cells] from the source's
    lower corner; :meth:`HeightMap.height_at` interpolates (NaN off the map and in holes).
    Sampled a block of rows at a time, so the temporaries stay small.
    """
    x_min, _, y_min, _ = src.bounds
    x = x_min + (np.arange(shape[0]) + 0.5 - offset[0]) * resolution  # [m] in src's frame
    y = y_min + (np.arange(shape[1]) + 0.5 - offset[1]) * resolution
    out = np.empty(shape)
    rows = max(1, _SAMPLE_POINTS // shape[1])
    for i in range(0, shape[0], rows):  # blocks of rows, not cells
        xx, yy = np.meshgrid(x[i:i + rows], y, indexing="ij")
        out[i:i + rows] = src.height_at(np.stack([xx, yy], axis=-1))
    return out


def _area_mean(heights: np.ndarray, ratio: float, shape: tuple[int, int],
               offset: tuple[float, float]) -> np.ndarray:
    """Area-weighted mean [m] of the data in ``heights`` over each cell of a coarser grid.

    A source cell is ``ratio`` (<= 1) grid cells wide; source cell (0, 0) has its lower
    corner ``offset`` [grid cells] from the grid's. A grid cell none of whose area is
    covered by a source cell with data is NaN.
    """
    along_x = _overlaps(shape[0], heights.shape[0], ratio, offset[0])
    along_y = _overlaps(shape[1], heights.shape[1], ratio, offset[1])
    has_data = ~np.isnan(heights)
    total = along_y @ (along_x @ np.where(has_data, heights, 0.0)).T  # (ny, nx) [m cells^2]
    area = along_y @ (along_x @ has_data.astype(np.float64)).T  # (ny, nx) [cells^2]
    out = np.full(area.shape, np.nan)
    np.divide(total, area, out=out, where=area > 0.0)
    return out.T


def _overlaps(n_out: int, n_in: int, ratio: float, offset: float) -> sparse.csr_matrix:
    """(n_out, n_in) overlap lengths [output cells] of input cells with output cells.

    Input cell k spans ``[offset + k ratio, offset + (k + 1) ratio)`` output cells, output
    cell i spans ``[i, i + 1)``; with ``ratio <= 1`` an input cell meets at most two output
    cells. Overlaps off the output grid are dropped.
    """
    k = np.arange(n_in)
    start = offset + k * ratio
    first = np.floor(start)
    in_first = np.minimum(start + ratio, first + 1.0) - start
    rows = np.concatenate([first, first + 1.0])
    lengths = np.concatenate([in_first, ratio - in_first])
    keep = (rows >= 0) & (rows < n_out) & (lengths > _SLIVER)
    return sparse.csr_matrix((lengths[keep], (rows[keep].astype(np.int64), np.tile(k, 2)[keep])),
                             shape=(n_out, n_in))
