"""The approximate body path planner: cell rewards, Dijkstra path, BodyPath geometry."""

import math

import numpy as np
import pytest

from footfall.control.body_path import (
    BodyPath,
    BodyPathConfig,
    cell_rewards,
    evaluate_cells,
    nominal_knees,
    plan_body_path,
    terrain_grids,
)
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES, LITTLEDOG
from footfall.core.state import RobotState
from footfall.features.candidates import lattice
from footfall.features.reward import default_reward
from footfall.features.scoring import score_footholds
from footfall.terrain.modules import make_module

REWARD = default_reward()


def reward_for(leg):
    return REWARD


def flat_map(length=1.2, width=0.6, res=0.001):
    """A flat map, x in [0, length), y centred on 0, at 1 mm."""
    nx, ny = int(round(length / res)), int(round(width / res))
    return HeightMap(np.zeros((nx, ny)), res, (res / 2, -width / 2 + res / 2))


def with_patch(hmap, x_range, y_range, heights):
    """The map with heights(X, Y) (or NaN) in a rectangle."""
    X, Y = np.meshgrid(hmap.x, hmap.y, indexing="ij")
    inside = (X >= x_range[0]) & (X <= x_range[1]) & (Y >= y_range[0]) & (Y <= y_range[1])
    h = hmap.heights.copy()
    h[inside] = heights(X[inside], Y[inside]) if callable(heights) else heights
    return HeightMap(h, hmap.resolution, hmap.origin)


@pytest.fixture(scope="module")
def flat():
    hmap = flat_map()
    return hmap, terrain_grids(hmap, reward_for)


@pytest.fixture(scope="module")
def rocky():
    hmap = make_module("rocky", 0.6, seed=3)
    return hmap, terrain_grids(hmap, reward_for)


# ------------------------------------------------------------- grids, cells
def test_terrain_grids_share_one_grid_per_reward_and_mirroring(flat):
    _, grids = flat
    assert grids["LF"] is grids["LH"] and grids["RF"] is grids["RH"]
    assert grids["LF"] is not grids["RF"]


def highest(hmap, cx, cy, hx, hy, grow):
    """Highest map cell [m] within hx + grow, hy + grow [m] of (cx, cy) along x and y."""
    sel_x, sel_y = abs(hmap.x - cx) <= hx + grow, abs(hmap.y - cy) <= hy + grow
    return hmap.heights[np.ix_(sel_x, sel_y)].max()


def test_cell_rewards_equal_a_direct_per_cell_computation(rocky):
    hmap, grids = rocky
    config = BodyPathConfig()
    cells = evaluate_cells(hmap, reward_for, LITTLEDOG, config, grids=grids)
    x, y, reward = cell_rewards(hmap, reward_for, LITTLEDOG, config, grids=grids)
    np.testing.assert_array_equal(reward, cells.reward)
    np.testing.assert_array_equal(x, cells.x)
    assert np.allclose(x / config.cell, np.round(x / config.cell))  # cells on multiples of 1 cm
    for cx, cy in ((0.25, 0.0), (0.31, -0.07), (0.36, 0.09)):  # three cells away from the border
        i, j = int(np.argmin(abs(x - cx))), int(np.argmin(abs(y - cy)))
        body = np.array([x[i], y[j]])
        total = 0.0
        for leg in LEG_NAMES:  # the slow way: every lattice point scored on its own
            foot = body + np.array(LITTLEDOG.nominal_foot(leg)[:2])
            snapped = np.asarray(hmap.origin) + np.round(
                (foot - np.asarray(hmap.origin)) / config.spacing) * config.spacing
            pts = lattice(hmap, (snapped[0] - 0.03, snapped[0] + 0.03),
                          (snapped[1] - 0.03, snapped[1] + 0.03), config.spacing)
            pts = pts[np.linalg.norm(pts - snapped, axis=1) <= config.search_radius + 1e-9]
            state = RobotState(np.zeros((4, 3)), np.array([*body, 0.14]), np.zeros(3), leg)
            values = [score_footholds(hmap, state, np.array([[px, py, 0.0]]), REWARD)[0]
                      for px, py in pts]
            total += sum(sorted(values, reverse=True)[:config.best_k])
        assert cells.footholds[i, j] == pytest.approx(total, rel=1e-5, abs=1e-4)

        # Clearances: conservative by at most a cell.
        feet = body + np.array([LITTLEDOG.nominal_foot(leg)[:2] for leg in LEG_NAMES])
        body_z = hmap.height_at(feet).mean() + LITTLEDOG.nominal_height
        lx, ly = LITTLEDOG.trunk_size[0] / 2, LITTLEDOG.trunk_size[1] / 2
        bottom = body_z - LITTLEDOG.trunk_size[2] / 2
        clear = cells.body_clearance[i, j]
        assert bottom - highest(hmap, *body, lx, ly, config.cell * 1.5) <= clear \
            <= bottom - highest(hmap, *body, lx, ly, 0.0) + 1e-12
        for k, knee in enumerate(nominal_knees()):
            z = body_z + knee[2] - LITTLEDOG.lower_leg_radius
            kx, ky = body + knee[:2]
            r = config.knee_radius
            inner = r / math.sqrt(2)  # a square within the disc
            assert z - highest(hmap, kx, ky, r, r, config.cell * 1.5) \
                <= cells.knee_clearance[i, j, k] <= z - highest(hmap, kx, ky, inner, inner, 0.0) + 1e-12
        short = (config.body_weight * max(config.body_margin - cells.body_clearance[i, j], 0)
                 + config.knee_weight * np.maximum(config.knee_margin - cells.knee_clearance[i, j],
                                                   0).sum())
        assert reward[i, j] == pytest.approx(cells.footholds[i, j] - cells.unit * short)


