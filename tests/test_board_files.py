"""Boards with height-map files as modules: resampling, holes, width, records, CLI, a walk."""

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.files import save_npz
from footfall.core.heightmap import FORMAT, VERSION, HeightMap
from footfall.core.limits import Limits, use_limits
from footfall.terrain import FileModule, make_board, make_module, parse_board_spec, register_kind
from footfall.terrain.geometry import MODULE_CELLS, MODULE_SIZE

BOARD_RES = 0.001  # [m/cell] of every board


def plane(x, y):
    """A tilted plane [m] at x, y [m] of the file's own corner frame."""
    return 0.02 + 0.05 * x - 0.03 * y


def bump(x, y):
    """A smooth Gaussian bump 3 cm high, 5 cm wide, centred at (0.2, 0.25) m."""
    return 0.03 * np.exp(-((x - 0.2) ** 2 + (y - 0.25) ** 2) / (2 * 0.05 ** 2))


def file_map(surface, resolution, nx, ny, holes=()):
    """``surface`` sampled at the cell centres of nx x ny cells; ``holes``: index slices -> NaN.

    The origin is far from the board's on purpose: a module is placed by its extent.
    """
    x = (np.arange(nx) + 0.5) * resolution
    y = (np.arange(ny) + 0.5) * resolution
    heights = surface(x[:, None], y[None, :])
    for hole in holes:
        heights[hole] = np.nan
    return HeightMap(heights, resolution, (12.3, -4.5), frame="scanner")


def file_module_of(board, k=1):
    """Heights of module ``k`` of a board and its record."""
    record = board.metadata["modules"][k]
    i0, i1 = (round(record[key] / BOARD_RES) for key in ("x_start", "x_end"))
    return board.heights[i0:i1], record


def expected(surface, src, n_x, record):
    """``surface`` at the board cells' centres, the file centred on the module, plus z_shift."""
    lx, ly = src.length
    x = (np.arange(n_x) + 0.5) * BOARD_RES - (n_x * BOARD_RES - lx) / 2
    y = (np.arange(MODULE_CELLS) + 0.5) * BOARD_RES - (MODULE_SIZE - ly) / 2
    return surface(x[:, None], y[None, :]) + record["z_shift"]


# ------------------------------------------------------------- resampling
def test_a_coarser_file_keeps_a_plane_exactly_and_a_bump_closely():
    src = file_map(plane, 0.002, 200, 305)  # 0.4 x 0.61 m at 2 mm
    board = make_board([("flat", 0.0), FileModule("plane.npz", src)], seed=1)
    heights, record = file_module_of(board)
    assert heights.shape == (400, 610) and np.isfinite(heights).all()
    # Bilinear reproduces a plane; within half a source cell of the file's edge it is held.
    inner = (slice(1, -1), slice(1, -1))
    np.testing.assert_allclose(heights[inner], expected(plane, src, 400, record)[inner],
                               atol=1e-12)
    assert np.nanmin(heights) == 0.0

    src = file_map(bump, 0.002, 200, 250)
    heights, record = file_module_of(make_board([FileModule("bump.npz", src)], seed=1))
    want = expected(bump, src, 400, record)
    data = ~np.isnan(heights)
    np.testing.assert_allclose(heights[data], want[data], atol=5e-5)  # 2 mm cells: < 0.05 mm


def test_a_finer_file_is_averaged_over_each_board_cell():
    src = file_map(plane, 0.0005, 600, 1220)  # 0.3 x 0.61 m at 0.5 mm: 2 x 2 cells a board cell
    heights, record = file_module_of(make_board([FileModule("fine.npz", src)], seed=1))
    assert heights.shape == (300, 610) and np.isfinite(heights).all()
    np.testing.assert_allclose(heights, expected(plane, src, 300, record), atol=1e-12)
    assert record["resolution"] == 0.0005 and record["width_fit"] == "exact"


@pytest.mark.parametrize("resolution, nx, ny, tolerance", [
    (0.0007, 500, 871, 1e-5),  # a file cell's height holds over the cell: 0.01 mm off a plane
    (0.0013, 300, 469, 1e-12),  # bilinear: exact on a plane
])
def test_a_file_at_an_odd_resolution_keeps_a_plane(resolution, nx, ny, tolerance):
    src = file_map(plane, resolution, nx, ny)  # 0.6097 m wide: 0.15 mm short on each side
    heights, record = file_module_of(make_board([FileModule("odd.npz", src)], seed=1))
    n_x = round(nx * resolution / BOARD_RES)
    assert heights.shape == (n_x, 610) and np.isfinite(heights).all()
    inner = (slice(2, -2), slice(2, -2))  # the edge cells are part-covered or held
    np.testing.assert_allclose(heights[inner], expected(plane, src, n_x, record)[inner],
                               atol=tolerance)
    np.testing.assert_allclose(heights, expected(plane, src, n_x, record), atol=5e-5)


