"""The elevation map: heights on a regular grid with explicit geometry.

One type for every terrain footfall touches -- generated modules, boards,
imported scans. Modelled on the elevation maps of legged robots (grid_map):
length [m], resolution [m/cell], the position of a cell [m] in a named frame
(x forward, y left, z up), and NaN for a cell with no data.

Index convention: ``heights[i, j]`` is the height of the cell whose centre is
at ``x = origin[0] + i * resolution``, ``y = origin[1] + j * resolution``.
"""

from __future__ import annotations

import hashlib
import math
import numbers
import os
import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from footfall.core.bilinear import map_at, map_patches
from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz
from footfall.core.limits import check_cells

FORMAT = "footfall.heightmap"
VERSION = 1


@dataclass(frozen=True)
class PatchGrid:
    """A rectangular grid of sample points around a foothold, in its heading frame.

    The grid is centred on the foothold, ``u`` along the body's x axis
    (forward) and ``v`` along its y axis (left). It has an odd number of
    samples along each axis so that the foothold itself is a sample:
    ``2 * round(length / (2 * resolution)) + 1`` of them, spanning
    ``2 * round(length / (2 * resolution)) * resolution`` metres.
    """

    length_x: float  # [m] extent along the body's x axis
    length_y: float  # [m] extent along the body's y axis
    resolution: float  # [m] spacing of the samples

    def __post_init__(self) -> None:
        if not (self.resolution > 0 and self.length_x > 0 and self.length_y > 0):
            raise FootfallError("patch lengths and resolution must be > 0")

    @property
    def half_counts(self) -> tuple[int, int]:
        """Samples on each side of the centre along u and v."""
        return (int(round(self.length_x / (2 * self.resolution))),
                int(round(self.length_y / (2 * self.resolution))))

    @property
    def shape(self) -> tuple[int, int]:
        """(nu, nv): number of samples along u and v."""
        hu, hv = self.half_counts
        return 2 * hu + 1, 2 * hv + 1

    @property
    def size(self) -> int:
        """Number of samples in the patch."""
        nu, nv = self.shape
        return nu * nv

    @property
    def u(self) -> np.ndarray:
        """Sample offsets along the body's x axis, shape (nu,) [m]."""
        hu, _ = self.half_counts
        return np.arange(-hu, hu + 1) * self.resolution

    @property
    def v(self) -> np.ndarray:
        """Sample offsets along the body's y axis, shape (nv,) [m]."""
        _, hv = self.half_counts
        return np.arange(-hv, hv + 1) * self.resolution


def _as_points(positions: Any) -> np.ndarray:
    p = np.asarray(positions, dtype=np.float64)
    if p.shape[-1:] != (2,) and p.shape[-1:] != (3,):
        raise FootfallError(f"positions must have 2 (x, y) or 3 coordinates, got shape {p.shape}")
    return p[..., :2]


