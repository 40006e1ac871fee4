"""How faithfully the simulated contact follows the map: where a ball foot rests, whether it creeps.

Two measures that any change to the physics (collision geometry, solver
settings, step) must keep, printed by ``footfall bench sim`` beside the
speed:

* :func:`ball_rest_errors` -- a ball foot loaded with its share of the
  robot's weight, lowered onto the terrain at many points, should come to
  rest where a rigid ball of the foot's radius rests on the map's surface
  (:func:`ball_rest_height`). The error is what the soft contact sinks plus
  what the height field's triangles add over the map.
* :func:`slope_creep` -- the robot stands still on a plane of gradient 0.3
  (17 deg) with every foot inside its friction cone: how far each foot
  slides in a few seconds. Coulomb friction says not at all; MuJoCo's soft
  contacts let a foot creep unless the friction constraints are stiff.
"""

from __future__ import annotations

import mujoco
import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import nominal_state
from footfall.sim.mjcf import compile_probe_model
from footfall.sim.simulation import Simulation


def ball_rest_height(hmap: HeightMap, xy: np.ndarray, radius: float) -> np.ndarray:
    """Height [m] of the centre of a rigid ball of ``radius`` [m] resting on the map at ``xy``.

    ``xy`` (n, 2) [m]: ball centres. The ball touches the highest of the
    map's cells under it: ``max over cells within radius of h + sqrt(r^2 - d^2)``
    with ``d`` the horizontal distance from the ball's centre to the cell's
    centre (cells without data are ignored). Vectorised over balls and cells.
    """
    xy = np.atleast_2d(np.asarray(xy, dtype=np.float64))
    res = hmap.resolution
    n = int(np.ceil(radius / res)) + 1
    offsets = np.arange(-n, n + 1)
    ij = hmap.position_to_index(xy)  # the cell under each centre
    i = ij[:, 0, None, None] + offsets[None, :, None]  # (n, k, 1)
    j = ij[:, 1, None, None] + offsets[None, None, :]  # (n, 1, k)
    i, j = np.broadcast_arrays(i, j)
    inside = (i >= 0) & (i < hmap.heights.shape[0]) & (j >= 0) & (j < hmap.heights.shape[1])
    h = np.where(inside, hmap.heights[np.clip(i, 0, hmap.heights.shape[0] - 1),
                                      np.clip(j, 0, hmap.heights.shape[1] - 1)], np.nan)
    cx = hmap.origin[0] + i * res  # cell centres
    cy = hmap.origin[1] + j * res
    d2 = (cx - xy[:, 0, None, None]) ** 2 + (cy - xy[:, 1, None, None]) ** 2
    lift = np.sqrt(np.maximum(radius ** 2 - d2, 0.0))
    top = np.where((d2 <= radius ** 2) & ~np.isnan(h), h + lift, -np.inf)
    return top.reshape(len(xy), top[0].size if len(xy) else 0).max(axis=1, initial=-np.inf)


def ball_rest_errors(hmap: HeightMap, xy: np.ndarray, robot: RobotDescription = LITTLEDOG,
                     settle: float = 1.0, tune=None) -> np.ndarray:
    """Settled height of a loaded ball foot minus the rigid ball's rest height [m], one per point.

    Balls of the foot's radius, each carrying a third of the robot's weight
    (one foot of three in stance), slide down vertical rails at ``xy`` (n, 2)
    [m] onto the terrain of the walking runs' physics
    (:func:`footfall.sim.mjcf.compile_probe_model`) and settle for
    ``settle`` [s]; each is compared with :func:`ball_rest_height`. Negative:
    the ball sinks in (the soft contact, or a height-field triangle below
    the map's surface). ``tune(model)``: changes to the physics under test.
    """
    xy = np.atleast_2d(np.asarray(xy, dtype=np.float64))
    load = robot.total_mass / 3.0
    model = compile_probe_model(robot, hmap, xy, load)
    if tune is not None:
        tune(model)
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, nstep=max(1, round(settle / model.opt.timestep)))
    mujoco.mj_kinematics(model, data)
    first = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "probe0")
    centres = data.xpos[first:first + len(xy)]
    return centres[:, 2] - ball_rest_height(hmap, xy, robot.foot_radius)


def slope_creep(robot: RobotDescription = LITTLEDOG, gradient: float = 0.3,
                seconds: float = 4.0, settle: float = 0.5, tune=None) -> np.ndarray:
    """Horizontal travel [m] of each foot of the robot standing still on a plane of ``gradient``.

    The plane rises along x (``z = gradient x``); the robot stands across it
    with its body level at the nominal height over the mean foot height,
    settles for ``settle`` [s], then holds for ``seconds`` [s]: the travel of
    each foot's centre over that hold, shape (4,). ``tune(model)``: changes to
    the physics under test.
    """
    res = 0.002
    n = round(0.6 / res)
    x = np.arange(n) * res
    plane = HeightMap(np.repeat((gradient * x)[:, None], n, axis=1), res, (0.0, -0.3))
    sim = Simulation(robot, plane)
    if tune is not None:
        tune(sim.model)
    try:
        st = nominal_state(plane, (0.3, 0.0), 0.0, robot.gait_order[0], robot=robot)
        sim.stand(st.body_position, st.body_rpy, st.feet)
        sim.advance(settle)
        start = sim.foot_positions()[:, :2].copy()
        sim.advance(seconds)
        return np.linalg.norm(sim.foot_positions()[:, :2] - start, axis=1)
    finally:
        sim.close()