def test_a_file_at_the_boards_resolution_is_copied():
    src = file_map(bump, 0.001, 250, 610)
    heights, record = file_module_of(make_board([FileModule("same.npz", src)], seed=1))
    np.testing.assert_array_equal(heights, src.heights + record["z_shift"])


def test_holes_stay_holes_and_no_new_no_data_appears():
    # 2 mm: a hole of 10 x 5 source cells is 20 x 10 board cells, exactly.
    src = file_map(bump, 0.002, 200, 305, holes=[(slice(50, 60), slice(100, 105))])
    heights, _ = file_module_of(make_board([FileModule("holes.npz", src)], seed=1))
    want = np.zeros((400, 610), dtype=bool)
    want[100:120, 200:210] = True
    np.testing.assert_array_equal(np.isnan(heights), want)

    # 0.5 mm: a board cell is NaN only if all four of its source cells are.
    src = file_map(bump, 0.0005, 600, 1220, holes=[(slice(100, 120), slice(200, 240)),
                                                     (slice(301, 302), slice(401, 402))])
    heights, _ = file_module_of(make_board([FileModule("holes.npz", src)], seed=1))
    want = np.zeros((300, 610), dtype=bool)
    want[50:60, 100:120] = True  # the single NaN source cell at (301, 401) leaves no hole
    np.testing.assert_array_equal(np.isnan(heights), want)


def test_a_narrow_file_is_padded_with_no_data_and_a_wide_one_cropped_centred_in_y():
    narrow = file_map(bump, 0.001, 300, 410)  # 0.41 m wide: 100 board cells of no data a side
    heights, record = file_module_of(make_board([FileModule("narrow.npz", narrow)], seed=1))
    assert record["width_fit"] == "padded" and record["width"] == pytest.approx(0.41)
    assert np.isnan(heights[:, :100]).all() and np.isnan(heights[:, -100:]).all()
    np.testing.assert_array_equal(heights[:, 100:-100], narrow.heights + record["z_shift"])

    wide = file_map(bump, 0.001, 300, 810)  # 0.81 m wide: 100 cells cropped a side
    heights, record = file_module_of(make_board([FileModule("wide.npz", wide)], seed=1))
    assert record["width_fit"] == "cropped" and np.isfinite(heights).all()
    np.testing.assert_array_equal(heights, wide.heights[:, 100:-100] + record["z_shift"])


def test_the_file_module_stands_on_z_0():
    src = HeightMap(np.full((100, 100), -2.5) + np.linspace(0, 0.01, 100)[:, None], 0.002)
    heights, record = file_module_of(make_board([FileModule("low.npz", src)], seed=1))
    assert np.nanmin(heights) == 0.0 and record["z_shift"] == pytest.approx(2.5)


# ---------------------------------------------------------------- records
def test_records_place_every_module_and_describe_the_file():
    src = file_map(bump, 0.002, 215, 305)  # 0.43 m long
    board = make_board([("flat", 0.0), FileModule("scan.npz", src), ("rocky", 0.5)], seed=1)
    records = board.metadata["modules"]
    assert [r["kind"] for r in records] == ["flat", "file", "rocky", "flat"]
    assert [r["x_start"] for r in records] == pytest.approx([0.0, 0.61, 1.04, 1.65])
    assert [r["x_end"] for r in records] == pytest.approx([0.61, 1.04, 1.65, 2.26])
    assert board.shape == (2260, 610) and board.length[0] == pytest.approx(records[-1]["x_end"])
    file_record = records[1]
    assert file_record["file"] == "scan.npz" and file_record["content_hash"] == src.content_hash()
    assert "seed" not in file_record and "difficulty" not in file_record
    assert file_record["resolution"] == 0.002 and file_record["width_fit"] == "exact"
    # The generated modules keep the seeds of the board's spawned sequence, by position.
    children = np.random.SeedSequence(1).spawn(4)
    for k in (0, 2, 3):
        assert records[k]["seed"] == int(children[k].generate_state(1)[0])
        alone = make_module(records[k]["kind"], records[k]["difficulty"], records[k]["seed"])
        i0 = round(records[k]["x_start"] / BOARD_RES)
        np.testing.assert_array_equal(board.heights[i0:i0 + 610], alone.heights)


