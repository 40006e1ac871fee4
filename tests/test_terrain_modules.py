"""Tests of the LittleDog-like terrain modules, boards and module specs.

Modules are 61 x 61 cm at 1 mm; the rocky generator is the slowest, so
generated modules are cached and shared between tests.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.terrain import (
    KINDS,
    MODULE_RESOLUTION,
    MODULE_SIZE,
    make_board,
    make_module,
    parse_module_spec,
)

ALL_KINDS = sorted(KINDS)
SHAPE_KINDS = ("ridges", "pitted", "pavers")  # added training kinds whose documented top is 5 cm at d = 1
HOLED_KINDS = ("scan", "rockyscan")  # kinds with no-data cells (footfall.terrain.occlusion)
OBSTACLE_KINDS = [k for k in ALL_KINDS if k != "flat"]
MAX_HEIGHT = 0.12  # [m] nothing a LittleDog (~18 cm legs) could not cross
EDGE_TOLERANCE = 1e-9  # [m] module ends "at" the ground plane


@functools.lru_cache(maxsize=None)
def module(kind: str, difficulty: float, seed: int) -> HeightMap:
    """Cached :func:`make_module` (HeightMaps are immutable)."""
    return make_module(kind, difficulty, seed)


# ------------------------------------------------------------------ registry
def test_registry_holds_the_paper_kinds_the_added_training_ones_and_the_held_out_ones():
    from footfall.terrain.kinds import ADDED_KINDS, HELD_OUT_KINDS, PAPER_KINDS, TRAINING_KINDS

    assert PAPER_KINDS == ("flat", "steps", "barrier", "slope", "logs", "rocky")
    assert ADDED_KINDS == ("ridges", "pitted", "rockyscan", "pavers")
    assert TRAINING_KINDS == ("steps", "barrier", "slope", "logs", "rocky", "ridges", "pitted",
                              "rockyscan", "pavers")
    assert HELD_OUT_KINDS == ("stones", "washboard", "scree", "logbarrier", "rolling", "scan")
    assert set(KINDS) == set(PAPER_KINDS + ADDED_KINDS + HELD_OUT_KINDS)
    assert all(callable(g) for _, g in KINDS.items())


@pytest.mark.parametrize("kind", ALL_KINDS)
def test_generators_have_the_documented_signature(kind):
    heights = KINDS.get(kind)(0.5, np.random.default_rng(0))
    assert isinstance(heights, np.ndarray)
    assert heights.shape == (610, 610)
    assert heights.dtype == np.float64


# --------------------------------------------------------------- determinism
@pytest.mark.parametrize("kind", ALL_KINDS)
def test_same_seed_gives_bit_identical_module(kind):
    a = make_module(kind, 0.7, 123)
    b = make_module(kind, 0.7, 123)
    assert np.array_equal(a.heights, b.heights, equal_nan=True)  # a scan's no-data cells too
    assert a.content_hash() == b.content_hash()
    assert a.metadata == b.metadata


def test_generation_does_not_use_or_disturb_global_random_state():
    np.random.seed(5)
    expected = np.random.random()
    np.random.seed(5)
    first = make_module("rocky", 0.5, 9)
    assert np.random.random() == expected  # global stream untouched
    np.random.seed(77)
    assert np.array_equal(make_module("rocky", 0.5, 9).heights, first.heights)


@pytest.mark.parametrize("kind", OBSTACLE_KINDS)
def test_different_seeds_give_different_modules(kind):
    assert not np.array_equal(module(kind, 0.6, 1).heights, module(kind, 0.6, 2).heights)


def test_flat_module_is_flat_whatever_the_seed():
    for seed in (1, 2):
        assert np.array_equal(module("flat", 0.6, seed).heights, np.zeros((610, 610)))


# ------------------------------------------------------------------ geometry
@pytest.mark.parametrize("kind", ALL_KINDS)
def test_module_geometry_and_metadata(kind):
    m = module(kind, 0.6, 1)
    assert m.shape == (610, 610)
    assert m.resolution == MODULE_RESOLUTION == 0.001
    assert MODULE_SIZE == 0.61
    assert m.x[0] == pytest.approx(0.0005) and m.x[-1] == pytest.approx(0.6095)
    assert m.y[0] == pytest.approx(-0.3045) and m.y[-1] == pytest.approx(0.3045)
    assert m.bounds == pytest.approx((0.0, 0.61, -0.305, 0.305))
    assert m.metadata == {"generator": "footfall.terrain",
                          "modules": [{"kind": kind, "difficulty": 0.6, "seed": 1,
                                       "x_start": 0.0, "x_end": pytest.approx(0.61)}]}


@pytest.mark.parametrize("kind", ALL_KINDS)
@pytest.mark.parametrize("difficulty", [0.0, 0.6, 1.0])
def test_heights_are_finite_non_negative_and_crossable(kind, difficulty):
    h = module(kind, difficulty, 1).heights
    assert kind in HOLED_KINDS or not np.isnan(h).any()  # only scanned kinds have no-data cells
    assert not np.isinf(h).any()
    assert np.nanmin(h) >= 0.0
    assert np.nanmax(h) <= MAX_HEIGHT
    # Both ends of the module meet the ground plane, so modules join cleanly.
    assert np.abs(h[0]).max() < EDGE_TOLERANCE
    assert np.abs(h[-1]).max() < EDGE_TOLERANCE


@pytest.mark.parametrize("kind", OBSTACLE_KINDS)
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_max_obstacle_height_grows_with_difficulty(kind, seed):
    tops = [np.nanmax(module(kind, d, seed).heights) for d in (0.2, 0.6, 1.0)]
    assert tops[0] < tops[1] < tops[2]
    assert tops[0] < 0.05  # easy modules have small obstacles ...
    # ... hard ones real obstacles of several cm (the added training kinds' character is their
    # shape -- flanks, pits -- and their documented top is 5 cm at d = 1)
    assert tops[2] > (0.035 if kind in SHAPE_KINDS else 0.06)


def test_steps_climb_to_a_platform_and_back_down():
    h = module("steps", 1.0, 2).heights
    profile = h[:, 305]  # along the centre line
    levels = np.unique(profile)
    assert 3 <= len(levels) <= 7  # ground, 1-3 risers up, 1-3 down, one platform
    peak = profile.max()
    assert 0.08 <= peak <= 0.10
    top = np.flatnonzero(profile == peak)
    assert np.all(np.diff(profile[:top[0] + 1]) >= 0)  # monotone up
    assert np.all(np.diff(profile[top[-1]:]) <= 0)  # monotone down


def test_slope_ramps_are_within_the_documented_angles():
    m = module("slope", 1.0, 1)
    grad_x = np.diff(m.heights[:, 305]) / m.resolution  # along the centre line
    assert grad_x.max() == pytest.approx(np.tan(np.radians(25.0)), abs=0.1)
    assert grad_x.max() <= np.tan(np.radians(25.0)) + 1e-9
    assert grad_x.min() >= -np.tan(np.radians(25.0)) - 1e-9


def test_logs_are_half_cylinders():
    m = module("logs", 0.6, 1)
    profile = m.heights[:, 305]
    top = profile.max()
    width = np.count_nonzero(profile > 0) * m.resolution  # widest log across y = 0 ...
    # ... a half-cylinder is twice as wide as tall (several logs can only add width).
    assert width >= 2 * top * 0.9


def test_rocky_module_is_rough_with_cracks_and_slanted_faces():
    def steep_share(heights: np.ndarray) -> float:
        """Share of the bed steeper than 20 degrees on a 5 mm scale."""
        coarse = heights[::5, ::5]
        slope = np.hypot(*np.gradient(coarse, 5 * MODULE_RESOLUTION))
        return float(np.mean(slope > np.tan(np.radians(20.0))))

    h = module("rocky", 1.0, 1).heights
    bed = h[20:-20]  # away from the bare board at the ends
    easy = module("rocky", 0.2, 1).heights[20:-20]
    assert steep_share(bed) > 0.5  # slanted faces and rounded edges
    assert steep_share(bed) > steep_share(easy) + 0.1
    # Narrow cracks: cells at least 1 cm below the cells 3 mm to either side.
    x_crack = (bed[3:-3] < bed[:-6] - 0.01) & (bed[3:-3] < bed[6:] - 0.01)
    assert x_crack.sum() > 500
    # Harder rocky terrain is rougher.
    assert easy.std() < bed.std()


# --------------------------------------------------------------- validation
def test_unknown_kind_lists_the_known_kinds():
    with pytest.raises(FootfallError, match=r"unknown terrain module kind 'lava'.*flat.*rocky"):
        make_module("lava", 0.5, 0)


@pytest.mark.parametrize("difficulty", [-0.1, 1.01, math.nan, math.inf, "hard", None])
def test_bad_difficulty_is_rejected(difficulty):
    with pytest.raises(FootfallError, match="difficulty"):
        make_module("rocky", difficulty, 0)


@pytest.mark.parametrize("seed", [-1, 1.5, "7", True])
def test_bad_seed_is_rejected(seed):
    with pytest.raises(FootfallError, match="seed"):
        make_module("flat", 0.5, seed)


def test_difficulty_bounds_are_inclusive():
    assert module("slope", 0.0, 1).metadata["modules"][0]["difficulty"] == 0.0
    assert module("slope", 1.0, 1).metadata["modules"][0]["difficulty"] == 1.0


# -------------------------------------------------------------------- boards
def test_board_adds_flat_ends_around_non_flat_specs():
    board = make_board([("rocky", 0.5), ("rocky", 0.8)], seed=3)
    records = board.metadata["modules"]
    assert [r["kind"] for r in records] == ["flat", "rocky", "rocky", "flat"]
    assert [r["difficulty"] for r in records][1:3] == [0.5, 0.8]
    assert board.shape == (4 * 610, 610)
    assert board.length[0] == pytest.approx(4 * MODULE_SIZE)
    assert board.origin == pytest.approx((0.0005, -0.3045))
    assert [r["x_start"] for r in records] == pytest.approx([0.0, 0.61, 1.22, 1.83])
    assert [r["x_end"] for r in records] == pytest.approx([0.61, 1.22, 1.83, 2.44])
    assert board.metadata["generator"] == "footfall.terrain"
    assert np.all(board.heights[:610] == 0) and np.all(board.heights[-610:] == 0)


def test_board_module_seeds_reproduce_each_module():
    board = make_board([("logs", 0.4), ("rocky", 0.8)], seed=11)
    for k, record in enumerate(board.metadata["modules"]):
        alone = make_module(record["kind"], record["difficulty"], record["seed"])
        assert np.array_equal(board.heights[k * 610:(k + 1) * 610], alone.heights)
    seeds = [r["seed"] for r in board.metadata["modules"]]
    assert len(set(seeds)) == len(seeds)


def test_board_keeps_flat_ends_the_user_gave():
    board = make_board([("flat", 0.0), ("steps", 0.5), ("flat", 0.0)], seed=1)
    assert [r["kind"] for r in board.metadata["modules"]] == ["flat", "steps", "flat"]
    one_end = make_board([("flat", 0.0), ("steps", 0.5)], seed=1)
    assert [r["kind"] for r in one_end.metadata["modules"]] == ["flat", "steps", "flat"]


def test_board_without_flat_ends():
    board = make_board([("steps", 0.5), ("barrier", 0.5)], seed=1, flat_ends=False)
    assert [r["kind"] for r in board.metadata["modules"]] == ["steps", "barrier"]
    assert board.shape == (2 * 610, 610)


def test_board_is_deterministic_for_a_seed():
    specs = [("steps", 0.3), ("barrier", 0.9)]
    a, b = make_board(specs, seed=5), make_board(specs, seed=5)
    assert a.content_hash() == b.content_hash()
    assert a.metadata == b.metadata
    assert make_board(specs, seed=6).content_hash() != a.content_hash()


@pytest.mark.parametrize("specs, match", [
    ([], "at least one module"),
    ([("lava", 0.5)], "unknown terrain module kind"),
    ([("steps", 1.5)], "difficulty"),
    (["steps:0.5"], "pairs"),
])
def test_bad_board_specs_are_rejected(specs, match):
    with pytest.raises(FootfallError, match=match):
        make_board(specs, seed=0)


# --------------------------------------------------------------------- specs
@pytest.mark.parametrize("spec, expected", [
    ("rocky:0.5", ("rocky", 0.5)),
    ("rocky", ("rocky", 0.5)),
    ("steps:1", ("steps", 1.0)),
    ("flat:0", ("flat", 0.0)),
    (" Logs : 0.25 ", ("logs", 0.25)),
])
def test_parse_module_spec(spec, expected):
    kind, difficulty = parse_module_spec(spec)
    assert (kind, difficulty) == expected
    assert isinstance(difficulty, float)


@pytest.mark.parametrize("spec, match", [
    ("", "bad module spec"),
    (":0.5", "bad module spec"),
    ("rocky:", "not a number"),
    ("rocky:hard", "not a number"),
    ("rocky:0.5:1", "not a number"),
    ("rocky:1.5", "difficulty must be in"),
    ("rocky:nan", "difficulty must be in"),
    ("lava:0.3", "unknown terrain module kind 'lava'"),
])
def test_parse_module_spec_rejects_bad_specs(spec, match):
    with pytest.raises(FootfallError, match=match):
        parse_module_spec(spec)


# -------------------------------------------------------------------- relief
def test_save_relief_writes_a_png_atomically(tmp_path):
    from footfall.plots.relief import save_relief

    heights = module("logs", 0.6, 1).heights[::10, ::10].copy()
    heights[10:15, 10:15] = np.nan  # no-data cells are drawn, not an error
    hmap = HeightMap(heights, 0.01, (0.005, -0.3))
    out = tmp_path / "relief.png"
    save_relief(hmap, out, title="logs")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["relief.png"]  # no temp file left
    with pytest.raises(FootfallError, match="does not exist"):
        save_relief(hmap, tmp_path / "missing" / "relief.png")


# ----------------------------------------------------------- a kind of one's own
def _craters(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A toy kind: round pits up to 1 + 3 d cm deep on a 2 cm plinth, flat edges."""
    x = (np.arange(610) + 0.5) / 1000.0
    xx, yy = np.meshgrid(x, x, indexing="ij")
    z = np.where((xx > 0.1) & (xx < 0.51), 0.02, 0.0)
    for cx, cy in rng.uniform(0.15, 0.46, size=(6, 2)):
        pit = np.hypot(xx - cx, yy - cy) < 0.03
        z[pit] = 0.02 - (0.01 + 0.03 * difficulty)
    return np.clip(z, 0.0, None)


