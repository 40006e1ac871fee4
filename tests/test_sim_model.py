"""The MuJoCo robot model, its terrain and the simulation wrapper (footfall.sim)."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is first imported: headless rendering

import mujoco
import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import (
    body_to_world,
    forward_kinematics,
    inverse_kinematics,
    knee_position,
    rotation_matrix,
)
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.core.state import nominal_state
from footfall.sim.hfield import terrain_layout, terrain_surface
from footfall.sim.mjcf import TERRAIN_GEOM_GROUP, build_mjcf, compile_model
from footfall.sim.sensors import LEG_PARTS, Sensors
from footfall.sim.simulation import (
    PerturbationConfig,
    SimPerturbation,
    Simulation,
    bench_stepping,
)
from footfall.terrain.modules import make_module

R = LITTLEDOG
GRAVITY = 9.81  # [m/s^2] MuJoCo's default gravity


def _bumpy_map(res: float = 0.004) -> HeightMap:
    """A smooth bumpy map, flat (exactly 3 mm high) for x < 0.25 m so that some tiles are boxes."""
    x = 0.1 + np.arange(70) * res
    y = -0.08 + np.arange(45) * res
    envelope = np.clip((x - 0.25) / 0.05, 0.0, 1.0)[:, None] ** 2
    h = 0.003 + envelope * (0.02 * np.sin(x[:, None] / 0.05) * np.cos(y[None, :] / 0.07) + 0.02)
    return HeightMap(h, res, (0.1, -0.08))


def _ray_heights(model: mujoco.MjModel, xy: np.ndarray) -> np.ndarray:
    """Terrain height [m] under each point (n, 2): a vertical ray against the terrain geoms only."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    groups = np.zeros(6, np.uint8)
    groups[TERRAIN_GEOM_GROUP] = 1
    geom = np.zeros(1, np.int32)
    top = 1.0
    dist = [mujoco.mj_ray(model, data, np.array([p[0], p[1], top]), np.array([0.0, 0.0, -1.0]),
                          groups, 1, -1, geom) for p in xy]
    return top - np.array(dist)


def _world_feet(state) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return state.body_position, state.body_rpy, state.feet


def _flat_stance():
    flat = HeightMap(np.zeros((3, 3)), 1.0, (-1.0, -1.0))
    return nominal_state(flat, (0.0, 0.0), 0.0, "LF")


# ----------------------------------------------------------------------- model
def test_model_compiles_with_every_named_part_and_the_robot_mass():
    model = compile_model(R, None)
    names = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, i) for i in range(model.njnt)}
    assert {f"{leg}_{j}" for leg in LEG_NAMES for j in ("hip_roll", "hip_pitch", "knee")} < names
    assert model.nu == 12 and model.nq == 7 + 12
    sensors = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_SENSOR, i) for i in range(model.nsensor)}
    assert sensors == {f"{leg}_foot_force" for leg in LEG_NAMES} | {"imu_quat", "imu_gyro",
                                                                     "imu_accel"}
    assert model.body_mass.sum() == pytest.approx(R.total_mass, abs=1e-12)
    def body(name: str) -> float:
        return model.body_mass[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)]

    for leg in LEG_NAMES:
        assert body(f"{leg}_hip") == pytest.approx(R.hip_link_mass)
        assert body(f"{leg}_upper") == pytest.approx(R.upper_leg_mass)
        assert body(f"{leg}_lower") + body(f"{leg}_foot") == pytest.approx(R.lower_leg_mass)
    assert (model.body_inertia[1:] > 0).all()  # every link has an inertia from its shape


def test_joint_limits_actuators_and_friction_come_from_the_description():
    model = compile_model(R, None, friction=0.6)
    for leg in R.legs:
        for j, lim in zip(("hip_roll", "hip_pitch", "knee"), leg.limits):
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"{leg.name}_{j}")
            np.testing.assert_array_equal(model.jnt_range[jid], lim)
            aid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{leg.name}_{j}")
            np.testing.assert_array_equal(model.actuator_forcerange[aid],
                                          [-R.max_joint_torque, R.max_joint_torque])
            assert model.actuator_gainprm[aid, 0] == R.joint_kp
            np.testing.assert_array_equal(model.actuator_biasprm[aid, :3],
                                          [0.0, -R.joint_kp, -R.joint_kd])
        foot = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"{leg.name}_foot")
        assert model.geom_size[foot, 0] == R.foot_radius and model.geom_friction[foot, 0] == 0.6
    assert model.opt.timestep == pytest.approx(1.0 / R.servo_rate)
    assert model.opt.jacobian == mujoco.mjtJacobian.mjJAC_SPARSE  # faster while walking
    assert compile_model(R, None).geom_friction[foot, 0] == R.foot_friction


