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
import os
import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz

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
        h = np.asarray(self.heights)
        if h.ndim != 2:
            raise FootfallError(f"height map must be 2-D, got shape {h.shape}")
        if h.shape[0] < 2 or h.shape[1] < 2:
            raise FootfallError(f"height map must be at least 2 x 2 cells, got {h.shape}")
        if not np.issubdtype(h.dtype, np.floating) and not np.issubdtype(h.dtype, np.integer):
            raise FootfallError(f"height map must hold numbers, got dtype {h.dtype}")
        h = np.array(h, dtype=np.float64)  # private copy: nobody else can change it
        if np.isinf(h).any():
            raise FootfallError("height map holds infinite heights")
        if np.isnan(h).all():
            raise FootfallError("height map holds no data (all cells are NaN)")
        res = float(self.resolution)
        if not (math.isfinite(res) and res > 0):
            raise FootfallError(f"resolution must be > 0, got {self.resolution}")
        origin = tuple(float(o) for o in self.origin)
        if len(origin) != 2 or not all(math.isfinite(o) for o in origin):
            raise FootfallError(f"origin must be two finite numbers, got {self.origin}")
        h.setflags(write=False)
        object.__setattr__(self, "heights", h)
        object.__setattr__(self, "resolution", res)
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "metadata", dict(self.metadata))

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
        f = self.continuous_index(positions)
        nx, ny = self.shape
        fi, fj = f[..., 0], f[..., 1]
        inside = (fi >= -0.5) & (fi < nx - 0.5) & (fj >= -0.5) & (fj < ny - 0.5)
        fi = np.clip(np.where(inside, fi, 0.0), 0.0, nx - 1.0)
        fj = np.clip(np.where(inside, fj, 0.0), 0.0, ny - 1.0)
        i0 = np.minimum(np.floor(fi).astype(np.intp), nx - 2)
        j0 = np.minimum(np.floor(fj).astype(np.intp), ny - 2)
        ti, tj = fi - i0, fj - j0
        h = self.heights
        corners = (h[i0, j0], h[i0 + 1, j0], h[i0, j0 + 1], h[i0 + 1, j0 + 1])
        weights = ((1 - ti) * (1 - tj), ti * (1 - tj), (1 - ti) * tj, ti * tj)
        num = np.zeros(fi.shape)
        den = np.zeros(fi.shape)
        for c, w in zip(corners, weights):  # four corners, not a loop over points
            ok = ~np.isnan(c)
            num += np.where(ok, c, 0.0) * w
            den += ok * w
        nearest = h[np.floor(fi + 0.5).astype(np.intp), np.floor(fj + 0.5).astype(np.intp)]
        out = np.full(fi.shape, np.nan)
        good = inside & ~np.isnan(nearest) & (den > 0)
        np.divide(num, den, out=out, where=good)
        return out

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
        return self.height_at(self.sample_points(positions, yaw, mirror, grid))

    # -------------------------------------------------------------- transforms
    def mirrored_y(self) -> "HeightMap":
        """The map mirrored about its frame's x axis: height(x, y) -> height(x, -y)."""
        ny = self.shape[1]
        origin = (self.origin[0], -(self.origin[1] + (ny - 1) * self.resolution))
        return HeightMap(self.heights[:, ::-1], self.resolution, origin, self.frame,
                         {**self.metadata, "mirrored_y": True})

    def content_hash(self) -> str:
        """SHA-256 of the heights and geometry: the map's identity in stores and models."""
        digest = hashlib.sha256()
        digest.update(struct.pack("<2q3d", *self.shape, self.resolution, *self.origin))
        digest.update(self.frame.encode())
        digest.update(np.ascontiguousarray(self.heights, dtype="<f8").tobytes())
        return digest.hexdigest()

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
        """Read a map written by :meth:`save`; bad files raise :class:`FootfallError`."""
        _, arrays, meta = load_npz(path, FORMAT, VERSION)
        try:
            heights = arrays["heights"]
            return cls(heights, float(meta["resolution"]), tuple(meta["origin"]),
                       str(meta["frame"]), dict(meta.get("metadata", {})))
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, FootfallError):
                raise FootfallError(f"{path}: {exc}") from None
            raise FootfallError(f"{path}: malformed height map ({exc})") from None
