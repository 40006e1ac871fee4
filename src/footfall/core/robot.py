"""The robot description: the single source of every number about the robot.

Kinematics, candidate footholds, features, planners and the simulator all read
their link lengths, hip offsets, joint limits, foot radius and masses from a
:class:`RobotDescription`; nothing else in footfall spells a robot number.
The default, :data:`LITTLEDOG`, is a LittleDog-class quadruped (Boston
Dynamics' LittleDog as described in Kalakrishnan et al., IROS 2009, §IV-A).

Frames: the body frame has x forward, y left, z up, its origin at the centre of
the four hip roll axes. Joint angles follow the right-hand rule: hip roll
about the body's x axis, hip pitch and knee about the leg's (rolled) y axis,
so a positive hip pitch swings the foot backward.
"""

from __future__ import annotations

import dataclasses
from dataclasses import asdict, dataclass, field
from typing import Any, Callable, TypeVar

from footfall.core.errors import FootfallError
from footfall.core.validate import require_number, require_type, shown

LEG_NAMES = ("LF", "RF", "LH", "RH")  # left-front, right-front, left-hind, right-hind
DEFAULT_STRIDE = 0.08  # [m] body advance per crawl-gait cycle of four steps (0.02 m per step): the
# kinematic demonstration walker's stride and the footstep planner's default step


@dataclass(frozen=True)
class Leg:
    """One 3-joint leg: hip roll, hip pitch, knee."""

    name: str  # one of LEG_NAMES
    hip: tuple[float, float, float]  # [m] hip roll axis origin in the body frame
    side: int  # +1 left leg, -1 right leg (the lateral offset points outward)
    front: bool  # True for a front leg
    knee_forward: bool  # True: the knee points forward (knee angle > 0)
    hip_roll_limits: tuple[float, float]  # [rad]
    hip_pitch_limits: tuple[float, float]  # [rad]
    knee_limits: tuple[float, float]  # [rad]

    @property
    def limits(self) -> tuple[tuple[float, float], ...]:
        """Joint limits [rad] as ((lo, hi) hip roll, hip pitch, knee)."""
        return (self.hip_roll_limits, self.hip_pitch_limits, self.knee_limits)

    @property
    def mirrored(self) -> bool:
        """Right legs use features mirrored in y, so they look like left legs."""
        return self.side < 0


SERVO_FIELDS = ("servo_rate", "joint_kp", "joint_kd", "joint_armature", "joint_damping")
"""Fields of the low-level servo only: they change how the simulated robot tracks its
set-points, not its geometry, so a learned foothold model stays valid when they change."""


