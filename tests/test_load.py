"""Stance load control (footfall.control.load): the shares of the weight and the height offsets."""

import numpy as np
import pytest

from footfall.control.controller import Controller
from footfall.control.load import load_held, load_offsets, load_shares, pressed
from footfall.control.lowlevel import LowLevelConfig
from scenes import staged

FEET = np.array([[0.1, 0.08], [0.1, -0.08], [-0.1, 0.08], [-0.1, -0.08]])  # [m] LF RF LH RH


def test_four_feet_around_the_centre_share_evenly():
    assert np.allclose(load_shares(FEET, [0.0, 0.0], np.ones(4)), 0.25)


@pytest.mark.parametrize("com", [[0.02, 0.01], [-0.03, 0.02], [0.0, -0.05]])
def test_shares_balance_the_moment_about_the_centre_of_mass(com):
    shares = load_shares(FEET, com, np.ones(4))
    assert shares.sum() == pytest.approx(1.0)
    assert np.allclose(shares @ (FEET - com), 0.0, atol=1e-12)
    assert (shares > 0).all()


def test_three_feet_carry_the_barycentric_coordinates_of_the_centre_of_mass():
    tri = FEET[[0, 1, 3]]
    weights = np.array([0.5, 0.2, 0.3])
    com = weights @ tri
    shares = load_shares(FEET, com, [1.0, 1.0, 0.0, 1.0])
    assert np.allclose(shares, [0.5, 0.2, 0.0, 0.3])


def test_a_leg_being_unloaded_carries_less_as_its_availability_falls():
    com = np.array([0.01, -0.01])  # inside the triangle without LH
    carried = [load_shares(FEET, com, [1.0, 1.0, a, 1.0])[2] for a in (1.0, 0.5, 0.1, 0.0)]
    assert carried[0] > carried[1] > carried[2] > carried[3] == 0.0


def test_a_leg_that_cannot_be_spared_keeps_its_part():
    com = np.array([-0.05, 0.05])  # outside the triangle without LH: LH must stay loaded
    shares = load_shares(FEET, com, [1.0, 1.0, 0.05, 1.0])
    assert shares[2] > 0.25
    assert shares.sum() == pytest.approx(1.0)
    assert (shares >= 0).all()


def test_a_centre_of_mass_outside_the_support_gives_the_nearest_shares_that_are_possible():
    shares = load_shares(FEET, [0.3, 0.0], [1.0, 1.0, 1.0, 1.0])
    assert (shares >= 0).all() and shares.sum() == pytest.approx(1.0)
    assert shares[:2].sum() > 0.9  # the front feet take it all


def test_no_available_foot_carries_nothing():
    assert not load_shares(FEET, [0.0, 0.0], np.zeros(4)).any()


def test_a_foot_carrying_too_much_goes_up_and_one_carrying_too_little_goes_down():
    shares = np.full(4, 0.25)
    measured = np.array([12.0, 4.0, 8.0, 8.0])  # [N]
    stance = np.ones(4, dtype=bool)
    out = load_offsets(np.zeros(4), measured, shares, stance, gain=1e-4, limit=0.01)
    assert out[0] > 0 > out[1]
    assert out[2] == out[3] == 0.0
    assert out.sum() == pytest.approx(0.0)  # the body height is left alone


def test_load_offsets_are_bounded_and_zero_for_legs_not_in_stance():
    stance = np.array([True, True, False, True])
    measured = np.array([30.0, 0.0, 5.0, 0.0])
    shares = load_shares(FEET, [0.0, 0.0], stance.astype(float))
    out = load_offsets(np.array([0.0, 0.0, 0.003, 0.0]), measured, shares, stance, gain=1.0,
                       limit=0.01)
    assert out[2] == 0.0
    assert np.abs(out).max() == pytest.approx(0.01)
    assert out[0] == pytest.approx(0.01)


def test_a_negative_force_reading_counts_as_no_load():
    shares = np.array([0.5, 0.5, 0.0, 0.0])
    stance = np.array([True, True, False, False])
    out = load_offsets(np.zeros(4), np.array([-3.0, 10.0, 0.0, 0.0]), shares, stance, 1e-3, 1.0)
    assert out[0] == pytest.approx(-5e-3)  # it carries 0 of its 5 N: down


