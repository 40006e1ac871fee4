"""The simulated robot's senses: foot force sensors and an IMU with seeded noise, and contacts.

:class:`Sensors` reads the sensor values and the contact list MuJoCo computed during the last
physics step of a :class:`~footfall.sim.simulation.Simulation` (see the timing note there);
stepping and the kinematic readings (poses, joint angles) stay with the simulation.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.robot import LEG_NAMES
from footfall.sim.mjcf import SHIN_PIECES

if TYPE_CHECKING:
    from footfall.sim.simulation import SimPerturbation

LEG_PARTS = ("foot", "knee", "shin")  # parts of a leg that collide with the terrain


def model_ids(model: mujoco.MjModel, objtype: mujoco.mjtObj, names) -> np.ndarray:
    """MuJoCo ids (n,) of the named objects of one type."""
    return np.array([mujoco.mj_name2id(model, objtype, n) for n in names], dtype=np.intp)


class Sensors:
    """The foot force sensors, the trunk IMU and the terrain contacts of a simulated robot.

    Parameters
    ----------
    model, data : mujoco.MjModel, mujoco.MjData
        The compiled robot (see :mod:`footfall.sim.mjcf`) and its state, read at every call.
    noise : SimPerturbation
        Its ``force_noise`` [N], ``gyro_noise`` [rad/s], ``accel_noise`` [m/s^2] and
        ``orientation_noise`` [rad] are the standard deviations of the sensor noise.
    rng : np.random.Generator
        Source of the sensor noise, drawn at every reading.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, noise: SimPerturbation,
                 rng: np.random.Generator) -> None:
        self.model, self.data, self.noise = model, data, noise
        self._rng = rng
        obj = mujoco.mjtObj
        self._foot_sites = model_ids(model, obj.mjOBJ_SITE, [f"{leg}_foot" for leg in LEG_NAMES])
        pieces = {"foot": [""], "knee": [""], "shin": [str(k) for k in range(SHIN_PIECES)]}
        self._part_geoms = {part: model_ids(model, obj.mjOBJ_GEOM,
                                            [f"{leg}_{part}{k}" for leg in LEG_NAMES
                                             for k in pieces[part]]).reshape(4, -1)
                            for part in LEG_PARTS}
        self._trunk_geom = mujoco.mj_name2id(model, obj.mjOBJ_GEOM, "trunk")

        def sensor(name: str) -> np.ndarray:
            i = mujoco.mj_name2id(model, obj.mjOBJ_SENSOR, name)
            return model.sensor_adr[i] + np.arange(model.sensor_dim[i])

        self._force_adr = np.stack([sensor(f"{leg}_foot_force") for leg in LEG_NAMES])
        self._imu_adr = {k: sensor(f"imu_{k}") for k in ("quat", "gyro", "accel")}

    def noise_state(self) -> dict:
        """The noise generator's state (a copy; numpy's ``bit_generator.state``)."""
        return copy.deepcopy(self._rng.bit_generator.state)

    def set_noise_state(self, state: dict) -> None:
        """The noise generator put back into ``state`` (from :meth:`noise_state`)."""
        self._rng.bit_generator.state = copy.deepcopy(state)

    def foot_forces(self, frame: str = "world", noise: bool = True) -> np.ndarray:
        """3-axis foot force sensor readings (4, 3) [N], with sensor noise.

        The force the foot passes into the lower leg: in contact, the ground
        reaction force on the foot less the foot's own weight and inertia
        (``foot_mass``, 10 g). ``frame="sensor"``: in the foot's frame (which
        turns with the shin), as the sensor reports it; ``"world"``: rotated
        into the world frame, +z up for a foot pressed onto the ground.
        ``noise=False``: the true force, as only the simulator knows it (for
        diagnostics; it draws nothing from the noise generator).
        """
        if frame not in ("world", "sensor"):
            raise FootfallError(f"frame must be 'world' or 'sensor', got {frame!r}")
        # MuJoCo reports the force on the child body (the foot) from its parent; negate it.
        local = -self.data.sensordata[self._force_adr]
        if noise:
            local = local + self._rng.normal(0.0, 1.0, (4, 3)) * self.noise.force_noise
        if frame == "sensor":
            return local
        rot = self.data.site_xmat[self._foot_sites].reshape(4, 3, 3)
        return (rot @ local[:, :, None])[:, :, 0]  # per foot R @ f (np.einsum costs more here)

    def imu(self) -> dict[str, np.ndarray]:
        """The trunk IMU, with sensor noise.

        Returns
        -------
        dict
            ``quat`` (4,) orientation (w, x, y, z) of the trunk in the world,
            ``gyro`` (3,) [rad/s] angular rate and ``accel`` (3,) [m/s^2]
            specific force (+9.81 up at rest), both in the trunk frame.
        """
        p, s = self.noise, self.data.sensordata
        quat = s[self._imu_adr["quat"]].copy()
        mujoco.mju_quatIntegrate(quat, self._rng.normal(0.0, p.orientation_noise, 3), 1.0)
        return {"quat": quat,
                "gyro": s[self._imu_adr["gyro"]] + self._rng.normal(0.0, p.gyro_noise, 3),
                "accel": s[self._imu_adr["accel"]] + self._rng.normal(0.0, p.accel_noise, 3)}

    def _touching(self) -> np.ndarray:
        """Whether each geom is in contact now, (ngeom,) bool (robot geoms touch only the terrain)."""
        touching = np.zeros(self.model.ngeom, dtype=bool)
        touching[self.data.contact.geom[:self.data.ncon].ravel()] = True
        return touching

    def touches_terrain(self, part: str) -> np.ndarray:
        """Whether each leg's ``part`` ("foot", "knee" or "shin") touches the terrain, (4,) bool."""
        if part not in LEG_PARTS:
            raise FootfallError(f"unknown leg part {part!r}; parts are {', '.join(LEG_PARTS)}")
        return self._touching()[self._part_geoms[part]].any(axis=1)

    def trunk_touches_terrain(self) -> bool:
        """Whether the trunk box touches the terrain (a fall, in a walking run)."""
        # (checked every control period: no per-geom table as in _touching)
        return bool((self.data.contact.geom[:self.data.ncon] == self._trunk_geom).any())
