"""Import elevation data from common file formats into a :class:`HeightMap`.

The bridge from the outside world (depth-camera clouds, DEM exports, 16-bit
height images, raw arrays) to footfall's one terrain type. Every problem with
an input file is reported as a :class:`FootfallError` naming that file.

Supported suffixes (case-insensitive), :data:`SUFFIXES`, read by :func:`import_terrain`:

``.npz``
    A footfall height map written by :meth:`HeightMap.save`, read by
    :meth:`HeightMap.load`; carries its own geometry and frame, so none of
    the geometry/scaling arguments may be given.
``.npy``
    A 2-D integer or float array, read without pickle, indexed ``[x, y]``
    exactly like :attr:`HeightMap.heights` (footfall's own convention).
``.png``
    A 16-bit greyscale PNG (Pillow mode ``I;16``). Image rows are y with
    row 0 at the top (largest y), columns are x, so
    ``heights = img[::-1, :].T * z_scale``. 8-bit, palette and colour
    PNGs are rejected: 256 levels are too coarse for footholds and such
    images are usually renderings of terrain rather than elevation data.
``.ply``
    A point cloud, ASCII or binary PLY read with plyfile: the ``vertex``
    element's scalar ``x``, ``y``, ``z`` properties; other elements are ignored.
``.xyz``
    A text point cloud: UTF-8, one point per line, whitespace- and/or
    comma-separated; the first three columns are x, y, z [m], further
    columns are ignored, ``#`` starts a comment.

Point clouds are rasterised by :func:`rasterize_points` (the highest point
per cell, empty cells NaN, points with non-finite coordinates dropped).

Sizes are checked before anything is allocated, against the limits in force
(:mod:`footfall.core.limits`): the file against ``max_file_bytes``, a
``.npy`` header's shape and a PNG's width x height against
``max_map_cells``, a PLY header's element counts and an ``.xyz`` file's lines
against ``max_scan_points``, and the grid a cloud rasterises to against
``max_map_cells``.
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import warnings
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import MAX_COORDINATE, HeightMap
from footfall.core.limits import Limits, current_limits
from footfall.core.npz import HEADER_ERRORS, npy_header
from footfall.core.paths import readable_file

__all__ = ["import_terrain", "rasterize_points", "SUFFIXES", "MAX_CELLS"]

MAX_CELLS = Limits().max_map_cells  # the default of the limit on rasterised grids (raise the
# limit max_map_cells, not this constant: the limit in force is current_limits().max_map_cells)
PLY_HEADER_BYTES = 1 << 16  # [bytes] the longest PLY header read
_NPY_HEADER_ERRORS = HEADER_ERRORS + (OSError,)


@dataclass(frozen=True)
class _Options:
    """The validated user arguments handed to a reader (``None`` = not given)."""

    resolution: float | None  # [m/cell]
    z_scale: float | None  # [m per raw unit]
    nodata: float | None  # raw value meaning "no data"
    origin: tuple[float, float] | None  # [m]
    frame: str | None


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


def _validate(path: Path, resolution: Any, z_scale: Any, nodata: Any, origin: Any,
              frame: Any) -> _Options:
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
    return _Options(res, zs, nd, org, frame)  # type: ignore[arg-type]


def _require_resolution(path: Path, opts: _Options, kind: str) -> float:
    if opts.resolution is None:
        raise FootfallError(f"{path}: resolution [m/cell] is required to import a {kind}")
    return opts.resolution


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _make_map(path: Path, heights: np.ndarray, resolution: float, origin: tuple[float, float],
              frame: str, metadata: dict) -> HeightMap:
    try:
        return HeightMap(heights, resolution, origin, frame, metadata)
    except FootfallError as exc:
        raise FootfallError(f"{path}: {exc}") from None


def _grid_metadata(path: Path, fmt: str, opts: _Options, z_scale: float) -> dict:
    return {"source": str(path), "source_sha256": _sha256(path), "source_format": fmt,
            "importer": "footfall.terrain.scans", "z_scale": z_scale, "nodata": opts.nodata}


def _grid_to_map(path: Path, raw: np.ndarray, fmt: str, opts: _Options,
                 z_scale: float) -> HeightMap:
    """Heights = raw * z_scale on a grid already indexed [x, y]; raw == nodata -> NaN."""
    resolution = _require_resolution(path, opts, f".{fmt} grid")
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
    return _make_map(path, heights, resolution, opts.origin or (0.0, 0.0),
                     opts.frame or "world", _grid_metadata(path, fmt, opts, z_scale))


# -------------------------------------------------------------------- readers
def _read_npz(path: Path, opts: _Options) -> HeightMap:
    given = [name for name in ("resolution", "z_scale", "nodata", "origin", "frame")
             if getattr(opts, name) is not None]
    if given:
        raise FootfallError(f"{path}: a .npz footfall height map carries its own geometry; "
                            f"do not pass {', '.join(given)}")
    return HeightMap.load(path)


def _read_npy(path: Path, opts: _Options) -> HeightMap:
    try:
        with open(path, "rb") as fh:
            shape, _, dtype = npy_header(fh)
            if len(shape) == 2 and not dtype.hasobject:
                _check_cells(path, shape, "the .npy array")
            fh.seek(0)
            raw = np.lib.format.read_array(fh, allow_pickle=False)
    except FootfallError:
        raise
    except _NPY_HEADER_ERRORS as exc:
        raise FootfallError(f"{path}: not a readable .npy array ({exc or type(exc).__name__})"
                            ) from None
    if raw.dtype.names is not None or not (np.issubdtype(raw.dtype, np.integer)
                                           or np.issubdtype(raw.dtype, np.floating)):
        raise FootfallError(f"{path}: .npy must hold integer or float heights, "
                            f"got dtype {raw.dtype}")
    if raw.ndim != 2:
        raise FootfallError(f"{path}: .npy must be a 2-D array indexed [x, y], "
                            f"got shape {raw.shape}")
    return _grid_to_map(path, raw, "npy", opts, 1.0 if opts.z_scale is None else opts.z_scale)


_PNG_16BIT_MODES = ("I;16", "I;16B", "I;16L", "I")  # "I": how older Pillows open 16-bit grey


def _check_cells(path: Path, shape: tuple[int, ...], what: str) -> None:
    """Refuse a grid above the ``max_map_cells`` limit, before it is read."""
    cells = math.prod(int(n) for n in shape)
    limit = current_limits().max_map_cells
    if cells > limit:
        raise FootfallError(f"{path}: {what} has {cells} cells, above the limit of {limit} "
                            f"(raise it with --limit max_map_cells=N)")


@contextlib.contextmanager
def _pillow_limit(cells: int) -> Any:
    """Pillow's decompression-bomb check at our limit, and without its warning (one line)."""
    from PIL import Image

    before = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = cells  # Pillow raises above twice this, warns above it
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            yield
    finally:
        Image.MAX_IMAGE_PIXELS = before


