"""Candidate footholds and pose features."""

import json

import numpy as np
import pytest

from cli_helpers import run
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import inverse_kinematics, world_to_body
from footfall.core.robot import LEG_NAMES, LITTLEDOG
from footfall.core.state import RobotState, nominal_state
from footfall.experiments.bench.pose import hull_area_reference, triangle_margins_reference
from footfall.features.candidates import lattice, reachable_footholds
from footfall.features.config import FeatureConfig
from footfall.features.pose_features import (
    POSE_FEATURE_DOCS,
    POSE_FEATURE_NAMES,
    hull_area,
    pose_features,
    triangle_margins,
)


def flat(size=(800, 600), origin=(-0.4, -0.3), z=0.0):
    return HeightMap(np.full(size, z), 0.001, origin)


@pytest.mark.parametrize("leg", LEG_NAMES)
def test_candidates_are_reachable_lattice_points_on_the_terrain(leg):
    hm = flat()
    state = nominal_state(hm, (0.0, 0.0), 0.0, leg)
    f = reachable_footholds(hm, state, spacing=0.005)
    assert f.shape[0] > 100 and f.shape[1] == 3
    np.testing.assert_allclose(f[:, 2], 0.0)
    # Points on the 5 mm lattice of the map.
    k = (f[:, :2] - np.array(hm.origin)) / 0.005
    np.testing.assert_allclose(k, np.round(k), atol=1e-9)
    # Every candidate is reachable; the leg's nominal foot is among them (to 5 mm).
    centre = f + [0, 0, LITTLEDOG.foot_radius]
    _, ok = inverse_kinematics(LITTLEDOG.leg(leg), world_to_body(centre, state.body_position,
                                                                 state.body_rpy), LITTLEDOG)
    assert ok.all()
    nominal = state.feet[LEG_NAMES.index(leg), :2]
    assert np.min(np.linalg.norm(f[:, :2] - nominal, axis=1)) < 0.004
    # Nothing outside the leg's reach from its hip.
    hip = np.array(LITTLEDOG.leg(leg).hip[:2])
    assert np.max(np.linalg.norm(f[:, :2] - hip, axis=1)) < LITTLEDOG.max_reach


def test_candidates_skip_holes_and_low_coverage():
    h = np.zeros((800, 600))
    h[470:530, 340:410] = np.nan  # a hole near the LF foot ...
    h[497:503, 372:378] = 0.0  # ... with a 6 mm island of data at (0.1, 0.075) in it
    hm = HeightMap(h, 0.001, (-0.4, -0.3))
    state = nominal_state(hm, (0.0, 0.0), 0.0, "LF")
    f = reachable_footholds(hm, state)
    assert np.isfinite(f).all()
    in_hole = (f[:, 0] >= 0.07) & (f[:, 0] < 0.13) & (f[:, 1] >= 0.04) & (f[:, 1] < 0.11)
    np.testing.assert_allclose(f[in_hole, :2], [[0.1, 0.075]])  # only the island
    f2 = reachable_footholds(hm, state, config=FeatureConfig())
    # The island's patches are nearly all hole: not a candidate once coverage counts.
    in_hole2 = (f2[:, 0] >= 0.07) & (f2[:, 0] < 0.13) & (f2[:, 1] >= 0.04) & (f2[:, 1] < 0.11)
    assert not in_hole2.any() and f2.shape[0] < f.shape[0]
    with pytest.raises(FootfallError):
        lattice(hm, (0, 1), (0, 1), 0.0)


def test_pose_feature_names_and_docs():
    assert len(POSE_FEATURE_NAMES) == 26
    assert all("[" in POSE_FEATURE_DOCS[n] for n in POSE_FEATURE_NAMES)  # every one has a unit


