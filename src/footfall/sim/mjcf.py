"""The simulated robot and terrain as a MuJoCo model, generated from the robot description.

Every length, mass, limit and gain comes from a
:class:`~footfall.core.robot.RobotDescription`; the kinematic tree reproduces
:mod:`footfall.core.kinematics` exactly, so MuJoCo's forward kinematics and the
closed-form one agree to rounding. The terrain is made from a
:class:`~footfall.core.heightmap.HeightMap`: MuJoCo height fields whose vertices
are map cells, at most 2 mm apart (:mod:`footfall.sim.hfield`). A physics variant
under measurement (:mod:`footfall.sim.variants`) changes the model while it lasts.

Model layout (names are the API the simulation wrapper and tests rely on):

- body ``trunk`` with a free joint ``root`` (or welded to the world for a
  test rig), a box geom ``trunk``, an IMU site ``imu`` at the body origin
  and a tracking camera ``track``;
- per leg ``L`` in LEG_NAMES: bodies ``L_hip`` (joint ``L_hip_roll``),
  ``L_upper`` (joint ``L_hip_pitch``), ``L_lower`` (joint ``L_knee``;
  collision geoms ``L_knee`` and ``L_shin0`` ... ``L_shin2``) and a welded
  ``L_foot`` (geom and site ``L_foot``); one position actuator per joint,
  named after it. Masses sit on capsules ``L_hip_link``, ``L_thigh``,
  ``L_lower_leg`` (which do not collide) and the foot sphere, so MuJoCo
  derives every inertia from the link shapes;
- sensors ``L_foot_force`` (3-axis force at the foot site), ``imu_quat``,
  ``imu_gyro``, ``imu_accel``;
- terrain geoms ``terrain0``, ``terrain1``, ... (or one plane ``terrain`` at
  z = 0 without a map) and a catch-all ``floor`` plane below them. Robot
  geoms collide with the terrain only, never with each other.

Physics: the timestep is one period of the robot's PD servo
(``1 / robot.servo_rate``, 2.5 ms at 400 Hz), so MuJoCo's position
actuators *are* the 400 Hz servo: each step applies
``kp (q* - q) - kd qdot`` clipped to the torque limit, as the robot's
on-board loop does. The ``implicitfast`` integrator treats the servo damping,
joint damping and armature implicitly, which keeps the light legs stable at
this step; a finer step would only slow the simulation down. Contacts use
elliptic friction cones with a high impedance ratio, so that a foot inside
its friction cone stays put instead of creeping as MuJoCo's soft contacts
otherwise do; the constraint solver works on sparse Jacobians (faster with
elliptic cones, see JACOBIAN).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES, RobotDescription
from footfall.sim.foot_pads import PAD_HALF_SIZE, PAD_HALF_THICKNESS, BallSurface, pad_pose
from footfall.sim.hfield import (
    MAX_HFIELD_SPACING,
    registration_centre,
    terrain_layout,
    terrain_surface,
)
from footfall.sim.variants import VARIANT, pads_on

JOINTS = ("hip_roll", "hip_pitch", "knee")  # joint name suffixes, in kinematics.py order
CONTACT_TIMECONST_STEPS = 2.0  # [steps] contact time constant in physics steps: the stiffest
# MuJoCo recommends, so that a foot sinks < 0.1 mm under the robot's weight
IMPRATIO = 100.0  # [-] friction-to-normal impedance ratio of MuJoCo's elliptic friction cones:
# makes static friction hold (a standing foot creeps < 0.2 mm in 4 s on a 0.3 slope, against
# 14 mm with MuJoCo's defaults)
JACOBIAN = "sparse"  # MuJoCo's constraint Jacobian storage. Its "auto" picks dense for so few
# degrees of freedom (18), but with elliptic cones the sparse Newton solver is faster while
# walking: 240 instead of 360 us per step over rocks (~14 contacts, ~8 iterations per step; the
# same iterations, the same solution up to rounding). A robot standing still, where the warm-
# started solver stops almost at once, steps ~5-10 % faster with dense
SHIN_PIECES = 3  # [-] the shin collides as this many collinear capsules: the same shape, but
# each piece's bounding box covers fewer height-field cells than the whole slanted shin's
FIXED_BASE_CLEARANCE = 0.5  # [m] test rig: trunk welded this far above the highest terrain point
CAMERA_OFFSET = (0.25, -0.6, 0.25)  # [m] tracking camera position from the robot's centre of mass
# (front right, above: the side view of the paper's Fig. 4)

TERRAIN_GEOM_GROUP = 2  # MuJoCo geom group of every terrain geom (robot geoms use 0, 1 and 3),
# so rays and renders can pick the terrain alone
_ROBOT_GROUP = 1  # collision bit of robot geoms; the terrain has the matching affinity
_PAD_GROUP = 2  # collision bit of the feet and their pads in the "pads" foot contact
_VISUAL_RGBA = "0.75 0.75 0.78 1"
_FOOT_RGBA = "0.15 0.15 0.15 1"
_TERRAIN_RGBA = "0.72 0.62 0.48 1"


def _f(*values: float) -> str:
    """Numbers for XML, written so that they read back bit for bit."""
    return " ".join(repr(float(v)) for v in values)


# ------------------------------------------------------------------------ robot
def _camera_axes(offset) -> tuple[np.ndarray, np.ndarray]:
    """x and y axes of a camera at ``offset`` [m] looking at the origin, horizon level."""
    back = np.asarray(offset, dtype=np.float64)
    back = back / np.linalg.norm(back)  # camera z axis: from the target towards the camera
    x = np.cross([0.0, 0.0, 1.0], back)
    x /= np.linalg.norm(x)
    return x, np.cross(back, x)


def _leg_xml(robot: RobotDescription, name: str, friction: float,
             foot_group: int = _ROBOT_GROUP) -> str:
    leg = robot.leg(name)
    (rlo, rhi), (plo, phi), (klo, khi) = leg.limits
    r_hip, r_up = robot.hip_link_radius, robot.upper_leg_radius
    shin_end = robot.lower_leg - robot.foot_radius - robot.lower_leg_radius  # shin meets the ball
    cuts = np.linspace(0.0, -shin_end, SHIN_PIECES + 1)
    collide = (f'contype="{_ROBOT_GROUP}" conaffinity="0" condim="3" '
               f'friction="{_f(friction)} 0 0" density="0"')
    visual = 'contype="0" conaffinity="0" group="1"'
    shin = "".join(
        f"""
          <geom name="{name}_shin{k}" type="capsule" fromto="0 0 {_f(cuts[k])} 0 0 {_f(cuts[k + 1])}"
                size="{_f(robot.lower_leg_radius)}" {collide} group="3"/>"""
        for k in range(SHIN_PIECES))
    return f"""
    <body name="{name}_hip" pos="{_f(*leg.hip)}">
      <joint name="{name}_hip_roll" axis="1 0 0" range="{_f(rlo, rhi)}"/>
      <geom name="{name}_hip_link" type="capsule" fromto="0 0 0 0 {_f(leg.side * robot.hip_offset)} 0"
            size="{_f(r_hip)}" mass="{_f(robot.hip_link_mass)}" {visual} rgba="{_VISUAL_RGBA}"/>
      <body name="{name}_upper" pos="0 {_f(leg.side * robot.hip_offset)} 0">
        <joint name="{name}_hip_pitch" axis="0 1 0" range="{_f(plo, phi)}"/>
        <geom name="{name}_thigh" type="capsule" fromto="0 0 0 0 0 {_f(-robot.upper_leg)}"
              size="{_f(r_up)}" mass="{_f(robot.upper_leg_mass)}" {visual} rgba="{_VISUAL_RGBA}"/>
        <body name="{name}_lower" pos="0 0 {_f(-robot.upper_leg)}">
          <joint name="{name}_knee" axis="0 1 0" range="{_f(klo, khi)}"/>
          <geom name="{name}_lower_leg" type="capsule" fromto="0 0 0 0 0 {_f(-shin_end)}"
                size="{_f(robot.lower_leg_radius)}"
                mass="{_f(robot.lower_leg_mass - robot.foot_mass)}" {visual}
                rgba="{_VISUAL_RGBA}"/>
          <geom name="{name}_knee" type="sphere" size="{_f(robot.knee_radius)}" {collide}
                rgba="{_VISUAL_RGBA}"/>{shin}
          <body name="{name}_foot" pos="0 0 {_f(-robot.lower_leg)}">
            <geom name="{name}_foot" type="sphere" size="{_f(robot.foot_radius)}"
                  {collide.replace('density="0"', f'mass="{_f(robot.foot_mass)}"').replace(
                      f'contype="{_ROBOT_GROUP}"', f'contype="{foot_group}"')}
                  rgba="{_FOOT_RGBA}"/>
            <site name="{name}_foot" size="{_f(0.5 * robot.foot_radius)}"/>
          </body>
        </body>
      </body>
    </body>"""


def build_mjcf(robot: RobotDescription, hmap: HeightMap | None, *,
               terrain_offset=(0.0, 0.0, 0.0), terrain_yaw: float = 0.0,
               friction: float | None = None, fixed_base: bool = False,
               max_spacing: float | None = MAX_HFIELD_SPACING) -> str:
    """The MJCF (MuJoCo XML) of the robot on a terrain.

    The height field is declared with its size but no data (the data --
    a million numbers for a board -- is filled in by :func:`compile_model`).

    Parameters
    ----------
    robot : RobotDescription
        The one source of every robot number.
    hmap : HeightMap or None
        The terrain; None: a flat plane at z = 0 (raised by ``terrain_offset[2]``;
        horizontal offsets and yaw leave a plane unchanged).
    terrain_offset : (3,) [m]
        Translation of the simulated terrain relative to the map
        (registration error); see :func:`terrain_layout`.
    terrain_yaw : float [rad]
        Rotation of the simulated terrain about the vertical through the
        map's centre.
    friction : float or None [-]
        Coulomb friction of every robot-terrain contact; None:
        ``robot.foot_friction``. The terrain's own friction is zero, so
        MuJoCo's max rule takes the robot geom's.
    fixed_base : bool
        Test rig: no free joint, the trunk hangs level
        FIXED_BASE_CLEARANCE above the highest terrain point.
    max_spacing : float or None [m]
        Coarsest height-field vertex spacing (see :func:`terrain_layout`);
        None: the map's full resolution.

    Returns
    -------
    str
        The MJCF document.
    """
    tiles = _checked_layout(robot, hmap, terrain_offset, terrain_yaw, max_spacing)
    return _mjcf(robot, tiles, terrain_offset, friction, fixed_base)


def _checked_layout(robot, hmap, terrain_offset, terrain_yaw, max_spacing) -> list | None:
    if not isinstance(robot, RobotDescription):
        raise FootfallError(f"robot must be a RobotDescription, got {type(robot).__name__}")
    if hmap is None:
        offset = np.asarray(terrain_offset, dtype=np.float64)
        if offset.shape != (3,) or not np.isfinite(offset).all():
            raise FootfallError(f"terrain_offset must be 3 finite numbers [m], got {terrain_offset!r}")
        return None
    if not isinstance(hmap, HeightMap):
        raise FootfallError(f"hmap must be a HeightMap or None, got {type(hmap).__name__}")
    if VARIANT.get("max_spacing") is not None:
        max_spacing = VARIANT["max_spacing"]
    return terrain_layout(hmap, terrain_offset, terrain_yaw, max_spacing)


def _terrain_xml(tiles: list[dict]) -> tuple[str, str, float]:
    """(asset XML, worldbody XML, top height [m]) of terrain tiles and the floor under them."""
    assets, geoms = [], []
    common = (f'contype="0" conaffinity="{_ROBOT_GROUP}" friction="0 0 0" group="{TERRAIN_GEOM_GROUP}" '
              f'rgba="{_TERRAIN_RGBA}"')
    for n, t in enumerate(tiles):
        pose = f'pos="{_f(*t["pos"])}" quat="{_f(*t["quat"])}"'
        if t["kind"] == "box":
            geoms.append(f'<geom name="terrain{n}" type="box" size="{_f(*t["size"])}" {pose} {common}/>')
        else:
            assets.append(f'<hfield name="terrain{n}" nrow="{t["nrow"]}" ncol="{t["ncol"]}" '
                          f'size="{_f(*t["size"])}"/>')
            geoms.append(f'<geom name="terrain{n}" type="hfield" hfield="terrain{n}" {pose} {common}/>')
    top = max(float(t["pos"][2] + t["size"][2]) for t in tiles)  # box half height / elevation
    bottom = min(float(t["pos"][2] - t["size"][3 if t["kind"] == "hfield" else 2]) for t in tiles)
    geoms.append(f'<geom name="floor" type="plane" size="0 0 0.05" pos="0 0 {_f(bottom)}" '
                 f'material="floor" contype="0" conaffinity="{_ROBOT_GROUP}" friction="0 0 0" '
                 f'group="{TERRAIN_GEOM_GROUP}"/>')
    return "\n    ".join(assets), "\n    ".join(geoms), top


def _mjcf(robot: RobotDescription, tiles: list[dict] | None, terrain_offset,
          friction: float | None, fixed_base: bool) -> str:
    mu = robot.foot_friction if friction is None else friction
    if not (isinstance(mu, (int, float)) and math.isfinite(mu) and mu > 0):
        raise FootfallError(f"friction must be a finite number > 0, got {friction!r}")
    timestep = 1.0 / robot.servo_rate
    option = {"timestep": _f(timestep), "integrator": "implicitfast", "cone": "elliptic",
              "impratio": _f(IMPRATIO), "jacobian": JACOBIAN, **VARIANT.get("options", {})}
    option_xml = " ".join(f'{k}="{v}"' for k, v in option.items())

    if tiles is None:  # a plane is invariant under xy shifts and yaw: only the height offset counts
        terrain_top = float(terrain_offset[2])
        asset_terrain = ""
        terrain = (f'<geom name="terrain" type="plane" size="0 0 0.05" material="floor" '
                   f'pos="0 0 {_f(terrain_top)}" contype="0" conaffinity="{_ROBOT_GROUP}" '
                   f'friction="0 0 0" group="{TERRAIN_GEOM_GROUP}"/>')
    else:
        asset_terrain, terrain, terrain_top = _terrain_xml(tiles)

    trunk_z = terrain_top + (FIXED_BASE_CLEARANCE if fixed_base else robot.nominal_height)
    base_joint = "" if fixed_base else '<freejoint name="root"/>'
    cam_x, cam_y = _camera_axes(CAMERA_OFFSET)
    half = np.asarray(robot.trunk_size) / 2
    # with pads, each ball foot meets only its own pad (footfall.sim.foot_pads)
    legs = "".join(_leg_xml(robot, name, mu, _PAD_GROUP if pads_on() else _ROBOT_GROUP)
                   for name in LEG_NAMES)
    pads = "".join(f'\n    <body name="{name}_pad" mocap="true" pos="0 0 -1">{_pad_geom()}</body>'
                   for name in LEG_NAMES) if pads_on() else ""
    actuators = "\n    ".join(
        f'<position name="{leg}_{j}" joint="{leg}_{j}" kp="{_f(robot.joint_kp)}" '
        f'kv="{_f(robot.joint_kd)}" forcelimited="true" '
        f'forcerange="{_f(-robot.max_joint_torque, robot.max_joint_torque)}"/>'
        for leg in LEG_NAMES for j in JOINTS)
    forces = "\n    ".join(f'<force name="{leg}_foot_force" site="{leg}_foot"/>'
                           for leg in LEG_NAMES)
    return f"""<mujoco model="{robot.name}">
  <compiler angle="radian" autolimits="true" inertiafromgeom="true"/>
  <option {option_xml}/>
  <visual><global offwidth="1920" offheight="1080"/><quality shadowsize="1024"/></visual>
  <default>
    <joint armature="{_f(robot.joint_armature)}" damping="{_f(robot.joint_damping)}"/>
    <geom solref="{_f(CONTACT_TIMECONST_STEPS * timestep)} 1"/>
  </default>
  <asset>
    <texture name="floor" type="2d" builtin="checker" width="512" height="512"
             rgb1="0.35 0.37 0.40" rgb2="0.30 0.32 0.35"/>
    <material name="floor" texture="floor" texrepeat="8 8"/>
    {asset_terrain}
  </asset>
  <worldbody>
    <light name="sun" pos="0 0 3" dir="0 0 -1" directional="true"/>
    {terrain}
    <body name="trunk" pos="0 0 {_f(trunk_z)}">
      {base_joint}
      <geom name="trunk" type="box" size="{_f(*half)}" mass="{_f(robot.trunk_mass)}"
            contype="{_ROBOT_GROUP}" conaffinity="0" condim="3" friction="{_f(mu)} 0 0"
            rgba="0.25 0.35 0.55 1"/>
      <site name="imu" size="0.005"/>
      <camera name="track" mode="trackcom" pos="{_f(*CAMERA_OFFSET)}"
              xyaxes="{_f(*cam_x, *cam_y)}"/>{legs}
    </body>{pads}
  </worldbody>
  <actuator>
    {actuators}
  </actuator>
  <sensor>
    {forces}
    <framequat name="imu_quat" objtype="site" objname="imu"/>
    <gyro name="imu_gyro" site="imu"/>
    <accelerometer name="imu_accel" site="imu"/>
  </sensor>
