"""HeightMap: geometry, lookup, patches, mirroring, files, bad input."""

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap, PatchGrid


def plane_map(a=0.1, b=-0.05, c=0.02, shape=(60, 40), res=0.002, origin=(0.1, -0.04)):
    x = origin[0] + np.arange(shape[0]) * res
    y = origin[1] + np.arange(shape[1]) * res
    xx, yy = np.meshgrid(x, y, indexing="ij")
    return HeightMap(a * xx + b * yy + c, res, origin)


def test_position_index_round_trip():
    hm = plane_map()
    idx = np.array([[0, 0], [59, 39], [17, 23]])
    pos = hm.index_to_position(idx)
    np.testing.assert_allclose(pos[2], [0.1 + 17 * 0.002, -0.04 + 23 * 0.002])
    np.testing.assert_array_equal(hm.position_to_index(pos), idx)
    # Any point within half a cell of a centre maps to that cell.
    jitter = pos + np.array([0.00099, -0.00099])
    np.testing.assert_array_equal(hm.position_to_index(jitter), idx)


def test_is_inside_and_bounds():
    hm = plane_map()
    x0, x1, y0, y1 = hm.bounds
    assert (x0, y0) == pytest.approx((0.099, -0.041))
    assert hm.length == pytest.approx((0.12, 0.08))
    inside = hm.is_inside([[x0 + 1e-9, y0 + 1e-9], [x1 - 1e-9, y1 - 1e-9], [x0 - 1e-6, 0.0], [0.15, y1]])
    assert inside.tolist() == [True, True, False, False]


def test_bilinear_is_exact_on_a_plane_and_nan_outside():
    hm = plane_map()
    rng = np.random.default_rng(0)
    p = np.column_stack([rng.uniform(0.1, 0.218, 200), rng.uniform(-0.04, 0.038, 200)])
    np.testing.assert_allclose(hm.height_at(p), 0.1 * p[:, 0] - 0.05 * p[:, 1] + 0.02, atol=1e-12)
    assert np.isnan(hm.height_at([[0.0, 0.0], [0.5, 0.0]])).all()


def test_nan_cells_keep_their_extent_and_do_not_leak():
    h = np.zeros((10, 10))
    h[4, 4] = np.nan
    h[5, 4] = 1.0
    hm = HeightMap(h, 1.0)
    assert np.isnan(hm.height_at([[4.0, 4.0], [4.4, 4.4]])).all()  # nearest cell is the hole
    # Between the hole and its neighbour (1.0) the valid corners are renormalised.
    assert hm.height_at([[4.6, 4.0]])[0] == pytest.approx(1.0)
    assert hm.height_at([[5.0, 4.5]])[0] == pytest.approx(0.5)


def test_patch_against_hand_computed_with_yaw_and_mirroring():
    # Height = x + 10 y on a fine grid: a sample at world (x, y) reads x + 10 y.
    res = 0.001
    x = np.arange(200) * res
    y = np.arange(200) * res
    hm = HeightMap(x[:, None] + 10 * y[None, :], res)
    grid = PatchGrid(0.004, 0.004, 0.002)  # u, v in {-2, 0, 2} mm
    assert grid.shape == (3, 3)
    np.testing.assert_allclose(grid.u, [-0.002, 0.0, 0.002])
    np.testing.assert_allclose(grid.v, [-0.002, 0.0, 0.002])
    c = np.array([0.1, 0.1])
    expected = {}
    for yaw, mirror in ((0.0, False), (np.pi / 2, False), (0.3, True)):
        e = np.empty((3, 3))
        for a, u in enumerate(grid.u):
            for b, v in enumerate(grid.v):
                vv = -v if mirror else v
                px = c[0] + np.cos(yaw) * u - np.sin(yaw) * vv
                py = c[1] + np.sin(yaw) * u + np.cos(yaw) * vv
                e[a, b] = px + 10 * py
        expected[(yaw, mirror)] = e
        got = hm.patches(c[None], yaw, mirror, grid)[0]
        np.testing.assert_allclose(got, e, atol=1e-12)
    # Yaw pi/2: u points along +y, so stepping u raises the height by 10 per metre.
    p = hm.patches(c[None], np.pi / 2, False, grid)[0]
    assert p[2, 1] - p[1, 1] == pytest.approx(10 * 0.002)