MIN_RESOLUTION = 1e-5  # [m/cell] finest resolution accepted (10 um)
MAX_RESOLUTION = 10.0  # [m/cell] coarsest resolution accepted
MAX_COORDINATE = 1e6  # [m] a map must lie within this distance of its frame's origin
MAX_HEIGHT = 1e5  # [m] largest |height| accepted (far beyond any terrain; keeps sums finite)
MAX_FRAME_LENGTH = 256  # [characters] longest frame name


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _real(value: Any, what: str) -> float:
    """``value`` as a finite float; bools, strings, complex numbers and NaN/inf are refused."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise FootfallError(f"{what} must be a number, got {_short(value)}")
    out = float(value)
    if not math.isfinite(out):
        raise FootfallError(f"{what} must be a finite number, got {_short(value)}")
    return out


def _checked_heights(heights: Any) -> np.ndarray:
    """A private float64 copy of the heights: 2-D, real numbers, finite or NaN, within limits."""
    h = np.asarray(heights)
    if h.ndim != 2:
        raise FootfallError(f"height map must be 2-D, got shape {h.shape}")
    if h.shape[0] < 2 or h.shape[1] < 2:
        raise FootfallError(f"height map must be at least 2 x 2 cells, got {h.shape}")
    if h.dtype.kind not in "iuf":
        raise FootfallError(f"height map must hold numbers (float or integer heights [m]), "
                            f"got dtype {h.dtype}")
    check_cells(h.shape, "the height map")
    with np.errstate(over="ignore", invalid="ignore"):
        h = np.array(h, dtype=np.float64)  # private copy: nobody else can change it
    if np.isinf(h).any():
        raise FootfallError("height map holds infinite heights")
    if np.isnan(h).all():
        raise FootfallError("height map holds no data (all cells are NaN)")
    if float(np.nanmax(np.abs(h))) > MAX_HEIGHT:
        raise FootfallError(f"height map holds heights beyond +-{MAX_HEIGHT:g} m "
                            f"(largest {float(np.nanmax(np.abs(h))):.3g} m)")
    return h


def _checked_resolution(value: Any) -> float:
    try:
        res = _real(value, "resolution")
    except FootfallError:
        res = math.nan
    if not MIN_RESOLUTION <= res <= MAX_RESOLUTION:
        raise FootfallError(f"resolution must be > 0: a finite number of {MIN_RESOLUTION:g} .. "
                            f"{MAX_RESOLUTION:g} m/cell, got {_short(value)}")
    return res


def _checked_origin(value: Any) -> tuple[float, float]:
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise FootfallError(f"origin must be two finite numbers (x, y) [m], got {_short(value)}")
    origin = (_real(value[0], "origin x [m]"), _real(value[1], "origin y [m]"))
    if max(abs(o) for o in origin) > MAX_COORDINATE:
        raise FootfallError(f"origin must be within +-{MAX_COORDINATE:g} m, got {origin}")
    return origin


def _checked_metadata(metadata: Any) -> dict:
    """A shallow copy of the metadata, which must be a dict (a JSON object)."""
    if not isinstance(metadata, dict):
        raise FootfallError(f"metadata must be a JSON object, got {type(metadata).__name__}")
    return dict(metadata)


def module_records(metadata: Any, what: str = "metadata") -> list[dict]:
    """The module records of a board's metadata (``metadata["modules"]``), checked.

    A board made by :func:`footfall.terrain.make_board` lists its modules in
    order along x, each ``{"kind": str, "x_start": m, "x_end": m}`` and
    usually ``"difficulty"`` in [0, 1] and ``"seed"`` >= 0 (a module made from a
    height-map file, kind ``"file"``, has neither: its ``"file"`` name, content
    hash, resolution and height shift instead). Code that walks a
    board relies on these types; a file holding something else is refused
    here, by field, rather than failing deep inside with a TypeError.
    Returns ``[]`` when the metadata lists no modules.

    Raises
    ------
    FootfallError
        Naming ``what`` and the field: ``modules`` not a list, a record not an
        object, a missing or mistyped field, or ``x_start >= x_end``.
    """
    if not isinstance(metadata, dict) or "modules" not in metadata:
        return []
    modules = metadata["modules"]
    if not isinstance(modules, list):
        raise FootfallError(f"{what}.modules must be a list of module records, got "
                            f"{_short(modules)}")
    for k, record in enumerate(modules):
        _check_module_record(record, f"{what}.modules[{k}]")
    return modules


MAX_BOARD_OFFSET = 1000.0  # [m] a board that is walked lies within this of its frame's origin


def board_records(hmap: HeightMap, what: str = "the board") -> list[dict]:
    """The module records of a board that is walked, checked against its map.

    A board's records give each module's x range [m] from the map's start
    (:func:`module_records`); a walk reads its start and goal from them. They
    must tile the map: the first starts at 0, each starts where the one before
    ends, the last ends at the map's length -- all to within one cell. A
    resolution that disagrees with the records (a 1 mm board saved as 2 mm)
    or records that lie off the map are refused here, as is a board farther
    than :data:`MAX_BOARD_OFFSET` from its frame's origin (the simulator's
    contacts lose precision there). Returns ``[]`` for a map without records.

    Raises
    ------
    FootfallError
        Naming ``what`` and the disagreement.
    """
    x0, x1, y0, y1 = hmap.bounds
    if max(abs(x0), abs(x1), abs(y0), abs(y1)) > MAX_BOARD_OFFSET:
        raise FootfallError(f"{what} lies {max(abs(x0), abs(x1), abs(y0), abs(y1)):g} m from "
                            f"its frame's origin; a board that is walked must lie within "
                            f"{MAX_BOARD_OFFSET:g} m of it (move its origin)")
    modules = module_records(hmap.metadata, f"{what}: metadata")
    length, tol = x1 - x0, hmap.resolution + 1e-9
    ends = [0.0] + [float(m["x_end"]) for m in modules]
    for k, m in enumerate(modules):
        if abs(float(m["x_start"]) - ends[k]) > tol:
            raise FootfallError(f"{what}: module {k} starts at {float(m['x_start']):g} m, not "
                                f"where " + ("the map starts (0 m)" if k == 0 else
                                             f"module {k - 1} ends ({ends[k]:g} m)"))
    if modules and abs(ends[-1] - length) > tol:
        raise FootfallError(f"{what}: its modules end at {ends[-1]:g} m but the map is "
                            f"{length:g} m long ({hmap.shape[0]} cells of {hmap.resolution:g} m):"
                            f" its resolution or its module records are wrong")
    return modules


def _check_module_record(record: Any, what: str) -> None:
    """One module record: {"kind", "x_start", "x_end"[, "difficulty", "seed"]} of the right types."""
    if not isinstance(record, dict):
        raise FootfallError(f"{what} must be a module record (an object with kind, x_start, "
                            f"x_end), got {_short(record)}")
    missing = [k for k in ("kind", "x_start", "x_end") if k not in record]
    if missing:
        raise FootfallError(f"{what} lacks {', '.join(missing)}")
    if not isinstance(record["kind"], str):
        raise FootfallError(f"{what}.kind must be a string, got {_short(record['kind'])}")
    seed = record.get("seed", 0)
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise FootfallError(f"{what}.seed must be a whole number >= 0, got {_short(seed)}")
    difficulty = record.get("difficulty", 0.0)
    if not 0.0 <= _real(difficulty, f"{what}.difficulty") <= 1.0:
        raise FootfallError(f"{what}.difficulty must be in [0, 1], got {difficulty}")
    x_start = _real(record["x_start"], f"{what}.x_start")
    x_end = _real(record["x_end"], f"{what}.x_end")
    if not (x_start < x_end and max(abs(x_start), abs(x_end)) <= MAX_COORDINATE):
        raise FootfallError(f"{what}: x_start {x_start:g} must be below x_end {x_end:g} "
                            f"[m], both within +-{MAX_COORDINATE:g} m")


@dataclass(frozen=True, eq=False)
class HeightMap:
    """Heights [m] on a regular grid; NaN marks a cell with no data.

    Parameters
    ----------
    heights : array of shape (nx, ny)
        Terrain height [m] of each cell; ``heights[i, j]`` is at
        ``origin + (i, j) * resolution``. NaN: no data.
    resolution : float
        Cell size [m/cell].
    origin : (float, float)
        Position [m] of the centre of cell (0, 0) in ``frame``.
    frame : str
        Name of the frame the positions are in (x forward, y left, z up).
    metadata : dict
        JSON-serialisable provenance (generator, modules, seeds, source file).
    """

    heights: np.ndarray  # (nx, ny) [m], NaN = no data
    resolution: float  # [m/cell]
    origin: tuple[float, float] = (0.0, 0.0)  # [m] centre of cell (0, 0)
    frame: str = "world"  # frame of positions: x forward, y left, z up
    metadata: dict = field(default_factory=dict)  # provenance, JSON-serialisable

    def __post_init__(self) -> None:
        h = _checked_heights(self.heights)
        res = _checked_resolution(self.resolution)
        origin = _checked_origin(self.origin)
        for k in (0, 1):
            if abs(origin[k]) + h.shape[k] * res > MAX_COORDINATE:
                raise FootfallError(f"the map reaches beyond {MAX_COORDINATE:g} m from its frame's "
                                    f"origin (origin {origin}, {h.shape} cells of {res:g} m)")
        if not isinstance(self.frame, str) or not 0 < len(self.frame) <= MAX_FRAME_LENGTH:
            raise FootfallError(f"frame must be a name of 1 to {MAX_FRAME_LENGTH} characters, "
                                f"got {_short(self.frame)}")
        metadata = _checked_metadata(self.metadata)
        h.setflags(write=False)
        object.__setattr__(self, "heights", h)
        object.__setattr__(self, "resolution", res)
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "metadata", metadata)

    # ----------------------------------------------------------------- geometry
    @property
    def shape(self) -> tuple[int, int]:
        """(nx, ny): number of cells along x and y."""
        return self.heights.shape  # type: ignore[return-value]

    @property
    def length(self) -> tuple[float, float]:
        """Extent of the map along x and y [m]."""
        nx, ny = self.shape
        return nx * self.resolution, ny * self.resolution

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) of the area the cells cover [m]."""
        nx, ny = self.shape
        r = self.resolution
        return (self.origin[0] - r / 2, self.origin[0] + (nx - 0.5) * r,
                self.origin[1] - r / 2, self.origin[1] + (ny - 0.5) * r)

    @property
    def x(self) -> np.ndarray:
        """Cell-centre x coordinates, shape (nx,) [m]."""
        return self.origin[0] + np.arange(self.shape[0]) * self.resolution

    @property
    def y(self) -> np.ndarray:
        """Cell-centre y coordinates, shape (ny,) [m]."""
        return self.origin[1] + np.arange(self.shape[1]) * self.resolution

    def continuous_index(self, positions: Any) -> np.ndarray:
        """Fractional cell index of positions [m], shape (..., 2); cell centres are integers."""
        p = _as_points(positions)
        return (p - np.asarray(self.origin)) / self.resolution

    def position_to_index(self, positions: Any) -> np.ndarray:
        """Index (i, j) of the cell containing each position, shape (..., 2), int64.

        Positions outside the map give indices outside ``[0, nx) x [0, ny)``;
        check with :meth:`is_inside`.
        """
        return np.floor(self.continuous_index(positions) + 0.5).astype(np.int64)

    def index_to_position(self, index: Any) -> np.ndarray:
        """Position [m] of the centre of cell(s) ``index``, shape (..., 2)."""
        idx = np.asarray(index, dtype=np.float64)
        return np.asarray(self.origin) + idx * self.resolution

    def is_inside(self, positions: Any) -> np.ndarray:
        """Whether each position [m] lies within the area the cells cover, shape (...)."""
        f = self.continuous_index(positions)
        nx, ny = self.shape
        return ((f[..., 0] >= -0.5) & (f[..., 0] < nx - 0.5)
                & (f[..., 1] >= -0.5) & (f[..., 1] < ny - 0.5))

    # ------------------------------------------------------------------ lookup
    def height_at(self, positions: Any) -> np.ndarray:
        """Bilinearly interpolated height [m] at positions (..., 2) -> (...).

        NaN handling: NaN outside the map and wherever the nearest cell has
        no data, so a hole keeps its exact extent; elsewhere the bilinear
        weights of the corners that have data are renormalised, so a hole
        never leaks into its neighbours' heights. Within half a cell of the
        border the edge cells are held constant.
        """
        p = _as_points(positions)
        flat = np.ascontiguousarray(p.reshape(-1, 2))
        out = map_at(self.heights, float(self.origin[0]), float(self.origin[1]),
                     float(self.resolution), flat[:, 0], flat[:, 1])
        return out.reshape(p.shape[:-1])

    def sample_points(self, positions: Any, yaw: Any, mirror: Any, grid: PatchGrid) -> np.ndarray:
        """World positions [m] of a patch grid's samples, shape (n, nu, nv, 2).

        ``positions`` (n, 2) are the patch centres, ``yaw`` (n,) or scalar the
        heading [rad] of the patch's u axis, ``mirror`` (n,) or scalar: if
        true the v axis is flipped (right legs), so that a mirrored patch on
        a terrain equals an unmirrored one on the y-mirrored terrain.
        """
        p = _as_points(positions).reshape(-1, 2)
        n = p.shape[0]
        psi = np.broadcast_to(np.asarray(yaw, dtype=np.float64), (n,))
        sign = np.where(np.broadcast_to(np.asarray(mirror, dtype=bool), (n,)), -1.0, 1.0)
        c, s = np.cos(psi)[:, None, None], np.sin(psi)[:, None, None]
        u = grid.u[None, :, None]
        v = grid.v[None, None, :] * sign[:, None, None]
        x = p[:, 0, None, None] + c * u - s * v
        y = p[:, 1, None, None] + s * u + c * v
        return np.stack([x, y], axis=-1)

    def patches(self, positions: Any, yaw: Any, mirror: Any, grid: PatchGrid) -> np.ndarray:
        """Heights [m] of a patch grid around each position, shape (n, nu, nv).

        ``patch[k, a, b]`` is the height at offset ``(grid.u[a], grid.v[b])``
        in the heading frame of patch k (rotated by ``yaw``, v flipped if
        ``mirror``), bilinearly interpolated with the NaN rules of
        :meth:`height_at`; samples off the map or in holes are NaN.
        """
        p = np.ascontiguousarray(_as_points(positions).reshape(-1, 2))
        n = p.shape[0]
        psi = np.broadcast_to(np.asarray(yaw, dtype=np.float64), (n,))
        sign = np.where(np.broadcast_to(np.asarray(mirror, dtype=bool), (n,)), -1.0, 1.0)
        return map_patches(self.heights, float(self.origin[0]), float(self.origin[1]),
                           float(self.resolution), p, np.cos(psi), np.sin(psi), sign,
                           np.ascontiguousarray(grid.u, dtype=np.float64),
                           np.ascontiguousarray(grid.v, dtype=np.float64))

    # -------------------------------------------------------------- transforms
    def mirrored_y(self) -> "HeightMap":
        """The map mirrored about its frame's x axis: height(x, y) -> height(x, -y)."""
        ny = self.shape[1]
        origin = (self.origin[0], -(self.origin[1] + (ny - 1) * self.resolution))
        return HeightMap(self.heights[:, ::-1], self.resolution, origin, self.frame,
                         {**self.metadata, "mirrored_y": True})

    def content_hash(self) -> str:
        """SHA-256 of the heights and geometry: the map's identity in stores and models.

        Worked out once (the map cannot change: its heights are a private read-only copy)."""
        known = self.__dict__.get("_content_hash")
        if known is None:
            digest = hashlib.sha256()
            digest.update(struct.pack("<2q3d", *self.shape, self.resolution, *self.origin))
            digest.update(self.frame.encode())
            digest.update(np.ascontiguousarray(self.heights, dtype="<f8").tobytes())
            known = digest.hexdigest()
            object.__setattr__(self, "_content_hash", known)
        return known

    # --------------------------------------------------------------------- I/O
    def save(self, path: str | os.PathLike) -> None:
        """Write the map as a versioned, self-describing ``.npz`` (atomically)."""
        save_npz(path, FORMAT, VERSION, {"heights": self.heights},
                 {"resolution": self.resolution, "origin": list(self.origin),
                  "frame": self.frame, "units": {"heights": "m", "resolution": "m/cell",
                                                  "origin": "m"},
                  "index": "heights[i, j] at origin + (i, j) * resolution; NaN = no data",
                  "metadata": self.metadata})

    @classmethod
    def load(cls, path: str | os.PathLike) -> "HeightMap":
        """Read a map written by :meth:`save`; bad files raise :class:`FootfallError`.

        The heights must be a 2-D float32/float64 array within the
        ``max_map_cells`` limit (checked before it is read); ``meta`` must
        hold ``resolution`` [m/cell], ``origin`` [m], ``frame`` and optionally
        ``metadata``, each of the right JSON type; the message names the file
        and the field.
        """
        _, arrays, meta = load_npz(path, FORMAT, VERSION, check_member=_check_heights_member)
        if "heights" not in arrays:
            raise FootfallError(f"{path}: the file holds no heights array")
        missing = [k for k in ("resolution", "origin", "frame") if k not in meta]
        if missing:
            raise FootfallError(f"{path}: meta lacks {', '.join(missing)}")
        fields = {"heights": arrays["heights"], "resolution": meta["resolution"],
                  "origin": meta["origin"], "frame": meta["frame"],
                  "metadata": meta.get("metadata", {})}
        if not isinstance(fields["origin"], list):
            raise FootfallError(f"{path}: meta.origin must be a list of two numbers [m], got "
                                f"{_short(fields['origin'])}")
        try:
            return cls(**fields)
        except FootfallError as exc:
            raise FootfallError(f"{path}: {exc}") from None


def _check_heights_member(name: str, shape: tuple[int, ...], dtype: np.dtype) -> None:
    """Refuse a heights array of another dtype, dimension or too many cells, before reading it."""
    if name != "heights":
        return
    if dtype not in (np.dtype("<f4"), np.dtype(">f4"), np.dtype("<f8"), np.dtype(">f8")):
        raise FootfallError(f"heights must be float32 or float64 [m], got dtype {dtype}")
    if len(shape) != 2:
        raise FootfallError(f"heights must be 2-D, got shape {shape}")
    check_cells(shape, "the height map")
