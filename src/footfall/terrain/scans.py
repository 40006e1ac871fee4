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

``.mcap``, ``.db3`` or a bag folder
    A ROS 2 bag of ``grid_map_msgs/GridMap`` (:mod:`footfall.terrain.bags`): one
    layer of one message, chosen by ``topic``, ``layer``, ``message`` or ``time``.
``.las``, ``.laz``
    A LiDAR point cloud (:mod:`footfall.terrain.lidar`): the kept ``classes``
    gridded at ``resolution`` by a ``statistic`` per cell, in the local frame.
``.tif``, ``.tiff``
    A GeoTIFF elevation model (:mod:`footfall.terrain.geotiff`): one ``band``,
    optionally a window (``bounds``), in the local frame.

Point clouds (``.ply``, ``.xyz``) are rasterised as by :func:`footfall.terrain.raster.rasterize_points`
(the highest point per cell, empty cells NaN, points with non-finite
coordinates dropped); the readers' shared steps are :mod:`footfall.terrain.raster`.

Sizes are checked before anything is allocated, against the limits in force
(:mod:`footfall.core.limits`): the file against ``max_file_bytes``, a
``.npy`` header's shape and a PNG's width x height against
``max_map_cells``, a PLY header's element counts and an ``.xyz`` file's lines
against ``max_scan_points``, and the grid a cloud rasterises to against
``max_map_cells``.
"""

from __future__ import annotations

import contextlib
import os
import warnings
import zlib
from pathlib import Path
from typing import Any, Callable

import numpy as np
from PIL import Image, UnidentifiedImageError
from plyfile import PlyData, PlyParseError

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.limits import current_limits
from footfall.core.npz import HEADER_ERRORS, npy_header
from footfall.core.paths import readable_file
from footfall.terrain.grid_map import DEFAULT_LAYER
from footfall.terrain.raster import (
    LOCAL_FRAME,
    ScanOptions,
    check_grid_cells,
    file_sha256,
    grid_to_map,
    make_map,
    rasterize_cloud,
    require_resolution,
    scan_options,
)

__all__ = ["import_terrain", "SUFFIXES"]

PLY_HEADER_BYTES = 1 << 16  # [bytes] the longest PLY header read
_NPY_HEADER_ERRORS = HEADER_ERRORS + (OSError,)


# -------------------------------------------------------------------- readers
def _read_npz(path: Path, opts: ScanOptions) -> HeightMap:
    given = [name for name in ("resolution", "z_scale", "nodata", "origin", "frame")
             if getattr(opts, name) is not None]
    if given:
        raise FootfallError(f"{path}: a .npz footfall height map carries its own geometry; "
                            f"do not pass {', '.join(given)}")
    return HeightMap.load(path)


def _read_npy(path: Path, opts: ScanOptions) -> HeightMap:
    try:
        with open(path, "rb") as fh:
            shape, _, dtype = npy_header(fh)
            if len(shape) == 2 and not dtype.hasobject:
                check_grid_cells(path, shape, "the .npy array")
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
    return grid_to_map(path, raw, "npy", opts, 1.0 if opts.z_scale is None else opts.z_scale)


_PNG_16BIT_MODES = ("I;16", "I;16B", "I;16L", "I")  # "I": how older Pillows open 16-bit grey


@contextlib.contextmanager
def _pillow_limit(cells: int) -> Any:
    """Pillow's decompression-bomb check at our limit, and without its warning (one line)."""
    before = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = cells  # Pillow raises above twice this, warns above it
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            yield
    finally:
        Image.MAX_IMAGE_PIXELS = before


def _read_png(path: Path, opts: ScanOptions) -> HeightMap:
    if opts.z_scale is None:
        raise FootfallError(f"{path}: z_scale [m per count] is required to import a 16-bit PNG")
    try:
        with _pillow_limit(current_limits().max_map_cells), Image.open(path) as img:
            fmt, mode = img.format, img.mode
            if fmt == "PNG" and mode in _PNG_16BIT_MODES:
                check_grid_cells(path, img.size, "the PNG image")  # before decoding a pixel
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
    return grid_to_map(path, raw[::-1, :].T, "png", opts, opts.z_scale)


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


def _read_ply(path: Path, opts: ScanOptions) -> np.ndarray:
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


def _read_xyz(path: Path, opts: ScanOptions) -> np.ndarray:
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


