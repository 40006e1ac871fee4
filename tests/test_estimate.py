"""The controller's view of its body from encoders and motion capture
(footfall.control.estimate, footfall.core.kinematics, footfall.core.mass), against the
simulator's own values."""

import numpy as np

from footfall.control.estimate import BodyEstimate
from footfall.control.measurements import Measurements
from footfall.core.kinematics import legs_forward_kinematics, legs_jacobians
from footfall.core.mass import centre_of_mass, leg_mass_points, leg_masses
from footfall.core.robot import LEG_NAMES, LITTLEDOG
from footfall.sim.simulation import Simulation

R = LITTLEDOG
AGREE = 1e-12  # [m], [m/rad], [N]: rounding, not modelling


def _random_states(sim: Simulation, n: int, seed: int):
    """The simulated robot in ``n`` random states: joints anywhere within their limits, the body
    anywhere and tilted, moving (a few servo periods after a jump of its set-points, so that
    the feet's force sensors read the feet's inertia)."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = np.array([[rng.uniform(*lim) for lim in leg.limits] for leg in R.legs])
        sim.reset(rng.uniform(-1.0, 1.0, 3) + [0, 0, 1.5], rng.uniform(-0.8, 0.8, 3), q)
        sim.set_targets(q + rng.normal(0.0, 0.1, (4, 3)))
        sim.step(3)
        position, rpy = sim.body_pose()
        yield Measurements(sim.time, sim.joint_angles(), position, rpy,
                           sim.foot_forces(frame="sensor", noise=False))


def test_feet_centre_of_mass_jacobians_and_forces_agree_with_the_simulator():
    sim = Simulation(R, None)
    moved = 0.0
    for m in _random_states(sim, 100, 3):
        est = BodyEstimate(m, R)
        np.testing.assert_allclose(est.feet, sim.foot_positions(), rtol=0, atol=AGREE)
        np.testing.assert_allclose(est.com, sim.centre_of_mass(), rtol=0, atol=AGREE)
        np.testing.assert_allclose(est.jacobians(), sim.foot_jacobians(), rtol=0, atol=AGREE)
        np.testing.assert_allclose(est.forces(), sim.foot_forces(noise=False), rtol=0,
                                   atol=AGREE)
        np.testing.assert_allclose(centre_of_mass(R, m.joint_angles, *est.pose),
                                   sim.centre_of_mass(), rtol=0, atol=AGREE)
        moved = max(moved, float(np.abs(m.foot_forces).max()))
    assert moved > 0.01  # the forces compared were not all zero


def test_the_masses_sit_where_the_simulators_model_puts_them():
    import mujoco

    sim = Simulation(R, None)
    model, data = sim.model, sim.data
    q = np.array([[0.2, -0.5, 1.1], [-0.1, -0.3, 0.9], [0.1, 0.4, -1.0], [-0.2, 0.6, -1.2]])
    sim.reset(np.zeros(3), np.zeros(3), q)
    points = leg_mass_points(R, q)  # body frame; the body is at the origin, level
    for k, leg in enumerate(LEG_NAMES):
        for part, body in enumerate(("hip", "upper", "lower", "foot")):
            i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{leg}_{body}")
            assert model.body_mass[i] == leg_masses(R)[part]
            np.testing.assert_allclose(data.xipos[i], points[k, part], rtol=0, atol=AGREE)


def test_jacobians_are_the_derivatives_of_the_forward_kinematics():
    rng = np.random.default_rng(8)
    q = np.array([[rng.uniform(*lim) for lim in leg.limits] for leg in R.legs])
    jac = legs_jacobians(R, q)
    eps = 1e-6  # [rad]
    for j in range(3):
        step = np.zeros((4, 3))
        step[:, j] = eps
        slope = (legs_forward_kinematics(R, q + step) - legs_forward_kinematics(R, q - step)) / (
            2 * eps)
        np.testing.assert_allclose(jac[:, :, j], slope, rtol=0, atol=1e-9)


def test_the_controllers_fast_path_is_the_kinematics_of_core():
    from footfall.control.estimate import body_jacobians, body_points
    from footfall.core.mass import body_centre_of_mass

    rng = np.random.default_rng(2)
    for _ in range(200):
        q = np.array([[rng.uniform(*lim) for lim in leg.limits] for leg in R.legs])
        feet, com = body_points(R, q)
        np.testing.assert_allclose(feet, legs_forward_kinematics(R, q), rtol=0, atol=1e-15)
        np.testing.assert_allclose(com, body_centre_of_mass(R, q), rtol=0, atol=1e-15)
        np.testing.assert_allclose(body_jacobians(R, q), legs_jacobians(R, q), rtol=0,
                                   atol=1e-15)