def test_mirrored_patch_equals_patch_on_mirrored_map():
    rng = np.random.default_rng(3)
    hm = HeightMap(rng.normal(size=(80, 70)) * 0.01, 0.002, (0.0, -0.05))
    grid = PatchGrid(0.03, 0.02, 0.003)
    pos = np.array([[0.07, 0.02], [0.09, -0.01]])
    right = hm.patches(pos, 0.2, True, grid)
    mirrored = hm.mirrored_y()
    left = mirrored.patches(pos * [1, -1], -0.2, False, grid)
    np.testing.assert_allclose(right, left, atol=1e-12)


def test_save_load_round_trip(tmp_path):
    h = np.random.default_rng(1).normal(size=(30, 20))
    h[3:5, 7] = np.nan
    hm = HeightMap(h, 0.005, (1.0, -2.0), "board", {"kind": "test", "modules": [1, 2]})
    path = tmp_path / "map.npz"
    hm.save(path)
    back = HeightMap.load(path)
    np.testing.assert_array_equal(back.heights, hm.heights)
    assert (back.resolution, back.origin, back.frame, back.metadata) == \
        (0.005, (1.0, -2.0), "board", {"kind": "test", "modules": [1, 2]})
    assert back.content_hash() == hm.content_hash()
    assert not list(tmp_path.glob("*.tmp*"))  # nothing half-written left behind


def test_content_hash_sees_heights_and_geometry():
    h = np.zeros((5, 5))
    a = HeightMap(h, 0.01)
    assert a.content_hash() == HeightMap(h.copy(), 0.01).content_hash()
    assert a.content_hash() != HeightMap(h, 0.02).content_hash()
    h2 = h.copy()
    h2[2, 2] = 1e-6
    assert a.content_hash() != HeightMap(h2, 0.01).content_hash()


def test_heights_are_private_and_read_only():
    h = np.zeros((4, 4))
    hm = HeightMap(h, 0.01)
    h[0, 0] = 5.0
    assert hm.heights[0, 0] == 0.0
    with pytest.raises(ValueError):
        hm.heights[0, 0] = 1.0


@pytest.mark.parametrize("kwargs, match", [
    ({"heights": np.zeros(5), "resolution": 0.01}, "must be 2-D"),
    ({"heights": np.zeros((1, 5)), "resolution": 0.01}, "at least 2 x 2"),
    ({"heights": np.zeros((3, 3)), "resolution": 0.0}, "resolution must be > 0"),
    ({"heights": np.zeros((3, 3)), "resolution": -1.0}, "resolution must be > 0"),
    ({"heights": np.full((3, 3), np.nan), "resolution": 0.01}, "no data"),
    ({"heights": np.array([[1, np.inf], [0, 0]]), "resolution": 0.01}, "infinite"),
    ({"heights": np.array([["a", "b"], ["c", "d"]]), "resolution": 0.01}, "numbers"),
    ({"heights": np.zeros((3, 3)), "resolution": 0.01, "origin": (np.nan, 0)}, "origin"),
])
def test_bad_maps_are_rejected(kwargs, match):
    with pytest.raises(FootfallError, match=match):
        HeightMap(**kwargs)


def test_bad_files_are_rejected(tmp_path):
    with pytest.raises(FootfallError, match="no such file"):
        HeightMap.load(tmp_path / "missing.npz")
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip at all")
    with pytest.raises(FootfallError, match="not a readable"):
        HeightMap.load(junk)
    good = tmp_path / "good.npz"
    HeightMap(np.zeros((40, 40)), 0.01).save(good)
    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(FootfallError, match="not a readable"):
        HeightMap.load(truncated)
    other = tmp_path / "other.npz"
    np.savez(other, heights=np.zeros((3, 3)))
    with pytest.raises(FootfallError, match="not a footfall file"):
        HeightMap.load(other)


def test_loading_a_newer_version_fails(tmp_path):
    from footfall.core.files import save_npz

    path = tmp_path / "future.npz"
    save_npz(path, "footfall.heightmap", 99, {"heights": np.zeros((3, 3))},
             {"resolution": 0.01, "origin": [0, 0], "frame": "world"})
    with pytest.raises(FootfallError, match="version 99 is not supported"):
        HeightMap.load(path)
