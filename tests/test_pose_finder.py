"""The pose finder: body height, roll, pitch and yaw for a stance."""

import numpy as np
import pytest

from footfall.control.pose_finder import TERMS, PoseConfig, find_pose, preferred_pose
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import body_to_world, inverse_kinematics, knee_position, world_to_body
from footfall.core.robot import LEG_NAMES, LITTLEDOG
from footfall.core.state import nominal_state

ORIGIN = (-0.3, -0.2)  # [m] the maps of these tests: 0.6 x 0.4 m at 1 mm
X = ORIGIN[0] + np.arange(600) * 0.001
Y = ORIGIN[1] + np.arange(400) * 0.001
GX, GY = np.meshgrid(X, Y, indexing="ij")


def terrain(heights):
    return HeightMap(heights, 0.001, ORIGIN)


def flat(z=0.0):
    return terrain(np.full((600, 400), z))


def nominal_feet(xy=(0.0, 0.0), yaw=0.0, z=0.0):
    return nominal_state(flat(z), xy, yaw, "LF").feet.copy()


@pytest.mark.parametrize("xy, yaw, z", [((0.0, 0.0), 0.0, 0.0), ((0.05, -0.03), 0.4, 0.2)])
def test_flat_ground_nominal_stance_gives_the_nominal_pose(xy, yaw, z):
    feet = nominal_feet(xy, yaw, z)
    pose = find_pose(flat(z), feet, np.array(xy), yaw)
    assert pose.height == pytest.approx(z + LITTLEDOG.nominal_height, abs=1e-12)
    np.testing.assert_allclose(pose.rpy, [0.0, 0.0, yaw], atol=1e-12)
    assert pose.score == 0.0 and set(pose.terms) == set(TERMS)
    assert pose.reachable
    assert pose.joint_margin >= PoseConfig().joint_margin
    assert pose.leg_clearance >= PoseConfig().leg_clearance
    assert pose.trunk_clearance == pytest.approx(LITTLEDOG.nominal_height - LITTLEDOG.trunk_size[2] / 2)
    np.testing.assert_allclose(pose.position, [*xy, z + LITTLEDOG.nominal_height])


def test_step_under_the_front_feet_pitches_nose_up_to_keep_the_hind_feet_in_reach():
    step = 0.1
    hm = terrain(np.where(GX > 0.05, step, 0.0))
    feet = nominal_state(hm, (0.0, 0.0), 0.0, "LF").feet
    config = PoseConfig(attitude_follow=0.0)  # prefer a level body: only reach makes it pitch
    level = preferred_pose(feet, np.zeros(2), 0.0, LITTLEDOG, config)
    np.testing.assert_allclose(level[1:], 0.0, atol=1e-12)

    def reach_margins(height, rpy):
        centres = world_to_body(feet + [0, 0, LITTLEDOG.foot_radius], [0, 0, height], rpy)
        return np.array([LITTLEDOG.max_reach - np.linalg.norm(centres[k] - LITTLEDOG.leg(n).hip)
                         for k, n in enumerate(LEG_NAMES)])

    # Level at the preferred height, the hind legs are short of the wanted reach margin ...
    assert reach_margins(level[0], level[1:]).min() < 0.5 * config.reach_margin
    pose = find_pose(hm, feet, np.zeros(2), 0.0, config=config)
    # ... so the finder pitches nose up (negative pitch), bringing the hind hips down.
    assert pose.rpy[1] < -0.08
    assert pose.reachable
    assert pose.reach_margin >= 0.8 * config.reach_margin
    assert reach_margins(pose.height, pose.rpy).min() == pytest.approx(pose.reach_margin)
    # Body raised above the hind feet beyond the nominal height, below it over the front feet.
    assert pose.height - 0.0 > LITTLEDOG.nominal_height > pose.height - step
    # By default the body leans with the feet from the start (and need not lean much further).
    default = find_pose(hm, feet, np.zeros(2), 0.0)
    assert default.rpy[1] < pose.rpy[1] and default.reachable and default.score > -0.1


def test_trunk_rises_over_a_bump_and_its_clearance_is_conservative():
    hm = terrain(np.where((np.abs(GX) < 0.03) & (np.abs(GY) < 0.02), 0.1, 0.0))
    pose = find_pose(hm, nominal_feet(), np.zeros(2), 0.0)
    wanted = PoseConfig().trunk_clearance
    assert pose.trunk_clearance >= wanted - 1e-9
    assert pose.height > LITTLEDOG.nominal_height
    # Brute force: the underside of the trunk box, densely sampled at the pose found.
    lx, ly, lz = (s / 2 for s in LITTLEDOG.trunk_size)
    u, v = np.meshgrid(np.linspace(-lx, lx, 121), np.linspace(-ly, ly, 46), indexing="ij")
    under = np.stack([u.ravel(), v.ravel(), np.full(u.size, -lz)], axis=-1)
    world = body_to_world(under, pose.position, pose.rpy)
    true_clearance = np.min(world[:, 2] - hm.height_at(world[:, :2]))
    assert pose.trunk_clearance <= true_clearance + 1e-9
    assert pose.trunk_clearance == pytest.approx(true_clearance, abs=2e-3)


