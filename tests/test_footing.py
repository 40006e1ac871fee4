"""The friction check: a ball foot's contact tilt on scripted maps, and the planner's use of it."""

import math

import numpy as np
import pytest

from footfall.control.body_path import BodyPath, terrain_grids
from footfall.control.footstep import FootstepConfig, FootstepPlanner
from footfall.control.stance_checks import stride_on
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import inverse_kinematics, world_to_body
from footfall.core.robot import LITTLEDOG
from footfall.core.state import nominal_state
from footfall.features.candidates import joint_margins
from footfall.features.footing import contact_tilt, footing_grid, tilt_limit
from footfall.features.reward import default_reward
from footfall.terrain.modules import make_module

R = LITTLEDOG.foot_radius  # [m] 0.01


def plane(slope: float, res: float = 0.0005, size: float = 0.1) -> HeightMap:
    """A plane rising along x with ``slope`` [rad]."""
    n = int(round(size / res)) + 1
    x = np.arange(n) * res
    return HeightMap(np.repeat((np.tan(slope) * x)[:, None], n, axis=1), res, (0.0, 0.0))


def ledge(res: float = 0.0005) -> HeightMap:
    """A 5 cm high plateau for x < 0.05 m, the ground at 0 beyond it."""
    n = 201
    x = np.arange(n) * res
    return HeightMap(np.repeat(np.where(x < 0.05, 0.05, 0.0)[:, None], n, axis=1), res)


def test_flat_ground_has_no_tilt():
    hmap = plane(0.0)
    centres = hmap.index_to_position(np.random.default_rng(0).integers(40, 160, (50, 2)))
    np.testing.assert_array_equal(contact_tilt(hmap, centres, R), 0.0)
    # between cell centres the contact is the nearest cell: off by at most half a diagonal
    pts = np.random.default_rng(0).uniform(0.02, 0.08, (50, 2))
    assert np.all(contact_tilt(hmap, pts, R) <= np.arcsin(0.5 * math.sqrt(2) * 0.0005 / R))


@pytest.mark.parametrize("slope", [0.1, 0.4, 0.7, 1.0])
def test_on_a_plane_the_tilt_is_its_slope(slope):
    pts = np.random.default_rng(1).uniform(0.03, 0.07, (40, 2))
    # the contact is a cell, so the tilt is the slope to about one cell in the foot's radius
    np.testing.assert_allclose(contact_tilt(plane(slope), pts, R), slope, atol=0.06)


def test_a_ball_over_an_edge_hangs_on_its_corner():
    hmap = ledge()
    d = np.array([0.001, 0.003, 0.005, 0.007, 0.009])  # [m] beyond the edge
    pts = np.column_stack([0.0495 + d, np.full(d.size, 0.05)])  # the corner cell is at 0.0495
    np.testing.assert_allclose(contact_tilt(hmap, pts, R), np.arcsin(d / R), atol=1e-9)
    on_top = contact_tilt(hmap, np.array([[0.02, 0.05], [0.035, 0.05]]), R)
    np.testing.assert_allclose(on_top, 0.0, atol=1e-9)  # away from the edge the plateau is flat
    beyond = contact_tilt(hmap, np.array([[0.0495 + R + 0.002, 0.05]]), R)
    np.testing.assert_allclose(beyond, 0.0, atol=1e-9)  # clear of the corner: on the ground


def test_cells_without_data_do_not_hold_the_foot():
    heights = np.asarray(ledge().heights, dtype=np.float64).copy()
    heights[:100] = np.nan  # the plateau's edge, and all behind it, unknown
    hmap = HeightMap(heights, 0.0005)
    np.testing.assert_allclose(contact_tilt(hmap, np.array([[0.052, 0.05]]), R), 0.0, atol=1e-9)
    assert np.isnan(contact_tilt(hmap, np.array([[0.02, 0.05]]), R)[0])  # nothing under it
    grid = footing_grid(hmap, 0.005, R, 0.0)
    assert grid.at(np.array([0.02, 0.05])) == pytest.approx(math.pi / 2)  # cannot stand there


def test_the_limit_is_the_friction_cone_reduced_by_the_safety_factor():
    assert tilt_limit(0.8, 1.0) == pytest.approx(math.atan(0.8))
    assert tilt_limit(0.8, 1.5) == pytest.approx(math.atan(0.8 / 1.5))
    for bad in ((0.0, 1.5), (0.8, 0.0), (-1.0, 1.0), (math.nan, 1.0)):
        with pytest.raises(FootfallError):
            tilt_limit(*bad)
    with pytest.raises(FootfallError):
        contact_tilt(plane(0.0), np.zeros((1, 2)), 0.0)


