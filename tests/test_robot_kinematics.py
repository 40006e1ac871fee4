"""Robot description and closed-form leg kinematics."""

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.kinematics import (
    body_to_world,
    forward_kinematics,
    inverse_kinematics,
    joint_limit_margin,
    knee_position,
    legs_inverse_kinematics,
    legs_joint_limit_margin,
    legs_knee_position,
    rotation_matrix,
    world_to_body,
)
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription


def test_littledog_numbers_match_the_paper_class():
    r = LITTLEDOG
    assert 2.5 <= r.total_mass <= 2.75
    assert r.trunk_mass == pytest.approx(1.8)
    assert (r.hip_x, r.hip_y, r.hip_offset) == (0.101, 0.036, 0.024)
    assert (r.upper_leg, r.lower_leg, r.foot_radius) == (0.075, 0.100, 0.010)
    assert r.overall_length == 0.30 and r.overall_width == 0.18
    assert [leg.name for leg in r.legs] == list(LEG_NAMES)
    for leg in r.legs:
        assert leg.hip_roll_limits == (-0.6, 0.6)
        assert leg.hip == (0.101 if leg.front else -0.101, 0.036 * leg.side, 0.0)
        assert leg.mirrored == (leg.side < 0)


def test_description_round_trips_through_plain_data():
    d = LITTLEDOG.to_dict()
    assert RobotDescription.from_dict(d) == LITTLEDOG
    assert RobotDescription.from_dict({**d, "upper_leg": 0.08}) != LITTLEDOG
    with pytest.raises(FootfallError, match="malformed"):
        RobotDescription.from_dict({**d, "wings": 2})
    with pytest.raises(FootfallError, match="unknown leg"):
        LITTLEDOG.leg("XX")
    for hips in ({"hip_x": 0.61}, {"hip_y": 0.05}, {"trunk_size": (0.24, 0.09, 0.0)}):
        with pytest.raises(FootfallError, match="must lie within the trunk"):
            RobotDescription.from_dict({**d, **hips})
    assert RobotDescription.from_dict({**d, "hip_x": 0.2, "trunk_size": (0.5, 0.09, 0.055)})


def _random_joints(leg, n, rng):
    lo = np.array([lim[0] for lim in leg.limits])
    hi = np.array([lim[1] for lim in leg.limits])
    return rng.uniform(lo, hi, size=(n, 3))


@pytest.mark.parametrize("name", LEG_NAMES)
def test_ik_fk_round_trip_over_the_workspace(name):
    leg = LITTLEDOG.leg(name)
    rng = np.random.default_rng(7)
    q = _random_joints(leg, 20000, rng)
    l1, l2 = LITTLEDOG.upper_leg, LITTLEDOG.lower_leg
    planar_z = -l1 * np.cos(q[:, 1]) - l2 * np.cos(q[:, 1] + q[:, 2])
    q = q[planar_z < -1e-3]  # the IK's branch: the leg hangs below its roll axis
    assert q.shape[0] > 10000
    foot = forward_kinematics(leg, q, LITTLEDOG)
    q_back, ok = inverse_kinematics(leg, foot, LITTLEDOG)
    assert ok.all()
    np.testing.assert_allclose(q_back, q, atol=1e-9)
    np.testing.assert_allclose(forward_kinematics(leg, q_back, LITTLEDOG), foot, atol=1e-12)


@pytest.mark.parametrize("name", LEG_NAMES)
def test_ik_rejects_unreachable_and_out_of_limit_points(name):
    leg = LITTLEDOG.leg(name)
    hip = np.array(leg.hip)
    far = hip + [0.0, 0.0, -0.3]  # beyond the legs' reach
    inside_roll = hip + [0.0, 0.0, -0.01]  # closer to the roll axis than the hip offset
    q, ok = inverse_kinematics(leg, np.stack([far, inside_roll]), LITTLEDOG)
    assert not ok.any()
    # Straight out sideways needs a hip roll of about 90 degrees: beyond the 0.6 rad limit.
    side = hip + [0.0, leg.side * 0.15, -0.02]
    assert not inverse_kinematics(leg, side, LITTLEDOG)[1]


@pytest.mark.parametrize("name", LEG_NAMES)
def test_nominal_stance_is_reachable_with_margin(name):
    leg = LITTLEDOG.leg(name)
    foot = np.array(LITTLEDOG.nominal_foot(name)) + [0, 0, LITTLEDOG.foot_radius]
    q, ok = inverse_kinematics(leg, foot, LITTLEDOG)
    assert ok
    assert joint_limit_margin(leg, q) > 0.1
    knee = knee_position(leg, q, LITTLEDOG)
    # Front knees point forward, hind knees backward (LittleDog's configuration).
    assert (knee[0] > foot[0]) == leg.front


def test_rotation_and_frames():
    rpy = np.array([0.1, -0.2, 0.7])
    rot = rotation_matrix(rpy)
    np.testing.assert_allclose(rot @ rot.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0)
    yaw_only = rotation_matrix(np.array([0.0, 0.0, np.pi / 2]))
    np.testing.assert_allclose(yaw_only @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    p = np.random.default_rng(2).normal(size=(5, 3))
    body = np.array([0.3, -0.1, 0.2])
    np.testing.assert_allclose(world_to_body(body_to_world(p, body, rpy), body, rpy), p, atol=1e-12)


def test_all_legs_at_once_give_each_legs_own_numbers_exactly():
    rng = np.random.default_rng(5)
    r = LITTLEDOG
    # (n, 4, 3) body-frame targets around each hip: reachable, past a limit, out of reach
    local = np.array([leg.hip for leg in r.legs]) + rng.uniform(
        [-0.12, -0.08, -0.22], [0.12, 0.08, 0.02], size=(300, 4, 3))
    q, ok = legs_inverse_kinematics(r, local)
    margin, knee = legs_joint_limit_margin(r, q), legs_knee_position(r, q)
    assert ok.any() and not ok.all() and np.isnan(q).any()
    for k, leg in enumerate(r.legs):
        qk, okk = inverse_kinematics(leg, local[:, k], r)
        np.testing.assert_array_equal(q[:, k], qk)  # bit for bit, NaN where no solution
        np.testing.assert_array_equal(ok[:, k], okk)
        np.testing.assert_array_equal(margin[:, k], joint_limit_margin(leg, qk))
        np.testing.assert_array_equal(knee[:, k], knee_position(leg, qk, r))