def test_a_new_foot_short_of_its_load_is_pressed_down_a_step_at_a_time_to_the_depth():
    new = np.array([True, True, True, False])
    owed = np.full(4, 4.0)  # [N]
    measured = np.array([1.0, 6.0, 0.0, 0.0])  # LF short, RF loaded, LH short, RH not new
    offsets = np.array([0.0, 0.0, -0.0035, 0.0])
    out = pressed(offsets, new, measured, owed, step=0.001, depth=0.004)
    assert out[0] == pytest.approx(-0.001)  # one step down
    assert out[1] == 0.0  # carries what it is owed: left alone
    assert out[2] == pytest.approx(-0.004)  # no deeper than the depth
    assert out[3] == 0.0  # not new: the load control's alone
    again = pressed(np.array([-0.006, 0.0, 0.0, 0.0]), new, measured, owed, 0.001, 0.004)
    assert again[0] == -0.006  # an offset the load control already put lower is never raised


def test_the_offsets_are_held_while_a_stance_foot_set_down_lately_settles():
    stance = np.array([True, True, False, True])
    elapsed = np.array([0.5, 0.15, 0.01, 0.9])  # [s] leg 1 touched down 0.15 s ago
    assert load_held(stance, elapsed, 0.2)
    assert not load_held(stance, elapsed, 0.1)  # settled by then
    assert not load_held(stance, elapsed, 0.0)  # off
    # a leg that lifted lately (not in stance) holds nothing
    assert not load_held(stance, np.array([0.5, 0.3, 0.01, 0.9]), 0.2)


def test_pressing_leaves_its_arguments_alone():
    offsets = np.zeros(4)
    pressed(offsets, np.ones(4, dtype=bool), np.zeros(4), np.ones(4), 0.001, 0.004)
    assert not offsets.any()


# ---------------------------------------------------------------- on the robot, standing
class Wobbles(Controller):
    """Stands on four feet after the left front foot's target was set 4 mm into the ground:
    the LF-RH diagonal would carry the robot and the other diagonal next to nothing, as on
    uneven ground, for ``STAND`` s."""

    STAND = 1.0  # [s]

    def step_phases(self, k):
        self.legs.anchor[0, 2] -= 0.004
        for _ in range(round(self.STAND / self.period)):
            yield from self.tick(*self.desired, None)
        return True


def _stand(load_gain: float) -> np.ndarray:
    """The true vertical foot forces [N] at the end of the stand (the run ends there)."""
    return staged(Wobbles, lowlevel=LowLevelConfig(load_gain=load_gain)).sim.foot_forces(
        noise=False)[:, 2]


def test_load_control_spreads_the_weight_over_a_wobbling_stance():
    off, on = _stand(0.0), _stand(LowLevelConfig().load_gain or 0.002)
    # without it one diagonal (LF, RH) carries most of the weight
    assert off[0] + off[3] > 2.0 * (off[1] + off[2])
    # with it the feet share the weight evenly (the centre of mass is near the middle)
    assert on.min() > 0.6 * on.mean()
    assert abs(on.sum() - off.sum()) < 0.05 * off.sum()  # the same weight, shared out


def _shares_by_pseudo_inverse(feet_xy, com_xy, availability):
    """The definition of load_shares written with NumPy's pseudo-inverse (its first version)."""
    p = np.asarray(feet_xy, float) - np.asarray(com_xy, float)
    a = np.clip(np.asarray(availability, float), 0.0, 1.0)
    if not a.any():
        return np.zeros(a.shape)
    rows = np.vstack([np.ones(len(a)), p.T])

    def balanced(a):
        return a * (rows.T @ (np.linalg.pinv((rows * a) @ rows.T, rcond=1e-9) @ [1.0, 0.0, 0.0]))

    s = balanced(a)
    if s.min() < 0 and (a < 1).any():
        s = balanced((a > 0).astype(float))
    s = np.maximum(s, 0.0)
    return s / s.sum() if s.sum() > 0 else a / a.sum()


def test_the_compiled_shares_are_the_pseudo_inverse_ones_on_random_stances():
    # the kernel takes the Gram matrix's adjugate while it is well conditioned and the
    # pseudo-inverse otherwise: both branches, two to four feet, some on a line
    rng = np.random.default_rng(4)
    for i in range(3000):
        k = int(rng.choice([2, 3, 4]))
        feet = rng.normal(0.0, 0.1, (k, 2))
        if i % 5 == 0 and k >= 3:
            feet[2] = feet[0] + rng.uniform(-1, 2) * (feet[1] - feet[0])  # three on a line
        com = rng.normal(0.0, 0.05, 2)
        avail = rng.choice([0.0, 1.0, 0.5, rng.uniform()], k)
        np.testing.assert_allclose(load_shares(feet, com, avail),
                                   _shares_by_pseudo_inverse(feet, com, avail), rtol=0, atol=1e-9)