def test_mujoco_forward_kinematics_equals_the_closed_form():
    rng = np.random.default_rng(1)
    model = compile_model(R, None)
    data = mujoco.MjData(model)
    feet, knees = ([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"{leg}_{part}")
                    for leg in LEG_NAMES] for part in ("foot", "lower"))
    for _ in range(20):
        q = np.array([[rng.uniform(*lim) for lim in leg.limits] for leg in R.legs])
        pos, rpy = rng.uniform(-0.5, 0.5, 3), rng.uniform(-0.4, 0.4, 3)
        data.qpos[:3] = pos
        mujoco.mju_mat2Quat(data.qpos[3:7], rotation_matrix(rpy).ravel())
        data.qpos[7:] = q.ravel()
        mujoco.mj_kinematics(model, data)
        for k, leg in enumerate(R.legs):
            np.testing.assert_allclose(data.xpos[feet[k]],
                                       body_to_world(forward_kinematics(leg, q[k], R), pos, rpy),
                                       atol=1e-9)
            np.testing.assert_allclose(data.xpos[knees[k]],
                                       body_to_world(knee_position(leg, q[k], R), pos, rpy),
                                       atol=1e-9)


# --------------------------------------------------------------------- terrain
def test_terrain_heights_match_the_map_along_rays():
    hmap = _bumpy_map()
    model = compile_model(R, hmap)
    kinds = [t["kind"] for t in terrain_layout(hmap)]
    assert kinds.count("box") == 1 and "hfield" in kinds  # the flat end is one box
    rng = np.random.default_rng(2)
    (x0, x1, y0, y1), r = hmap.bounds, hmap.resolution
    xy = np.column_stack([rng.uniform(x0 + r, x1 - r, 400), rng.uniform(y0 + r, y1 - r, 400)])
    # MuJoCo's surface is planar triangles between the vertices, the map bilinear: they differ
    # by curvature * resolution^2 / 4 at most (3e-5 m here); at the vertices they coincide.
    np.testing.assert_allclose(_ray_heights(model, xy), hmap.height_at(xy), atol=1e-4)
    cells = np.array([[i, j] for i in range(1, 69, 3) for j in range(1, 44, 4)])  # off the rim
    np.testing.assert_allclose(_ray_heights(model, hmap.index_to_position(cells)),
                               hmap.heights[cells[:, 0], cells[:, 1]], atol=1e-7)


def test_terrain_registration_moves_the_map_rigidly_about_its_centre():
    hmap = _bumpy_map()
    offset, yaw = np.array([0.003, -0.002, 0.001]), 0.005
    model = compile_model(R, hmap, terrain_offset=offset, terrain_yaw=yaw)
    centre = np.asarray(hmap.origin) + 0.5 * (np.array(hmap.shape) - 1) * hmap.resolution
    rng = np.random.default_rng(3)
    x0, x1, y0, y1 = hmap.bounds
    xy = np.column_stack([rng.uniform(x0 + 0.01, x1 - 0.01, 300),
                          rng.uniform(y0 + 0.01, y1 - 0.01, 300)])
    rot = rotation_matrix(np.array([0.0, 0.0, yaw]))[:2, :2]
    in_map = centre + (xy - centre - offset[:2]) @ rot  # R^T (world - c - offset)
    heights = _ray_heights(model, xy)
    np.testing.assert_allclose(heights, hmap.height_at(in_map) + offset[2], atol=1e-4)
    assert np.abs(heights - hmap.height_at(xy)).max() > 1e-3  # the registration error shows


