"""The reflexes' detectors and choices, as pure functions of measured arrays."""

import numpy as np
import pytest

from footfall.control.cog import incircle
from footfall.control.reflexes import (
    REFLEXES,
    ReflexConfig,
    com_in_triangle,
    gate_step,
    next_best_candidate,
    slipped,
    tilt_error,
)
from footfall.core.errors import FootfallError

DEFAULT_ON = ("lift_off_gate", "touchdown_check", "tilt_reflex")  # the rest measured worse
TRIANGLE = np.array([[0.1, 0.08], [-0.1, 0.08], [0.1, -0.08]])


def test_the_gate_opens_only_with_the_centre_of_mass_inside_by_the_margin():
    centre, radius = incircle(TRIANGLE)
    assert com_in_triangle(centre, TRIANGLE, 0.9 * radius)
    assert not com_in_triangle(centre, TRIANGLE, 1.1 * radius)
    assert not com_in_triangle(np.array([-0.05, -0.05]), TRIANGLE, 0.0)  # outside


def test_waiting_at_the_gate_moves_the_body_toward_the_incentre_at_its_speed():
    centre, _ = incircle(TRIANGLE)
    desired = np.array([-0.06, -0.04])
    com = desired + [0.004, 0.0]  # the centre of mass sits 4 mm ahead of the body origin
    nxt = gate_step(com, desired, TRIANGLE, speed=0.05, period=0.01)
    assert np.hypot(*(nxt - desired)) == pytest.approx(0.0005)
    goal = centre - [0.004, 0.0]
    assert np.hypot(*(goal - nxt)) < np.hypot(*(goal - desired))
    # close enough: it goes all the way
    np.testing.assert_allclose(gate_step(goal + [0.004, 1e-4], goal + [0.0, 1e-4], TRIANGLE,
                                         0.05, 0.01), goal)


def test_a_loaded_stance_foot_far_from_its_target_has_slipped():
    targets = np.zeros((4, 2))
    feet = np.array([[0.013, 0.0], [0.0, 0.011], [0.02, 0.02], [0.0, 0.0]])
    loaded = np.array([True, True, False, True])
    assert slipped(feet, targets, loaded, 0.012).tolist() == [True, False, False, False]


def test_tilt_error_is_the_larger_of_roll_and_pitch_error_and_wraps():
    assert tilt_error(np.array([0.1, -0.2, 3.0]), np.array([0.0, 0.0, -3.0])) \
        == pytest.approx(0.2)
    assert tilt_error(np.array([np.pi - 0.01, 0.0, 0.0]),
                      np.array([-np.pi + 0.01, 0.0, 0.0])) == pytest.approx(0.02)


def test_the_next_best_candidate_keeps_away_from_every_spot_tried():
    cand = np.array([[0.0, 0.0, 0.0], [0.005, 0.0, 0.0], [0.03, 0.0, 0.0], [0.0, 0.05, 0.0]])
    score = np.array([5.0, 4.0, 3.0, np.nan])
    assert next_best_candidate(cand, score, np.array([[0.0, 0.0]]), 0.012) == 2
    assert next_best_candidate(cand, score, np.array([[0.0, 0.0], [0.03, 0.0]]), 0.012) is None
    assert next_best_candidate(cand, score, np.array([[1.0, 1.0, 0.0]]), 0.012) == 0


def test_each_reflex_switches_off_alone():
    base = ReflexConfig()
    assert [name for name in REFLEXES if getattr(base, name)] == list(DEFAULT_ON)
    for name in DEFAULT_ON:
        off = base.without(name)
        assert [getattr(off, n) for n in REFLEXES] == [n in DEFAULT_ON and n != name
                                                       for n in REFLEXES]
    with pytest.raises(ValueError, match="unknown reflex"):
        base.without("sneeze")
    with pytest.raises(FootfallError, match="slip_distance"):
        ReflexConfig(slip_distance=0.0)