def test_a_high_ridge_under_the_trunk_is_penalised(flat):
    hmap, _ = flat
    ridge = with_patch(hmap, (0.55, 0.65), (-0.02, 0.02), 0.12)  # 12 cm: the trunk would hit it
    cells = evaluate_cells(ridge, reward_for)
    i = int(np.argmin(abs(cells.x - 0.6)))
    j = int(np.argmin(abs(cells.y)))
    expected = ridge.height_at(np.array([[0.6 + 0.101, 0.08]]))[0]  # feet on the floor: 0
    assert expected == 0.0
    assert cells.body_clearance[i, j] == pytest.approx(
        LITTLEDOG.nominal_height - LITTLEDOG.trunk_size[2] / 2 - 0.12)
    config = BodyPathConfig()
    shortfall = config.body_margin - cells.body_clearance[i, j]
    assert cells.reward[i, j] - cells.footholds[i, j] == pytest.approx(
        -cells.unit * config.body_weight * shortfall)
    assert cells.body_clearance[i, 0] > 0.1  # far to the side nothing is under the trunk


def test_cells_without_a_valid_foothold_are_impassable(flat):
    hmap, _ = flat
    holed = with_patch(hmap, (0.5, 0.7), (-0.3, 0.3), np.nan)  # a trench across the board
    _, _, reward = cell_rewards(holed, reward_for)
    x = np.arange(reward.shape[0]) * 0.01
    # A leg's whole search disc (2.5 cm) in the trench: no foothold for it.
    hind_in_trench = (x + LITTLEDOG.nominal_foot("LH")[0] > 0.53) & \
                     (x + LITTLEDOG.nominal_foot("LH")[0] < 0.67)
    assert np.all(np.isinf(reward[hind_in_trench]))
    with pytest.raises(FootfallError, match="no passable body path"):
        plan_body_path(holed, reward_for, (0.25, 0.0), (1.0, 0.0))


# --------------------------------------------------------------- the path
def test_path_on_flat_ground_is_straight(flat):
    hmap, grids = flat
    for goal in (1.0, (1.0, 0.0)):  # a goal line and a goal point
        path = plan_body_path(hmap, reward_for, (0.25, 0.0), goal, grids=grids)
        assert np.abs(path.waypoints[:, 1]).max() <= 0.005  # within half a cell of y = 0
        assert path.waypoints[0] == pytest.approx([0.25, 0.0])
        assert path.waypoints[-1] == pytest.approx([1.0, 0.0])
        assert path.length == pytest.approx(0.75, abs=0.01)


@pytest.mark.parametrize("bad", ["rough", "hole"])
def test_path_goes_around_bad_terrain(flat, bad):
    hmap, _ = flat
    rng = np.random.default_rng(0)
    region = ((0.5, 0.75), (-0.3, 0.04))  # the right side of the board's middle
    heights = (lambda X, Y: rng.uniform(0.0, 0.03, X.shape)) if bad == "rough" else np.nan
    board = with_patch(hmap, *region, heights)
    path = plan_body_path(board, reward_for, (0.25, 0.0), 1.0)
    s = np.linspace(0.0, path.length, 400)
    p = path.point_at(s)
    over = (p[:, 0] > region[0][0]) & (p[:, 0] < region[0][1])
    assert over.any() and p[over, 1].min() > 0.10  # right feet (0.08 m out) stay off it
    assert p[-1] == pytest.approx([1.0, p[-1, 1]])


