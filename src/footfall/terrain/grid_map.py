"""grid_map's conventions: a ``grid_map_msgs/GridMap`` layer to footfall's heights and back.

Pure numerics, no I/O (the bags are :mod:`footfall.terrain.bags`). What grid_map
(ANYbotics' library, the map type of elevation_mapping and elevation_mapping_cupy)
writes, as its ROS 2 converter does:

* A layer is a ``std_msgs/Float32MultiArray`` of an Eigen matrix of ``rows x cols``
  cells; rows run along the map's x axis, columns along its y axis. The layout's
  first dimension names the storage order: ``column_index`` (Eigen's default,
  column-major: ``data[col * rows + row]``, ``dim[0].size = cols``,
  ``dim[1].size = rows``) or ``row_index`` (row-major).
* The matrix is a circular buffer: the cell at *unwrapped* index ``(u, v)`` is
  stored at ``((u + outer_start_index) mod rows, (v + inner_start_index) mod cols)``.
* Unwrapped index ``(0, 0)`` is the corner of largest x and largest y: the cell at
  unwrapped ``(u, v)`` has its centre at
  ``x = px + length_x / 2 - (u + 1/2) r``, ``y = py + length_y / 2 - (v + 1/2) r``,
  with ``(px, py)`` the map's centre (``info.pose.position``) and ``r`` its resolution.
* Cells without data are NaN. grid_map keeps its maps axis-aligned in their frame:
  its converter ignores ``info.pose.orientation`` and writes the identity; footfall
  refuses any other orientation rather than place the cells wrongly.

A footfall height map is indexed ``[i, j]`` with ``i`` along +x and ``j`` along +y
and its origin at the centre of cell ``(0, 0)`` (:class:`~footfall.core.heightmap.HeightMap`),
so the unwrapped matrix is the height map reversed along both axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from footfall.core.errors import FootfallError

GRID_MAP_TYPE = "grid_map_msgs/msg/GridMap"
GRID_MAP_INFO_TYPE = "grid_map_msgs/msg/GridMapInfo"
COLUMN_MAJOR, ROW_MAJOR = "column_index", "row_index"  # grid_map's storage order labels
DEFAULT_LAYER = "elevation"  # the layer a map is read from unless another is named
SCORE_LAYER = "footfall_score"  # the layer footfall writes its scores to
ORIENTATION_TOLERANCE = 1e-9  # a pose quaternion this close to the identity is the identity

# The message definitions of grid_map_msgs for ROS 2 (grid_map_msgs/msg/*.msg).
GRID_MAP_MSG = """\
std_msgs/Header header
grid_map_msgs/GridMapInfo info
string[] layers
string[] basic_layers
std_msgs/Float32MultiArray[] data
uint16 outer_start_index
uint16 inner_start_index
"""
GRID_MAP_INFO_MSG = """\
float64 resolution
float64 length_x
float64 length_y
geometry_msgs/Pose pose
"""


@dataclass(frozen=True)
class GridGeometry:
    """Where a grid map lies: its cell size and the centre of its extent in its frame."""

    resolution: float  # [m/cell]
    centre: tuple[float, float]  # [m] the map's centre (info.pose.position) in ``frame``
    frame: str  # header.frame_id

    def origin(self, shape: tuple[int, int]) -> tuple[float, float]:
        """The centre [m] of footfall's cell (0, 0) -- the corner of least x and y -- of a
        map of ``shape`` (nx, ny) cells."""
        r = self.resolution
        return (self.centre[0] - shape[0] * r / 2 + r / 2,
                self.centre[1] - shape[1] * r / 2 + r / 2)


def layer_matrix(data: np.ndarray, labels: tuple[str, ...], sizes: tuple[int, ...],
                 offset: int = 0) -> np.ndarray:
    """The stored ``rows x cols`` matrix of a layer from its Float32MultiArray parts.

    ``labels`` and ``sizes`` are the layout's dimensions' labels and sizes, ``offset``
    its ``data_offset``.

    Raises
    ------
    FootfallError
        If the layout is not grid_map's (two dimensions labelled ``column_index`` and
        ``row_index``) or the data does not hold ``rows x cols`` values.
    """
    if len(labels) != 2 or set(labels) != {COLUMN_MAJOR, ROW_MAJOR}:
        raise FootfallError(f"the layer's layout is not grid_map's (two dimensions "
                            f"'{COLUMN_MAJOR}' and '{ROW_MAJOR}'), got {list(labels)}")
    outer, inner = (int(s) for s in sizes)
    values = np.asarray(data, dtype=np.float32)[int(offset):]
    if outer < 1 or inner < 1 or values.size != outer * inner:
        raise FootfallError(f"the layer holds {values.size} values, not the {outer} x {inner} "
                            "its layout gives")
    if labels[0] == COLUMN_MAJOR:  # column-major: outer = columns (y), inner = rows (x)
        return values.reshape(outer, inner).T
    return values.reshape(outer, inner)  # row-major: outer = rows, inner = columns


def unwrapped(matrix: np.ndarray, outer_start: int, inner_start: int) -> np.ndarray:
    """The matrix with grid_map's circular buffer undone: unwrapped ``(0, 0)`` first.

    ``outer_start`` is the start index along the rows (x), ``inner_start`` along the
    columns (y), as the message's ``outer_start_index`` and ``inner_start_index``.
    """
    rows, cols = matrix.shape
    return np.roll(matrix, (-(int(outer_start) % rows), -(int(inner_start) % cols)),
                   axis=(0, 1))


def heights_of(matrix: np.ndarray, outer_start: int = 0, inner_start: int = 0) -> np.ndarray:
    """footfall's heights ``[i, j]`` (float64, NaN where no data) of a stored layer matrix."""
    with np.errstate(invalid="ignore"):  # a signalling NaN of damaged data: a quiet NaN, a hole
        return unwrapped(matrix, outer_start, inner_start)[::-1, ::-1].astype(np.float64)


