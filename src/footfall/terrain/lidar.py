"""LiDAR point clouds in LAS and LAZ files, gridded into height maps.

Read with ``laspy`` (LAZ through its ``lazrs`` backend). The rule per cell, written
here and in docs/maps.md:

* **which points**: a class filter on the ASPRS classification. By default the
  ground: where the file classifies any point as ground (class 2) only those
  points are kept; where it classifies none (every point "never classified" or
  "unclassified", as from a scanner that does not classify), every point is kept.
  ``classes`` chooses the kept classes instead. Points flagged withheld are dropped.
* **which height**: a statistic of the kept points in each cell -- ``max`` (default:
  the highest ground return, what a foot stands on), ``min`` or ``mean`` -- at the
  cell size given (``resolution`` [m]); cells without a kept point are holes (NaN).
  The grid is anchored on the lowest x and y, as every footfall point cloud
  (:func:`footfall.terrain.raster.rasterize_points`).
* **units**: coordinates in metres. The file's CRS (a WKT VLR, or the GeoTIFF keys of
  older files) is read for its unit: feet or degrees are refused. A file naming no
  CRS is taken in metres.

The map is placed in the local frame of :mod:`footfall.terrain.georeference`, the
file's CRS and the grid's transform kept in its metadata.
"""

from __future__ import annotations

import logging
import struct
from pathlib import Path
from typing import Any

import laspy
import numpy as np
from laspy.errors import LaspyException
from laspy.vlrs.known import GeoKeyDirectoryVlr, WktCoordinateSystemVlr
from rasterio.crs import CRS

from footfall.core.errors import FootfallError
from footfall.core.limits import current_limits
from footfall.terrain.georeference import (
    Georeference,
    check_metres,
    crs_from_wkt,
    crs_unit,
    north_up_transform,
)
from footfall.terrain.raster import STATISTICS, rasterize_cloud

LIDAR_SUFFIXES = (".las", ".laz")
GROUND = 2  # ASPRS class of ground points
UNCLASSIFIED = (0, 1)  # "created, never classified" and "unclassified"
# GeoTIFF keys (GeoKeyDirectory) that name units, and the unit codes footfall reads
_MODEL_TYPE, _PROJECTED_CS, _LINEAR_UNITS, _VERTICAL_UNITS = 1024, 3072, 3076, 4099
_GEOGRAPHIC_MODEL, _METRE = 2, 9001
_UNIT_NAMES = {9001: "metre", 9002: "foot", 9003: "US survey foot", 9030: "nautical mile"}


def _vlr_crs(vlrs: Any) -> tuple[str | None, str]:
    """(the CRS as WKT or None, its horizontal unit) from a file's VLRs."""
    for vlr in vlrs:
        if isinstance(vlr, WktCoordinateSystemVlr) and vlr.string.strip("\x00 "):
            wkt = vlr.string.strip("\x00 ")
            return wkt, crs_unit(crs_from_wkt(wkt))
    for vlr in vlrs:
        if isinstance(vlr, GeoKeyDirectoryVlr):
            keys = {int(k.id): int(k.value_offset) for k in vlr.geo_keys
                    if int(k.tiff_tag_location) == 0}
            if keys.get(_MODEL_TYPE) == _GEOGRAPHIC_MODEL:
                return None, "degree"
            for key in (_LINEAR_UNITS, _VERTICAL_UNITS):
                if key in keys and keys[key] != _METRE:
                    return None, _UNIT_NAMES.get(keys[key], f"unit code {keys[key]}")
            if _PROJECTED_CS in keys and keys[_PROJECTED_CS] not in (0, 32767):
                crs = CRS.from_epsg(keys[_PROJECTED_CS])
                return crs.to_wkt(), crs_unit(crs)
            return None, "metre" if keys.get(_LINEAR_UNITS) == _METRE else "none"
    return None, "none"


def _check_record_counts(path: Path) -> None:
    """Refuse a LAS header whose counts of variable-length records cannot fit in the file:
    laspy reads as many as the header states, past the file's end (a damaged count of four
    billion reads for hours). Public header: the VLR count at byte 100 (54 bytes a record at
    least), and from LAS 1.4 the EVLR count at byte 243 (60 bytes a record at least)."""
    size = path.stat().st_size
    with open(path, "rb") as fh:
        head = fh.read(247)
    if len(head) < 104 or head[:4] != b"LASF":
        raise FootfallError("not a LAS / LAZ file (no LASF signature, or a header cut short)")
    (vlrs,) = struct.unpack_from("<I", head, 100)
    evlrs = struct.unpack_from("<I", head, 243)[0] if head[25] >= 4 and len(head) >= 247 else 0
    if vlrs * 54 > size or evlrs * 60 > size:
        raise FootfallError(f"the header counts {vlrs} variable-length records and {evlrs} "
                            f"extended ones, more than {size} bytes can hold: a damaged file")