@dataclass(frozen=True)
class RobotDescription:
    """Geometry, mass and limits of a quadruped with 3-joint legs and ball feet."""

    name: str = "littledog"
    overall_length: float = 0.30  # [m] nose to tail, legs included (for body lengths / s)
    overall_width: float = 0.18  # [m] across the legs
    trunk_size: tuple[float, float, float] = (0.24, 0.09, 0.055)  # [m] full box lengths x, y, z
    hip_x: float = 0.101  # [m] fore/aft distance of the hip roll axes from the body origin
    hip_y: float = 0.036  # [m] lateral distance of the hip roll axes from the body origin
    hip_offset: float = 0.024  # [m] further lateral offset from the roll axis to the upper leg
    upper_leg: float = 0.075  # [m] hip pitch axis to knee axis
    lower_leg: float = 0.100  # [m] knee axis to the centre of the ball foot
    foot_radius: float = 0.010  # [m] radius of the ball foot
    lower_leg_radius: float = 0.006  # [m] half thickness of the shin, for clearance checks
    trunk_mass: float = 1.80  # [kg]
    hip_link_mass: float = 0.05  # [kg] per leg, the part turned by the hip roll joint
    upper_leg_mass: float = 0.12  # [kg] per leg
    lower_leg_mass: float = 0.05  # [kg] per leg, foot included
    hip_roll_limits: tuple[float, float] = (-0.6, 0.6)  # [rad]
    hip_pitch_limits_front: tuple[float, float] = (-2.0, 1.2)  # [rad] knee-forward legs
    knee_limits_front: tuple[float, float] = (0.05, 2.8)  # [rad] knee-forward legs
    max_joint_torque: float = 3.0  # [N m] per joint actuator
    max_joint_speed: float = 10.0  # [rad/s]
    nominal_height: float = 0.14  # [m] body origin above the stance feet's contact points
    nominal_foot_y: float = 0.080  # [m] lateral distance of a nominal foot from the body axis
    foot_friction: float = 0.8  # [-] Coulomb friction coefficient, ball foot on terrain
    front_knees_forward: bool = True  # LittleDog: front knees forward, hind knees backward
    gait_order: tuple[str, ...] = ("LH", "LF", "RH", "RF")  # crawl gait swing sequence
    # Simulation (footfall.sim): link shapes for inertia and collision, the servo and the drives.
    hip_link_radius: float = 0.015  # [m] hip link housing, a capsule from roll axis to thigh (inertia)
    upper_leg_radius: float = 0.010  # [m] half thickness of the thigh capsule (inertia)
    knee_radius: float = 0.012  # [m] knee housing sphere, collides with the terrain
    foot_mass: float = 0.010  # [kg] ball foot, part of lower_leg_mass (carries the force sensor)
    servo_rate: float = 400.0  # [Hz] rate of the on-board PD joint servo (paper §IV-B)
    joint_kp: float = 40.0  # [N m/rad] PD servo stiffness (the torque limit at 0.075 rad error);
    # at 15 the legs give so much under load that the robot tips within a few steps of a walk
    joint_kd: float = 1.0  # [N m s/rad] PD servo damping: the body swaying on the stance legs is
    # well damped (at 0.5 it rings and the ZMP swings by tens of mm; 1.5 and more fell more often)
    joint_armature: float = 5e-4  # [kg m^2] reflected rotor inertia of a geared joint motor
    joint_damping: float = 0.01  # [N m s/rad] viscous friction of a joint's gearbox
    legs: tuple[Leg, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        for name in ("hip_x", "hip_y", "upper_leg", "lower_leg", "foot_radius", "trunk_mass",
                     "nominal_height"):
            if not getattr(self, name) > 0:
                raise FootfallError(f"robot description: {name} must be > 0")
        if not (len(self.trunk_size) == 3 and all(v > 0 for v in self.trunk_size)
                and self.hip_x <= self.trunk_size[0] / 2 and self.hip_y <= self.trunk_size[1] / 2):
            raise FootfallError(f"robot description: the hips (hip_x {self.hip_x}, hip_y "
                                f"{self.hip_y} m) must lie within the trunk (trunk_size "
                                f"{self.trunk_size} m, each > 0)")
        if not 0 < self.foot_mass < self.lower_leg_mass:
            raise FootfallError("robot description: foot_mass must be > 0 and < lower_leg_mass")
        for name in ("hip_roll_limits", "hip_pitch_limits_front", "knee_limits_front"):
            low, high = getattr(self, name)
            if not low < high:
                raise FootfallError(f"robot description: {name} must be (low, high) with "
                                    f"low < high, got {getattr(self, name)}")
        if sorted(self.gait_order) != sorted(LEG_NAMES):
            raise FootfallError(f"robot description: gait_order must be a permutation of {LEG_NAMES}")
        lo, hi = self.hip_pitch_limits_front
        klo, khi = self.knee_limits_front
        legs = []
        for name in LEG_NAMES:
            front = name[1] == "F"
            side = 1 if name[0] == "L" else -1
            knee_forward = self.front_knees_forward == front
            # A knee-backward leg is the knee-forward one reflected front to back.
            pitch = (lo, hi) if knee_forward else (-hi, -lo)
            knee = (klo, khi) if knee_forward else (-khi, -klo)
            legs.append(Leg(name=name,
                            hip=((1 if front else -1) * self.hip_x, side * self.hip_y, 0.0),
                            side=side, front=front, knee_forward=knee_forward,
                            hip_roll_limits=self.hip_roll_limits, hip_pitch_limits=pitch,
                            knee_limits=knee))
        object.__setattr__(self, "legs", tuple(legs))

    # ----------------------------------------------------------------- derived
    def leg(self, name: str) -> Leg:
        """The leg called ``name`` (LF, RF, LH or RH)."""
        for leg in self.legs:
            if leg.name == name:
                return leg
        raise FootfallError(f"unknown leg {name!r}; legs are {', '.join(LEG_NAMES)}")

    @property
    def leg_mass(self) -> float:
        """Mass of one leg [kg]."""
        return self.hip_link_mass + self.upper_leg_mass + self.lower_leg_mass

    @property
    def total_mass(self) -> float:
        """Mass of the whole robot [kg]."""
        return self.trunk_mass + 4 * self.leg_mass

    @property
    def max_reach(self) -> float:
        """Largest hip-roll-axis to foot-centre distance [m]."""
        return float((self.hip_offset ** 2 + (self.upper_leg + self.lower_leg) ** 2) ** 0.5)

    def nominal_foot(self, name: str) -> tuple[float, float, float]:
        """Default stance position [m] of a foot's contact point in the body frame."""
        leg = self.leg(name)
        return (leg.hip[0], leg.side * self.nominal_foot_y, -self.nominal_height)

    # ----------------------------------------------------------- serialisation
    def to_dict(self) -> dict[str, Any]:
        """The description as plain JSON-serialisable data (for model files)."""
        d = asdict(self)
        d.pop("legs")
        return d

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "RobotDescription":
        """Rebuild a description written by :meth:`to_dict`, every field checked.

        A field the data lacks keeps its default (files written before it existed);
        an unknown field, a value of the wrong type, a non-finite number or one of
        magnitude above :data:`MAX_ROBOT_NUMBER` is refused, naming the field.
        """
        require_type(data, dict, "robot")
        defaults = {f.name: f.default for f in dataclasses.fields(cls) if f.init}
        unknown = sorted(str(k) for k in data if k not in defaults)
        if unknown:
            raise FootfallError(f"malformed robot description: robot has unknown field(s) "
                                f"{', '.join(map(repr, unknown))}")
        fields = {k: _robot_field(f"robot.{k}", v, defaults[k]) for k, v in data.items()}
        try:
            return cls(**fields)
        except FootfallError as exc:
            raise FootfallError(f"robot: {str(exc).removeprefix('robot description: ')}") from None


MAX_ROBOT_NUMBER = 1e6  # largest magnitude of any number in a robot description [its unit]


def _robot_field(what: str, value: Any, default: Any) -> Any:
    """A description field read from plain data, of the same kind as its ``default``."""
    if isinstance(default, bool):
        return require_type(value, bool, what)
    if isinstance(default, str):
        return require_type(value, str, what)
    if isinstance(default, float):
        return require_number(value, what, -MAX_ROBOT_NUMBER, MAX_ROBOT_NUMBER)
    require_type(value, (list, tuple), what)
    if len(value) != len(default):
        raise FootfallError(f"{what} must hold {len(default)} items, got {shown(value)}")
    return tuple(_robot_field(f"{what}[{k}]", v, d) for k, (v, d) in enumerate(zip(value, default)))


LITTLEDOG = RobotDescription()
"""The default robot: a LittleDog-class quadruped."""


_T = TypeVar("_T")


def per_robot(make: Callable[[RobotDescription], _T]) -> Callable[[RobotDescription], _T]:
    """``make(robot)``, remembered for the last robot asked, found by identity.

    For tables the controller reads at 100 Hz: a run has one robot, and
    ``functools.lru_cache`` would hash the whole frozen description at every call."""
    last: list = [None, None]

    def remembered(robot: RobotDescription) -> _T:
        if last[0] is not robot:
            last[:] = [robot, make(robot)]
        return last[1]

    remembered.__doc__ = make.__doc__
    return remembered