def _read_png(path: Path, opts: _Options) -> HeightMap:
    from PIL import Image, UnidentifiedImageError

    if opts.z_scale is None:
        raise FootfallError(f"{path}: z_scale [m per count] is required to import a 16-bit PNG")
    try:
        with _pillow_limit(current_limits().max_map_cells), Image.open(path) as img:
            fmt, mode = img.format, img.mode
            if fmt == "PNG" and mode in _PNG_16BIT_MODES:
                _check_cells(path, img.size, "the PNG image")  # before decoding a pixel
                img.load()
                raw = np.array(img)
    except FootfallError:
        raise
    except UnidentifiedImageError:
        raise FootfallError(f"{path}: not a readable PNG image") from None
    except Image.DecompressionBombError:
        raise FootfallError(f"{path}: the PNG image has more pixels than the limit of "
                            f"{current_limits().max_map_cells} (raise it with "
                            f"--limit max_map_cells=N)") from None
    except (OSError, SyntaxError, ValueError, EOFError, zlib.error) as exc:
        raise FootfallError(f"{path}: corrupt or truncated PNG ({exc})") from None
    if fmt != "PNG":
        raise FootfallError(f"{path}: holds a {fmt} image, not a PNG")
    if mode not in _PNG_16BIT_MODES:
        raise FootfallError(
            f"{path}: a PNG of mode {mode!r} (8-bit, colour or palette) is not a height "
            "image; footfall reads 16-bit greyscale PNGs only -- re-export the elevation "
            "as a 16-bit greyscale PNG (or a .npy array)")
    if raw.ndim != 2:
        raise FootfallError(f"{path}: expected a single-channel image, got shape {raw.shape}")
    # Image rows are y with row 0 at the top (largest y), columns are x.
    return _grid_to_map(path, raw[::-1, :].T, "png", opts, opts.z_scale)


