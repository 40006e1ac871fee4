"""The four legs at the control rate: their roles, their stance anchors, and their set-points.

:class:`Legs` is the low-level part of the controller (paper §IV-B.6, and the
closed loop of :mod:`footfall.control.lowlevel`): it remembers which legs
stand and where each stance foot was put down, and every control period turns
the desired body pose and the feet's targets into joint set-points -- each
stance foot held where it was put (moved on as far as its ball has rolled),
its height set by its force sensor so that it carries its share of the weight
(:mod:`footfall.control.load`), the torques that carry that share fed forward.
"""

from __future__ import annotations

import math

import numpy as np

from footfall.control.estimate import BodyEstimate
from footfall.control.load import load_held, load_offsets, load_shares, pressed, support_torques
from footfall.control.lowlevel import (
    BodyCorrection,
    LowLevelConfig,
    body_rotation,
    handed_over,
    handed_over_pose,
    joint_targets,
    reanchor,
    rolled,
    shin_rotations,
    transfer_weight,
)
from footfall.control.measurements import JointTargets
from footfall.core.robot import RobotDescription

GRAVITY = 9.81  # [m/s^2] the simulator's and the testbed's
OTHER_LEGS = np.array([[j for j in range(4) if j != k] for k in range(4)])  # stance legs while
# leg k swings, in order (an index array: np.delete's overhead counts at 100 Hz)


