"""The simulated robot: MuJoCo physics behind the interface of the real LittleDog testbed.

A :class:`Simulation` holds a compiled model (see :mod:`footfall.sim.mjcf`)
and its state. The controller talks to it as to the robot: joint set-points
in (at 100 Hz), the 400 Hz PD servo runs inside the physics step, and out
come the true body pose (the simulator stands in for motion capture), joint
angles, foot force sensors and an IMU, the last two with seeded noise
(:mod:`footfall.sim.sensors`).
A :class:`SimPerturbation` makes runs differ as real runs do; the same seed
gives the same run, bit for bit.

Timing of the readings: poses, foot positions and joint angles and
velocities are those after the last physics step; the sensors and the
contact list are those MuJoCo computed during that step, from its starting
state -- a sample read out one servo period (2.5 ms) late.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass
from typing import Self

import mujoco
import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import inverse_kinematics, rotation_matrix, world_to_body
from footfall.core.params import Params, at_least, param, within
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.sim.foot_pads import BallSurface, FootPads
from footfall.sim.mjcf import (
    JOINTS,
    MAX_HFIELD_SPACING,
    compile_model,
    registration_centre,
    terrain_surface,
)
from footfall.sim.sensors import LEG_PARTS, Sensors, model_ids

__all__ = ["LEG_PARTS", "PHYSICS_STATE", "PerturbationConfig", "SimPerturbation", "Simulation", "bench_stepping"]


PHYSICS_STATE = mujoco.mjtState.mjSTATE_INTEGRATION  # what MuJoCo's next step depends on: time,
# positions, velocities, controls, mocap poses and the constraint solver's warm start


# ----------------------------------------------------------------- perturbation
@dataclass(frozen=True)
class PerturbationConfig(Params):
    """How much runs differ from one another: the ranges :meth:`SimPerturbation.sample` draws from.

    Bounded errors are drawn uniformly in ``[-limit, +limit]`` (independently
    per axis); sensor noise is zero-mean Gaussian, fresh at every reading.
    The defaults are those of a motion-capture-registered LittleDog testbed.
    """

    terrain_shift: float = param(0.003, unit="m", range=at_least(0),
                                 doc="terrain registration error along x and y (a few mm)")
    terrain_lift: float = param(0.001, unit="m", range=at_least(0),
                                doc="terrain registration error along z")
    terrain_yaw: float = param(math.radians(0.3), unit="rad", range=at_least(0),
                               doc="terrain registration error about z")
    friction: float = param(0.15, unit="-", range=within(0, 1, high_open=True),
                            doc="relative friction error: the scale is uniform in 1 +- this")
    start_shift: float = param(0.005, unit="m", range=at_least(0),
                               doc="error of the start body position, per axis")
    start_tilt: float = param(math.radians(1.0), unit="rad", range=at_least(0),
                              doc="error of the start roll, pitch and yaw")
    force_noise: float = param(0.1, unit="N", range=at_least(0),
                               doc="std of each foot force sensor axis")
    gyro_noise: float = param(0.005, unit="rad/s", range=at_least(0),
                              doc="std of each gyro axis")
    accel_noise: float = param(0.05, unit="m/s^2", range=at_least(0),
                               doc="std of each accelerometer axis")
    orientation_noise: float = param(math.radians(0.1), unit="rad", range=at_least(0),
                                     doc="std of the IMU orientation, per axis")


@dataclass(frozen=True)
class SimPerturbation:
    """One run's deviations from the nominal testbed.

    The terrain registration moves the simulated terrain relative to the
    map the planner sees (see :func:`footfall.sim.mjcf.terrain_layout`); the
    start offsets displace the trunk in :meth:`Simulation.stand` (the feet
    stay on their footholds); the noise levels apply to every sensor
    reading.
    """

    terrain_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m] terrain shift x, y, z
    terrain_yaw: float = 0.0  # [rad] terrain rotation about the map centre's vertical
    friction_scale: float = 1.0  # [-] factor on robot.foot_friction
    start_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m] start body position error
    start_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [rad] start roll/pitch/yaw error
    force_noise: float = 0.0  # [N] std of each foot force sensor axis
    gyro_noise: float = 0.0  # [rad/s] std of each gyro axis
    accel_noise: float = 0.0  # [m/s^2] std of each accelerometer axis
    orientation_noise: float = 0.0  # [rad] std of the IMU orientation error, per axis

    def __post_init__(self) -> None:
        for name in ("terrain_offset", "start_offset", "start_rpy"):
            v = np.asarray(getattr(self, name), dtype=np.float64)
            if v.shape != (3,) or not np.isfinite(v).all():
                raise FootfallError(f"perturbation: {name} must be 3 finite numbers")
            object.__setattr__(self, name, tuple(float(x) for x in v))
        for name in ("terrain_yaw", "friction_scale", "force_noise", "gyro_noise",
                     "accel_noise", "orientation_noise"):
            value = float(getattr(self, name))
            if not math.isfinite(value) or (name != "terrain_yaw" and value < 0):
                raise FootfallError(f"perturbation: {name} must be finite"
                                    + ("" if name == "terrain_yaw" else " and >= 0"))
            object.__setattr__(self, name, value)
        if self.friction_scale <= 0:
            raise FootfallError("perturbation: friction_scale must be > 0")

    @classmethod
    def none(cls) -> SimPerturbation:
        """The nominal testbed: exact registration, nominal friction, noiseless sensors."""
        return cls()

    @classmethod
    def sample(cls, rng: np.random.Generator | int,
               config: PerturbationConfig = PerturbationConfig()) -> SimPerturbation:
        """Draw one run's perturbation (bounded errors uniform, noise levels as configured)."""
        rng = np.random.default_rng(rng)
        c = config
        u = rng.uniform(-1.0, 1.0, size=11)
        return cls(terrain_offset=(u[0] * c.terrain_shift, u[1] * c.terrain_shift,
                                   u[2] * c.terrain_lift),
                   terrain_yaw=u[3] * c.terrain_yaw,
                   friction_scale=1.0 + u[4] * c.friction,
                   start_offset=tuple(u[5:8] * c.start_shift),
                   start_rpy=tuple(u[8:11] * c.start_tilt),
                   force_noise=c.force_noise, gyro_noise=c.gyro_noise,
                   accel_noise=c.accel_noise, orientation_noise=c.orientation_noise)

    def to_dict(self) -> dict:
        """The perturbation as plain JSON-serialisable data (to record next to a run)."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


# ------------------------------------------------------------------- validation
def _array(value, shape: tuple[int, ...], name: str) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.shape != shape:
        raise FootfallError(f"{name} must have shape {shape}, got {a.shape}")
    if not np.isfinite(a).all():
        raise FootfallError(f"{name} must be finite")
    return a


# ------------------------------------------------------------------- simulation
def foot_pads(model: mujoco.MjModel, hmap: HeightMap | None, robot: RobotDescription,
              perturbation: SimPerturbation, max_spacing: float | None) -> FootPads | None:
    """The feet's pads if ``model`` has them (the "pads" physics variant), else None.

    ``max_spacing`` [m] is the height field's largest cell, as the model was compiled with.
    """
    if hmap is None or mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY,
                                         f"{LEG_NAMES[0]}_pad") < 0:
        return None
    p = perturbation
    surface = BallSurface(terrain_surface(hmap), hmap, robot.foot_radius,
                          registration_centre(hmap, max_spacing), p.terrain_yaw,
                          np.asarray(p.terrain_offset, dtype=np.float64))
    return FootPads(model, surface, [f"{leg}_pad" for leg in LEG_NAMES])


class Simulation:
    """The robot on a terrain in MuJoCo, seen and driven as the real robot is.

    Parameters
    ----------
    robot : RobotDescription
        The robot (every number of the model comes from it).
    hmap : HeightMap or None
        The terrain as the planner knows it; None: flat ground at z = 0.
    perturbation : SimPerturbation or None
        This run's deviations from the nominal testbed; None: none.
    rng : np.random.Generator or int
        Source (or seed) of the sensor noise.
    fixed_base : bool
        Test rig: the trunk is welded in the air (see
        :func:`footfall.sim.mjcf.build_mjcf`) and only the legs move.
    max_spacing : float or None
        Coarsest height-field vertex spacing [m] (2 mm: a 1 mm map is
        decimated to every other cell, see
        :func:`footfall.sim.mjcf.terrain_layout`); None: full resolution.

    Attributes
    ----------
    model : mujoco.MjModel
    data : mujoco.MjData
    timestep : float
        Physics step = PD servo period [s].
    physics_cpu : float
        CPU time [s] this process has spent in MuJoCo's steps so far.
    sensors : Sensors
        The foot force sensors, the IMU and the contacts (also read through the
        methods of the same names here).
    """

    def __init__(self, robot: RobotDescription = LITTLEDOG, hmap: HeightMap | None = None, *,
                 perturbation: SimPerturbation | None = None,
                 rng: np.random.Generator | int = 0, fixed_base: bool = False,
                 max_spacing: float | None = MAX_HFIELD_SPACING) -> None:
        if perturbation is not None and not isinstance(perturbation, SimPerturbation):
            raise FootfallError("perturbation must be a SimPerturbation or None")
        self.robot = robot
        self.hmap = hmap
        self.perturbation = perturbation or SimPerturbation.none()
        self.fixed_base = bool(fixed_base)
        p = self.perturbation
        self.model = compile_model(robot, hmap, terrain_offset=p.terrain_offset,
                                   terrain_yaw=p.terrain_yaw,
                                   friction=robot.foot_friction * p.friction_scale,
                                   fixed_base=self.fixed_base, max_spacing=max_spacing)
        self.data = mujoco.MjData(self.model)
        self.timestep = float(self.model.opt.timestep)
        self.sensors = Sensors(self.model, self.data, self.perturbation, np.random.default_rng(rng))
        self._renderer: mujoco.Renderer | None = None
        m, obj = self.model, mujoco.mjtObj
        joints = model_ids(m, obj.mjOBJ_JOINT, [f"{leg}_{j}" for leg in LEG_NAMES for j in JOINTS])
        self._qadr = m.jnt_qposadr[joints].reshape(4, 3)
        self._vadr = m.jnt_dofadr[joints].reshape(4, 3)
        self._act = model_ids(m, obj.mjOBJ_ACTUATOR,
                              [f"{leg}_{j}" for leg in LEG_NAMES for j in JOINTS]).reshape(4, 3)
        self._trunk = mujoco.mj_name2id(m, obj.mjOBJ_BODY, "trunk")
        self._feet = model_ids(m, obj.mjOBJ_BODY, [f"{leg}_foot" for leg in LEG_NAMES])
        self._qd_gain = robot.joint_kd / robot.joint_kp  # [s] see set_targets
        self._jac = np.zeros((3, m.nv))  # foot_jacobians' work array
        self.physics_cpu = 0.0  # [s] CPU time spent in MuJoCo's steps (for benchmarks)
        self._pads = foot_pads(self.model, hmap, robot, self.perturbation, max_spacing)  # None: the feet meet the terrain
        mujoco.mj_forward(self.model, self.data)

    @classmethod
    def from_seed(cls, robot: RobotDescription, hmap: HeightMap | None, seed: int,
                  config: PerturbationConfig = PerturbationConfig(),
                  max_spacing: float | None = MAX_HFIELD_SPACING) -> Simulation:
        """A run of the testbed: perturbation and sensor noise both drawn from ``seed``."""
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise FootfallError(f"seed must be a non-negative integer, got {seed!r}")
        perturbation_rng, noise_rng = (np.random.default_rng(s)
                                       for s in np.random.SeedSequence(seed).spawn(2))
        return cls(robot, hmap, perturbation=SimPerturbation.sample(perturbation_rng, config),
                   rng=noise_rng, max_spacing=max_spacing)

    # ----------------------------------------------------------------- driving
    def reset(self, body_position=None, body_rpy=None, q=None) -> None:
        """Place the robot at rest: trunk pose, joint angles (4, 3) [rad], zero velocities.

        ``body_position`` (3,) [m] and ``body_rpy`` (3,) [rad] (Z-Y-X) are the
        exact trunk pose (required unless the base is fixed, where they must
        be None); ``q`` defaults to all zeros. The servo set-points are set
        to ``q``, so the robot holds its posture. Time restarts at 0.
        """
        q = np.zeros((4, 3)) if q is None else _array(q, (4, 3), "joint angles q")
        if self.fixed_base:
            if body_position is not None or body_rpy is not None:
                raise FootfallError("the trunk of a fixed-base simulation cannot be placed")
        elif body_position is None or body_rpy is None:
            raise FootfallError("reset needs the body position and roll/pitch/yaw")
        else:
            body_position = _array(body_position, (3,), "body_position")
            body_rpy = _array(body_rpy, (3,), "body_rpy")
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        if not self.fixed_base:
            d.qpos[0:3] = body_position
            mujoco.mju_mat2Quat(d.qpos[3:7], rotation_matrix(body_rpy).ravel())
        d.qpos[self._qadr] = q
        d.ctrl[self._act] = q
        mujoco.mj_forward(m, d)
        if self._pads is not None:
            self._pads.update(d, self.foot_positions())
            mujoco.mj_forward(m, d)

    def stand(self, body_position, body_rpy, feet) -> np.ndarray:
        """Reset standing on footholds: the joint angles that put each ball foot on its contact point.

        ``feet`` (4, 3) [m] are world contact points (the terrain point under
        each ball foot; the foot centre is ``foot_radius`` above) in
        LEG_NAMES order. The trunk goes to ``body_position`` (3,) [m],
        ``body_rpy`` (3,) [rad] plus this run's start offsets, and the legs
        reach from there to the footholds, so the start posture differs
        between runs but the feet do not. With a terrain registration error
        the true surface is a few mm off the map, so the robot settles in
        its first steps. Returns the joint angles (4, 3) [rad], also the
        servo set-points.
        """
        if self.fixed_base:
            raise FootfallError("a fixed-base simulation cannot stand on its feet")
        p = self.perturbation
        pos = _array(body_position, (3,), "body_position") + np.asarray(p.start_offset)
        rpy = _array(body_rpy, (3,), "body_rpy") + np.asarray(p.start_rpy)
        centres = _array(feet, (4, 3), "feet") + np.array([0.0, 0.0, self.robot.foot_radius])
        local = world_to_body(centres, pos, rpy)
        q = np.empty((4, 3))
        bad = []
        for k, leg in enumerate(self.robot.legs):  # four legs, each its own closed form
            q[k], ok = inverse_kinematics(leg, local[k], self.robot)
            if not ok:
                bad.append(leg.name)
        if bad:
            raise FootfallError(f"stand: foothold out of reach or joint limits for {', '.join(bad)}")
        self.reset(pos, rpy, q)
        return q

    def set_targets(self, q, qd=None, torque=None) -> None:
        """Joint set-points of the PD servo: angles ``q`` (4, 3) [rad], velocities ``qd`` (4, 3)
        [rad/s] and feed-forward torques ``torque`` (4, 3) [N m].

        The servo applies ``kp (q - q_meas) + kd (qd - qd_meas) + torque``
        clipped to the torque limit at every physics step (400 Hz), holding the
        set-points until the next call (the controller's 100 Hz). MuJoCo's
        position actuator computes ``kp (ctrl - q_meas) - kd qd_meas``, so
        the control is ``ctrl = q + (kd / kp) qd + torque / kp``.
        """
        target = _array(q, (4, 3), "joint set-points q")
        if qd is not None:
            target = target + self._qd_gain * _array(qd, (4, 3), "joint velocity set-points qd")
        if torque is not None:
            target = target + _array(torque, (4, 3), "feed-forward torques") / self.robot.joint_kp
        self.data.ctrl[self._act] = target

    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps (servo periods) with the current set-points."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise FootfallError(f"step count must be an integer >= 1, got {n!r}")
        self._step(int(n))

    def advance(self, seconds: float) -> None:
        """Advance ``seconds`` [s], a whole number of physics steps."""
        try:
            s = float(seconds)
        except (TypeError, ValueError):
            s = math.nan
        n = round(s / self.timestep) if math.isfinite(s) else -1
        if n < 1 or abs(n * self.timestep - s) > 1e-9:
            raise FootfallError(f"advance: {seconds!r} s is not a positive whole number of "
                                f"{self.timestep * 1e3:g} ms steps")
        self._step(n)

    def _step(self, n: int) -> None:
        if self._pads is not None:  # the pads under the feet as they stand now
            self._pads.update(self.data, self.foot_positions())
        cpu = time.process_time()
        mujoco.mj_step(self.model, self.data, nstep=n)
        self.physics_cpu += time.process_time() - cpu
        # mj_step leaves poses at the start of its last step: bring them and the centre of mass
        # up to the new joint state (poses, foot positions and joint angles agree).
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_comPos(self.model, self.data)

    def state(self) -> np.ndarray:
        """The integration state (:data:`PHYSICS_STATE`, SI units) to :meth:`restore`."""
        state = np.empty(mujoco.mj_stateSize(self.model, PHYSICS_STATE))
        mujoco.mj_getState(self.model, self.data, state, PHYSICS_STATE)
        return state

    def restore(self, state: np.ndarray) -> None:
        """Back to ``state``, as after a step: stepping on is bit for bit as from there."""
        state = _array(state, (mujoco.mj_stateSize(self.model, PHYSICS_STATE),), "state")
        mujoco.mj_setState(self.model, self.data, state, PHYSICS_STATE)
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_comPos(self.model, self.data)

    # ----------------------------------------------------------------- reading
    @property
    def time(self) -> float:
        """Simulated time since the last reset [s]."""
        return float(self.data.time)

    def body_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """True trunk pose: position (3,) [m] and roll, pitch, yaw (3,) [rad] (Z-Y-X)."""
        r = self.data.xmat[self._trunk]  # row-major R = Rz(yaw) Ry(pitch) Rx(roll)
        rpy = np.array([math.atan2(r[7], r[8]), -math.asin(min(1.0, max(-1.0, r[6]))),
                        math.atan2(r[3], r[0])])
        return self.data.xpos[self._trunk].copy(), rpy

    def centre_of_mass(self) -> np.ndarray:
        """World position (3,) [m] of the whole robot's centre of mass."""
        return self.data.subtree_com[self._trunk].copy()

    def body_velocity(self) -> tuple[np.ndarray, np.ndarray]:
        """Trunk velocity in the world frame: linear (3,) [m/s] of the body origin, angular (3,) [rad/s]."""
        if self.fixed_base:
            return np.zeros(3), np.zeros(3)
        v = self.data.qvel  # free joint: world linear velocity, then body-frame angular velocity
        return v[0:3].copy(), self.data.xmat[self._trunk].reshape(3, 3) @ v[3:6]

    def joint_angles(self) -> np.ndarray:
        """Measured joint angles (4, 3) [rad], LEG_NAMES x (hip roll, hip pitch, knee)."""
        return self.data.qpos[self._qadr]

    def joint_velocities(self) -> np.ndarray:
        """Measured joint velocities (4, 3) [rad/s]."""
        return self.data.qvel[self._vadr]

    def joint_torques(self) -> np.ndarray:
        """Servo torques (4, 3) [N m] applied in the last step (after the torque limit)."""
        return self.data.actuator_force[self._act]

    def foot_positions(self) -> np.ndarray:
        """World positions (4, 3) [m] of the ball-foot centres."""
        return self.data.xpos[self._feet].copy()

    def foot_jacobians(self) -> np.ndarray:
        """Jacobians (4, 3, 3) [m/rad] of the ball-foot centres (world frame) with respect to
        their own leg's joint angles: ``J[i, :, j]`` is how far foot i moves per radian of its
        joint j (hip roll, hip pitch, knee), at the current state."""
        m, d = self.model, self.data
        jac = self._jac
        out = np.empty((4, 3, 3))
        for i, body in enumerate(self._feet):  # four bodies: MuJoCo's own call per body
            mujoco.mj_jacBody(m, d, jac, None, int(body))
            out[i] = jac[:, self._vadr[i]]
        return out

    # --------------------------------------------------------------- sensing
    def foot_forces(self, frame: str = "world", noise: bool = True) -> np.ndarray:
        """Foot force sensor readings (4, 3) [N], with noise: :meth:`Sensors.foot_forces`."""
        return self.sensors.foot_forces(frame, noise)

    def imu(self) -> dict[str, np.ndarray]:
        """The trunk IMU (quat, gyro [rad/s], accel [m/s^2]), with noise: :meth:`Sensors.imu`."""
        return self.sensors.imu()

    def touches_terrain(self, part: str) -> np.ndarray:
        """Whether each leg's ``part`` ("foot", "knee" or "shin") touches the terrain, (4,) bool."""
        return self.sensors.touches_terrain(part)

    def foot_contact(self) -> np.ndarray:
        """Whether each ball foot touches the terrain, (4,) bool (true geometric contact)."""
        return self.sensors.touches_terrain("foot")

    def trunk_touches_terrain(self) -> bool:
        """Whether the trunk box touches the terrain (a fall, in a walking run)."""
        return self.sensors.trunk_touches_terrain()

    # --------------------------------------------------------------- rendering
    def render(self, camera: str = "track", width: int = 640, height: int = 480) -> np.ndarray:
        """An image (height, width, 3) uint8 of the current state from a model camera.

        ``"track"`` follows the trunk from the front right, above (the
        paper's Fig. 4). Needs an OpenGL backend (``MUJOCO_GL``; EGL by
        default, see :mod:`footfall`); call :meth:`close` when done.
        """
        if mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
            raise FootfallError(f"unknown camera {camera!r}")
        if self._renderer is None or (self._renderer.height, self._renderer.width) != (height, width):
            self.close()
            self._renderer = mujoco.Renderer(self.model, height=height, width=width)
        self._renderer.update_scene(self.data, camera=camera)
        return self._renderer.render()

    def close(self) -> None:
        """Release the renderer (and its OpenGL context), if one was made."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def bench_stepping(sim: Simulation, seconds: float) -> dict[str, float]:
    """Bare MuJoCo stepping speed of a simulation's model from its current state.

    Steps a copy of ``sim.data`` (``sim`` is left untouched) for ``seconds``
    [s] of simulated time with the set-points held: the ceiling any
    controller on top can reach. Speeds are per second of this process's
    CPU time (MuJoCo steps on one core), so other work on a shared machine
    does not count; the wall-clock figure is reported beside them.

    Returns
    -------
    dict
        ``steps`` taken, ``steps_per_second`` [1/s] and ``real_time_factor``
        [-] (simulated time over CPU time), ``wall_real_time_factor`` [-]
        (simulated over wall-clock time).
    """
    n = round(float(seconds) / sim.timestep)
    if n < 1:
        raise FootfallError(f"bench_stepping: {seconds!r} s is less than one step")
    data = mujoco.MjData(sim.model)
    mujoco.mj_copyData(data, sim.model, sim.data)
    wall, cpu = time.perf_counter(), time.process_time()
    mujoco.mj_step(sim.model, data, nstep=n)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return {"steps": float(n), "steps_per_second": n / cpu,
            "real_time_factor": n * sim.timestep / cpu,
            "wall_real_time_factor": n * sim.timestep / wall}