def _cloud(reader: Callable[[Path, ScanOptions], np.ndarray], fmt: str
           ) -> Callable[[Path, ScanOptions], HeightMap]:
    """Turn a reader of an (n, 3) point array into a reader of a rasterised HeightMap."""

    def read(path: Path, opts: ScanOptions) -> HeightMap:
        if opts.origin is not None:
            raise FootfallError(f"{path}: a point cloud's coordinates are positions already; "
                                "origin applies to .npy/.png grids only")
        resolution = require_resolution(path, opts, f".{fmt} point cloud")
        points = reader(path, opts)
        z_scale = 1.0 if opts.z_scale is None else opts.z_scale
        try:
            heights, origin, info = rasterize_cloud(points, resolution, z_scale, opts.nodata)
        except FootfallError as exc:
            raise FootfallError(f"{path}: {exc}") from None
        meta = {"source": str(path), "source_sha256": file_sha256(path), "source_format": fmt,
                "importer": "footfall.terrain.scans", "z_scale": z_scale, "nodata": opts.nodata,
                "rasterization": "highest point per cell", **info}
        return make_map(path, heights, resolution, origin, opts.frame or "world", meta)

    return read


def _refuse(path: Path, opts: ScanOptions, names: tuple[str, ...], why: str) -> None:
    """Refuse the general options ``names`` where they were given: ``why`` says what the
    format carries instead."""
    given = [n for n in names if getattr(opts, n) is not None]
    if given:
        raise FootfallError(f"{path}: {why}; do not pass {', '.join(given)}")


def _read_bag(path: Path, opts: ScanOptions) -> HeightMap:
    from footfall.terrain.bags import BagChoice, read_grid_map

    _refuse(path, opts, ("resolution", "z_scale", "nodata", "origin", "frame"),
            "a ROS 2 bag's grid map carries its own geometry, frame and holes")
    f = opts.formats
    hmap, _ = read_grid_map(path, BagChoice(f.get("topic"), f.get("layer", DEFAULT_LAYER),
                                            f.get("message"), f.get("time")))
    return hmap


def _georeferenced(path: Path, heights: np.ndarray, resolution: float, fmt: str,
                   meta: dict) -> HeightMap:
    """A map of a georeferenced file in the local frame (:mod:`footfall.terrain.georeference`)."""
    return make_map(path, heights, resolution, (0.0, 0.0), LOCAL_FRAME,
                    {"source": str(path), "source_sha256": file_sha256(path),
                     "source_format": fmt, "importer": "footfall.terrain.scans", **meta})


def _read_lidar(path: Path, opts: ScanOptions) -> HeightMap:
    from footfall.terrain.lidar import read_lidar

    _refuse(path, opts, ("z_scale", "nodata", "origin", "frame"),
            "a LAS / LAZ file carries its own scale, and is placed in its local frame")
    resolution = require_resolution(path, opts, "LAS / LAZ point cloud")
    classes = opts.formats.get("classes")
    try:
        heights, res, meta = read_lidar(path, resolution,
                                        None if classes is None else tuple(classes),
                                        opts.formats.get("statistic", "max"))
    except FootfallError as exc:
        raise FootfallError(f"{path}: {exc}") from None
    return _georeferenced(path, heights, res, path.suffix.lower()[1:], meta)


def _read_geotiff(path: Path, opts: ScanOptions) -> HeightMap:
    from footfall.terrain.geotiff import read_geotiff

    _refuse(path, opts, ("origin", "frame"), "a GeoTIFF is placed by its own transform, in "
            "its local frame")
    try:
        heights, res, meta = read_geotiff(path, opts.formats.get("band", 1), opts.resolution,
                                          opts.formats.get("bounds"))
    except FootfallError as exc:
        raise FootfallError(f"{path}: {exc}") from None
    if opts.nodata is not None:
        heights[heights == opts.nodata] = np.nan
    z_scale = 1.0 if opts.z_scale is None else opts.z_scale
    with np.errstate(over="ignore", invalid="ignore"):  # inf is refused by HeightMap by name
        heights = heights * z_scale
    if np.isnan(heights).all():
        raise FootfallError(f"{path}: no data (every cell is nodata)")
    return _georeferenced(path, heights, res, "geotiff", {**meta, "z_scale": z_scale})


