"""GeoTIFF elevation models read into height maps, and layers written back as GeoTIFF.

Read and written with ``rasterio`` (GDAL). Reading takes one band (default 1) of a
north-up raster with square pixels; the file's nodata value, and NaN, are holes.
The cell size is the transform's pixel size where the CRS is in metres (or names
none); a geographic CRS (degrees) or one in feet is refused unless ``resolution``
gives the cell size in metres. ``bounds`` (x min, y min, x max, y max in the file's
own coordinates) reads a window of a large file: the pixels it touches. Its size is
checked against ``max_map_cells`` before a pixel is read.

Rows of a raster run from north to south, footfall's ``heights[i, j]`` along +x and
+y, so ``heights = band[::-1, :].T``; the map is placed in the local frame of
:mod:`footfall.terrain.georeference` with the window's CRS and transform kept.
"""

from __future__ import annotations

import contextlib
import math
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import rasterio
from rasterio.errors import NotGeoreferencedWarning, RasterioError
from rasterio.transform import Affine
from rasterio.windows import Window

from footfall.core.atomic import atomic_path
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.limits import current_limits
from footfall.terrain.georeference import (
    Georeference,
    check_metres,
    crs_from_wkt,
    crs_unit,
)

GEOTIFF_SUFFIXES = (".tif", ".tiff")
_SQUARE = 1e-9  # relative difference of pixel width and height still taken as square
_EDGE = 1e-6  # [pixels] a bound this close to a pixel edge is on it (survey coordinates round)


# What a damaged raster raises inside rasterio (GDAL).
_OPEN_ERRORS = (RasterioError, OSError, ValueError, IndexError, TypeError, RuntimeError,
                MemoryError, OverflowError)


def _window(ds: Any, t: Any, bounds: tuple[float, float, float, float] | None) -> Any:
    """The pixel window ``bounds`` touches (the whole raster for None), within the raster."""
    if bounds is None:
        return Window(0, 0, ds.width, ds.height)
    x0, y0, x1, y1 = bounds
    if not (x1 > x0 and y1 > y0):
        raise FootfallError(f"bounds must be x min, y min, x max, y max with max > min, got "
                            f"{list(bounds)}")
    # t: the raster's transform, north-up (checked): column = (x - c) / a, row = (y - f) / e
    col0, col1 = math.floor((x0 - t.c) / t.a + _EDGE), math.ceil((x1 - t.c) / t.a - _EDGE)
    row0, row1 = math.floor((y1 - t.f) / t.e + _EDGE), math.ceil((y0 - t.f) / t.e - _EDGE)
    col0, row0 = max(col0, 0), max(row0, 0)
    col1, row1 = min(col1, ds.width), min(row1, ds.height)
    if col1 - col0 < 1 or row1 - row0 < 1:
        l, b, r, t = ds.bounds
        raise FootfallError(f"bounds {list(bounds)} do not overlap the raster ({l:g}, {b:g}, "
                            f"{r:g}, {t:g})")
    return Window(col0, row0, col1 - col0, row1 - row0)


def read_geotiff(path: Path, band: int = 1, resolution: float | None = None,
                 bounds: tuple[float, float, float, float] | None = None
                 ) -> tuple[np.ndarray, float, dict]:
    """One band of a GeoTIFF: (heights (nx, ny) [m] NaN where no data, resolution [m],
    metadata with the georeference of the part read).

    Raises
    ------
    FootfallError
        (without the file's name; the caller adds it) for a file that is not a readable
        GeoTIFF, a missing band, a rotated raster or one with oblong pixels, a CRS in
        degrees or feet without ``resolution``, bounds outside the raster, or more
        cells than ``max_map_cells``.
    """
    try:
        with contextlib.ExitStack() as stack, warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)  # said below, in a line
            ds = stack.enter_context(rasterio.open(path))
            if ds.driver != "GTiff":
                raise FootfallError(f"a {ds.driver} raster, not a GeoTIFF")
            if not 1 <= band <= ds.count:
                raise FootfallError(f"the file has {ds.count} band(s); band {band} does not "
                                    "exist")
            t = ds.transform
            if t.is_identity:  # GDAL's answer for a file without a geotransform
                if resolution is None:
                    raise FootfallError("the raster has no geotransform (no pixel size or "
                                        "place); give --resolution to state its cell size")
                t = Affine(resolution, 0.0, 0.0, 0.0, -resolution, ds.height * resolution)
            if t.b != 0 or t.d != 0 or t.a <= 0 or t.e >= 0:
                raise FootfallError(f"the raster is not north-up (transform {list(t)[:6]}); "
                                    "footfall reads north-up rasters")
            if abs(t.a + t.e) > _SQUARE * t.a:
                raise FootfallError(f"the raster's pixels are not square ({t.a:g} x {-t.e:g})")
            unit = crs_unit(ds.crs)
            if resolution is None:
                check_metres("the raster's coordinates", unit, "--resolution")
            window = _window(ds, t, bounds)
            cells = int(window.width) * int(window.height)
            limit = current_limits().max_map_cells
            if cells > limit:
                raise FootfallError(f"the raster{' window' if bounds else ''} has {cells} "
                                    f"cells, above the limit of {limit} (raise it with "
                                    "--limit max_map_cells=N, or read a part with --bounds)")
            with np.errstate(invalid="ignore"):  # a signalling NaN: a quiet one, a hole
                data = ds.read(band, window=window).astype(np.float64)
            nodata = ds.nodatavals[band - 1]
            win_t = (t.a, 0.0, t.c + int(window.col_off) * t.a, 0.0, t.e,
                     t.f + int(window.row_off) * t.e)
            wkt = ds.crs.to_wkt() if ds.crs is not None else None
            dtype, size = ds.dtypes[band - 1], (ds.width, ds.height)
    except FootfallError:
        raise
    except _OPEN_ERRORS as exc:
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise FootfallError(f"not a readable GeoTIFF, or a damaged one ({text})") from None
    if nodata is not None and not math.isnan(nodata):
        data[data == nodata] = np.nan
    heights = data[::-1, :].T
    if np.isnan(heights).all():
        raise FootfallError("no data (every cell read is nodata)")
    res = float(t.a) if resolution is None else float(resolution)
    geo = Georeference(wkt, tuple(float(v) for v in win_t))  # type: ignore[arg-type]
    meta = {"band": band, "band_dtype": dtype, "nodata": nodata, "crs_unit": unit,
            "raster_size": list(size),
            "window": [int(window.col_off), int(window.row_off), int(window.width),
                       int(window.height)],
            "georeference": geo.as_dict(),
            "cell_size_from": "the transform" if resolution is None else "--resolution"}
    return heights, res, meta


def write_geotiff(path: str | os.PathLike, layers: dict[str, np.ndarray], hmap: HeightMap
                  ) -> Path:
    """Write ``layers`` (name -> an array of ``hmap``'s shape, NaN = no data) as the bands of
    a float32 GeoTIFF, atomically, each band described by its name; the map's georeference
    (:meth:`Georeference.of`) gives its transform and CRS."""
    geo = Georeference.of(hmap)

    nx, ny = hmap.shape
    target = Path(path)
    with atomic_path(target) as tmp:
        with rasterio.open(tmp, "w", driver="GTiff", width=nx, height=ny, count=len(layers),
                           dtype="float32", crs=crs_from_wkt(geo.crs_wkt),
                           transform=Affine(*geo.transform), nodata=float("nan")) as ds:
            for k, (name, values) in enumerate(layers.items(), start=1):
                ds.write(np.asarray(values, dtype=np.float32).T[::-1, :], k)
                ds.set_band_description(k, name)
    return target
