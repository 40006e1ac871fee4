"""Tests for footfall.terrain.scans: importing elevation files into a HeightMap."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from PIL import Image
from plyfile import PlyData, PlyElement

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.terrain.raster import MAX_CELLS, rasterize_points
from footfall.terrain.scans import SUFFIXES, import_terrain

RES = 0.1  # [m/cell]


# -------------------------------------------------------------------- helpers
def plane(x, y):
    """The test surface z = 0.1 x + 0.02 y [m]."""
    return 0.1 * np.asarray(x) + 0.02 * np.asarray(y)


def grid_points(nx=5, ny=4, x0=1.0, y0=-0.5, res=RES):
    """Points of the plane at the nodes of an nx x ny grid, shape (nx * ny, 3)."""
    x, y = np.meshgrid(x0 + np.arange(nx) * res, y0 + np.arange(ny) * res, indexing="ij")
    x, y = x.ravel(), y.ravel()
    return np.stack([x, y, plane(x, y)], axis=1)


def write_ply(path, points, *, text, dtype="f8", extra_elements=()):
    v = np.empty(len(points), dtype=[("x", dtype), ("y", dtype), ("z", dtype)])
    if len(points):
        v["x"], v["y"], v["z"] = points[:, 0], points[:, 1], points[:, 2]
    PlyData([PlyElement.describe(v, "vertex"), *extra_elements], text=text).write(str(path))


def write_xyz(path, points, sep=" "):
    path.write_text("\n".join(sep.join(repr(float(c)) for c in p) for p in points) + "\n")


def write_png16(path, img):
    """Write a uint16 image (rows, cols) as a 16-bit greyscale PNG."""
    im = Image.fromarray(np.asarray(img, dtype=np.uint16))
    assert im.mode == "I;16"
    im.save(path)


def expect_error(path, pattern, **kwargs):
    """import_terrain(path) raises a FootfallError matching pattern and naming the file."""
    with pytest.raises(FootfallError, match=pattern) as info:
        import_terrain(path, **kwargs)
    assert str(path) in str(info.value)
    return info.value


# ------------------------------------------------------------------- registry
def test_registry_lists_the_formats():
    assert SUFFIXES == (".npz", ".npy", ".png", ".ply", ".xyz", ".las", ".laz", ".tif", ".tiff",
                        ".mcap", ".db3")


def test_suffix_is_case_insensitive(tmp_path):
    path = tmp_path / "cloud.XYZ"
    write_xyz(path, grid_points())
    hm = import_terrain(path, resolution=RES)
    assert hm.shape == (5, 4)


def test_unknown_suffix_lists_the_known_ones(tmp_path):
    path = tmp_path / "terrain.dem"
    path.write_bytes(b"II*\x00")
    expect_error(path, re.escape("known: .npz, .npy, .png, .ply, .xyz, .las, .laz, .tif, "
                                 ".tiff, .mcap, .db3 or a ROS 2 bag folder"))


def test_no_suffix_is_unknown(tmp_path):
    path = tmp_path / "terrain"
    path.write_text("1 2 3\n")
    expect_error(path, r"unknown terrain file type '\(no suffix\)'")


def test_missing_file(tmp_path):
    expect_error(tmp_path / "absent.ply", "no such file", resolution=RES)


def test_directory_is_not_a_file(tmp_path):
    path = tmp_path / "dir.npy"
    path.mkdir()
    expect_error(path, "not a regular file", resolution=RES)


# ------------------------------------------------------------------------ npz
def test_npz_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    h = rng.normal(size=(6, 4))
    h[2, 3] = np.nan
    original = HeightMap(h, 0.02, (0.5, -1.0), "odom", {"generator": "test"})
    path = tmp_path / "map.npz"
    original.save(path)
    hm = import_terrain(path)
    assert hm.content_hash() == original.content_hash()
    assert hm.frame == "odom" and hm.origin == (0.5, -1.0)
    assert hm.metadata == {"generator": "test"}


@pytest.mark.parametrize("kwargs", [{"resolution": 0.1}, {"z_scale": 2.0}, {"nodata": 0},
                                    {"origin": (0, 0)}, {"frame": "world"}])
def test_npz_rejects_geometry_arguments(tmp_path, kwargs):
    path = tmp_path / "map.npz"
    HeightMap(np.zeros((2, 2)), 0.1).save(path)
    expect_error(path, f"carries its own geometry; do not pass {next(iter(kwargs))}", **kwargs)


def test_npz_corrupt(tmp_path):
    path = tmp_path / "map.npz"
    path.write_bytes(b"PK\x03\x04 this is not a zip archive")
    expect_error(path, "not a readable footfall .npz")


# ------------------------------------------------------------------------ npy
def test_npy_round_trip_and_orientation(tmp_path):
    i, j = np.meshgrid(np.arange(5), np.arange(3), indexing="ij")
    a = 10.0 * i + j  # asymmetric: a[i, j] identifies (i, j)
    path = tmp_path / "grid.npy"
    np.save(path, a)
    hm = import_terrain(path, resolution=0.05, origin=(1.0, 2.0), frame="odom")
    np.testing.assert_array_equal(hm.heights, a)
    assert hm.origin == (1.0, 2.0) and hm.resolution == 0.05 and hm.frame == "odom"
    # cell (3, 1) is at x = 1 + 3 * 0.05, y = 2 + 1 * 0.05
    assert hm.height_at([1.15, 2.05]) == pytest.approx(31.0)
    assert hm.metadata["source_format"] == "npy" and hm.metadata["z_scale"] == 1.0


def test_npy_default_origin_frame_and_z_scale(tmp_path):
    path = tmp_path / "grid.npy"
    np.save(path, np.arange(6, dtype=np.float32).reshape(2, 3))
    hm = import_terrain(path, resolution=0.1, z_scale=0.5)
    assert hm.origin == (0.0, 0.0) and hm.frame == "world"
    np.testing.assert_allclose(hm.heights, 0.5 * np.arange(6).reshape(2, 3))


def test_npy_integer_counts_with_nodata(tmp_path):
    raw = np.array([[100, 0, 300], [400, 500, 0]], dtype=np.uint16)
    path = tmp_path / "counts.npy"
    np.save(path, raw)
    hm = import_terrain(path, resolution=0.1, z_scale=0.001, nodata=0)
    expected = np.array([[0.1, np.nan, 0.3], [0.4, 0.5, np.nan]])
    np.testing.assert_allclose(hm.heights, expected)
    hm_all = import_terrain(path, resolution=0.1, z_scale=0.001)  # without nodata 0 is data
    assert hm_all.heights[0, 1] == 0.0


def test_npy_nan_is_no_data(tmp_path):
    a = np.array([[1.0, np.nan], [3.0, 4.0]])
    path = tmp_path / "holes.npy"
    np.save(path, a)
    hm = import_terrain(path, resolution=0.1)
    assert np.isnan(hm.heights[0, 1]) and hm.heights[1, 0] == 3.0


def test_npy_requires_resolution(tmp_path):
    path = tmp_path / "grid.npy"
    np.save(path, np.zeros((3, 3)))
    expect_error(path, r"resolution \[m/cell\] is required")


@pytest.mark.parametrize("array, pattern", [
    (np.zeros((2, 3, 4)), "must be a 2-D array.*shape \\(2, 3, 4\\)"),
    (np.zeros(5), "must be a 2-D array.*shape \\(5,\\)"),
    (np.array([["a", "b"], ["c", "d"]]), "integer or float heights, got dtype <U1"),
    (np.zeros((2, 2), dtype=[("z", "f8"), ("w", "f8")]), "integer or float heights"),
    (np.zeros((2, 2), dtype=complex), "integer or float heights, got dtype complex128"),
    (np.zeros((2, 2), dtype=bool), "integer or float heights, got dtype bool"),
    (np.zeros((1, 5)), "at least 2 x 2 cells"),
    (np.full((3, 3), np.nan), "no data"),
    (np.array([[1.0, np.inf], [0.0, 0.0]]), "infinite heights"),
])
def test_npy_bad_arrays(tmp_path, array, pattern):
    path = tmp_path / "bad.npy"
    np.save(path, array)
    expect_error(path, pattern, resolution=0.1)


def test_npy_object_array_is_refused_without_unpickling(tmp_path):
    path = tmp_path / "objects.npy"
    np.save(path, np.array([[1, "a"], [None, 2.0]], dtype=object), allow_pickle=True)
    expect_error(path, "not a readable .npy array.*allow_pickle", resolution=0.1)


def test_npy_truncated(tmp_path):
    path = tmp_path / "cut.npy"
    np.save(path, np.ones((10, 10)))
    data = path.read_bytes()
    path.write_bytes(data[:-40])
    expect_error(path, "not a readable .npy array", resolution=0.1)


def test_npy_that_is_really_an_npz(tmp_path):
    path = tmp_path / "archive.npy"
    with open(path, "wb") as fh:
        np.savez(fh, a=np.ones((3, 3)))
    expect_error(path, "not a readable .npy array.*magic string", resolution=0.1)


def test_npy_all_nodata(tmp_path):
    path = tmp_path / "empty.npy"
    np.save(path, np.full((3, 3), -9999.0))
    expect_error(path, "no data.*nodata=-9999", resolution=0.1, nodata=-9999)


@pytest.mark.parametrize("value", [0, -0.1, float("nan"), float("inf"), "abc", True])
def test_bad_resolution(tmp_path, value):
    path = tmp_path / "grid.npy"
    np.save(path, np.zeros((3, 3)))
    expect_error(path, "resolution", resolution=value)


@pytest.mark.parametrize("value", [0, -2.0, float("nan")])
def test_bad_z_scale(tmp_path, value):
    path = tmp_path / "grid.npy"
    np.save(path, np.zeros((3, 3)))
    expect_error(path, r"z_scale \[m per raw unit\] must be a finite number > 0",
                 resolution=0.1, z_scale=value)


@pytest.mark.parametrize("origin", [(0.0,), (0.0, float("nan")), "ab", 5])
def test_bad_origin(tmp_path, origin):
    path = tmp_path / "grid.npy"
    np.save(path, np.zeros((3, 3)))
    expect_error(path, "origin must be two", resolution=0.1, origin=origin)


def test_bad_frame(tmp_path):
    path = tmp_path / "grid.npy"
    np.save(path, np.zeros((3, 3)))
    expect_error(path, "frame must be a non-empty string", resolution=0.1, frame="")


# ------------------------------------------------------------------------ png
def test_png_round_trip_and_orientation(tmp_path):
    nx, ny = 5, 3
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    counts = 1000 * i + 10 * j + 7  # counts[i, j] in footfall's [x, y] order
    img = counts.T[::-1, :]  # image rows = y from the top, columns = x
    img = img.copy()
    img[0, 0] = 60000  # top-left pixel: smallest x, largest y
    img[-1, -1] = 50000  # bottom-right pixel: largest x, smallest y
    path = tmp_path / "height.png"
    write_png16(path, img)
    hm = import_terrain(path, resolution=RES, z_scale=0.001, origin=(2.0, 3.0))
    assert hm.shape == (nx, ny)
    assert hm.height_at([2.0, 3.0 + (ny - 1) * RES]) == pytest.approx(60.0)
    assert hm.height_at([2.0 + (nx - 1) * RES, 3.0]) == pytest.approx(50.0)
    expected = counts * 0.001
    expected[0, ny - 1], expected[nx - 1, 0] = 60.0, 50.0
    np.testing.assert_allclose(hm.heights, expected)
    # cell (3, 1): x = 2.3, y = 3.1
    assert hm.height_at([2.3, 3.1]) == pytest.approx((3000 + 10 + 7) * 0.001)
    assert hm.metadata["source_format"] == "png"


def test_png_nodata_zero(tmp_path):
    img = np.array([[0, 200, 300], [400, 500, 600]], dtype=np.uint16)
    path = tmp_path / "holes.png"
    write_png16(path, img)
    hm = import_terrain(path, resolution=RES, z_scale=0.01, nodata=0)
    # pixel (row 0, col 0) is x index 0, y index 1 (top row = largest y)
    assert np.isnan(hm.heights[0, 1])
    assert np.isnan(hm.height_at([0.0, RES]))
    assert np.count_nonzero(np.isnan(hm.heights)) == 1
    assert hm.heights[0, 0] == pytest.approx(4.0)
    without = import_terrain(path, resolution=RES, z_scale=0.01)
    assert without.heights[0, 1] == 0.0


def test_png_all_nodata(tmp_path):
    path = tmp_path / "zeros.png"
    write_png16(path, np.zeros((3, 3)))
    expect_error(path, "no data", resolution=RES, z_scale=0.01, nodata=0)


def test_png_requires_z_scale_and_resolution(tmp_path):
    path = tmp_path / "height.png"
    write_png16(path, np.ones((3, 3)))
    expect_error(path, r"z_scale \[m per count\] is required", resolution=RES)
    expect_error(path, r"resolution \[m/cell\] is required", z_scale=0.01)


@pytest.mark.parametrize("mode", ["L", "RGB", "P", "LA"])
def test_png_8bit_or_colour_is_rejected(tmp_path, mode):
    path = tmp_path / "render.png"
    Image.new(mode, (4, 3)).save(path)
    expect_error(path, f"mode '{mode}'.*16-bit greyscale PNG", resolution=RES, z_scale=0.01)


def test_png_truncated(tmp_path):
    path = tmp_path / "cut.png"
    write_png16(path, np.random.default_rng(1).integers(0, 65535, size=(40, 40)))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    expect_error(path, "corrupt or truncated PNG", resolution=RES, z_scale=0.01)


def test_png_garbage(tmp_path):
    path = tmp_path / "junk.png"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\x00garbage" * 10)
    expect_error(path, "not a readable PNG|corrupt or truncated PNG",
                 resolution=RES, z_scale=0.01)


def test_png_suffix_on_another_image_format(tmp_path):
    path = tmp_path / "photo.png"
    Image.new("L", (4, 4)).save(path, format="JPEG")
    expect_error(path, "holds a JPEG image, not a PNG", resolution=RES, z_scale=0.01)


# ------------------------------------------------------------------------ ply
@pytest.mark.parametrize("text", [True, False], ids=["ascii", "binary"])
@pytest.mark.parametrize("dtype", ["f8", "f4"])
def test_ply_round_trip_of_a_plane(tmp_path, text, dtype):
    pts = grid_points(nx=5, ny=4, x0=1.0, y0=-0.5)
    path = tmp_path / "cloud.ply"
    write_ply(path, pts, text=text, dtype=dtype)
    hm = import_terrain(path, resolution=RES)
    assert hm.shape == (5, 4)
    assert hm.origin == pytest.approx((1.0, -0.5))
    tol = 1e-12 if dtype == "f8" else 1e-6
    np.testing.assert_allclose(hm.heights, plane(hm.x[:, None], hm.y[None, :]), atol=tol)
    # asymmetric check: the point at (1.3, -0.4) lands at its own position
    assert hm.height_at([1.3, -0.4]) == pytest.approx(plane(1.3, -0.4), abs=tol)
    assert hm.metadata["points_used"] == 20


def test_ply_ignores_other_elements_and_properties(tmp_path):
    pts = grid_points(nx=3, ny=3)
    v = np.empty(len(pts), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8"), ("red", "u1")])
    v["x"], v["y"], v["z"], v["red"] = pts[:, 0], pts[:, 1], pts[:, 2], 255
    faces = np.empty(1, dtype=[("vertex_indices", "i4", (3,))])
    faces["vertex_indices"] = [[0, 1, 2]]
    path = tmp_path / "mesh.ply"
    PlyData([PlyElement.describe(v, "vertex"), PlyElement.describe(faces, "face")],
            text=False).write(str(path))
    hm = import_terrain(path, resolution=RES)
    np.testing.assert_allclose(hm.heights, plane(hm.x[:, None], hm.y[None, :]))


def test_ply_z_scale(tmp_path):
    pts = grid_points(nx=3, ny=3)
    path = tmp_path / "mm.ply"
    write_ply(path, pts * [1, 1, 1000], text=True)
    hm = import_terrain(path, resolution=RES, z_scale=0.001)
    np.testing.assert_allclose(hm.heights, plane(hm.x[:, None], hm.y[None, :]), atol=1e-12)


def test_ply_without_vertex_element(tmp_path):
    e = np.zeros(3, dtype=[("a", "f4")])
    path = tmp_path / "novertex.ply"
    PlyData([PlyElement.describe(e, "camera")], text=True).write(str(path))
    expect_error(path, "no 'vertex' element", resolution=RES)


def test_ply_vertex_without_z(tmp_path):
    v = np.zeros(3, dtype=[("x", "f4"), ("y", "f4")])
    path = tmp_path / "flat.ply"
    PlyData([PlyElement.describe(v, "vertex")], text=True).write(str(path))
    expect_error(path, "lacks z", resolution=RES)


def test_ply_list_property(tmp_path):
    path = tmp_path / "list.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                     b"property float y\nproperty list uchar int z\nend_header\n"
                     b"1 2 1 3\n1 2 1 3\n")
    expect_error(path, "property 'z' must be a number", resolution=RES)


def test_ply_empty_cloud(tmp_path):
    path = tmp_path / "empty.ply"
    write_ply(path, np.empty((0, 3)), text=False)
    expect_error(path, "point cloud is empty", resolution=RES)


@pytest.mark.parametrize("text", [True, False], ids=["ascii", "binary"])
def test_ply_truncated(tmp_path, text):
    path = tmp_path / "cut.ply"
    write_ply(path, grid_points(), text=text)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - 100])  # cuts the last rows (ascii: mid-row)
    expect_error(path, "corrupt or truncated PLY", resolution=RES)


def test_ply_garbage(tmp_path):
    path = tmp_path / "junk.ply"
    path.write_bytes(bytes(range(256)) * 4)
    expect_error(path, "corrupt or truncated PLY", resolution=RES)


def test_ply_malformed_ascii_value(tmp_path):
    path = tmp_path / "bad.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                     b"property float y\nproperty float z\nend_header\n1 2 a\n1 2 3\n")
    expect_error(path, "corrupt or truncated PLY.*malformed", resolution=RES)


# ------------------------------------------------------------------------ xyz
def test_xyz_commas_comments_and_extra_columns(tmp_path):
    pts = grid_points(nx=4, ny=3, x0=-0.2, y0=0.3)
    lines = ["# exported by a scanner", "#x,y,z,intensity"]
    for k, (x, y, z) in enumerate(pts):
        sep = ", " if k % 2 else "\t "
        lines.append(sep.join([repr(float(x)), repr(float(y)), repr(float(z)), "42"]))
    path = tmp_path / "scan.xyz"
    path.write_text("\n".join(lines) + "\n")
    hm = import_terrain(path, resolution=RES)
    assert hm.shape == (4, 3)
    np.testing.assert_allclose(hm.heights, plane(hm.x[:, None], hm.y[None, :]), atol=1e-12)
    assert hm.height_at([0.1, 0.3]) == pytest.approx(plane(0.1, 0.3))
    assert hm.metadata["source_format"] == "xyz"


def test_highest_point_per_cell_and_empty_cells(tmp_path):
    pts = np.array([
        [0.00, 0.00, 1.0],
        [0.03, -0.02, 5.0],  # same cell (0, 0) as the first point, higher
        [0.01, 0.01, 2.0],  # same cell again, lower
        [0.20, 0.00, 0.5],  # cell (2, 0)
        [0.00, 0.20, 0.7],  # cell (0, 2)
        [0.21, 0.19, -1.0],  # cell (2, 2)
    ])
    path = tmp_path / "cloud.xyz"
    write_xyz(path, pts)
    hm = import_terrain(path, resolution=RES)
    assert hm.origin == (0.0, -0.02)
    # y0 = -0.02: y = 0.2 -> floor(2.2 + 0.5) = 2; y = 0.19 -> floor(2.1 + 0.5) = 2
    assert hm.shape == (3, 3)
    assert hm.heights[0, 0] == 5.0
    assert hm.heights[2, 0] == 0.5 and hm.heights[0, 2] == 0.7 and hm.heights[2, 2] == -1.0
    empty = np.isnan(hm.heights)
    assert empty.sum() == 5 and empty[1, 1] and empty[1, 0] and empty[0, 1]


def test_cloud_cells_follow_position_to_index(tmp_path):
    rng = np.random.default_rng(3)
    pts = np.column_stack([rng.uniform(-1, 1, 500), rng.uniform(2, 3, 500),
                           rng.normal(size=500)])
    hm = rasterize_points(pts, 0.07)
    assert hm.origin == (pts[:, 0].min(), pts[:, 1].min())
    idx = hm.position_to_index(pts[:, :2])
    assert hm.is_inside(pts[:, :2]).all()
    cell_max = hm.heights[idx[:, 0], idx[:, 1]]
    assert (pts[:, 2] <= cell_max).all()
    # every non-empty cell's height is one of its points' heights
    for value in hm.heights[~np.isnan(hm.heights)][:20]:
        assert value in pts[:, 2]
    # no cell is higher than the highest point, and the maximum is kept
    assert np.nanmax(hm.heights) == pts[:, 2].max()


def test_non_finite_points_are_dropped(tmp_path):
    pts = grid_points(nx=3, ny=3)
    path = tmp_path / "holes.xyz"
    path.write_text("\n".join(" ".join(repr(float(c)) for c in p) for p in pts)
                    + "\nnan 0.1 0.2\n1.1 inf 0.3\n1.1 -0.4 -inf\n")
    hm = import_terrain(path, resolution=RES)
    reference = rasterize_points(pts, RES)
    np.testing.assert_array_equal(hm.heights, reference.heights)
    assert hm.metadata["points_dropped_nonfinite"] == 3
    assert hm.metadata["points_used"] == 9


def test_only_non_finite_points(tmp_path):
    path = tmp_path / "nan.xyz"
    path.write_text("nan nan nan\ninf 1 2\n")
    expect_error(path, "no usable points among 2 \\(2 non-finite", resolution=RES)


def test_cloud_nodata_points_are_dropped(tmp_path):
    pts = grid_points(nx=3, ny=3)
    # a missing point on top of a real one must not hide it, and the centre is missing
    pts_nd = np.vstack([pts, [[pts[0, 0], pts[0, 1], -9999.0]]])
    pts_nd[4, 2] = -9999.0
    path = tmp_path / "dem.xyz"
    write_xyz(path, pts_nd)
    hm = import_terrain(path, resolution=RES, nodata=-9999)
    assert np.isnan(hm.heights[1, 1])
    assert hm.heights[0, 0] == pytest.approx(plane(*pts[0, :2]))
    assert hm.metadata["points_dropped_nodata"] == 2


def test_cloud_requires_resolution_and_refuses_origin(tmp_path):
    path = tmp_path / "cloud.xyz"
    write_xyz(path, grid_points())
    expect_error(path, r"resolution \[m/cell\] is required to import a .xyz point cloud")
    expect_error(path, "origin applies to .npy/.png grids only",
                 resolution=RES, origin=(0.0, 0.0))


@pytest.mark.parametrize("content", ["", "# only a comment\n\n"])
def test_xyz_empty(tmp_path, content):
    path = tmp_path / "empty.xyz"
    path.write_text(content)
    expect_error(path, "point cloud is empty", resolution=RES)


@pytest.mark.parametrize("content, pattern", [
    ("1 2 3\n4 5\n", "not a readable .xyz"),
    ("1 2 3\n4 five 6\n", "not a readable .xyz.*five"),
])
def test_xyz_malformed(tmp_path, content, pattern):
    path = tmp_path / "bad.xyz"
    path.write_text(content)
    expect_error(path, pattern, resolution=RES)


def test_xyz_binary_content(tmp_path):
    path = tmp_path / "binary.xyz"
    path.write_bytes(b"\x93NUMPY\xff\xfe\x00\x01" * 8)
    expect_error(path, "not a readable .xyz", resolution=RES)


def test_cloud_narrower_than_two_cells(tmp_path):
    path = tmp_path / "line.xyz"
    write_xyz(path, [[0.0, 0.0, 1.0], [0.5, 0.01, 1.0], [1.0, 0.02, 1.0]])
    expect_error(path, "span only 11 x 1 cells.*at least 2 x 2", resolution=RES)


def test_cloud_too_many_cells(tmp_path):
    path = tmp_path / "wide.xyz"
    write_xyz(path, [[0.0, 0.0, 1.0], [1000.0, 1000.0, 1.0]])
    expect_error(path, f"more than {MAX_CELLS}.*coarser resolution", resolution=0.01)


# ------------------------------------------------------------------ provenance
def test_imported_map_saves_and_reloads_with_provenance(tmp_path):
    src = tmp_path / "scan.ply"
    write_ply(src, grid_points(), text=False)
    hm = import_terrain(src, resolution=RES, frame="odom")
    json.dumps(hm.metadata)  # serialisable
    assert hm.metadata["source"] == str(src) and len(hm.metadata["source_sha256"]) == 64
    out = tmp_path / "map.npz"
    hm.save(out)
    again = import_terrain(out)
    assert again.content_hash() == hm.content_hash()
    assert again.metadata == hm.metadata and again.frame == "odom"


def test_rasterize_points_rejects_bad_input():
    with pytest.raises(FootfallError, match="point cloud is empty"):
        rasterize_points(np.empty((0, 3)), 0.1)
    with pytest.raises(FootfallError, match=r"shape \(n, 3\)"):
        rasterize_points(np.zeros((4, 2)), 0.1)
    with pytest.raises(FootfallError, match="resolution"):
        rasterize_points(np.zeros((4, 3)), -1.0)


def test_npz_truncated_and_foreign(tmp_path):
    path = tmp_path / "cut.npz"
    HeightMap(np.ones((4, 4)), 0.1).save(path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    expect_error(path, "not a readable footfall .npz file")
    foreign = tmp_path / "plain.npz"
    np.savez(foreign, heights=np.ones((3, 3)))
    expect_error(foreign, "not a footfall file")