def test_boards_without_files_are_unchanged():
    # Measured before file modules existed (`footfall terrain board rocky:0.7 steps:0.7
    # --seed 500`, the reproduction's test board).
    board = make_board([("rocky", 0.7), ("steps", 0.7)], seed=500)
    assert board.content_hash() == \
        "edd383787e12c65591a1ca990dfda5078596ae60c6cf0bc9654cec324dd91e92"
    assert [(r["seed"], r["x_start"], r["x_end"]) for r in board.metadata["modules"]] == [
        (2142847655, 0.0, 0.61), (3468886739, 0.61, 1.22), (2616834282, 1.22, 1.83),
        (512696676, 1.83, 2.44)]


def test_board_line_starts_in_the_first_module_and_ends_in_the_last():
    from footfall.core.robot import LITTLEDOG
    from footfall.sim.episode import WalkConfig, board_line

    src = file_map(bump, 0.002, 300, 250)  # 0.6 m long
    board = make_board([FileModule("scan.npz", src), FileModule("scan.npz", src)], seed=2)
    first, last = board.metadata["modules"][0], board.metadata["modules"][-1]
    start, goal = board_line(board, LITTLEDOG, WalkConfig())
    assert first["x_start"] <= start[0] < first["x_end"]
    assert last["x_start"] <= goal < last["x_end"]
    assert [r["kind"] for r in board.metadata["modules"]] == ["flat", "file", "file", "flat"]


def test_a_store_label_names_the_file():
    from footfall.data.inventory import terrain_label

    board = make_board([FileModule("scan.npz", file_map(bump, 0.002, 100, 100))], seed=2)
    assert terrain_label({"metadata": board.metadata}) == "flat, scan.npz, flat"


# ----------------------------------------------------------------- specs
def test_a_spec_naming_a_npz_is_a_module_file(tmp_path):
    path = tmp_path / "scan.npz"
    src = file_map(bump, 0.002, 100, 100)
    src.save(path)
    module = parse_board_spec(str(path))
    assert isinstance(module, FileModule) and module.name == "scan.npz"
    assert module.hmap.content_hash() == src.content_hash()
    assert parse_board_spec("rocky:0.3") == ("rocky", 0.3)


def test_a_file_module_holds_a_height_map():
    with pytest.raises(FootfallError, match="scan.npz: a file module holds a HeightMap, got "
                                            "ndarray"):
        FileModule("scan.npz", np.zeros((10, 10)))
    with pytest.raises(FootfallError, match="needs its file's name"):
        FileModule("", file_map(bump, 0.002, 10, 10))


def test_file_is_not_a_kind_name():
    with pytest.raises(ValueError, match="'file' names the board modules read from files"):
        register_kind("file", lambda d, rng: np.zeros((610, 610)))


@pytest.mark.parametrize("name, match", [
    ("none.npz", "no such file: {tmp}/none.npz"),
    ("raw.npy", "{tmp}/raw.npy: a board module file must be a footfall height map (.npz); "
                "import a scan first"),
    ("junk.npz", "{tmp}/junk.npz: not a readable footfall .npz file (not a zip archive)"),
    ("plain.npz", "{tmp}/plain.npz: not a footfall file (no format/version/meta header)"),
    ("nan.npz", "{tmp}/nan.npz: height map holds no data (all cells are NaN)"),
    ("off.npz", "off.npz: no height data within the board's 0.61 m width (centred in y)"),
    ("tiny.npz", "tiny.npz: the map is 0.02 mm long, shorter than one board cell (1 mm)"),
])
def test_bad_module_files_are_one_line_naming_the_file(tmp_path, capsys, name, match):
    _bad_files(tmp_path)
    code, out, err = run(capsys, "terrain", "board", "flat", tmp_path / name, "--seed", "1",
                         "-o", tmp_path / "b.npz")
    assert_user_error(code, err, match.format(tmp=tmp_path))
    assert out == "" and not (tmp_path / "b.npz").exists()


