"""The seen footing: footholds beside a hole in a scan wider than the ball leave F."""

import numpy as np

from footfall.control.footstep import FootstepConfig
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG
from footfall.core.sphere_surface import seen_under_sphere
from footfall.core.state import nominal_state
from scenes import centre_line_planner

R = LITTLEDOG.foot_radius  # [m] 0.01


def holed_map(hole: tuple[float, float, float, float] | None, crack: float | None = None
              ) -> HeightMap:
    """Flat ground at 1 mm cells, x in [0, 0.9], y in [-0.3, 0.3] m, with no data (NaN) in the
    rectangle ``hole`` = (x0, x1, y0, y1) [m] and a 2 mm crack without data across the
    path at x = ``crack`` [m]."""
    x = np.arange(901)[:, None] * 0.001
    y = -0.3 + np.arange(601)[None, :] * 0.001
    h = np.zeros((901, 601))
    if hole is not None:
        x0, x1, y0, y1 = hole
        h[((x >= x0) & (x <= x1)) & ((y >= y0) & (y <= y1))] = np.nan
    if crack is not None:
        h[((x >= crack) & (x < crack + 0.002)) & (y == y)] = np.nan
    return HeightMap(h, 0.001, (0.0, -0.3))


def test_a_sphere_is_blind_only_over_a_hole_wider_than_itself():
    hmap = holed_map((0.40, 0.46, -0.03, 0.03), crack=0.2)
    x = np.linspace(0.3, 0.56, 261)
    on_line = np.column_stack([x, np.zeros_like(x)])
    seen = seen_under_sphere(hmap, on_line, R, 0.017)
    # The hole is 6 cm wide: a 1 cm ball has nothing under it within 2 cm of its middle, so
    # the blind place is x in [0.41, 0.45] m, and a point is seen beyond 17 mm of it.
    assert np.all(seen[(x < 0.41 - 0.0175) | (x > 0.45 + 0.0175)])
    assert not np.any(seen[(x > 0.41 - 0.0165) & (x < 0.45 + 0.0165)])
    # A 2 mm crack without data is narrower than the ball: nothing near it is blind.
    across = np.column_stack([np.linspace(0.18, 0.22, 41), np.zeros(41)])
    assert seen_under_sphere(hmap, across, R, 0.017).all()
    # A map with no hole at all: every point on it is seen, none off it.
    plain = holed_map(None)
    assert seen_under_sphere(plain, on_line, R, 0.05).all()
    assert not seen_under_sphere(plain, np.array([[-0.1, 0.0], [0.5, 0.4]]), R, 0.0).any()


def test_the_planner_drops_footholds_beside_a_hole_wider_than_the_ball():
    start = (0.23, 0.0)
    flat = holed_map(None)
    probe = centre_line_planner(flat).plan(nominal_state(flat, start, 0.0, "LF"))
    fx, fy = probe.foothold[:2]  # where the front foot steps on flat ground
    hmap = holed_map((fx + 0.012, fx + 0.05, fy - 0.03, fy + 0.03))  # a hole just ahead of it
    state = nominal_state(hmap, start, 0.0, "LF")
    plain = centre_line_planner(hmap).plan(state)
    seen = seen_under_sphere(hmap, plain.candidates[:, :2], R, 0.017)
    assert 0 < seen.sum() < seen.size  # the hole's rim is in F
    checked = centre_line_planner(hmap, seen_footing=0.017).plan(state)
    np.testing.assert_array_equal(checked.candidates, plain.candidates[seen])
    assert seen_under_sphere(hmap, checked.foothold[None, :2], R, 0.017)[0]
    # a reach no candidate of F satisfies drops nothing
    wide = centre_line_planner(hmap, seen_footing=1.0).plan(state)
    np.testing.assert_array_equal(wide.candidates, plain.candidates)


def test_without_holes_the_check_changes_nothing():
    hmap = holed_map(None, crack=0.35)  # a crack narrower than the ball: no blind place
    state = nominal_state(hmap, (0.23, 0.0), 0.0, "LF")
    plain = centre_line_planner(hmap).plan(state)
    checked = centre_line_planner(hmap, seen_footing=0.017).plan(state)
    np.testing.assert_array_equal(checked.candidates, plain.candidates)
    np.testing.assert_array_equal(checked.foothold, plain.foothold)


def test_the_walk_checks_for_holes_wider_than_the_ball_by_default():
    from footfall.expert.synthetic import WALKER_PLACEMENT_ERROR
    from footfall.sim.episode import WalkConfig

    assert WalkConfig().footstep.seen_footing == R + WALKER_PLACEMENT_ERROR  # [m] 0.017
    assert FootstepConfig().seen_footing is None  # a planner made by hand checks only if asked