def _check_chunk_table(path: Path, point_data: int, count: int) -> None:
    """Refuse a LAZ file whose chunk table cannot be its own: the LAZ decoder sizes its table
    by the count the file states, before reading a chunk (a damaged count asks for gigabytes).

    The table's offset is the 8 bytes at the start of the point data (-1: in the last 8
    bytes of the file); the table opens with its version and its number of chunks (4 bytes
    each). Every chunk holds at least one point and one byte.
    """
    size = path.stat().st_size
    with open(path, "rb") as fh:
        fh.seek(point_data)
        head = fh.read(8)
        if len(head) < 8:
            raise FootfallError("the file is truncated: no point data")
        (offset,) = struct.unpack("<q", head)
        if offset == -1 and size >= 8:
            fh.seek(size - 8)
            (offset,) = struct.unpack("<q", fh.read(8))
        if not point_data + 8 <= offset <= size - 8:
            raise FootfallError(f"the LAZ chunk table's offset ({offset}) lies outside the "
                                f"file ({size} bytes): a truncated or damaged file")
        fh.seek(offset)
        _, chunks = struct.unpack("<II", fh.read(8))
    if chunks > min(count, size) + 1:
        raise FootfallError(f"the LAZ chunk table counts {chunks} chunks for {count} points "
                            f"in {size} bytes: a damaged file")


def _kept(classification: np.ndarray, withheld: np.ndarray | None,
          classes: tuple[int, ...] | None) -> tuple[np.ndarray, str]:
    """Which points the class filter keeps (n,) bool, and the rule it applied, in words."""
    keep = np.ones(classification.shape, dtype=bool) if withheld is None else ~withheld
    if classes is not None:
        return keep & np.isin(classification, classes), f"classes {list(classes)}"
    if (classification == GROUND).any():
        return keep & (classification == GROUND), "ground (class 2)"
    if np.isin(classification, UNCLASSIFIED).all():
        return keep, "all (the file classifies no point)"
    return keep & np.isin(classification, UNCLASSIFIED), \
        "unclassified (no ground class in a classified file)"


def read_lidar(path: Path, resolution: float, classes: tuple[int, ...] | None = None,
               statistic: str = "max") -> tuple[np.ndarray, float, dict]:
    """Grid a LAS / LAZ file: (heights (nx, ny) [m] NaN where no point, resolution [m],
    metadata with the georeference, the filter and the point counts).

    Raises
    ------
    FootfallError
        (without the file's name; the caller adds it) for a damaged or truncated file,
        more points than ``max_scan_points``, coordinates not in metres, no point kept,
        or a grid above ``max_map_cells``.
    """
    if statistic not in STATISTICS:
        raise FootfallError(f"statistic must be one of {', '.join(STATISTICS)}, got "
                            f"{statistic!r}")
    quiet = logging.getLogger("laspy")  # it logs a damaged file's errors itself; the
    level, quiet.level = quiet.level, logging.CRITICAL  # FootfallError below says them once
    try:
        _check_record_counts(path)
        with laspy.open(path) as reader:
            header = reader.header
            count = int(header.point_count)
            limit = current_limits().max_scan_points
            if count > limit:
                raise FootfallError(f"the file holds {count} points, above the limit of "
                                    f"{limit} (raise it with --limit max_scan_points=N)")
            if header.are_points_compressed:
                _check_chunk_table(path, int(header.offset_to_point_data), count)
            wkt, unit = _vlr_crs(header.vlrs)
            check_metres("the file's coordinates", unit, "")
            points = reader.read_points(count) if count else None
    except FootfallError:
        raise
    except (LaspyException, OSError, ValueError, EOFError, IndexError, KeyError, TypeError,
            AttributeError, RuntimeError, MemoryError, OverflowError) as exc:
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise FootfallError(f"not a readable LAS / LAZ file, or a truncated one ({text})"
                            ) from None
    except BaseException as exc:  # the LAZ decoder (Rust) panics on some damaged chunks:
        if type(exc).__name__ != "PanicException":  # pyo3's, a BaseException by design
            raise
        text = str(exc).splitlines()[0] if str(exc) else "a panic"
        raise FootfallError(f"not a readable LAZ file: its decoder failed on damaged data "
                            f"({text})") from None
    finally:
        quiet.level = level
    if points is None or len(points) == 0:
        raise FootfallError("the file holds no points")
    if len(points) < count:
        raise FootfallError(f"the file is truncated: its header declares {count} points, "
                            f"{len(points)} could be read")
    xyz = np.column_stack([np.asarray(points.x, dtype=np.float64),
                           np.asarray(points.y, dtype=np.float64),
                           np.asarray(points.z, dtype=np.float64)])
    withheld = np.asarray(points.withheld, dtype=bool) \
        if "withheld" in points.point_format.dimension_names else None
    keep, rule = _kept(np.asarray(points.classification), withheld, classes)
    if not keep.any():
        raise FootfallError(f"no point is kept by the class filter ({rule}) among {count}")
    kept = xyz[keep]
    finite = np.isfinite(kept).all(axis=1)
    if not finite.any():
        raise FootfallError(f"no kept point has finite coordinates among {count}")
    x0, y0 = kept[finite, 0].min(), kept[finite, 1].min()  # the local frame's anchor [m]
    kept[:, :2] -= (x0, y0)  # survey coordinates are far from footfall's frames
    heights, _, info = rasterize_cloud(kept, resolution, 1.0, None, statistic)
    geo = Georeference(wkt, north_up_transform((x0, y0), resolution, heights.shape[1]))
    meta = {"rasterization": f"{statistic} of the kept points per cell",
            "class_filter": rule, "points_in_file": count,
            "points_filtered_out": int(count - keep.sum()), **info,
            "las_version": str(header.version), "point_format": int(header.point_format.id),
            "georeference": geo.as_dict(), "local_origin_in_crs": [x0, y0]}
    return heights, resolution, meta