def _bad_files(folder):
    """Module files of every kind of bad: not a map, no data, data outside the board, tiny."""
    np.save(folder / "raw.npy", np.zeros((20, 20)))
    (folder / "junk.npz").write_bytes(b"not a zip archive at all")
    np.savez(folder / "plain.npz", heights=np.zeros((20, 20)))
    save_npz(folder / "nan.npz", FORMAT, VERSION, {"heights": np.full((20, 20), np.nan)},
             {"resolution": 0.002, "origin": [0.0, 0.0], "frame": "world"})
    off = np.full((50, 2000), np.nan)
    off[:, :5] = 0.01  # data only at one side of a 2 m wide map: cropped away
    HeightMap(off, 0.001).save(folder / "off.npz")
    HeightMap(np.zeros((2, 2)), 1e-5).save(folder / "tiny.npz")


def test_module_files_and_boards_above_the_limits_are_one_line(tmp_path, capsys):
    path = tmp_path / "scan.npz"
    file_map(bump, 0.002, 200, 250).save(path)  # 50 000 cells, a 400 x 610 module
    code, _, err = run(capsys, "--limit", "max_map_cells=40000", "terrain", "board", path,
                       "--seed", "1", "-o", tmp_path / "b.npz")
    assert_user_error(code, err, f"{path}: the height map would have 5e+04 cells, above the "
                                 "limit of 40000")
    code, _, err = run(capsys, "--limit", "max_map_cells=900000", "terrain", "board", path,
                       "--seed", "1", "-o", tmp_path / "b.npz")  # flat + 0.4 m + flat
    assert_user_error(code, err, "scan.npz: the board would have 9.88e+05 cells, above the "
                                 "limit of 900000")
    HeightMap(np.zeros((100, 2)), 1.0).save(tmp_path / "long.npz")  # 100 m long
    code, _, err = run(capsys, "terrain", "board", tmp_path / "long.npz", "--seed", "1",
                       "-o", tmp_path / "b.npz")
    assert_user_error(code, err, "long.npz: the module resampled to the board's 1 mm grid "
                                 "(100 m long) would have 6.1e+07 cells, above the limit")
    assert not (tmp_path / "b.npz").exists()


def test_the_library_refuses_a_board_above_the_limit_before_making_it():
    src = file_map(bump, 0.002, 200, 250)
    with use_limits(Limits(max_map_cells=900_000)), \
            pytest.raises(FootfallError, match="scan.npz: the board would have"):
        make_board([FileModule("scan.npz", src)], seed=1)


# ------------------------------------------------------------------- CLI
def test_cli_board_with_a_module_file(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    src = file_map(lambda x, y: bump(x, y) + 0.05, 0.002, 200, 400)  # 0.4 x 0.8 m: cropped
    src.save(tmp_path / "my.npz")
    code, out, err = run(capsys, "terrain", "board", "flat", "my.npz", "rocky:0.5", "--seed", "1",
                         "-o", "b.npz")
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert lines[0].startswith("wrote b.npz: 2230 x 610 cells at 1 mm")
    assert lines[1] == ("  module 1: my.npz (2 mm, 0.800 m wide) at x 0.610 .. 1.010 m, "
                        "cropped to the board's width (centred in y), heights shifted by "
                        "-50.0 mm")
    board = HeightMap.load(tmp_path / "b.npz")
    assert [m["kind"] for m in board.metadata["modules"]] == ["flat", "file", "rocky", "flat"]
    assert board.metadata["modules"][1]["file"] == "my.npz"


# ------------------------------------------------------------------ walk
def test_a_short_walk_over_a_file_module_with_holes():
    from footfall.features.reward import default_reward
    from footfall.sim.episode import WalkConfig, walk

    # The robot starts on the file module (0.6 m long, wavy, three holes ahead of its feet).
    holes = [(slice(225, 240), slice(100, 125)), (slice(230, 245), slice(180, 205)),
             (slice(200, 210), slice(140, 160))]
    src = file_map(lambda x, y: 0.005 * np.sin(20 * x) * np.cos(15 * y), 0.002, 300, 305,
                   holes=holes)
    board = make_board([FileModule("holes.npz", src), ("flat", 0.0)], seed=3, flat_ends=False)
    assert np.isnan(board.heights).sum() == 4 * (15 * 25 + 15 * 25 + 10 * 20)
    reward = default_reward()
    rec = walk(board, lambda leg: reward, 5, WalkConfig(start_setback=0.2, max_steps=4))
    assert 1 <= len(rec.steps) <= 4 and isinstance(rec.result["reason"], str)
    touchdowns = np.array([step.touchdown[:2] for step in rec.steps])
    assert (touchdowns[:, 0] < board.metadata["modules"][0]["x_end"]).any()  # on the file
    assert not np.isnan(board.height_at(touchdowns)).any()  # never in a hole