def test_the_grid_is_the_worst_tilt_within_the_margin_of_every_lattice_point():
    hmap = make_module("rocky", 0.8, seed=3)
    exact = footing_grid(hmap, 0.005, R, 0.0)
    # the strided lattice path is the per-point definition
    xx, yy = np.meshgrid(exact.x, exact.y, indexing="ij")
    pts = np.column_stack([xx.ravel(), yy.ravel()])
    np.testing.assert_allclose(exact.tilt, contact_tilt(hmap, pts, R).reshape(exact.tilt.shape),
                               atol=1e-12)
    # a lattice that does not fall on cells takes the per-point path
    odd = footing_grid(hmap, 0.0045, R, 0.0)
    xx, yy = np.meshgrid(odd.x, odd.y, indexing="ij")
    pts = np.column_stack([xx.ravel(), yy.ravel()])
    np.testing.assert_array_equal(odd.tilt, contact_tilt(hmap, pts, R).reshape(odd.tilt.shape))
    margin = footing_grid(hmap, 0.005, R, 0.005)
    t = exact.tilt
    worst = t.copy()  # one spacing: the four neighbours
    worst[1:] = np.maximum(worst[1:], t[:-1])
    worst[:-1] = np.maximum(worst[:-1], t[1:])
    worst[:, 1:] = np.maximum(worst[:, 1:], t[:, :-1])
    worst[:, :-1] = np.maximum(worst[:, :-1], t[:, 1:])
    np.testing.assert_array_equal(margin.tilt[1:-1, 1:-1], worst[1:-1, 1:-1])
    assert footing_grid(hmap, 0.005, R, 0.005) is margin  # once per map and settings


def step_map() -> HeightMap:
    """Flat ground with a 4 cm high, 6 cm deep block across the path at x in [0.40, 0.46] m."""
    x = np.arange(901) * 0.001
    heights = np.repeat(np.where((x >= 0.40) & (x <= 0.46), 0.04, 0.0)[:, None], 601, axis=1)
    return HeightMap(heights, 0.001, (0.0, -0.3))


def planner(hmap: HeightMap, **config) -> FootstepPlanner:
    """The hand-tuned reward's planner along the board's centre line, with ``config``."""
    reward = default_reward()
    return FootstepPlanner(hmap, lambda leg: reward, BodyPath.straight((0.2, 0.0), (0.8, 0.0)),
                           grids=terrain_grids(hmap, lambda leg: reward),
                           config=FootstepConfig(**config))


def test_the_planner_drops_footholds_that_would_not_hold_unless_none_would():
    hmap = step_map()
    state = nominal_state(hmap, (0.3, 0.0), 0.0, "LF")
    checked, plain = planner(hmap, friction_safety=1.5), planner(hmap)
    a, b = checked.plan(state), plain.plan(state)
    limit = math.atan(LITTLEDOG.foot_friction / 1.5)
    tilt = checked.friction_.grid.at(b.candidates[:, :2])
    assert np.any(tilt > limit)  # the block's edges are in reach
    np.testing.assert_array_equal(a.candidates, b.candidates[tilt <= limit])
    assert checked.friction_.holds(a.foothold[:2])
    assert checked.friction_.limit == pytest.approx(limit)
    # on ground where nothing holds, the check drops nothing: the foot must go somewhere
    steep = HeightMap(np.repeat((np.arange(901) * 0.001)[:, None], 601, axis=1), 0.001,
                      (0.0, -0.3))  # 45 degrees everywhere
    state = nominal_state(steep, (0.3, 0.0), 0.0, "LF")
    a = planner(steep, friction_safety=1.5).plan(state)
    b = planner(steep).plan(state)
    np.testing.assert_array_equal(a.candidates, b.candidates)


def test_the_planner_keeps_the_swing_leg_s_joints_off_their_limits_now_and_a_stride_on():
    hmap = step_map()
    state = nominal_state(hmap, (0.3, 0.0), 0.0, "LF")
    plain = planner(hmap).plan(state)
    margin = 0.3  # [rad]
    kept = planner(hmap, joint_margin=margin).plan(state)
    touchdown = plain.state
    ahead = planner(hmap)._horizon(state)
    stride = stride_on(touchdown, ahead.legs, ahead.body_xy, ahead.grounds)
    assert stride.body_position[0] - touchdown.body_position[0] == pytest.approx(
        plain.body_xy[-1, 0] - plain.body_xy[0, 0])
    now = joint_margins(touchdown, plain.candidates)
    later = joint_margins(stride, plain.candidates)
    assert np.all(now >= 0)  # every candidate is reachable at touch-down ...
    clear = np.fmin(now, later) >= margin  # NaN (out of reach a stride on): not clear
    assert 0 < clear.sum() < clear.size  # ... and some come near a limit
    np.testing.assert_array_equal(kept.candidates, plain.candidates[clear])
    assert np.min(joint_margins(touchdown, kept.foothold[None])) >= margin
    # a margin no foothold meets drops nothing
    none = planner(hmap, joint_margin=3.0).plan(state)
    np.testing.assert_array_equal(none.candidates, plain.candidates)


def test_joint_margins_are_the_distance_of_the_nearest_joint_from_its_limit():
    hmap = plane(0.0, res=0.001, size=0.6)
    state = nominal_state(hmap, (0.3, 0.3), 0.0, "RH")
    leg = LITTLEDOG.leg("RH")
    foot = state.feet[LITTLEDOG.legs.index(leg)][None]
    centre = foot + (0.0, 0.0, LITTLEDOG.foot_radius)
    q, ok = inverse_kinematics(leg, world_to_body(centre, state.body_position, state.body_rpy),
                               LITTLEDOG)
    assert ok[0]
    lo, hi = np.array(leg.limits).T
    assert joint_margins(state, foot)[0] == pytest.approx(np.min(np.minimum(q[0] - lo, hi - q[0])))
    assert np.isnan(joint_margins(state, foot + (1.0, 0.0, 0.0))[0])  # out of reach