def test_pose_features_on_flat_ground():
    hm = flat()
    state = nominal_state(hm, (0.0, 0.0), 0.0, "LF")
    lf = state.feet[0]
    f = np.array([lf + [0.04, 0.0, 0.0], lf + [0.0, 0.02, 0.0], lf])
    x = dict(zip(POSE_FEATURE_NAMES, pose_features(hm, state, f).T))
    np.testing.assert_allclose(x["progress"], [0.04, 0.0, 0.0])
    np.testing.assert_allclose(x["step_length"], [0.04, 0.02, 0.0])
    np.testing.assert_allclose(x["nominal_dy_out"], [0.0, 0.02, 0.0], atol=1e-12)
    np.testing.assert_allclose(x["step_up"] + x["step_down"], 0.0)
    np.testing.assert_allclose(x["leg_drop"], LITTLEDOG.nominal_height)
    # Flat ground: the knee is far above it, and the clearances hit their caps.
    np.testing.assert_allclose(x["knee_clearance"], 0.05)
    assert (x["joint_margin"] > 0).all() and (x["reach_margin"] > 0).all()
    # Moving LF forward makes the quadrilateral of the feet larger.
    assert x["support_area"][0] > x["support_area"][2]


def test_right_leg_features_mirror_left_leg_features():
    rng = np.random.default_rng(0)
    from scipy.ndimage import gaussian_filter
    hm = HeightMap(gaussian_filter(rng.normal(size=(800, 600)), 8) * 0.2, 0.001, (-0.4, -0.3))
    left = nominal_state(hm, (0.0, 0.0), 0.0, "LF")
    mirrored = hm.mirrored_y()
    right = nominal_state(mirrored, (0.0, 0.0), 0.0, "RF")
    fl = reachable_footholds(hm, left)[::7]
    fr = fl * [1, -1, 1]
    np.testing.assert_allclose(pose_features(hm, left, fl), pose_features(mirrored, right, fr),
                               atol=1e-9)


def test_triangle_margins_and_hull_area():
    tri = np.array([[[0, 0], [1, 0], [0, 1]]], float)
    inradius, margin = triangle_margins(tri, np.array([0.25, 0.25]))
    assert inradius[0] == pytest.approx(1 / (2 + np.sqrt(2)))
    assert margin[0] == pytest.approx(0.25)
    assert triangle_margins(tri[:, ::-1], np.array([2.0, 2.0]))[1][0] < 0  # outside, any winding
    quads = np.array([[[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 0], [1, 1], [1, 0], [0, 1]],
                      [[0, 0], [2, 0], [0, 2], [0.2, 0.2]]], float)
    np.testing.assert_allclose(hull_area(quads), [1.0, 1.0, 2.0])


@pytest.mark.parametrize("n", [1, 2, 7, 32, 128, 1500])
def test_the_compiled_support_features_are_the_numpy_definitions_to_the_last_bit(n):
    rng = np.random.default_rng(n)
    feet = rng.normal(0.0, 0.12, (n, 4, 2)) + rng.normal(0.0, 3.0, 2)  # metres, off the origin
    # degenerate rows: two feet on one spot, three on a line, a NaN
    feet[0, 1] = feet[0, 0]
    if n > 2:
        feet[1, 2] = 0.5 * (feet[1, 0] + feet[1, 1])
        feet[2, 3, 1] = np.nan
    point = rng.normal(0.0, 3.0, 2)
    for lifted in range(4):
        tri = feet[:, [k for k in range(4) if k != lifted]]
        got, want = triangle_margins(tri, point), triangle_margins_reference(tri, point)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)
    np.testing.assert_array_equal(hull_area(feet), hull_area_reference(feet))


def test_the_pose_benchmark_compares_equal_features(capsys):
    code, out, _ = run(capsys, "bench", "pose", "--states", "1", "--json")
    assert code == 0
    result = json.loads(out)
    assert result["equal"] is True and set(result["sets"]) == {"128", "32"}
    assert all(s["numpy_us"] > 0 and s["compiled_us"] > 0 for s in result["sets"].values())


def test_state_validation_and_vector_round_trip():
    hm = flat()
    s = nominal_state(hm, (0.1, 0.0), 0.2, "RH")
    back = RobotState.from_vector(s.to_vector(), "RH")
    np.testing.assert_array_equal(back.feet, s.feet)
    assert back.yaw == pytest.approx(0.2)
    with pytest.raises(FootfallError, match="unknown swing leg"):
        RobotState(s.feet, s.body_position, s.body_rpy, "XX")
    with pytest.raises(FootfallError, match="finite"):
        RobotState(s.feet * np.nan, s.body_position, s.body_rpy, "LF")
