"""The body correction handed over to the stance anchors at a touch-down
(footfall.control.lowlevel.handed_over and handed_over_pose, LowLevelConfig.hand_over,
hand_over_height, hand_over_attitude): on paper and on the robot."""

import numpy as np
import pytest

from footfall.control.controller import Controller
from footfall.control.lowlevel import (
    BodyCorrection,
    LowLevelConfig,
    body_rotation,
    handed_over,
    handed_over_pose,
    joint_targets,
)
from footfall.core.kinematics import body_to_world, forward_kinematics
from footfall.core.robot import LITTLEDOG
from scenes import staged

R = LITTLEDOG
Q0 = np.array([[0.0, -0.6, 1.2], [0.0, -0.6, 1.2], [0.0, 0.6, -1.2], [0.0, 0.6, -1.2]])  # [rad]
RPY = np.array([0.03, -0.02, 0.3])  # [rad]
DESIRED = np.array([0.2, 0.05, 0.14])  # [m]


def _feet(position: np.ndarray) -> np.ndarray:
    """World foot centres (4, 3) [m] of the legs at Q0 with the body at ``position``."""
    return np.array([body_to_world(forward_kinematics(leg, Q0[k], R), position, RPY)
                     for k, leg in enumerate(R.legs)])


def test_only_the_stance_anchors_move_and_by_what_the_correction_gave_up():
    anchors = _feet(DESIRED)
    stance = np.array([True, True, False, True])
    out = handed_over(anchors, stance, np.array([0.01, -0.02, 0.0]))
    np.testing.assert_allclose(out[stance], anchors[stance] - [0.01, -0.02, 0.0])
    np.testing.assert_array_equal(out[2], anchors[2])
    np.testing.assert_array_equal(anchors, _feet(DESIRED))  # the input is left alone


def test_the_correction_gives_up_its_horizontal_part_and_keeps_its_height():
    correction = BodyCorrection(LowLevelConfig())
    correction.position = np.array([0.012, -0.02, 0.004])
    taken = correction.take_horizontal()
    np.testing.assert_allclose(taken, [0.012, -0.02, 0.0])
    np.testing.assert_allclose(correction.position, [0.0, 0.0, 0.004])


def test_the_correction_gives_up_its_height_and_attitude_only_when_asked():
    correction = BodyCorrection(LowLevelConfig())
    correction.position = np.array([0.012, -0.02, -0.008])
    correction.attitude = np.array([0.05, -0.03])
    taken, turned = correction.take(height=True, attitude=False)
    np.testing.assert_allclose(taken, [0.012, -0.02, -0.008])
    np.testing.assert_array_equal(turned, [0.0, 0.0])
    np.testing.assert_allclose(correction.attitude, [0.05, -0.03])
    taken, turned = correction.take(height=True, attitude=True)
    np.testing.assert_array_equal(taken, [0.0, 0.0, 0.0])
    np.testing.assert_allclose(turned, [0.05, -0.03])
    np.testing.assert_array_equal(correction.attitude, [0.0, 0.0])


def test_the_pose_hand_over_keeps_stance_set_points_and_a_new_foot_is_not_lifted():
    # The correction lowers the commanded body by 10 mm and rolls it by 0.08 rad against the
    # stance feet's offsets (the body stands where it is wanted). A new foot put down where it
    # stands and solved in the commanded frame with that correction is lifted off its spot;
    # after the pose hand-over it is asked to stay, and the stance set-points do not change.
    position, attitude = np.array([0.004, -0.003, -0.010]), np.array([0.08, -0.02])  # [m], [rad]
    stance = np.array([True, False, True, True])  # RF is being set down
    rpy_c = RPY.copy()
    rpy_c[:2] += attitude
    before = (DESIRED + position, body_rotation(rpy_c))
    after = (DESIRED, body_rotation(RPY))
    targets = np.array([body_to_world(forward_kinematics(leg, Q0[k], R), before[0], rpy_c)
                        for k, leg in enumerate(R.legs)])  # Q0 in the commanded frame
    measured = (DESIRED, body_rotation(RPY))
    q_before, _ = joint_targets(R, targets, before, measured, stance.astype(float), Q0)
    moved = handed_over_pose(targets, stance, before, after)
    q_after, _ = joint_targets(R, moved, after, measured, stance.astype(float), Q0)
    np.testing.assert_allclose(q_after[stance], q_before[stance], atol=1e-12)
    np.testing.assert_array_equal(moved[1], targets[1])  # the new foot's row is left alone
    down = _feet(DESIRED)[1]  # where RF stands, the body as measured
    for commanded, lifted in ((before, True), (after, False)):
        target = moved.copy()
        target[1] = down
        q, _ = joint_targets(R, target, commanded, measured, np.ones(4), Q0)
        reached = body_to_world(forward_kinematics(R.legs[1], q[1], R), DESIRED, RPY)
        off = float(np.linalg.norm(reached - down))
        assert (off > 0.005) if lifted else (off < 1e-9), off