def layer_of(heights: np.ndarray) -> tuple[np.ndarray, list[tuple[str, int, int]]]:
    """grid_map's Float32MultiArray parts of footfall's heights ``[i, j]``, unwrapped (start
    indices 0), column-major as grid_map writes them: the data (rows * cols,) float32 and
    the layout's dimensions as ``(label, size, stride)``."""
    matrix = np.asarray(heights)[::-1, ::-1].astype(np.float32)
    rows, cols = matrix.shape
    dims = [(COLUMN_MAJOR, cols, rows * cols), (ROW_MAJOR, rows, rows)]
    return matrix.ravel(order="F"), dims


def check_orientation(quaternion: tuple[float, float, float, float]) -> None:
    """Refuse a map pose whose orientation (x, y, z, w) is not the identity.

    grid_map's maps are axis-aligned in their frame; an all-zero quaternion (unset)
    is taken as the identity, as grid_map's converters do.
    """
    x, y, z, w = (float(q) for q in quaternion)
    if all(abs(q) <= ORIENTATION_TOLERANCE for q in (x, y, z, w)):
        return
    if max(abs(x), abs(y), abs(z)) > ORIENTATION_TOLERANCE or abs(abs(w) - 1.0) > \
            ORIENTATION_TOLERANCE:
        raise FootfallError(f"the map's pose is rotated (orientation x {x:g} y {y:g} z {z:g} "
                            f"w {w:g}); grid maps are axis-aligned in their frame and footfall "
                            "reads them so")


def check_lengths(resolution: float, length: tuple[float, float], shape: tuple[int, int]
                  ) -> None:
    """Refuse a map whose lengths [m] are not its cells times its resolution [m/cell]."""
    if not (np.isfinite(resolution) and resolution > 0):
        raise FootfallError(f"the map's resolution must be a number > 0 [m/cell], got "
                            f"{resolution!r}")
    for axis, n, n_cells in (("x", length[0], shape[0]), ("y", length[1], shape[1])):
        if not np.isfinite(n) or abs(n / resolution - n_cells) > 1e-3:
            raise FootfallError(f"the map's length along {axis} ({n:g} m) is not its "
                                f"{n_cells} cells at {resolution:g} m")
