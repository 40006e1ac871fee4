"""Raw elevation data to height maps: a grid of raw values, or a point cloud rasterised.

What every scan reader (:mod:`footfall.terrain.scans`) shares: the import's
arguments checked (:class:`ScanOptions`), a grid's size checked against the
``max_map_cells`` limit before it is read, raw values scaled to metres with
no data as NaN, and a point cloud rasterised to the highest point per cell
(:func:`rasterize_points`); the map records where it came from.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import MAX_COORDINATE, HeightMap
from footfall.core.limits import Limits, current_limits

LOCAL_FRAME = "local"  # the frame of a surveyed map's local coordinates
# (footfall.terrain.georeference)
STATISTICS = ("max", "min", "mean")  # what a rasterised cell holds of its points' heights
MAX_CELLS = Limits().max_map_cells  # the default of the limit on rasterised grids (raise the
# limit max_map_cells, not this constant: the limit in force is current_limits().max_map_cells)


@dataclass(frozen=True)
class ScanOptions:
    """The validated user arguments handed to a reader (``None`` = not given)."""

    resolution: float | None  # [m/cell]
    z_scale: float | None  # [m per raw unit]
    nodata: float | None  # raw value meaning "no data"
    origin: tuple[float, float] | None  # [m]
    frame: str | None
    formats: dict = field(default_factory=dict)  # the options of one format alone (a bag's
    # topic, a point cloud's class filter, a raster's band ...): name -> value, given ones only


# ----------------------------------------------------------------- validation
def _number(path: Path, name: str, value: Any) -> float:
    if isinstance(value, bool):
        raise FootfallError(f"{path}: {name} must be a number, got {value!r}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise FootfallError(f"{path}: {name} must be a number, got {value!r}") from None


def _positive(path: Path, name: str, value: Any, unit: str) -> float | None:
    if value is None:
        return None
    v = _number(path, name, value)
    if not (math.isfinite(v) and v > 0):
        raise FootfallError(f"{path}: {name} [{unit}] must be a finite number > 0, got {value!r}")
    return v


def scan_options(path: Path, resolution: Any, z_scale: Any, nodata: Any, origin: Any,
              frame: Any, formats: dict | None = None) -> ScanOptions:
    res = _positive(path, "resolution", resolution, "m/cell")
    zs = _positive(path, "z_scale", z_scale, "m per raw unit")
    nd = None if nodata is None else _number(path, "nodata", nodata)
    org = None
    if origin is not None:
        try:
            org = tuple(float(o) for o in origin)
        except (TypeError, ValueError):
            raise FootfallError(f"{path}: origin must be two numbers (x, y) [m], "
                                f"got {origin!r}") from None
        if len(org) != 2 or not all(math.isfinite(o) for o in org):
            raise FootfallError(f"{path}: origin must be two finite numbers (x, y) [m], "
                                f"got {origin!r}")
    if frame is not None and (not isinstance(frame, str) or not frame):
        raise FootfallError(f"{path}: frame must be a non-empty string, got {frame!r}")
    given = {k: v for k, v in (formats or {}).items() if v is not None}
    return ScanOptions(res, zs, nd, org, frame, given)  # type: ignore[arg-type]


def require_resolution(path: Path, opts: ScanOptions, kind: str) -> float:
    if opts.resolution is None:
        raise FootfallError(f"{path}: resolution [m/cell] is required to import a {kind}")
    return opts.resolution


def file_sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def make_map(path: Path, heights: np.ndarray, resolution: float, origin: tuple[float, float],
              frame: str, metadata: dict) -> HeightMap:
    try:
        return HeightMap(heights, resolution, origin, frame, metadata)
    except FootfallError as exc:
        raise FootfallError(f"{path}: {exc}") from None


def grid_metadata(path: Path, fmt: str, opts: ScanOptions, z_scale: float) -> dict:
    return {"source": str(path), "source_sha256": file_sha256(path), "source_format": fmt,
            "importer": "footfall.terrain.scans", "z_scale": z_scale, "nodata": opts.nodata}


def grid_to_map(path: Path, raw: np.ndarray, fmt: str, opts: ScanOptions,
                 z_scale: float) -> HeightMap:
    """Heights = raw * z_scale on a grid already indexed [x, y]; raw == nodata -> NaN."""
    resolution = require_resolution(path, opts, f".{fmt} grid")
    with np.errstate(over="ignore", invalid="ignore"):  # float128 beyond float64: inf, refused
        heights = raw.astype(np.float64)
    with np.errstate(over="ignore", invalid="ignore"):  # inf or NaN, refused by HeightMap
        if opts.nodata is not None:  # (a nodata beyond the raw dtype's range matches nothing)
            heights[raw == opts.nodata] = np.nan
        heights *= z_scale
    if np.isnan(heights).all():
        raise FootfallError(f"{path}: no data (every cell is NaN"
                            + (f" or equal to nodata={opts.nodata:g})" if opts.nodata is not None
                               else ")"))
    return make_map(path, heights, resolution, opts.origin or (0.0, 0.0),
                     opts.frame or "world", grid_metadata(path, fmt, opts, z_scale))


def check_grid_cells(path: Path, shape: tuple[int, ...], what: str) -> None:
    """Refuse a grid above the ``max_map_cells`` limit, before it is read."""
    cells = math.prod(int(n) for n in shape)
    limit = current_limits().max_map_cells
    if cells > limit:
        raise FootfallError(f"{path}: {what} has {cells} cells, above the limit of {limit} "
                            f"(raise it with --limit max_map_cells=N)")


# ------------------------------------------------------------- rasterisation
def rasterize_cloud(points: np.ndarray, resolution: float, z_scale: float, nodata: float | None,
                    statistic: str = "max") -> tuple[np.ndarray, tuple[float, float], dict]:
    """A cloud's grid (nx, ny) [m], the centre of its cell (0, 0) [m] and its point counts:
    each cell the ``statistic`` (:data:`STATISTICS`) of its points' z, NaN without one
    (the anchoring rule of :func:`rasterize_points`)."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.size == 0:
        raise FootfallError("the point cloud is empty")
    if pts.ndim != 2 or pts.shape[1] < 3:
        raise FootfallError(f"points must have shape (n, 3), got {pts.shape}")
    n_read = pts.shape[0]
    keep = np.isfinite(pts[:, :3]).all(axis=1)
    n_nonfinite = int(n_read - keep.sum())
    n_nodata = 0
    if nodata is not None:
        is_nd = keep & (pts[:, 2] == nodata)
        n_nodata = int(is_nd.sum())
        keep &= ~is_nd
    with np.errstate(over="ignore"):  # an overflow gives inf, which HeightMap refuses by name
        x, y, z = pts[keep, 0], pts[keep, 1], pts[keep, 2] * z_scale
    if x.size == 0:
        raise FootfallError(f"no usable points among {n_read} ({n_nonfinite} non-finite, "
                            f"{n_nodata} equal to nodata)")
    far = max(float(np.abs(x).max()), float(np.abs(y).max()))
    if far > MAX_COORDINATE:
        raise FootfallError(f"the points reach {far:.3g} m from the frame's origin, beyond "
                            f"+-{MAX_COORDINATE:g} m")
    x0, y0 = float(x.min()), float(y.min())
    with np.errstate(over="ignore"):  # a span too large gives inf: refused by the cell limit
        fi = np.floor((x - x0) / resolution + 0.5)  # cell index, same rule as position_to_index
        fj = np.floor((y - y0) / resolution + 0.5)
    nx_f, ny_f = float(fi.max()) + 1, float(fj.max()) + 1  # float: no overflow on huge spans
    if nx_f < 2 or ny_f < 2:
        raise FootfallError(f"the points span only {nx_f:.0f} x {ny_f:.0f} cells at resolution "
                            f"{resolution:g} m/cell; a height map needs at least 2 x 2 "
                            "(use a finer resolution)")
    limit = current_limits().max_map_cells
    if nx_f * ny_f > limit:
        raise FootfallError(f"rasterising at {resolution:g} m/cell would make {nx_f:.0f} x "
                            f"{ny_f:.0f} cells (more than {limit}, the max_map_cells limit); "
                            f"use a coarser resolution")
    nx, ny = int(nx_f), int(ny_f)
    i, j = fi.astype(np.int64), fj.astype(np.int64)
    cell = i * ny + j
    if statistic == "mean":
        counts = np.bincount(cell, minlength=nx * ny)
        with np.errstate(invalid="ignore", divide="ignore"):
            grid = np.bincount(cell, weights=z, minlength=nx * ny) / counts
    else:
        empty = -np.inf if statistic == "max" else np.inf
        grid = np.full(nx * ny, empty)
        (np.maximum if statistic == "max" else np.minimum).at(grid, cell, z)
        grid[grid == empty] = np.nan
    info = {"points_read": n_read, "points_used": int(x.size),
            "points_dropped_nonfinite": n_nonfinite, "points_dropped_nodata": n_nodata}
    return grid.reshape(nx, ny), (x0, y0), info