def test_fine_maps_are_decimated_to_2mm_keeping_exact_vertex_heights():
    rng = np.random.default_rng(4)
    h = np.cumsum(np.cumsum(rng.normal(0, 1e-4, (81, 61)), axis=0), axis=1)  # rough, no flat tile
    hmap = HeightMap(h, 0.001, (0.2, -0.03))
    tiles = terrain_layout(hmap)
    assert all(t["kind"] == "hfield" for t in tiles)
    np.testing.assert_allclose([2 * t["size"][0] / (t["ncol"] - 1) for t in tiles], 0.002)
    np.testing.assert_allclose([2 * t["size"][1] / (t["nrow"] - 1) for t in tiles], 0.002)
    model = compile_model(R, hmap)
    cells = np.array([[i, j] for i in range(2, 79, 4) for j in range(2, 59, 6)])  # vertices
    np.testing.assert_allclose(_ray_heights(model, hmap.index_to_position(cells)),
                               h[cells[:, 0], cells[:, 1]], atol=1e-7)
    full = compile_model(R, hmap, max_spacing=None)
    assert full.hfield_ncol.sum() > model.hfield_ncol.sum()


def test_nan_cells_become_holes_down_to_the_lowest_valid_height():
    h = np.full((40, 30), 0.05)
    h[0, 0] = 0.01  # the lowest valid cell
    h[15:25, 10:20] = np.nan
    hmap = HeightMap(h, 0.004, (0.0, 0.0))
    np.testing.assert_array_equal(terrain_surface(hmap)[20, 15], 0.01)
    model = compile_model(R, hmap)
    assert _ray_heights(model, hmap.index_to_position(np.array([[20, 15]])))[0] == \
        pytest.approx(0.01, abs=1e-7)
    assert _ray_heights(model, hmap.index_to_position(np.array([[5, 25]])))[0] == \
        pytest.approx(0.05, abs=1e-7)


def test_without_a_map_the_ground_is_the_plane_z0():
    model = compile_model(R, None)
    np.testing.assert_allclose(_ray_heights(model, np.array([[0.3, -2.0], [5.0, 1.0]])), 0.0,
                               atol=1e-12)


# -------------------------------------------------------------------- dynamics
def test_reset_places_the_trunk_exactly_and_at_rest():
    sim = Simulation(R, None)
    pos, rpy = np.array([0.1, -0.2, 0.3]), np.array([0.1, -0.2, 0.7])
    q = np.array([[leg.limits[0][0] / 2, 0.3 * (1 if leg.knee_forward else -1),
                   0.8 * (1 if leg.knee_forward else -1)] for leg in R.legs])
    sim.reset(pos, rpy, q)
    got_pos, got_rpy = sim.body_pose()
    np.testing.assert_allclose(got_pos, pos, atol=1e-12)
    np.testing.assert_allclose(got_rpy, rpy, atol=1e-12)
    np.testing.assert_array_equal(sim.joint_angles(), q)
    assert not sim.joint_velocities().any() and not np.concatenate(sim.body_velocity()).any()
    np.testing.assert_allclose(sim.foot_positions(),
                               body_to_world(np.stack([forward_kinematics(leg, q[k], R)
                                                       for k, leg in enumerate(R.legs)]),
                                             pos, rpy), atol=1e-12)
    assert sim.time == 0.0


def test_robot_stands_still_for_5_seconds_on_flat_ground():
    sim = Simulation(R, None)
    state = _flat_stance()
    q = sim.stand(*_world_feet(state))
    np.testing.assert_allclose(sim.foot_positions()[:, 2], R.foot_radius, atol=1e-12)
    sim.advance(0.5)  # the servo takes up the weight: the body sags by its compliance
    p0, r0 = sim.body_pose()
    assert abs(p0[2] - state.body_position[2]) < 0.005
    sim.advance(4.5)
    p1, r1 = sim.body_pose()
    assert sim.time == pytest.approx(5.0)
    assert np.linalg.norm(p1 - p0) < 0.001 and np.abs(r1 - r0).max() < 0.005
    assert sim.foot_contact().all() and not sim.trunk_touches_terrain()
    assert not sim.touches_terrain("knee").any() and not sim.touches_terrain("shin").any()
    np.testing.assert_allclose(sim.joint_angles(), q, atol=0.05)
    fk = np.stack([forward_kinematics(leg, sim.joint_angles()[k], R) for k, leg in enumerate(R.legs)])
    np.testing.assert_allclose(sim.foot_positions(), body_to_world(fk, p1, r1), atol=1e-12)
    assert np.abs(np.concatenate(sim.body_velocity())).max() < 1e-3
    com = sim.centre_of_mass()  # the stance is symmetric: the centre of mass is above the origin
    np.testing.assert_allclose(com[:2], p1[:2], atol=1e-3)
    assert com[2] < p1[2]  # the legs hang below the trunk
    forces = sim.foot_forces()
    feet_weight = 4 * R.foot_mass * GRAVITY  # below the sensors
    assert forces[:, 2].sum() == pytest.approx(R.total_mass * GRAVITY - feet_weight, rel=1e-3)
    imu = sim.imu()
    np.testing.assert_allclose(imu["accel"], [0.0, 0.0, GRAVITY], atol=1e-3)
    np.testing.assert_allclose(np.abs(imu["quat"]), [1.0, 0.0, 0.0, 0.0], atol=1e-3)