def _check_ply_counts(path: Path) -> None:
    """Refuse a PLY whose header declares more points (or other elements) than the limit.

    Read before plyfile, which allocates every element's declared count up front.
    """
    with open(path, "rb") as fh:
        head = fh.read(PLY_HEADER_BYTES)
    end = head.find(b"end_header")
    if end < 0:
        return  # plyfile reports the malformed header
    limit = current_limits().max_scan_points
    for line in head[:end].splitlines():
        words = line.split()
        if len(words) == 3 and words[0] == b"element":
            name = words[1].decode("ascii", "replace")
            try:
                count = int(words[2])
            except ValueError:
                raise FootfallError(f"{path}: PLY element {name!r} has a count that is not a "
                                    f"whole number: {words[2].decode('ascii', 'replace')!r}"
                                    ) from None
            if count > limit:
                raise FootfallError(f"{path}: PLY element {name!r} declares {count} items, "
                                    f"above the limit of {limit} (raise it with "
                                    f"--limit max_scan_points=N)")


def _read_ply(path: Path, opts: _Options) -> np.ndarray:
    from plyfile import PlyData, PlyParseError

    _check_ply_counts(path)
    try:
        with open(path, "rb") as fh:
            lines = fh.read(256).splitlines()
        # plyfile reads ASCII data through a TextIOWrapper it never closes around a binary
        # stream; handing it a text stream for ASCII files avoids the leaked wrapper.
        ascii_ply = len(lines) > 1 and lines[1].strip().startswith(b"format ascii")
        with (open(path, encoding="ascii") if ascii_ply else open(path, "rb")) as fh, \
                np.errstate(all="ignore"):  # an out-of-range value becomes inf, refused later
            ply = PlyData.read(fh, mmap=False)
    except (PlyParseError, ValueError, EOFError, OSError, IndexError) as exc:
        raise FootfallError(f"{path}: corrupt or truncated PLY file ({exc})") from None
    if "vertex" not in ply:
        raise FootfallError(f"{path}: PLY file has no 'vertex' element")
    data = ply["vertex"].data
    names = data.dtype.names or ()
    missing = [c for c in "xyz" if c not in names]
    if missing:
        raise FootfallError(f"{path}: PLY vertex element lacks {', '.join(missing)} "
                            f"(has {', '.join(names) or 'no properties'})")
    columns = []
    for c in "xyz":
        dt = data.dtype[c]
        if not (np.issubdtype(dt, np.integer) or np.issubdtype(dt, np.floating)):
            raise FootfallError(f"{path}: PLY vertex property {c!r} must be a number, "
                                f"not a list")
        columns.append(np.asarray(data[c], dtype=np.float64))
    return np.stack(columns, axis=1) if len(data) else np.empty((0, 3))


def _bounded_lines(path: Path, fh: Any) -> Any:
    """The lines of an .xyz file (commas as blanks), refused beyond ``max_scan_points``."""
    limit = current_limits().max_scan_points
    for n, line in enumerate(fh):
        if n >= limit and line.split("#", 1)[0].strip():
            raise FootfallError(f"{path}: more than {limit} points (lines), the limit "
                                f"(raise it with --limit max_scan_points=N)")
        yield line.replace(",", " ")


def _read_xyz(path: Path, opts: _Options) -> np.ndarray:
    try:
        with open(path, encoding="utf-8") as fh, warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            points = np.loadtxt(_bounded_lines(path, fh), dtype=np.float64,
                                comments="#", usecols=(0, 1, 2), ndmin=2)
    except FootfallError:
        raise
    except (ValueError, OSError) as exc:  # UnicodeDecodeError is a ValueError
        raise FootfallError(f"{path}: not a readable .xyz text file of x y z columns "
                            f"({exc})") from None
    return points


def _cloud(reader: Callable[[Path, _Options], np.ndarray], fmt: str
           ) -> Callable[[Path, _Options], HeightMap]:
    """Turn a reader of an (n, 3) point array into a reader of a rasterised HeightMap."""

    def read(path: Path, opts: _Options) -> HeightMap:
        if opts.origin is not None:
            raise FootfallError(f"{path}: a point cloud's coordinates are positions already; "
                                "origin applies to .npy/.png grids only")
        resolution = _require_resolution(path, opts, f".{fmt} point cloud")
        points = reader(path, opts)
        z_scale = 1.0 if opts.z_scale is None else opts.z_scale
        try:
            heights, origin, info = _rasterize(points, resolution, z_scale, opts.nodata)
        except FootfallError as exc:
            raise FootfallError(f"{path}: {exc}") from None
        meta = {"source": str(path), "source_sha256": _sha256(path), "source_format": fmt,
                "importer": "footfall.terrain.scans", "z_scale": z_scale, "nodata": opts.nodata,
                "rasterization": "highest point per cell", **info}
        return _make_map(path, heights, resolution, origin, opts.frame or "world", meta)

    return read