</mujoco>
"""


def compile_model(robot: RobotDescription, hmap: HeightMap | None, *,
                  terrain_offset=(0.0, 0.0, 0.0), terrain_yaw: float = 0.0,
                  friction: float | None = None, fixed_base: bool = False,
                  max_spacing: float | None = MAX_HFIELD_SPACING) -> mujoco.MjModel:
    """The compiled MuJoCo model of :func:`build_mjcf`, height-field data filled in.

    Same parameters as :func:`build_mjcf`.
    """
    tiles = _checked_layout(robot, hmap, terrain_offset, terrain_yaw, max_spacing)
    model = mujoco.MjModel.from_xml_string(_mjcf(robot, tiles, terrain_offset, friction, fixed_base))
    return _filled(model, tiles)


def _filled(model: mujoco.MjModel, tiles: list | None) -> mujoco.MjModel:
    """``model`` with its height fields' data filled in from the terrain tiles."""
    for n, tile in enumerate(tiles or ()):
        if tile["kind"] == "hfield":
            h = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_HFIELD, f"terrain{n}")
            adr = model.hfield_adr[h]
            model.hfield_data[adr:adr + tile["data"].size] = tile["data"]
    return model


def _pad_geom(name: str | None = None) -> str:
    named = "" if name is None else f'name="{name}" '
    return (f'<geom {named}type="box" '
            f'size="{_f(PAD_HALF_SIZE, PAD_HALF_SIZE, PAD_HALF_THICKNESS)}" '
            f'contype="0" conaffinity="{0 if name else _PAD_GROUP}" friction="0 0 0" '
            f'group="{TERRAIN_GEOM_GROUP}" rgba="0 0 0 0"/>')