def test_stance_set_points_do_not_change_and_the_new_foot_enters_a_frame_without_correction():
    # The body stands where it is wanted; the legs were commanded for a correction of 2.5 cm
    # (stale anchors of slipped feet): the stance legs' set-points are the same after the hand-over
    correction = np.array([0.015, -0.02, 0.003])  # [m]
    stance = np.array([True, True, True, False])  # RH is being set down
    anchors = _feet(DESIRED + correction)  # anchors that give Q0 in the corrected frame
    rot = body_rotation(RPY)
    measured = (DESIRED, rot)
    before, _ = joint_targets(R, anchors, (DESIRED + correction, rot), measured,
                              stance.astype(float), Q0)
    taken = np.array([correction[0], correction[1], 0.0])
    after_anchors = handed_over(anchors, stance, taken)
    after, _ = joint_targets(R, after_anchors, (DESIRED + correction - taken, rot), measured,
                             stance.astype(float), Q0)
    np.testing.assert_allclose(after[stance], before[stance], atol=1e-12)
    np.testing.assert_allclose(before[stance], Q0[stance], atol=1e-9)
    # RH, put down where it stands (its world position with the body as measured), and solved in
    # the commanded frame: with the correction it is asked to move by the correction's 2.5 cm
    # horizontally, without it only by the height part
    down = _feet(DESIRED)[3]
    for commanded, expected_move in ((DESIRED + correction, correction),
                                     (DESIRED + correction - taken, correction - taken)):
        target = after_anchors.copy()
        target[3] = down
        q, _ = joint_targets(R, target, (commanded, rot), measured, np.ones(4), Q0)
        reached = body_to_world(forward_kinematics(R.legs[3], q[3], R), DESIRED, RPY)
        np.testing.assert_allclose(down - reached, expected_move, atol=1e-9)


# ---------------------------------------------------------------- on the robot, standing
class Stale(Controller):
    """Stands 1.5 s with the front feet's anchors 15 mm to the left of where they stand (as if
    they had slid 15 mm right), so the body correction grows; then, if ``hand``, hands it over
    (as at a touch-down) and stands 0.5 s more. Records the correction [m] at the hand-over and
    at the end, and the feet [m] and body position [m] at the end."""

    hand = False

    def step_phases(self, k):
        self.legs.anchor[:2, 1] += 0.015
        for _ in range(150):
            yield from self.tick(*self.desired, None)
        self.before = self.legs.correction.position.copy()
        if self.hand:
            self.legs.hand_over()
        for _ in range(50):
            yield from self.tick(*self.desired, None)
        self.after = self.legs.correction.position.copy()
        self.feet, self.body = self.est.feet.copy(), self.pose[0].copy()
        return True


def _stand(hand: bool) -> Stale:
    return staged(type("Handed" if hand else "Kept", (Stale,), {"hand": hand}),
                  lowlevel=LowLevelConfig(hand_over=True, hand_over_height=False,
                                          hand_over_attitude=False)).controller


def test_on_the_robot_the_hand_over_moves_nothing_and_leaves_the_correction_small():
    kept, handed = _stand(False), _stand(True)
    np.testing.assert_array_equal(kept.before, handed.before)  # the same run up to the hand-over
    assert abs(kept.before[1]) > 0.004  # the stale anchors' pull
    # no foot and not the body moved because of it
    np.testing.assert_allclose(handed.feet, kept.feet, atol=2e-4)
    np.testing.assert_allclose(handed.body, kept.body, atol=2e-4)
    # the correction went on from zero, where the kept one went on from its centimetre
    assert abs(handed.after[1]) < 0.2 * abs(kept.after[1])
    assert handed.after[2] == pytest.approx(kept.after[2], abs=1e-4)  # its height part kept


class Pressed(Stale):
    """As :class:`Stale`, the front feet's anchors also 6 mm below where they stand (pressed),
    so the correction also grows a height and a pitch; the hand-over gives up all three."""

    def step_phases(self, k):
        self.legs.anchor[:2, 2] -= 0.006
        return (yield from super().step_phases(k))


def _pressed(hand: bool) -> Pressed:
    lowlevel = LowLevelConfig(hand_over=True, hand_over_height=True, hand_over_attitude=True)
    return staged(type("PoseHanded" if hand else "PoseKept", (Pressed,), {"hand": hand}),
                  lowlevel=lowlevel).controller


def test_on_the_robot_the_pose_hand_over_moves_nothing():
    kept, handed = _pressed(False), _pressed(True)
    np.testing.assert_array_equal(kept.before, handed.before)
    assert abs(kept.before[2]) > 0.001  # the pressed anchors' push, taken by the correction
    np.testing.assert_allclose(handed.feet, kept.feet, atol=1e-5)
    np.testing.assert_allclose(handed.body, kept.body, atol=1e-5)
    # every part of the correction went on from zero
    turned, kept_turned = handed.legs.correction.attitude, kept.legs.correction.attitude
    assert np.abs(kept_turned).max() > 0.01
    assert np.abs(turned).max() < 0.2 * np.abs(kept_turned).max()
    assert abs(handed.after[2]) < 0.5 * abs(kept.after[2])
    assert abs(handed.after[1]) < 0.2 * abs(kept.after[1])
