"""Where a surveyed map lies on the Earth: its coordinate reference system and raster transform.

A map imported from a georeferenced file (a GeoTIFF elevation model, a LAS / LAZ
point cloud) is placed in a *local* frame: survey coordinates (a UTM northing is
millions of metres) are far from anything a robot's frame holds, and footfall's
maps lie within ``MAX_COORDINATE`` of their frame's origin. The map's cell (0, 0)
centre is at (0, 0) of the frame ``"local"``; the file's georeference is kept in
the map's metadata (``"georeference"``: the CRS as WKT, or None where the file
names none, and the north-up affine transform of the map's own raster, rasterio's
``(a, b, c, d, e, f)``: ``x = a col + b row + c``, ``y = d col + e row + f`` at a
pixel's corner), so that what is written back -- a GeoTIFF of scores -- lands where
the input lay.

Units: footfall works in metres. A CRS whose horizontal unit is the metre is read
as it is; one in degrees (geographic) or feet is refused by the readers unless the
user gives the cell size in metres (GeoTIFF ``resolution``) -- see
:func:`crs_unit`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rasterio.crs import CRS
from rasterio.errors import CRSError

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap

METRE_NAMES = ("metre", "meter", "metres", "meters", "m")


@dataclass(frozen=True)
class Georeference:
    """A map's place in a coordinate reference system."""

    crs_wkt: str | None  # the CRS as WKT; None: the file names none
    transform: tuple[float, float, float, float, float, float]  # rasterio's (a, b, c, d, e, f)
    # of the map's north-up raster: pixel (col, row) corner -> CRS coordinates [m]

    def as_dict(self) -> dict[str, Any]:
        return {"crs_wkt": self.crs_wkt, "transform": list(self.transform)}

    @classmethod
    def of(cls, hmap: HeightMap) -> "Georeference":
        """The georeference a map carries, or a local one from its own origin and resolution
        (no CRS) for a map that carries none."""
        geo = hmap.metadata.get("georeference")
        if isinstance(geo, dict) and isinstance(geo.get("transform"), list) \
                and len(geo["transform"]) == 6:
            wkt = geo.get("crs_wkt")
            return cls(wkt if isinstance(wkt, str) else None,
                       tuple(float(v) for v in geo["transform"]))  # type: ignore[arg-type]
        return cls(None, north_up_transform(hmap.origin, hmap.resolution, hmap.shape[1]))


def north_up_transform(origin: tuple[float, float], resolution: float, ny: int
                       ) -> tuple[float, float, float, float, float, float]:
    """The north-up raster transform of a map whose cell (0, 0) centre is at ``origin`` [m],
    of cells ``resolution`` [m] and ``ny`` cells along y: the top-left pixel's corner is at
    (x0 - r/2, y0 + (ny - 1/2) r)."""
    r = float(resolution)
    return (r, 0.0, origin[0] - r / 2, 0.0, -r, origin[1] + (ny - 0.5) * r)


def crs_unit(crs: Any) -> str:
    """The horizontal unit of a rasterio ``CRS`` (None: no CRS): ``"metre"``, ``"degree"``
    (geographic), ``"none"`` (no CRS given), or the unit's own name (e.g. ``"US survey foot"``)."""
    if crs is None:
        return "none"
    if crs.is_geographic:
        return "degree"
    try:
        name, factor = crs.linear_units_factor
    except Exception:  # rasterio raises CRSError where a CRS has no linear unit
        return str(getattr(crs, "linear_units", "unknown") or "unknown")
    if str(name).lower() in METRE_NAMES or abs(float(factor) - 1.0) < 1e-12:
        return "metre"
    return str(name)


def check_metres(what: str, unit: str, override: str) -> None:
    """Refuse coordinates in ``unit`` other than metres, naming ``override`` (the option that
    states the cell size in metres), if any."""
    if unit in ("metre", "none"):
        return
    hint = f"; give {override} to state the cell size in metres" if override else ""
    raise FootfallError(f"{what} are in {'degrees (a geographic CRS)' if unit == 'degree' else unit}"
                        f", not metres{hint}")


def crs_from_wkt(wkt: str | None) -> Any:
    """A rasterio ``CRS`` of WKT text, None for None; an unreadable one raises FootfallError."""
    if wkt is None:
        return None
    try:
        return CRS.from_wkt(wkt)
    except CRSError as exc:
        raise FootfallError(f"the coordinate reference system is not readable WKT ({exc})"
                            ) from None