def compile_probe_model(robot: RobotDescription, hmap: HeightMap, xy: np.ndarray,
                        load: float, max_spacing: float | None = MAX_HFIELD_SPACING
                        ) -> mujoco.MjModel:
    """The robot's physics with ball feet on vertical sliders: where does a loaded foot rest?

    The model of :func:`compile_model` (same options, contact parameters and
    terrain; the robot on its test rig, far above) plus one ball of the foot's
    radius, friction and contact settings per point of ``xy`` (n, 2) [m],
    free only to slide vertically, each of mass ``load`` [kg] (the weight a
    stance foot carries), starting just clear of the terrain's highest point.
    Bodies ``probe0``, ``probe1``, ...; their joints' positions are the balls'
    drops [m].
    """
    xy = np.atleast_2d(np.asarray(xy, dtype=np.float64))
    tiles = _checked_layout(robot, hmap, (0.0, 0.0, 0.0), 0.0, max_spacing)
    xml = _mjcf(robot, tiles, (0.0, 0.0, 0.0), None, fixed_base=True)
    top = float(np.nanmax(hmap.heights)) + 2 * robot.foot_radius
    group = 0 if pads_on() else _ROBOT_GROUP  # with pads: only the explicit pairs below
    probes = "".join(
        f'\n    <body name="probe{k}" pos="{_f(x, y, top)}">'
        f'<joint name="probe{k}" type="slide" axis="0 0 1" damping="{_f(2.0 * load)}"/>'
        f'<geom name="probe{k}" type="sphere" size="{_f(robot.foot_radius)}" mass="{_f(load)}" '
        f'contype="{group}" conaffinity="0" condim="3" '
        f'friction="{_f(robot.foot_friction)} 0 0"/></body>'
        for k, (x, y) in enumerate(xy))
    pairs = ""
    if pads_on():  # each probe over its own fixed pad, as a foot over its pad
        surface = BallSurface(terrain_surface(hmap), hmap, robot.foot_radius,
                              registration_centre(hmap, max_spacing), 0.0, np.zeros(3))
        pos, quat = pad_pose(*surface.contact(xy))
        probes += "".join(f'\n    <body pos="{_f(*p)}" quat="{_f(*q)}">'
                          f'{_pad_geom(f"probe_pad{k}")}</body>'
                          for k, (p, q) in enumerate(zip(pos, quat)))
        solref = _f(CONTACT_TIMECONST_STEPS / robot.servo_rate, 1.0)
        pairs = "\n  <contact>" + "".join(
            f'<pair geom1="probe{k}" geom2="probe_pad{k}" condim="3" solref="{solref}" '
            f'friction="{_f(robot.foot_friction, robot.foot_friction, 0.005, 0.0001, 0.0001)}"/>'
            for k in range(len(xy))) + "</contact>"
    return _filled(mujoco.MjModel.from_xml_string(
        xml.replace("\n  </worldbody>", probes + "\n  </worldbody>" + pairs)), tiles)