_READERS: dict[str, Callable[[Path, ScanOptions], HeightMap]] = {
    ".npz": _read_npz,
    ".npy": _read_npy,
    ".png": _read_png,
    ".ply": _cloud(_read_ply, "ply"),
    ".xyz": _cloud(_read_xyz, "xyz"),
    ".las": _read_lidar,
    ".laz": _read_lidar,
    ".tif": _read_geotiff,
    ".tiff": _read_geotiff,
    ".mcap": _read_bag,
    ".db3": _read_bag,
}
BAG_FOLDER = "(a ROS 2 bag folder)"  # the key of a folder among the readers' names

SUFFIXES: tuple[str, ...] = tuple(_READERS)  # the file suffixes import_terrain understands

# The options of one format alone, and the readers that take each (the rest refuse it).
FORMAT_OPTIONS: dict[str, tuple[str, ...]] = {
    "topic": (".mcap", ".db3", BAG_FOLDER),
    "layer": (".mcap", ".db3", BAG_FOLDER),
    "message": (".mcap", ".db3", BAG_FOLDER),
    "time": (".mcap", ".db3", BAG_FOLDER),
    "classes": (".las", ".laz"),
    "statistic": (".las", ".laz"),
    "band": (".tif", ".tiff"),
    "bounds": (".tif", ".tiff"),
}
_FORMAT_NAMES = {".mcap": "ROS 2 bags", ".db3": "ROS 2 bags", BAG_FOLDER: "ROS 2 bags",
                 ".las": "LAS / LAZ point clouds", ".laz": "LAS / LAZ point clouds",
                 ".tif": "GeoTIFF rasters", ".tiff": "GeoTIFF rasters"}


def _check_format_options(path: Path, key: str, given: dict) -> None:
    """Refuse an option of another format than the file's (``key``: its suffix or folder)."""
    for name in given:
        readers = FORMAT_OPTIONS[name]
        if key not in readers:
            raise FootfallError(f"{path}: {name} applies to {_FORMAT_NAMES[readers[0]]} only")


# ---------------------------------------------------------------------- entry
def import_terrain(path: str | os.PathLike, *, resolution: float | None = None,
                   z_scale: float | None = None, origin: tuple[float, float] | None = None,
                   frame: str | None = None, nodata: float | None = None,
                   topic: str | None = None, layer: str | None = None,
                   message: int | None = None, time: float | None = None,
                   classes: tuple[int, ...] | None = None, statistic: str | None = None,
                   band: int | None = None,
                   bounds: tuple[float, float, float, float] | None = None) -> HeightMap:
    # long: one entry for every format, its options documented in one place
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
        from the points, see :func:`~footfall.terrain.raster.rasterize_points`) nor ``.npz``.
    frame : str, optional
        Name of the frame of the positions; default ``"world"``. Not allowed
        for ``.npz`` (the file records its frame).
    nodata : float, optional
        A raw value (before ``z_scale``) that means "no data": cells of a
        ``.npy``/``.png`` equal to it become NaN, points of a cloud whose z
        equals it are dropped. Not given: every value is data (NaN in a
        float ``.npy`` is always no data). Use ``nodata=0`` for PNGs whose
        0 count marks missing pixels.

    topic, layer, message, time : optional
        ROS 2 bags only: the GridMap topic (needed where there are several), the layer
        (default ``elevation``), the message's index (negative from the end; default
        the last) or the last message at or before ``time`` [s] after the bag's start.
    classes, statistic : optional
        LAS / LAZ only: the ASPRS classes kept (default: ground where classified) and
        a cell's height from its points (``max``, the default, ``min`` or ``mean``).
    band, bounds : optional
        GeoTIFF only: the band read (default 1) and a window (x min, y min, x max,
        y max) in the file's coordinates.

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
    formats = {"topic": topic, "layer": layer, "message": message, "time": time,
               "classes": classes, "statistic": statistic, "band": band, "bounds": bounds}
    if p.is_dir() and p.suffix.lower() not in SUFFIXES:  # a ROS 2 bag folder
        opts = scan_options(p, resolution, z_scale, nodata, origin, frame, formats)
        _check_format_options(p, BAG_FOLDER, opts.formats)
        return _read_bag(p, opts)
    suffix = p.suffix.lower()
    reader = _READERS.get(suffix)
    if reader is None:
        raise FootfallError(f"{p}: unknown terrain file type {suffix or '(no suffix)'!r}; "
                            f"known: {', '.join(SUFFIXES)} or a ROS 2 bag folder")
    readable_file(p)  # missing, not a file, permission denied, too large
    opts = scan_options(p, resolution, z_scale, nodata, origin, frame, formats)
    _check_format_options(p, suffix, opts.formats)
    return reader(p, opts)
