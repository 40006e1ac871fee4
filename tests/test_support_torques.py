"""The weight carried by feed-forward joint torques (footfall.control.load.support_torques,
LowLevelConfig.support_feedforward): the foot Jacobians, the sign, and the sag they take away."""

import mujoco
import numpy as np
import pytest

from footfall.control.controller import Controller
from footfall.control.load import support_torques
from footfall.control.lowlevel import LowLevelConfig
from footfall.core.robot import LITTLEDOG
from footfall.sim.episode import Walk
from footfall.sim.simulation import Simulation
from scenes import staged

R = LITTLEDOG
Q = np.array([[0.1, -0.5, 1.1], [-0.05, -0.7, 1.3], [0.08, 0.6, -1.2], [0.0, 0.5, -1.0]])  # [rad]


def test_support_torques_are_minus_the_jacobian_transpose_of_the_vertical_force():
    rng = np.random.default_rng(3)
    jac = rng.normal(size=(4, 3, 3))
    forces = np.array([6.0, 0.0, 7.5, 2.0])  # [N], RF a swing leg
    tau = support_torques(jac, forces)
    for i in range(4):
        np.testing.assert_allclose(tau[i], -jac[i].T @ np.array([0.0, 0.0, forces[i]]))
    assert not tau[1].any()


def test_foot_jacobians_match_finite_differences_of_the_foot_positions():
    sim = Simulation(R, None, fixed_base=True)
    sim.reset(q=Q)
    jac = sim.foot_jacobians()
    eps = 1e-6  # [rad]
    for leg in range(4):
        for j in range(3):
            moved = Q.copy()
            moved[leg, j] += eps
            sim.reset(q=moved)
            plus = sim.foot_positions()[leg]
            moved[leg, j] -= 2 * eps
            sim.reset(q=moved)
            minus = sim.foot_positions()[leg]
            np.testing.assert_allclose(jac[leg, :, j], (plus - minus) / (2 * eps), atol=1e-7)


class Stands(Controller):
    """Stands 1 s on flat ground."""

    def step_phases(self, k):
        for _ in range(100):
            yield from self.tick(*self.desired, None)
        return True


def _standing(feedforward: float) -> Walk:
    """A walk that stood 1 s on flat ground, with what its servos and feet did at the end (the
    run ends there): ``sag`` (4, 3) [rad] the servos' errors, ``torques`` (4, 3) [N m], the true
    foot ``forces`` (4, 3) [N] and the foot Jacobians ``jac`` (4, 3, 3) [m/rad]."""
    run = staged(Stands, lowlevel=LowLevelConfig(support_feedforward=feedforward))
    sim = run.sim
    run.sag = np.abs(run.controller.legs.q - sim.joint_angles())
    run.torques = sim.joint_torques().copy()
    run.forces = sim.foot_forces(noise=False)
    run.jac = sim.foot_jacobians()
    return run


def test_the_servos_of_a_standing_robot_carry_minus_j_transpose_of_the_foot_forces():
    # the sign and frame of the Jacobians: at rest the servo torques balance the ground forces
    # (the legs' own weight, a few hundredths of a newton metre, aside)
    run = _standing(0.0)
    balance = -np.einsum("kij,ki->kj", run.jac, run.forces)
    np.testing.assert_allclose(run.torques, balance, atol=0.08)
    assert np.abs(run.torques).max() > 0.15  # the test is not trivially met by zero torques


def test_fed_forward_support_torques_take_the_sag_off_the_servos():
    without, full = _standing(0.0), _standing(1.0)
    # without them each loaded joint stands off its set-point by torque / kp
    print("servo errors [rad] without:", without.sag.round(4), "with:", full.sag.round(4))
    assert without.sag.max() > 0.004
    assert full.sag.sum() < 0.5 * without.sag.sum()
    # the weight is the same, carried either way
    assert full.forces[:, 2].sum() == pytest.approx(without.forces[:, 2].sum(), rel=0.05)


def test_foot_jacobians_need_no_work_array_of_the_caller():
    sim = Simulation(R, None, fixed_base=True)
    sim.reset(q=Q)
    first = sim.foot_jacobians()
    mujoco.mj_forward(sim.model, sim.data)
    np.testing.assert_array_equal(first, sim.foot_jacobians())