def rasterize_points(points: Any, resolution: float, *, z_scale: float = 1.0,
                     nodata: float | None = None, frame: str = "world",
                     metadata: dict | None = None) -> HeightMap:
    """Rasterise a point cloud into a height map, keeping the highest point per cell.

    Parameters
    ----------
    points : array_like of shape (n, 3)
        Point positions x, y, z [m] in ``frame`` (extra columns are ignored).
    resolution : float
        Cell size [m/cell], > 0.
    z_scale : float, optional
        Factor [m per unit of z] applied to z before rasterising, > 0.
    nodata : float, optional
        A raw z value (before ``z_scale``) that marks a missing point; such
        points are dropped.
    frame : str, optional
        Frame of the points and of the map.
    metadata : dict, optional
        Provenance stored in the map (JSON-serialisable); point counts are added.

    Returns
    -------
    HeightMap
        ``origin = (min x, min y)`` of the usable points, so the minimum
        corner lies at the *centre* of cell (0, 0): cell ``(i, j)`` covers
        ``[x0 + (i - 1/2) r, x0 + (i + 1/2) r) x [y0 + (j - 1/2) r, y0 + (j + 1/2) r)``,
        the same rule as :meth:`HeightMap.position_to_index`. The grid spans
        the points' x-y bounding box (``nx = floor((max x - min x) / r + 1/2) + 1``);
        a cell holds the largest z [m] of its points, NaN if it has none.

    Notes
    -----
    Points with a NaN or infinite coordinate are dropped silently (their
    count is recorded in ``metadata``); an error is raised only if no point
    remains. Anchoring the grid on the minimum point (rather than on its
    lower edge) makes a gridded cloud -- e.g. a DEM exported at the nodes of
    a grid of spacing ``r`` -- put every point on a cell centre, far from the
    cell edges where rounding could pair two points in one cell.

    Raises
    ------
    FootfallError
        If the cloud is empty, has no usable point, spans fewer than 2 x 2
        cells or more than the ``max_map_cells`` limit, or an argument is invalid.
    """
    label = Path("<points>")
    opts = scan_options(label, resolution, z_scale, nodata, None, frame)
    if opts.resolution is None or opts.z_scale is None:
        raise FootfallError("resolution and z_scale must be given")
    try:
        pts = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise FootfallError(f"points must be numbers of shape (n, 3) ({exc})") from None
    heights, origin, info = rasterize_cloud(pts, opts.resolution, opts.z_scale, opts.nodata)
    return HeightMap(heights, opts.resolution, origin, frame,
                     {**(metadata or {}), "rasterization": "highest point per cell", **info})