_READERS: dict[str, Callable[[Path, _Options], HeightMap]] = {
    ".npz": _read_npz,
    ".npy": _read_npy,
    ".png": _read_png,
    ".ply": _cloud(_read_ply, "ply"),
    ".xyz": _cloud(_read_xyz, "xyz"),
}

SUFFIXES: tuple[str, ...] = tuple(_READERS)  # the file suffixes import_terrain understands


# ------------------------------------------------------------- rasterisation
def _rasterize(points: np.ndarray, resolution: float, z_scale: float, nodata: float | None
               ) -> tuple[np.ndarray, tuple[float, float], dict]:
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
    grid = np.full(nx * ny, -np.inf)
    np.maximum.at(grid, i * ny + j, z)
    grid[grid == -np.inf] = np.nan
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
    opts = _validate(label, resolution, z_scale, nodata, None, frame)
    if opts.resolution is None or opts.z_scale is None:
        raise FootfallError("resolution and z_scale must be given")
    try:
        pts = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise FootfallError(f"points must be numbers of shape (n, 3) ({exc})") from None
    heights, origin, info = _rasterize(pts, opts.resolution, opts.z_scale, opts.nodata)
    return HeightMap(heights, opts.resolution, origin, frame,
                     {**(metadata or {}), "rasterization": "highest point per cell", **info})


# ---------------------------------------------------------------------- entry
def import_terrain(path: str | os.PathLike, *, resolution: float | None = None,
                   z_scale: float | None = None, origin: tuple[float, float] | None = None,
                   frame: str | None = None, nodata: float | None = None) -> HeightMap:
    """Read elevation data from a file into a :class:`HeightMap`, by file suffix.

    Parameters
    ----------
    path : str or os.PathLike
        The file; its suffix (case-insensitive) picks the reader, one of
        :data:`SUFFIXES`: ``.npz``, ``.npy``, ``.png``, ``.ply``, ``.xyz``.
    resolution : float, optional
        Cell size [m/cell], > 0. Required for ``.npy``, ``.png`` (the
        spacing of the array's cells/pixels) and point clouds (the cell size
        to rasterise at); must not be given for ``.npz``.
    z_scale : float, optional
        Metres per raw unit of height, > 0: heights = raw * z_scale.
        Required for ``.png`` [m per count]; default 1 for ``.npy`` and
        point clouds (applied to z only); must not be given for ``.npz``.
    origin : (float, float), optional
        Position [m] of the centre of cell (0, 0) for ``.npy`` and ``.png``
        grids; default (0, 0). For a PNG that is the centre of the
        bottom-left pixel. Not allowed for point clouds (the origin comes
        from the points, see :func:`rasterize_points`) nor ``.npz``.
    frame : str, optional
        Name of the frame of the positions; default ``"world"``. Not allowed
        for ``.npz`` (the file records its frame).
    nodata : float, optional
        A raw value (before ``z_scale``) that means "no data": cells of a
        ``.npy``/``.png`` equal to it become NaN, points of a cloud whose z
        equals it are dropped. Not given: every value is data (NaN in a
        float ``.npy`` is always no data). Use ``nodata=0`` for PNGs whose
        0 count marks missing pixels.

    Returns
    -------
    HeightMap
        Heights [m]; ``metadata`` records the source file, its SHA-256, the
        format, ``z_scale``, ``nodata`` and, for clouds, point counts.

    Notes
    -----
    The formats are described in the module's docstring (:mod:`footfall.terrain.scans`).

    Raises
    ------
    FootfallError
        With a message naming the file: missing file, unknown suffix, corrupt
        or truncated file, wrong dimensionality or dtype, a missing or
        invalid argument, an empty cloud, fewer than 2 x 2 cells, or no data.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    reader = _READERS.get(suffix)
    if reader is None:
        raise FootfallError(f"{p}: unknown terrain file type {suffix or '(no suffix)'!r}; "
                            f"known: {', '.join(SUFFIXES)}")
    readable_file(p)  # missing, not a file, permission denied, too large
    opts = _validate(p, resolution, z_scale, nodata, origin, frame)
    return reader(p, opts)