def test_robot_stands_on_a_rocky_module():
    hmap = make_module("rocky", 0.3, seed=7)
    sim = Simulation(R, hmap)
    state = nominal_state(hmap, (0.3, 0.0), 0.0, "LF")
    sim.stand(*_world_feet(state))
    sim.advance(0.5)
    p0, _ = sim.body_pose()
    feet0 = sim.foot_positions()
    sim.advance(1.5)
    assert np.linalg.norm(sim.body_pose()[0] - p0) < 0.002
    assert np.linalg.norm(sim.foot_positions() - feet0, axis=1).max() < 0.002
    assert sim.foot_contact().all() and not sim.trunk_touches_terrain()


def test_each_leg_reaches_ik_targets_across_its_workspace_within_2mm():
    # Test rig: the trunk is welded in the air, gravity on; the legs carry their own weight.
    rng = np.random.default_rng(5)
    sim = Simulation(R, None, fixed_base=True)
    sim.reset(q=np.zeros((4, 3)))
    lo = np.array([[lim[0] for lim in leg.limits] for leg in R.legs])
    hi = np.array([[lim[1] for lim in leg.limits] for leg in R.legs])
    worst = 0.0
    for _ in range(8):
        targets = np.empty((4, 3))
        for k, leg in enumerate(R.legs):
            while True:  # a random reachable foot position below the hip
                q = rng.uniform(lo[k] + 0.1 * (hi[k] - lo[k]), hi[k] - 0.1 * (hi[k] - lo[k]))
                targets[k] = forward_kinematics(leg, q, R)
                if targets[k, 2] < -0.06:
                    break
        q = np.stack([inverse_kinematics(leg, targets[k], R)[0] for k, leg in enumerate(R.legs)])
        sim.set_targets(q)
        sim.advance(1.0)
        pos, rpy = sim.body_pose()
        error = np.linalg.norm(sim.foot_positions() - body_to_world(targets, pos, rpy), axis=1)
        worst = max(worst, error.max())
    assert worst < 0.002


def test_velocity_set_points_feed_the_servo_damping_term():
    sim = Simulation(R, None, fixed_base=True)
    sim.reset(q=np.zeros((4, 3)))
    qd = np.full((4, 3), 0.5)
    sim.set_targets(np.zeros((4, 3)), qd)
    np.testing.assert_allclose(sim.data.ctrl.reshape(4, 3), qd * R.joint_kd / R.joint_kp)
    sim.step()
    # at rest on the set-point, the servo pushes with kd * qd (before gravity moves anything)
    np.testing.assert_allclose(sim.joint_torques(), R.joint_kd * qd, atol=1e-9)


# ---------------------------------------------------------------- perturbation
def test_perturbation_sampling_is_deterministic_and_within_its_ranges():
    config = PerturbationConfig()
    a, b = SimPerturbation.sample(np.random.default_rng(9), config), SimPerturbation.sample(9)
    assert a == b and a != SimPerturbation.sample(10)
    draws = [SimPerturbation.sample(s, config) for s in range(50)]
    off = np.array([d.terrain_offset for d in draws])
    assert np.abs(off[:, :2]).max() <= config.terrain_shift
    assert np.abs(off[:, 2]).max() <= config.terrain_lift
    assert max(abs(d.terrain_yaw) for d in draws) <= config.terrain_yaw
    assert all(abs(d.friction_scale - 1) <= config.friction for d in draws)
    assert np.abs(np.array([d.start_rpy for d in draws])).max() <= config.start_tilt
    assert np.abs(off).max() > 0.5 * config.terrain_shift  # the draws do spread
    assert SimPerturbation.none().terrain_offset == (0.0, 0.0, 0.0)
    assert SimPerturbation.none().to_dict()["friction_scale"] == 1.0


