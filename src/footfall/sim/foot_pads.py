"""One contact per ball foot: each foot meets only its own pad, on the tangent plane under it.

MuJoCo collides a ball with a height field triangle by triangle: on rock a
loaded ball foot makes 4-10 contacts, and the constraint solver's work grows
with them (``footfall bench sim``: physics is half of a run). In this physics
variant each ball foot collides only with its pad -- a thin box carried by a
mocap body -- whose top face is moved, before every control period's
physics steps, onto the tangent plane of the map's ball-rest surface
(:func:`footfall.core.ball.ball_centre_surface`) under the foot's centre:
exactly where a rigid ball at that (x, y) would touch the map, with the
surface's slope there. One contact per foot, whatever the terrain. Shins,
knees and the trunk still meet the height field. The pads follow the
terrain's registration (the rigid move of
:func:`footfall.sim.hfield.terrain_layout`).

A variant under measurement (``footfall bench sim --foot-contact pads``,
:func:`footfall.sim.variants.physics_variant`), not the walking runs' contact.
"""

from __future__ import annotations

import math
import weakref

import mujoco
import numpy as np

from footfall.core.ball import ball_centre_surface
from footfall.core.heightmap import HeightMap

PAD_HALF_THICKNESS = 0.004  # [m] a pad's half thickness
PAD_HALF_SIZE = 0.03  # [m] a pad's half width: the foot moves ~1-2 mm between updates


class BallSurface:
    """The ball-rest surface of a map, in the world after the terrain's registration."""

    def __init__(self, heights: np.ndarray, hmap: HeightMap, radius: float,
                 centre: np.ndarray, yaw: float, offset: np.ndarray) -> None:
        self.surface = _rest_surface(hmap, heights, float(radius))
        self.radius, self.res = float(radius), float(hmap.resolution)
        self.origin = np.asarray(hmap.origin, dtype=np.float64)
        self.centre, self.offset = np.asarray(centre, dtype=np.float64), np.asarray(offset)
        c, s = math.cos(yaw), math.sin(yaw)
        self.rot = np.array([[c, -s], [s, c]])  # map -> world about the centre

    def contact(self, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where balls centred above ``centres`` (n, 2 or 3) [m] touch, and the surface normal.

        Returns the contact points (n, 3) [m] and unit normals (n, 3) in the world.
        """
        xy = (np.atleast_2d(centres)[:, :2] - self.centre - self.offset[:2]) @ self.rot
        f = (xy + self.centre - self.origin) / self.res  # map-frame fractional cell index
        top = np.array(self.surface.shape) - 2
        i0 = np.clip(np.floor(f).astype(np.intp), 0, top)
        t = np.clip(f - i0, 0.0, 1.0)
        ti, tj = t[:, 0], t[:, 1]
        z = self.surface
        z00, z10 = z[i0[:, 0], i0[:, 1]], z[i0[:, 0] + 1, i0[:, 1]]
        z01, z11 = z[i0[:, 0], i0[:, 1] + 1], z[i0[:, 0] + 1, i0[:, 1] + 1]
        height = (1 - ti) * (1 - tj) * z00 + ti * (1 - tj) * z10 + (1 - ti) * tj * z01 \
            + ti * tj * z11
        gx = ((1 - tj) * (z10 - z00) + tj * (z11 - z01)) / self.res
        gy = ((1 - ti) * (z01 - z00) + ti * (z11 - z10)) / self.res
        normal = np.column_stack([-gx, -gy, np.ones(len(gx))])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        normal[:, :2] = normal[:, :2] @ self.rot.T  # into the world
        world_xy = (xy @ self.rot.T) + self.centre + self.offset[:2]  # the centres' own (x, y)
        on = np.column_stack([world_xy, height + self.offset[2]])
        return on - self.radius * normal, normal


_SURFACES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
# map -> {radius [m]: surface}: each map's ball-rest surface, dilated once per process


def _rest_surface(hmap: HeightMap, heights: np.ndarray, radius: float) -> np.ndarray:
    """The ball-rest surface [m] of ``heights`` (the map as simulated), once per map and radius."""
    per_map = _SURFACES.setdefault(hmap, {})
    if radius not in per_map:
        surface = ball_centre_surface(heights, hmap.resolution, radius)
        per_map[radius] = np.where(np.isfinite(surface), surface, np.nanmin(heights) + radius)
        per_map[radius].setflags(write=False)
    return per_map[radius]


def pad_pose(contact: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position (n, 3) [m] and orientation (n, 4) (w, x, y, z) of pads whose top face touches
    ``contact`` (n, 3) with the outward ``normal`` (n, 3)."""
    quats = np.empty((len(normal), 4))
    for k in range(len(normal)):  # four feet
        mujoco.mju_quatZ2Vec(quats[k], normal[k])
    return contact - PAD_HALF_THICKNESS * normal, quats


class FootPads:
    """The four feet's pads of a simulation: moved under the feet before each physics stride."""

    def __init__(self, model: mujoco.MjModel, surface: BallSurface, names: list[str]) -> None:
        self.surface = surface
        self.mocap = np.array([model.body_mocapid[mujoco.mj_name2id(
            model, mujoco.mjtObj.mjOBJ_BODY, name)] for name in names])

    def update(self, data: mujoco.MjData, feet: np.ndarray) -> None:
        """Put each pad under its foot, ``feet`` (4, 3) [m] the ball centres."""
        pos, quat = pad_pose(*self.surface.contact(feet))
        data.mocap_pos[self.mocap] = pos
        data.mocap_quat[self.mocap] = quat
