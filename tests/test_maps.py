"""Elevation maps as robots and surveys record them: ROS 2 bags of grid_map, LAS / LAZ point
clouds and GeoTIFF rasters imported; foothold scores written back as a layer.

Every input here is written by the format's own library (rosbags' writer, laspy, rasterio),
with its cells placed by the format's conventions as the test states them, not by footfall's
writers, so that an import that got a convention wrong cannot agree with itself.
"""

import warnings

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.limits import Limits, use_limits
from footfall.terrain.bags import GRID_MAP_TYPE, grid_map_typestore
from footfall.terrain.scans import import_terrain


def surface(x, y):
    """A smooth test surface [m] at x, y [m]: distinct at every cell, a few cm of relief."""
    return 0.02 * np.sin(7 * x) + 0.015 * np.cos(5 * y) + 0.01 * x - 0.004 * y


# ------------------------------------------------------------------- ROS 2 bags
def grid_map_msg(store, rows, cols, r, centre, start=(0, 0), row_major=False, frame="odom",
                 holes=(), extra_layers=()):
    """A GridMap message written by grid_map's conventions as stated in its converter:
    matrix rows along x, columns along y, unwrapped (0, 0) at the corner of largest x and y,
    the stored matrix a circular buffer starting at ``start``; ``holes``: unwrapped
    (row, col) cells set to NaN."""
    from rosbags.typesys.stores.ros2_humble import (
        builtin_interfaces__msg__Time as Time,
    )
    from rosbags.typesys.stores.ros2_humble import (
        geometry_msgs__msg__Point as Point,
    )
    from rosbags.typesys.stores.ros2_humble import (
        geometry_msgs__msg__Pose as Pose,
    )
    from rosbags.typesys.stores.ros2_humble import (
        geometry_msgs__msg__Quaternion as Quaternion,
    )
    from rosbags.typesys.stores.ros2_humble import (
        std_msgs__msg__Float32MultiArray as F32,
    )
    from rosbags.typesys.stores.ros2_humble import (
        std_msgs__msg__Header as Header,
    )
    from rosbags.typesys.stores.ros2_humble import (
        std_msgs__msg__MultiArrayDimension as Dim,
    )
    from rosbags.typesys.stores.ros2_humble import (
        std_msgs__msg__MultiArrayLayout as Layout,
    )

    u = np.arange(rows)[:, None]
    v = np.arange(cols)[None, :]
    x = centre[0] + rows * r / 2 - (u + 0.5) * r
    y = centre[1] + cols * r / 2 - (v + 0.5) * r
    unwrapped = surface(x, y).astype(np.float32)
    for cell in holes:
        unwrapped[cell] = np.nan
    stored = np.empty_like(unwrapped)  # stored[(u + s) mod n] = unwrapped[u]
    su = (np.arange(rows) + start[0]) % rows
    sv = (np.arange(cols) + start[1]) % cols
    stored[np.ix_(su, sv)] = unwrapped

    def array(m):
        if row_major:
            dims = [Dim(label="row_index", size=rows, stride=rows * cols),
                    Dim(label="column_index", size=cols, stride=cols)]
            return F32(layout=Layout(dim=dims, data_offset=0), data=m.ravel(order="C"))
        dims = [Dim(label="column_index", size=cols, stride=rows * cols),
                Dim(label="row_index", size=rows, stride=rows)]
        return F32(layout=Layout(dim=dims, data_offset=0), data=m.ravel(order="F"))

    GridMap = store.types[GRID_MAP_TYPE]
    Info = store.types["grid_map_msgs/msg/GridMapInfo"]
    layers = ["elevation", *extra_layers]
    return GridMap(
        header=Header(stamp=Time(sec=5, nanosec=0), frame_id=frame),
        info=Info(resolution=r, length_x=rows * r, length_y=cols * r,
                  pose=Pose(position=Point(x=centre[0], y=centre[1], z=0.0),
                            orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0))),
        layers=layers, basic_layers=["elevation"],
        data=[array(stored)] + [array(stored * 0 + k) for k, _ in enumerate(extra_layers, 1)],
        outer_start_index=start[0], inner_start_index=start[1])