def test_a_perturbation_moves_the_terrain_and_changes_friction():
    hmap = _bumpy_map()
    p = SimPerturbation(terrain_offset=(0.002, 0.0, 0.001), friction_scale=0.9)
    sim = Simulation(R, hmap, perturbation=p)
    foot = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_GEOM, "LF_foot")
    assert sim.model.geom_friction[foot, 0] == pytest.approx(0.9 * R.foot_friction)
    cell = hmap.index_to_position(np.array([[5, 5]]))  # on the flat end
    assert _ray_heights(sim.model, cell)[0] == pytest.approx(hmap.heights[5, 5] + 0.001, abs=1e-9)


def test_same_seed_same_run_and_another_seed_another():
    hmap = _bumpy_map()
    state = nominal_state(hmap, (0.2, 0.0), 0.0, "LF")

    def run(seed: int) -> np.ndarray:
        sim = Simulation.from_seed(R, hmap, seed)
        q = sim.stand(*_world_feet(state))
        readings = []
        for k in range(20):  # a 100 Hz controller nodding the body
            sim.set_targets(q + 0.05 * np.sin(0.3 * k), np.zeros((4, 3)))
            sim.advance(0.01)
            imu = sim.imu()
            readings.append(np.concatenate([sim.data.qpos, sim.foot_forces().ravel(),
                                            imu["quat"], imu["gyro"], imu["accel"]]))
        return np.array(readings)

    first = run(11)
    np.testing.assert_array_equal(first, run(11))
    assert np.abs(first - run(12)).max() > 1e-4


def test_sensor_noise_has_the_configured_spread():
    p = SimPerturbation(force_noise=0.2, gyro_noise=0.01, accel_noise=0.05)
    sim = Simulation(R, None, perturbation=p, rng=3)
    sim.stand(*_world_feet(_flat_stance()))
    sim.advance(0.5)
    forces = np.array([sim.foot_forces("sensor") for _ in range(400)])
    gyros = np.array([sim.imu()["gyro"] for _ in range(400)])
    assert forces.std(axis=0).mean() == pytest.approx(0.2, rel=0.1)
    assert gyros.std(axis=0).mean() == pytest.approx(0.01, rel=0.1)


def test_sensors_read_the_simulation_they_were_given_and_draw_from_their_own_generator():
    p = SimPerturbation(force_noise=0.2, gyro_noise=0.01, accel_noise=0.05, orientation_noise=0.01)
    sims = [Simulation(R, None, perturbation=p, rng=5) for _ in range(2)]
    for sim in sims:
        sim.stand(*_world_feet(_flat_stance()))
        sim.advance(0.1)
    a, b = sims
    # The simulation's readings are its sensors' readings: the same noise, drawn in turn.
    np.testing.assert_array_equal(a.foot_forces(), b.sensors.foot_forces())
    imu_a, imu_b = a.imu(), b.sensors.imu()
    for key in ("quat", "gyro", "accel"):
        np.testing.assert_array_equal(imu_a[key], imu_b[key])
    # A separate Sensors on the same state with the same seed reads the same; the noiseless
    # reading is the MuJoCo sensor itself.
    twin = Sensors(a.model, a.data, p, np.random.default_rng(7))
    again = Sensors(a.model, a.data, p, np.random.default_rng(7))
    np.testing.assert_array_equal(twin.foot_forces("sensor"), again.foot_forces("sensor"))
    quiet = Sensors(a.model, a.data, SimPerturbation(), np.random.default_rng(0))
    assert quiet.foot_forces("world")[:, 2].sum() == pytest.approx(
        R.total_mass * GRAVITY - 4 * R.foot_mass * GRAVITY, rel=0.02)
    np.testing.assert_array_equal(quiet.touches_terrain("foot"), a.foot_contact())
    assert quiet.trunk_touches_terrain() is False
    assert set(LEG_PARTS) == {"foot", "knee", "shin"}
    with pytest.raises(FootfallError, match="unknown leg part 'arm'"):
        quiet.touches_terrain("arm")