def test_a_registered_kind_makes_modules_boards_and_specs_without_touching_the_others(tmp_path):
    from footfall.cli import main
    from footfall.terrain import register_kind, unregister_kind

    register_kind("craters", _craters)
    try:
        a, b = make_module("craters", 0.6, 5), make_module("craters", 0.6, 5)
        assert a.content_hash() == b.content_hash() and a.metadata["modules"][0]["kind"] == \
            "craters"
        assert a.heights.shape == (610, 610) and np.isfinite(a.heights).all()
        assert np.allclose(a.heights[[0, -1], :], 0.0, atol=EDGE_TOLERANCE)
        assert parse_module_spec("craters:0.3") == ("craters", 0.3)
        board = make_board([("craters", 0.3), ("rocky", 0.5)], seed=2)
        assert [m["kind"] for m in board.metadata["modules"]] == ["flat", "craters", "rocky",
                                                                   "flat"]
        assert main(["terrain", "make", "craters", "--seed", "1", "-o",
                     str(tmp_path / "c.npz")]) == 0
        with pytest.raises(ValueError, match="already registered"):
            register_kind("craters", lambda d, rng: np.zeros((610, 610)))
    finally:
        unregister_kind("craters")
    with pytest.raises(FootfallError, match="unknown terrain module kind 'craters'"):
        make_module("craters", 0.5, 1)
    unregister_kind("rocky")  # the paper's kinds cannot be removed
    assert "rocky" in KINDS