class Legs:
    """The legs' state and their joint set-points, one control period at a time.

    Parameters
    ----------
    robot : RobotDescription
    config : LowLevelConfig
        The closed loop's gains and limits (its ``period`` [s] is the control period).
    touchdown_force : float
        [N] a foot force sensor reading above this means the foot carries load.
    slip_watch : bool
        The stance slip reflex is on (it reads the force sensors every period).

    Attributes
    ----------
    q : ndarray (4, 3)
        The last set-points [rad].
    targets : ndarray (4, 3)
        Foot-centre targets [m], world frame.
    stance : ndarray (4,) bool
        Each leg's role: True stance, False swing.
    since : ndarray (4,)
        [s] when each leg took its role.
    anchor : ndarray (4, 3)
        [m] where each stance foot's centre is held (its target before rolling and load control).
    down : ndarray (4, 3)
        [m] where each stance foot's centre was when it was put down.
    unload : ndarray (4,)
        [-] each leg's availability to carry load (1 - the share unloaded before a lift-off).
    correction : BodyCorrection
        The integral correction of the commanded body pose.
    hold_yields : bool
        Whether the load hold (``load_hold``) yields: from the stance watch's alarm until the
        recovery ends, the load control moves the load whatever touched down.
    commanded : tuple of ndarray (3,), ndarray (3,)
        The commanded body pose of the last period: position [m], roll, pitch, yaw [rad].
    settled, forces : ndarray (4,) bool, ndarray (4,) or None
        Of the last period: the legs whose role change is complete, and the vertical force
        sensor readings [N] (None when nothing needed them), for the stance watch.
    """

    def __init__(self, robot: RobotDescription, config: LowLevelConfig, touchdown_force: float,
                 slip_watch: bool) -> None:
        self.robot, self.config = robot, config
        self.period = config.period  # [s]
        follow = config.anchor_follow_time  # [s] or None (slipped feet held)
        self._follow_rate = 0.0 if follow is None else 1.0 - math.exp(-self.period / follow)
        self.lift = np.array([0.0, 0.0, robot.foot_radius])  # contact point -> ball centre [m]
        self._weight = robot.total_mass * GRAVITY  # [N]
        self._touchdown_force = touchdown_force
        self._read_forces = config.load_gain > 0 or self._follow_rate > 0 or slip_watch

    def start(self, est: BodyEstimate, footholds: np.ndarray) -> None:
        """The robot stands on ``footholds`` (4, 3) [m] (contact points), as ``est`` measures it."""
        self.q = est.q.copy()
        self.targets = np.array(footholds) + self.lift
        self.stance = np.ones(4, dtype=bool)
        self.since = np.full(4, -np.inf)
        self.correction = BodyCorrection(self.config)
        self.anchor = self.targets.copy()
        self.down = self.targets.copy()
        self.shin0 = shin_rotations(self.q, body_rotation(est.pose[1]))  # (4, 3, 3) shins then
        self.press = np.zeros(4)  # [m] stance feet's load control offsets (target heights)
        self.hold_yields = False  # the load hold yields (the stance watch raised an alarm)
        self.unload = np.ones(4)
        self.settled, self.forces = np.ones(4, dtype=bool), None
        self.commanded = est.pose[0].copy(), est.pose[1].copy()  # [m], [rad] (no period yet)

    def set_role(self, leg: int, stance: bool, time: float) -> None:
        """Leg ``leg`` starts passing its load on (stance) or off (swing) at ``time`` [s]."""
        self.stance[leg] = stance
        self.since[leg] = time
        self.unload[leg] = 1.0

    def anchor_here(self, legs: int | np.ndarray, centres: np.ndarray, q: np.ndarray,
                    rpy: np.ndarray) -> None:
        """Anchor ``legs`` (an index or a mask) at their foot centres ``centres`` [m], where
        they stand now, with their shins' orientation now -- from the joint angles ``q``
        (4, 3) [rad] and the body attitude ``rpy`` (3,) [rad] -- so the ball's rolling counts
        from here."""
        self.anchor[legs] = self.targets[legs] = centres
        self.shin0[legs] = shin_rotations(q, body_rotation(rpy))[legs]

    def hand_over(self) -> None:
        """A foot is about to take a new anchor where it stands: with ``hand_over``, the
        horizontal body correction passes to the stance feet's anchors (their set-points stay),
        so that the foot enters a commanded frame without it (:func:`handed_over`); with
        ``hand_over_height`` and ``hand_over_attitude`` its height and its roll and pitch too
        (:func:`handed_over_pose`)."""
        cfg = self.config
        if not cfg.hand_over:
            return
        taken, turned = self.correction.take(cfg.hand_over_height, cfg.hand_over_attitude)
        position, rpy = self.commanded
        after = np.array(rpy, dtype=np.float64)
        after[:2] -= turned
        self.commanded = position - taken, after  # (what the correction now commands)
        if not turned.any():  # a translation: the anchors move by it (the stance targets
            self.anchor = handed_over(self.anchor, self.stance, taken)  # follow next period)
            return
        offsets = self.targets - self.anchor  # rolled and pressed (kept as they are)
        moved = handed_over_pose(self.targets, self.stance, (position, body_rotation(rpy)),
                                 (position - taken, body_rotation(after)))
        self.anchor = np.where(self.stance[:, None], moved - offsets, self.anchor)

    def set_points(self, position: np.ndarray, rpy: np.ndarray, est: BodyEstimate
                   ) -> JointTargets:
        """The set-points of one control period toward the desired body ``position`` (3,) [m]
        and ``rpy`` (3,) [rad], the robot as ``est`` measures it."""
        cfg = self.config
        mpos, mrpy = est.pose
        cpos, crpy = self.correction.update(position, rpy, mpos, mrpy)
        self.commanded = cpos, crpy  # [m], [rad]: the commanded body pose of this period
        rot = body_rotation(crpy), est.rotation  # commanded, measured
        ramp = transfer_weight(est.time - self.since, cfg.transfer_time)
        weight = np.where(self.stance, ramp, 1.0 - ramp)
        stance = self.stance
        forces = est.forces()[:, 2] if self._read_forces else None  # [N] vertical readings
        if self._follow_rate > 0:  # slipped feet re-anchored where they stand
            # (a foot that carries nothing, being unloaded or just set down, is not let go of:
            # its gap is the body dragging it, not a slip)
            loaded = stance & (ramp >= 1.0) & (self.unload >= 1.0) & (
                forces > self._touchdown_force)
            self.anchor, shift = reanchor(self.anchor, self.targets, est.feet, loaded, stance,
                                          self._follow_rate)
            self.correction.shift(shift)
        # Stance feet: where they touched down, moved on as far as their balls have rolled since.
        self.targets[stance] = self.anchor[stance] + rolled(
            self.shin0[stance], est.shins()[stance], self.robot.foot_radius)
        torque = self._supported(est, ramp, forces)
        q, _ = joint_targets(self.robot, self.targets, (cpos, rot[0]), (mpos, rot[1]), weight,
                             self.q)
        targets = JointTargets(q, (q - self.q) / self.period, torque)
        self.q = q
        self.settled, self.forces = ramp >= 1.0, forces
        return targets

    def _supported(self, est: BodyEstimate, ramp: np.ndarray, forces: np.ndarray | None
                   ) -> np.ndarray | None:
        """Stance load control: the target heights that share the weight out, and the
        feed-forward torques (4, 3) [N m] that carry it (None without them)."""
        cfg = self.config
        if not (cfg.load_gain > 0 or cfg.support_feedforward > 0):
            return None
        stance = self.stance
        shares = load_shares(est.feet[:, :2], est.com[:2],
                             np.where(stance, ramp, 0.0) * self.unload)
        if cfg.load_gain > 0:  # each stance foot carries its share (its force sensor)
            if not self.hold_yields and load_held(stance, est.time - self.since,
                                                  cfg.load_hold):  # a new foot settles
                self.press = np.where(stance, self.press, 0.0)
            else:
                self.press = load_offsets(self.press, forces, shares, stance,
                                          cfg.load_gain * self.period, cfg.load_limit)
            if cfg.press_speed > 0:  # new feet pressed down while they carry too little
                new = stance & (est.time - self.since < cfg.press_time)
                if new.any():
                    owed = cfg.press_share * self._weight * load_shares(
                        est.feet[:, :2], est.com[:2], np.where(stance, self.unload, 0.0))
                    self.press = pressed(self.press, new, forces, owed,
                                         cfg.press_speed * self.period, cfg.press_depth)
            self.targets[:, 2] += self.press
        if cfg.support_feedforward > 0:  # the servos are given the torques that carry it
            return support_torques(est.jacobians(),
                                   cfg.support_feedforward * self._weight * shares)
        return None