# ------------------------------------------------------------------ utilities
def test_bench_stepping_leaves_the_simulation_untouched():
    sim = Simulation(R, None)
    sim.stand(*_world_feet(_flat_stance()))
    qpos = sim.data.qpos.copy()
    result = bench_stepping(sim, 0.05)
    assert result["steps"] == 20 and result["steps_per_second"] > 0
    assert result["real_time_factor"] == pytest.approx(result["steps_per_second"] * sim.timestep)
    np.testing.assert_array_equal(sim.data.qpos, qpos)
    assert sim.time == 0.0


def test_render_returns_an_image_of_the_robot():
    sim = Simulation(R, _bumpy_map())
    sim.stand(*_world_feet(nominal_state(sim.hmap, (0.2, 0.0), 0.0, "LF")))
    try:
        image = sim.render(width=64, height=48)
    except (mujoco.FatalError, RuntimeError) as exc:  # no OpenGL on this machine
        pytest.skip(f"no rendering backend: {exc}")
    finally:
        sim.close()
    assert image.shape == (48, 64, 3) and image.dtype == np.uint8
    assert image.std() > 5  # not a blank frame


def test_bad_input_raises_footfall_error():
    sim = Simulation(R, None)
    with pytest.raises(FootfallError, match="shape"):
        sim.set_targets(np.zeros((4, 2)))
    with pytest.raises(FootfallError, match="finite"):
        sim.set_targets(np.full((4, 3), np.nan))
    with pytest.raises(FootfallError, match="shape"):
        sim.set_targets(np.zeros((4, 3)), np.zeros(3))
    with pytest.raises(FootfallError, match="body position"):
        sim.reset(q=np.zeros((4, 3)))
    with pytest.raises(FootfallError, match="shape"):
        sim.reset(np.zeros(2), np.zeros(3))
    with pytest.raises(FootfallError, match="out of reach"):
        sim.stand(np.array([0.0, 0.0, 0.5]), np.zeros(3), _flat_stance().feet)
    with pytest.raises(FootfallError, match="whole number"):
        sim.advance(0.001)
    with pytest.raises(FootfallError, match="integer"):
        sim.step(0)
    with pytest.raises(FootfallError, match="frame"):
        sim.foot_forces("body")
    with pytest.raises(FootfallError, match="part"):
        sim.touches_terrain("arm")
    with pytest.raises(FootfallError, match="camera"):
        sim.render(camera="nope")
    with pytest.raises(FootfallError, match="seed"):
        Simulation.from_seed(R, None, -1)
    with pytest.raises(FootfallError, match="friction_scale"):
        SimPerturbation(friction_scale=0.0)
    with pytest.raises(FootfallError, match="terrain_offset"):
        SimPerturbation(terrain_offset=(0.0, np.nan, 0.0))
    with pytest.raises(FootfallError, match="friction"):
        PerturbationConfig(friction=1.5)
    with pytest.raises(FootfallError, match="HeightMap"):
        build_mjcf(R, np.zeros((3, 3)))
    with pytest.raises(FootfallError, match="terrain_offset"):
        compile_model(R, _bumpy_map(), terrain_offset=(0.0, 0.0))
    with pytest.raises(FootfallError, match="terrain_yaw"):
        compile_model(R, _bumpy_map(), terrain_yaw=float("nan"))
    with pytest.raises(FootfallError, match="friction"):
        compile_model(R, None, friction=-1.0)
    with pytest.raises(FootfallError, match="max_spacing"):
        compile_model(R, _bumpy_map(), max_spacing=0.0)
    with pytest.raises(FootfallError, match="foot_mass"):
        RobotDescription(foot_mass=1.0)
    fixed = Simulation(R, None, fixed_base=True)
    with pytest.raises(FootfallError, match="fixed-base"):
        fixed.reset(np.zeros(3), np.zeros(3), np.zeros((4, 3)))
    with pytest.raises(FootfallError, match="fixed-base"):
        fixed.stand(np.zeros(3), np.zeros(3), np.zeros((4, 3)))
