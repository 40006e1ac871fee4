"""Stance re-anchoring (footfall.control.lowlevel.reanchor): slipped feet let go of, on paper and
on the standing robot."""


import numpy as np
import pytest

from footfall.control.controller import Controller
from footfall.control.lowlevel import BodyCorrection, LowLevelConfig, reanchor
from scenes import staged

ANCHORS = np.array([[0.1, 0.08, 0.01], [0.1, -0.08, 0.01], [-0.1, 0.08, 0.01],
                    [-0.1, -0.08, 0.01]])  # [m] LF RF LH RH


def test_a_following_foot_moves_its_anchor_by_the_rate_times_its_gap_horizontally():
    feet = ANCHORS + [[0.01, -0.02, 0.005], [0, 0, 0], [0, 0, 0], [0, 0, 0]]
    follow = np.array([True, False, False, False])
    anchors, shift = reanchor(ANCHORS, ANCHORS, feet, follow, np.ones(4, dtype=bool), 0.5)
    np.testing.assert_allclose(anchors[0], ANCHORS[0] + [0.005, -0.01, 0.0])  # height left alone
    np.testing.assert_allclose(anchors[1:], ANCHORS[1:])
    np.testing.assert_allclose(shift, [0.005 / 4, -0.01 / 4, 0.0])  # the mean over 4 stance feet


def test_a_slip_shared_by_every_foot_leaves_the_set_points_where_they_were():
    # every foot slid 12 mm along -y: the legs let go of all four alike and the body correction
    # takes the move over, so anchor - commanded body (the set-points) does not change
    feet = ANCHORS + [0.0, -0.012, 0.0]
    everyone = np.ones(4, dtype=bool)
    correction = BodyCorrection(LowLevelConfig())
    anchors, shift = reanchor(ANCHORS, ANCHORS, feet, everyone, everyone, 0.2)
    correction.shift(shift)
    np.testing.assert_allclose(anchors - correction.position, ANCHORS)


def test_feet_that_do_not_follow_or_do_not_stand_are_left_alone():
    feet = ANCHORS + 0.01
    anchors, shift = reanchor(ANCHORS, ANCHORS, feet, np.zeros(4, dtype=bool),
                              np.ones(4, dtype=bool), 0.3)
    np.testing.assert_array_equal(anchors, ANCHORS)
    assert not shift.any()


def test_the_correction_shift_stays_within_its_bound():
    correction = BodyCorrection(LowLevelConfig(max_position_correction=0.01))
    correction.shift(np.array([0.02, -0.005, 0.0]))
    np.testing.assert_allclose(correction.position, [0.01, -0.005, 0.0])


# ---------------------------------------------------------------- on the robot, standing
class Slipped(Controller):
    """Stands on four feet after the front feet's anchors were put 15 mm to the left of where
    they stand -- their legs hold them as if they had slid 15 mm to the right. Records the body
    correction [m] and the front feet's gaps from their anchors [m] after ``STAND`` s."""

    STAND = 1.5  # [s]

    def step_phases(self, k):
        self.legs.anchor[:2, 1] += 0.015
        for _ in range(round(self.STAND / self.period)):
            yield from self.tick(*self.desired, None)
        self.correction = self.legs.correction.position.copy()
        self.gaps = np.hypot(*(self.est.feet[:2, :2] - self.legs.anchor[:2, :2]).T)
        return True


def _stand(follow_time: float | None) -> Slipped:
    return staged(Slipped, lowlevel=LowLevelConfig(anchor_follow_time=follow_time)).controller


def test_re_anchored_feet_stop_pulling_and_the_body_correction_stays_small():
    held, let_go = _stand(None), _stand(0.3)
    # held: the legs keep pulling the front feet toward their anchors, and the correction grows by
    # the mean of those pulls -- what a foot set down next would be moved by
    assert held.gaps.min() > 0.008
    assert abs(held.correction[1]) > 0.004
    # let go of: the anchors come to the feet and the correction gives the pull back
    assert let_go.gaps.max() < 0.002
    assert abs(let_go.correction[1]) < 0.5 * abs(held.correction[1])
    assert let_go.correction[1] == pytest.approx(0.0, abs=0.003)