def write_bag(path, messages, storage="mcap"):
    """A ROS 2 bag folder written by rosbags' writer: ``messages`` as (topic, msgtype, msg)."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = grid_map_typestore()
    plugin = {"mcap": StoragePlugin.MCAP, "sqlite3": StoragePlugin.SQLITE3}[storage]
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        conns = {}
        for k, (topic, msgtype, msg) in enumerate(messages):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
            writer.write(conns[topic], (k + 1) * 1_000_000_000, store.serialize_cdr(msg, msgtype))
    return path


def expected_heights(rows, cols, r, centre):
    """The surface at footfall's cells: cell (0, 0) at the corner of least x and y."""
    x = centre[0] - rows * r / 2 + (np.arange(rows) + 0.5) * r
    y = centre[1] - cols * r / 2 + (np.arange(cols) + 0.5) * r
    return surface(x[:, None], y[None, :]).astype(np.float32).astype(np.float64)


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
@pytest.mark.parametrize("start,row_major", [((0, 0), False), ((7, 3), False), ((2, 11), True)])
def test_a_grid_map_bag_round_trips_heights_holes_and_geometry(tmp_path, storage, start,
                                                               row_major):
    store = grid_map_typestore()
    rows, cols, r, centre = 30, 24, 0.02, (1.5, -0.4)
    holes = [(3, 4), (10, 20), (29, 0)]
    msg = grid_map_msg(store, rows, cols, r, centre, start, row_major, holes=holes)
    bag = write_bag(tmp_path / "bag", [("/elevation_map", GRID_MAP_TYPE, msg)], storage)
    want = expected_heights(rows, cols, r, centre)
    for u, v in holes:  # unwrapped (u, v) is footfall's (rows-1-u, cols-1-v)
        want[rows - 1 - u, cols - 1 - v] = np.nan
    storage_file = next(f for f in bag.iterdir() if f.suffix in (".mcap", ".db3"))
    for source in (bag, storage_file):  # a bag folder, or its single storage file
        hmap = import_terrain(source)
        assert hmap.shape == (rows, cols) and hmap.resolution == pytest.approx(r)
        assert hmap.frame == "odom"
        np.testing.assert_allclose(hmap.origin, (centre[0] - rows * r / 2 + r / 2,
                                                 centre[1] - cols * r / 2 + r / 2))
        np.testing.assert_array_equal(np.isnan(hmap.heights), np.isnan(want))
        np.testing.assert_array_equal(hmap.heights[~np.isnan(want)], want[~np.isnan(want)])
        assert hmap.metadata["topic"] == "/elevation_map" and hmap.metadata["messages"] == 1


def test_a_bag_chooses_topic_layer_and_message_and_lists_them(tmp_path):
    store = grid_map_typestore()
    maps = [grid_map_msg(store, 10, 12, 0.05, (k, 0.0), extra_layers=("variance",))
            for k in range(3)]
    bag = write_bag(tmp_path / "bag", [("/a", GRID_MAP_TYPE, maps[0]),
                                      ("/b", GRID_MAP_TYPE, maps[1]),
                                      ("/b", GRID_MAP_TYPE, maps[2])])
    with pytest.raises(FootfallError, match="2 topics; choose one with --topic: /a, /b"):
        import_terrain(bag)
    last = import_terrain(bag, topic="/b")  # the last message by default
    assert last.metadata["message"] == 1 and last.origin[0] == pytest.approx(2 - 0.25 + 0.025)
    first = import_terrain(bag, topic="/b", message=-2)
    assert first.metadata["message"] == 0 and first.origin[0] == pytest.approx(1 - 0.225)
    by_time = import_terrain(bag, topic="/b", time=1.5)  # messages at 1, 2, 3 s: /b at 2, 3
    assert by_time.metadata["message"] == 0
    variance = import_terrain(bag, topic="/a", layer="variance")
    assert np.all(variance.heights == 1.0)
    with pytest.raises(FootfallError, match=r"no layer 'slope' \(it has: elevation, variance\)"):
        import_terrain(bag, topic="/a", layer="slope")
    with pytest.raises(FootfallError, match="message 2 does not exist: the topic holds 2"):
        import_terrain(bag, topic="/b", message=2)
    with pytest.raises(FootfallError, match="no message at or before 0.5 s"):
        import_terrain(bag, topic="/b", time=0.5)