def test_path_does_not_depend_on_the_reward_scale(flat):
    hmap, _ = flat
    board = with_patch(hmap, (0.5, 0.75), (-0.3, 0.04),
                       lambda X, Y: 0.015 * (1 + np.sin(300 * X) * np.cos(260 * Y)))
    scaled = REWARD.scaled(7.0)
    a = plan_body_path(board, reward_for, (0.25, 0.0), 1.0)
    b = plan_body_path(board, lambda leg: scaled, (0.25, 0.0), 1.0)
    assert a.waypoints.shape == b.waypoints.shape
    assert np.abs(a.waypoints - b.waypoints).max() < 0.01


def test_path_planning_is_deterministic(rocky):
    hmap, grids = rocky
    a = plan_body_path(hmap, reward_for, (0.2, 0.0), 0.45, grids=grids)
    b = plan_body_path(hmap, reward_for, (0.2, 0.0), 0.45)
    np.testing.assert_array_equal(a.waypoints, b.waypoints)


def test_bad_starts_goals_and_configs_raise(flat):
    hmap, grids = flat
    with pytest.raises(FootfallError, match="start .* off the map"):
        plan_body_path(hmap, reward_for, (3.0, 0.0), 1.0, grids=grids)
    with pytest.raises(FootfallError, match="impassable"):
        plan_body_path(hmap, reward_for, (0.25, 0.29), 1.0, grids=grids)  # feet off the map
    with pytest.raises(FootfallError, match="goal line"):
        plan_body_path(hmap, reward_for, (0.25, 0.0), 5.0, grids=grids)
    with pytest.raises(FootfallError, match="goal must be"):
        plan_body_path(hmap, reward_for, (0.25, 0.0), (1.0, np.nan), grids=grids)
    with pytest.raises(FootfallError, match="start must be"):
        plan_body_path(hmap, reward_for, (0.25,), 1.0, grids=grids)
    with pytest.raises(FootfallError, match="FootholdScorer"):
        terrain_grids(hmap, lambda leg: None)
    for bad in ({"cell": 0.0}, {"search_radius": -0.01}, {"best_k": 0}, {"best_k": 2.5},
                {"cost_weight": -1.0}, {"smoothing": np.nan}):
        with pytest.raises(FootfallError, match="body path config"):
            BodyPathConfig(**bad)


# -------------------------------------------------------------- BodyPath
def test_body_path_geometry():
    path = BodyPath(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.0, 1.0]]))
    assert path.waypoints.shape == (3, 2)  # the repeated point is dropped
    assert path.length == pytest.approx(2.0)
    np.testing.assert_allclose(path.point_at([0.5, 1.5, -1.0, 9.0]),
                               [[0.5, 0.0], [1.0, 0.5], [0.0, 0.0], [1.0, 1.0]])
    np.testing.assert_allclose(path.heading_at([0.5, 1.5, 2.0]), [0.0, math.pi / 2, math.pi / 2])
    np.testing.assert_allclose(path.closest(np.array([[0.3, 0.2], [1.2, 0.6], [-1.0, -1.0],
                                                      [3.0, 3.0]])), [0.3, 1.6, 0.0, 2.0])
    assert path.closest([0.3, -0.1]).shape == ()
    s = np.linspace(0, 2, 7)
    np.testing.assert_allclose(path.closest(path.point_at(s)), s, atol=1e-12)  # a round trip

    line = BodyPath.straight((0.2, 0.1), (0.5, 0.5))
    assert line.length == pytest.approx(0.5)
    assert float(line.heading_at(0.3)) == pytest.approx(math.atan2(0.4, 0.3))
    np.testing.assert_allclose(line.point_at(0.25), [0.35, 0.3])


@pytest.mark.parametrize("waypoints, match", [
    (np.zeros((1, 2)), "shape"), (np.zeros((3, 3)), "shape"),
    (np.array([[0.0, 0.0], [np.nan, 1.0]]), "finite"), (np.zeros((3, 2)), "distinct")])
def test_bad_body_paths_raise(waypoints, match):
    with pytest.raises(FootfallError, match=match):
        BodyPath(waypoints)
    with pytest.raises(FootfallError, match="shape"):
        BodyPath.straight((0, 0), (1, 0)).closest([1.0, 2.0, 3.0])