def test_knee_moves_away_from_a_block_under_it():
    leg = LITTLEDOG.leg("LF")
    foot = np.array(LITTLEDOG.nominal_foot("LF")) + [0, 0, LITTLEDOG.foot_radius]
    q, _ = inverse_kinematics(leg, foot, LITTLEDOG)
    knee = knee_position(leg, q, LITTLEDOG)  # body frame = world frame at the nominal pose
    block = (np.abs(GX - knee[0]) < 0.01) & (np.abs(GY - knee[1]) < 0.01)
    hm = terrain(np.where(block, knee[2] + LITTLEDOG.nominal_height - 0.008, 0.0))
    # At the nominal pose the knee is 8 mm above the block, its shin surface 2 mm.
    pose = find_pose(hm, nominal_feet(), np.zeros(2), 0.0)
    assert pose.leg_clearance >= PoseConfig().leg_clearance - 1e-3
    assert pose.reachable and pose.score < 0.0  # it had to leave the preferred pose


def test_feet_too_far_apart_are_reported_unreachable():
    feet = nominal_feet()
    feet[LEG_NAMES.index("LF"), 0] += 0.2
    feet[LEG_NAMES.index("LH"), 0] -= 0.2
    pose = find_pose(flat(), feet, np.zeros(2), 0.0)
    assert not pose.reachable
    assert pose.reach_margin < 0.0 and pose.score < 0.0


def test_cells_without_data_are_no_obstacle():
    heights = np.zeros((600, 400))
    heights[(np.abs(GX) < 0.1) & (np.abs(GY) < 0.05)] = np.nan  # a hole under the trunk
    pose = find_pose(terrain(heights), nominal_feet(), np.zeros(2), 0.0)
    assert pose.score == 0.0 and pose.height == pytest.approx(LITTLEDOG.nominal_height)


def test_bad_input_raises():
    hm = flat()
    with pytest.raises(FootfallError, match=r"feet \(4, 3\)"):
        find_pose(hm, np.zeros((3, 3)), np.zeros(2), 0.0)
    with pytest.raises(FootfallError, match="finite"):
        find_pose(hm, nominal_feet(), np.array([np.nan, 0.0]), 0.0)
    with pytest.raises(FootfallError, match="grid"):
        PoseConfig(grid=(4, 3, 3, 3))
    with pytest.raises(FootfallError, match="weight_yaw"):
        PoseConfig(weight_yaw=-1.0)
    with pytest.raises(FootfallError, match="joint_margin"):
        PoseConfig(joint_margin=0.0)


def test_the_compiled_leg_measures_are_the_kinematics_of_core():
    # footfall.control.pose_finder._leg_measures against the vectorised NumPy definitions: joint
    # margins (an unsolvable leg charged -pi), reach, the shins' clearance over the map, and
    # whether every leg reaches within its limits
    from footfall.control.pose_finder import _NO_SOLUTION_MARGIN, _leg_measures
    from footfall.core.kinematics import (
        _leg_arrays,
        legs_inverse_kinematics,
        legs_joint_limit_margin,
        legs_knee_position,
        rotation_matrix,
    )
    from footfall.terrain import make_board

    board = make_board([("rocky", 0.8)], seed=2)
    rng = np.random.default_rng(6)
    robot, cfg = LITTLEDOG, PoseConfig()
    centres = np.array([robot.nominal_foot(leg) for leg in LEG_NAMES]) + [0.9, 0.0, 0.0]
    centres[:, 2] = board.height_at(centres[:, :2]) + robot.foot_radius
    n = 400
    poses = np.column_stack([centres[:, 2].mean() + rng.uniform(0.05, 0.25, n),
                             rng.uniform(-0.5, 0.5, (n, 2)), rng.uniform(-0.3, 0.3, n)])
    body = np.column_stack([np.full((n, 2), [0.9, 0.0]), poses[:, 0]])
    rot = rotation_matrix(poses[:, 1:])
    frac = np.linspace(0.0, cfg.shin_fraction, cfg.shin_samples)
    joint, reach, clear, ok = _leg_measures(
        centres, body, rot, *_leg_arrays(robot),
        np.array([robot.upper_leg, robot.lower_leg, robot.hip_offset, robot.max_reach,
                  robot.lower_leg_radius]), frac, board.heights,
        np.array([*board.origin, board.resolution]))

    local = (centres[None] - body[:, None]) @ rot
    q, ok_legs = legs_inverse_kinematics(robot, local)
    margin = legs_joint_limit_margin(robot, q)
    hips = np.array([leg.hip for leg in robot.legs])
    knee = legs_knee_position(robot, q)
    points = knee[:, :, None] + frac[None, None, :, None] * (local - knee)[:, :, None]
    world = (points.reshape(n, -1, 3) @ rot.transpose(0, 2, 1)).reshape(points.shape)
    world += body[:, None, None]
    gap = world[..., 2] - board.height_at(world[..., :2]) - robot.lower_leg_radius
    np.testing.assert_allclose(
        joint, np.where(np.isnan(margin), _NO_SOLUTION_MARGIN, margin).min(axis=1), atol=1e-12)
    np.testing.assert_allclose(
        reach, (robot.max_reach - np.linalg.norm(local - hips, axis=2)).min(axis=1), atol=1e-12)
    np.testing.assert_allclose(clear, np.where(np.isnan(gap), np.inf, gap).min(axis=(1, 2)),
                               atol=1e-12)
    assert (ok == ok_legs.all(axis=1)).all() and 0 < ok.sum() < n  # both outcomes drawn