def test_bad_bags_are_refused_in_one_line(tmp_path, capsys):
    from rosbags.typesys.stores.ros2_humble import std_msgs__msg__String as String

    store = grid_map_typestore()
    msg = grid_map_msg(store, 10, 12, 0.05, (0.0, 0.0))
    bag = write_bag(tmp_path / "bag", [("/map", GRID_MAP_TYPE, msg),
                                      ("/chat", "std_msgs/msg/String", String(data="hi"))])
    cases = [
        (["--topic", "/chat"], "topic '/chat' carries std_msgs/msg/String, not grid_map_msgs"),
        (["--topic", "/nope"], "the bag has no topic '/nope' (it has: /chat, /map)"),
        (["--layer", "height"], "no layer 'height'"),
        (["--resolution", "0.01"], "carries its own geometry"),
        (["--classes", "2"], "classes applies to LAS / LAZ point clouds only"),
    ]
    for extra, match in cases:
        code, _, err = run(capsys, "terrain", "import", bag, *extra, "-o", tmp_path / "o.npz")
        assert_user_error(code, err, match)
    only_text = write_bag(tmp_path / "text", [("/chat", "std_msgs/msg/String", String(data="x"))])
    code, _, err = run(capsys, "terrain", "import", only_text, "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "holds no grid_map_msgs/msg/GridMap topic")
    mcap = next((tmp_path / "bag").glob("*.mcap"))
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(mcap.read_bytes()[: mcap.stat().st_size // 2])
    code, _, err = run(capsys, "terrain", "import", cut, "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "cut.mcap: not a readable ROS 2 bag, or a damaged one")
    folder = tmp_path / "folder"
    folder.mkdir()
    code, _, err = run(capsys, "terrain", "import", folder, "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "a folder, but not a ROS 2 bag (no metadata.yaml)")
    rotated = grid_map_msg(store, 10, 12, 0.05, (0.0, 0.0))
    rotated.info.pose.orientation.z, rotated.info.pose.orientation.w = 0.38268343, 0.92387953
    write_bag(tmp_path / "rot", [("/map", GRID_MAP_TYPE, rotated)])
    code, _, err = run(capsys, "terrain", "import", tmp_path / "rot", "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "the map's pose is rotated")
    with use_limits(Limits(max_map_cells=100)):
        with pytest.raises(FootfallError, match="120 cells, above the limit of 100"):
            import_terrain(tmp_path / "bag", topic="/map")


# --------------------------------------------------------------------- LAS / LAZ
def write_las(path, x, y, z, classification=None, wkt=None, geokeys=None):
    """A LAS 1.4 file (LAZ by its suffix) written by laspy, coordinates at 0.1 mm."""
    import laspy
    from laspy.vlrs.known import GeoKeyDirectoryVlr, WktCoordinateSystemVlr

    header = laspy.LasHeader(point_format=6, version="1.4")
    header.offsets = [float(np.floor(x.min())), float(np.floor(y.min())), 0.0]
    header.scales = [1e-4, 1e-4, 1e-4]
    if wkt is not None:
        header.vlrs.append(WktCoordinateSystemVlr(wkt))
    if geokeys is not None:
        vlr = GeoKeyDirectoryVlr()
        vlr.parse_record_data(np.array([1, 1, 0, len(geokeys)] + [
            v for key, value in geokeys for v in (key, 0, 1, value)], dtype="<u2").tobytes())
        header.vlrs.append(vlr)
    las = laspy.LasData(header)
    las.x, las.y, las.z = x, y, z
    if classification is not None:
        las.classification = classification
    las.write(path)
    return path


def lidar_cloud(r=0.01, nx=40, ny=30, x0=512_300.0, y0=5_401_200.0):
    """Ground points at the centres of an nx x ny grid of cell ``r`` (one cell left empty),
    each with a vegetation point 30 cm above it: (x, y, z, classes, expected heights)."""
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    keep = ~((i == 5) & (j == 7))
    gx, gy = x0 + i[keep] * r, y0 + j[keep] * r
    gz = 300.0 + surface(i[keep] * r, j[keep] * r)
    x = np.concatenate([gx, gx])
    y = np.concatenate([gy, gy])
    z = np.concatenate([gz, gz + 0.3])
    classes = np.concatenate([np.full(gx.size, 2), np.full(gx.size, 4)]).astype(np.uint8)
    want = np.full((nx, ny), np.nan)
    want[i[keep], j[keep]] = np.round(gz, 4)
    return x, y, z, classes, want


@pytest.mark.parametrize("suffix", [".las", ".laz"])
def test_a_lidar_cloud_round_trips_ground_heights_holes_and_resolution(tmp_path, suffix):
    from rasterio.crs import CRS

    x, y, z, classes, want = lidar_cloud()
    path = write_las(tmp_path / f"site{suffix}", x, y, z, classes,
                     wkt=CRS.from_epsg(32633).to_wkt())
    hmap = import_terrain(path, resolution=0.01)
    assert hmap.shape == want.shape and hmap.resolution == 0.01 and hmap.origin == (0, 0)
    np.testing.assert_array_equal(np.isnan(hmap.heights), np.isnan(want))  # the one hole
    np.testing.assert_allclose(hmap.heights[~np.isnan(want)], want[~np.isnan(want)], atol=2e-4)
    geo = hmap.metadata["georeference"]
    assert "32633" in geo["crs_wkt"] or "UTM zone 33N" in geo["crs_wkt"]
    np.testing.assert_allclose(geo["transform"], [0.01, 0, 512_300 - 0.005, 0, -0.01,
                                                  5_401_200 + 29.5 * 0.01], atol=1e-6)
    trees = import_terrain(path, resolution=0.01, classes=(4,))  # the vegetation instead
    np.testing.assert_allclose(np.nanmean(trees.heights - hmap.heights), 0.3, atol=1e-3)
    lowest = import_terrain(path, resolution=0.02, classes=(2, 4), statistic="min")
    assert lowest.resolution == 0.02 and np.nanmax(lowest.heights) < np.nanmax(trees.heights)
    unclassified = write_las(tmp_path / f"raw{suffix}", x[:100], y[:100], z[:100])
    assert import_terrain(unclassified, resolution=0.01).metadata["class_filter"].startswith(
        "all")


def test_lidar_files_not_in_metres_or_damaged_are_refused_in_one_line(tmp_path, capsys):
    from rasterio.crs import CRS

    x, y, z, classes, _ = lidar_cloud(nx=10, ny=10, x0=1000.0, y0=2000.0)
    cases = {
        "feet.las": dict(wkt=CRS.from_epsg(2263).to_wkt()),  # NY Long Island, US survey feet
        "degrees.las": dict(wkt=CRS.from_epsg(4326).to_wkt()),
        "keys_feet.las": dict(geokeys=[(1024, 1), (3076, 9002)]),
        "keys_degrees.las": dict(geokeys=[(1024, 2)]),
    }
    for name, kwargs in cases.items():
        path = write_las(tmp_path / name, x, y, z, classes, **kwargs)
        code, _, err = run(capsys, "terrain", "import", path, "--resolution", "0.01", "-o",
                           tmp_path / "o.npz")
        assert_user_error(code, err, "not metres")
    good = write_las(tmp_path / "good.laz", x, y, z, classes)
    cut = tmp_path / "cut.laz"
    cut.write_bytes(good.read_bytes()[:-200])
    code, _, err = run(capsys, "terrain", "import", cut, "--resolution", "0.01", "-o",
                       tmp_path / "o.npz")
    assert_user_error(code, err, "cut.laz:")
    code, _, err = run(capsys, "terrain", "import", good, "--resolution", "0.01", "--classes",
                       "9", "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "no point is kept by the class filter (classes [9])")
    code, _, err = run(capsys, "terrain", "import", good, "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "resolution [m/cell] is required")
    with use_limits(Limits(max_scan_points=50)):
        with pytest.raises(FootfallError, match="198 points, above the limit of 50"):
            import_terrain(good, resolution=0.01)


# ----------------------------------------------------------------------- GeoTIFF
def from_origin(left, top, width, height):
    """The north-up transform of a raster whose top-left corner is at (left, top) [m]."""
    from rasterio.transform import Affine

    return Affine(width, 0.0, left, 0.0, -height, top)


def write_geotiff(path, heights_rows, transform, crs="EPSG:32632", nodata=-9999.0,
                  dtype="float32"):
    """A GeoTIFF written by rasterio: ``heights_rows`` (rows north to south, columns west to
    east), as a DEM exporter writes it."""
    import rasterio

    with rasterio.open(path, "w", driver="GTiff", width=heights_rows.shape[1],
                       height=heights_rows.shape[0], count=1, dtype=dtype, crs=crs,
                       transform=transform, nodata=nodata) as ds:
        ds.write(heights_rows.astype(dtype), 1)
    return path


def dem(rows=40, cols=50, r=0.02, left=600_000.0, top=4_200_000.0):
    """A DEM: (rows north to south, the transform, footfall's expected heights [i, j])."""
    col = np.arange(cols)[None, :]
    row = np.arange(rows)[:, None]
    x = (col + 0.5) * r  # the local frame: the south-west pixel's centre at (0, 0)
    y = (rows - 1 - row + 0.5) * r - r / 2
    band = (200.0 + surface(x, y)).astype(np.float32)
    band[3, 4] = band[rows // 2, cols - 2] = -9999.0  # no data
    want = band[::-1, :].T.astype(np.float64)
    want[want == -9999.0] = np.nan
    return band, from_origin(left, top, r, r), want


def test_a_geotiff_round_trips_heights_holes_and_resolution(tmp_path):
    band, transform, want = dem()
    path = write_geotiff(tmp_path / "dem.tif", band, transform)
    hmap = import_terrain(path)
    assert hmap.shape == want.shape and hmap.resolution == pytest.approx(0.02)
    np.testing.assert_array_equal(np.isnan(hmap.heights), np.isnan(want))
    np.testing.assert_array_equal(hmap.heights[~np.isnan(want)], want[~np.isnan(want)])
    assert hmap.metadata["georeference"]["transform"] == list(transform)[:6]
    part = import_terrain(path, bounds=(600_000.1, 4_200_000 - 0.5, 600_000.3, 4_200_000))
    assert part.shape == (10, 25)  # the pixels the window touches: 0.1-0.3 m, 0.5 m
    np.testing.assert_array_equal(part.heights, want[5:15, 15:40])
    assert part.metadata["window"] == [5, 0, 10, 25]


def test_geotiffs_in_degrees_or_damaged_are_refused_in_one_line(tmp_path, capsys):
    import rasterio
    band, _, want = dem(rows=10, cols=12)
    geographic = write_geotiff(tmp_path / "wgs84.tif", band, from_origin(8.5, 47.4, 1e-6, 1e-6),
                               crs="EPSG:4326")
    code, _, err = run(capsys, "terrain", "import", geographic, "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "in degrees (a geographic CRS), not metres; give --resolution")
    stated = import_terrain(geographic, resolution=0.1)  # the user states the cell size
    assert stated.resolution == 0.1 and stated.metadata["cell_size_from"] == "--resolution"
    good = write_geotiff(tmp_path / "good.tif", band, from_origin(0, 10, 0.1, 0.1))
    cut = tmp_path / "cut.tif"
    cut.write_bytes(good.read_bytes()[:300])
    code, _, err = run(capsys, "terrain", "import", cut, "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "cut.tif: not a readable GeoTIFF")
    code, _, err = run(capsys, "terrain", "import", good, "--band", "2", "-o",
                       tmp_path / "o.npz")
    assert_user_error(code, err, "band 2 does not exist")
    code, _, err = run(capsys, "terrain", "import", good, "--bounds", "50", "50", "60", "60",
                       "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "do not overlap the raster")
    code, _, err = run(capsys, "terrain", "import", good, "--topic", "/x", "-o",
                       tmp_path / "o.npz")
    assert_user_error(code, err, "topic applies to ROS 2 bags only")
    bare = tmp_path / "bare.tif"  # no geotransform: pixel size and place unknown
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rasterio.errors.NotGeoreferencedWarning)
        with rasterio.open(bare, "w", driver="GTiff", width=12, height=10, count=1,
                           dtype="float32") as ds:
            ds.write(band, 1)
    code, _, err = run(capsys, "terrain", "import", bare, "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "no geotransform (no pixel size or place); give --resolution")
    stated = import_terrain(bare, resolution=0.01)
    assert stated.resolution == 0.01 and stated.shape == (12, 10)
    with use_limits(Limits(max_map_cells=100)):
        with pytest.raises(FootfallError, match="120 cells, above the limit of 100"):
            import_terrain(good)
        assert import_terrain(good, bounds=(0, 9, 0.5, 10)).shape == (5, 10)


# ------------------------------------------------------------------------ a walk
def test_a_map_imported_from_each_format_is_walked(tmp_path):
    """A board of a module from each importer (a bag, a LAZ cloud, a GeoTIFF), each walked."""
    from footfall.features.reward import default_reward
    from footfall.sim.episode import WalkConfig, walk
    from footfall.terrain import FileModule, make_board

    store = grid_map_typestore()
    flat = lambda x, y: 0.004 * np.sin(9 * x) * np.cos(6 * y)  # noqa: E731  gentle waves
    rows, cols, r = 160, 160, 0.004  # 0.64 m square at 4 mm
    msg = grid_map_msg(store, rows, cols, r, (0.0, 0.0), start=(40, 9))
    u, v = np.arange(rows)[:, None], np.arange(cols)[None, :]
    msg.data[0].data[:] = np.roll(flat(-(u + 0.5) * r, -(v + 0.5) * r),
                                  (40, 9), axis=(0, 1)).ravel(order="F")
    bag = write_bag(tmp_path / "bag", [("/map", GRID_MAP_TYPE, msg)], "sqlite3")
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    cloud = write_las(tmp_path / "site.laz", 100.0 + i.ravel() * r, 200.0 + j.ravel() * r,
                      flat(i.ravel() * r, j.ravel() * r))
    tif = write_geotiff(tmp_path / "dem.tif",
                        flat(np.arange(cols)[None, :] * r, np.arange(rows)[::-1, None] * r),
                        from_origin(0, rows * r, r, r))
    reward = default_reward()
    for source, options in ((bag, {}), (cloud, {"resolution": r}), (tif, {})):
        hmap = import_terrain(source, **options)
        board = make_board([FileModule(source.name, hmap), ("flat", 0.0)], seed=3,
                           flat_ends=False)
        rec = walk(board, lambda leg: reward, 5, WalkConfig(start_setback=0.2, max_steps=3))
        touchdowns = np.array([step.touchdown[:2] for step in rec.steps])
        assert rec.result["reason"] == "step limit" and len(rec.steps) == 3, (source, rec.result)
        assert (touchdowns[:, 0] < board.metadata["modules"][0]["x_end"]).any()  # on the file
        assert not np.isnan(board.height_at(touchdowns)).any()


# ------------------------------------------------------------------ score layers
def test_score_writes_npz_geotiff_and_bags_that_their_libraries_read(tmp_path, capsys):
    import rasterio
    from rosbags.rosbag2 import Reader

    from footfall.features.family import Candidates
    from footfall.features.reward import default_reward
    from footfall.terrain.layer_files import FORMAT

    band, transform, _ = dem(rows=60, cols=70, r=0.003)
    source = write_geotiff(tmp_path / "dem.tif", band, transform)
    hmap = import_terrain(source)
    for out in ("s.npz", "s.tif", "s.mcap", "s.db3"):
        code, text, err = run(capsys, "score", source, "--leg", "RF", "-o", tmp_path / out)
        assert code == 0 and "footfall_score of hand-tuned for RF" in text, err
    with rasterio.open(tmp_path / "s.tif") as ds:
        assert ds.transform == transform and ds.crs == rasterio.open(source).crs
        assert ds.descriptions == ("elevation", "footfall_score")
        elevation, scores = ds.read(1)[::-1, :].T, ds.read(2)[::-1, :].T
    np.testing.assert_array_equal(np.isnan(elevation), np.isnan(hmap.heights))
    store = grid_map_typestore()
    for bag in ("s.mcap", "s.db3"):
        with Reader(tmp_path / bag) as reader:
            (conn,) = reader.connections
            assert conn.msgtype == GRID_MAP_TYPE
            (_, _, raw), = list(reader.messages())
            msg = store.deserialize_cdr(raw, conn.msgtype)
        assert list(msg.layers) == ["elevation", "footfall_score"]
        back = import_terrain(tmp_path / bag, layer="footfall_score")
        np.testing.assert_array_equal(back.heights, scores.astype(np.float64))
    from footfall.core.files import load_npz

    _, arrays, meta = load_npz(tmp_path / "s.npz", FORMAT, 1, allow_nonfinite=True)
    assert meta["describe"]["leg"] == "RF" and meta["layers"] == ["elevation", "footfall_score"]
    np.testing.assert_allclose(arrays["footfall_score"], scores, rtol=1e-6)
    # Each cell's score is the scorer's own value of a foothold there (right leg: mirrored).
    reward = default_reward()
    rng = np.random.default_rng(0)
    cells = rng.integers(0, hmap.shape, size=(40, 2))
    xy = np.asarray(hmap.origin) + cells * hmap.resolution
    footholds = np.column_stack([xy, hmap.height_at(xy)])
    direct = reward.terrain_values(Candidates(hmap, footholds, 0.0, True, reward.config))
    got = arrays["footfall_score"][cells[:, 0], cells[:, 1]]
    np.testing.assert_array_equal(np.isfinite(direct), np.isfinite(got))
    ok = np.isfinite(direct)
    assert ok.sum() > 20
    np.testing.assert_allclose(got[ok], direct[ok], rtol=1e-6, atol=1e-9)


def test_score_refuses_bad_requests_in_one_line(tmp_path, capsys):
    band, transform, _ = dem(rows=10, cols=12)
    source = write_geotiff(tmp_path / "dem.tif", band, transform)
    for args, match in (
            (["-o", tmp_path / "s.png"], "unknown score layer format '.png'"),
            (["--reward", "nope", "-o", tmp_path / "s.npz"], "nope"),
            (["--model", tmp_path / "none.npz", "-o", tmp_path / "s.npz"], "none.npz"),
            (["--model", tmp_path / "m.npz", "--reward", "hand-tuned", "-o",
              tmp_path / "s.npz"], "give --model or --reward, not both"),
            (["-o", source], "is also an input")):
        code, _, err = run(capsys, "score", source, *args)
        assert_user_error(code, err, match)
    assert isinstance(HeightMap, type)
