"""Each reflex of the controller as a part on its own (footfall.control.reflexes.*), driven by a
scripted stand-in for the controller and the robot around it: no simulator, no planner."""

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from footfall.control.estimate import BodyEstimate
from footfall.control.legs import Legs
from footfall.control.lowlevel import LowLevelConfig
from footfall.control.measurements import Measurements
from footfall.control.reflexes import ReflexConfig
from footfall.control.reflexes.gate import LiftOffGate
from footfall.control.reflexes.rebase import Rebase
from footfall.control.reflexes.recovery import recover
from footfall.control.reflexes.slip import SlipReflex
from footfall.control.reflexes.tilt import TiltReflex
from footfall.control.reflexes.touchdown import TouchdownCheck
from footfall.core.kinematics import body_to_world, legs_forward_kinematics
from footfall.core.robot import LITTLEDOG

R = LITTLEDOG
RC = ReflexConfig()
PERIOD = 0.01  # [s]
Q0 = np.array([[0.0, -0.6, 1.2], [0.0, -0.6, 1.2], [0.0, 0.6, -1.2], [0.0, 0.6, -1.2]])  # [rad]
BODY = np.array([0.3, 0.0, 0.14])  # [m]


class Stand:
    """A stand-in for the controller around one reflex: the robot standing at BODY with its
    legs at Q0, as the controller sees it; ``world(stand)`` scripts what changes every period."""

    def __init__(self, world=lambda stand: None, reflexes: ReflexConfig = RC) -> None:
        m = Measurements(0.0, Q0.copy(), BODY.copy(), np.zeros(3), np.zeros((4, 3)))
        self.est = BodyEstimate(m, R)
        self.pose = self.est.pose
        self.legs = Legs(R, LowLevelConfig(), 2.0, False)
        self.legs.start(self.est, self.est.feet - self.legs.lift)
        self.desired = BODY.copy(), np.zeros(3)
        self.config = SimpleNamespace(reflexes=reflexes, touchdown_approach=0.008,
                                      touchdown_speed=0.1, touchdown_early=0.7,
                                      touchdown_search=0.02)
        self.robot, self.period, self.world = R, PERIOD, world
        self.alarm, self.held, self.recovering, self.replace = None, False, False, None
        self.slip, self.rebase = SlipReflex(reflexes, 2.0), Rebase(reflexes)
        self.events: list[tuple] = []
        self.periods = 0

    def tick(self, position, rpy, swing):
        self.periods += 1
        yield None  # (the targets are the low level's business, not the reflex's)
        self.est.time += PERIOD
        self.world(self)

    def event(self, kind, leg, **details):
        self.events.append((kind, leg, details))


def finish(phase):
    """Run a phase (a generator of periods) to its end; its answer."""
    try:
        while True:
            next(phase)
    except StopIteration as done:
        return done.value


def _others(s: int) -> list[int]:
    return [j for j in range(4) if j != s]


# ------------------------------------------------------------------ lift-off gate
def test_the_gate_opens_at_once_for_a_centre_of_mass_well_inside():
    stand = Stand()
    stand.est.com = np.array([*stand.est.feet[_others(2), :2].mean(axis=0), 0.1])
    assert finish(LiftOffGate(RC).wait(stand, 2)) is True
    assert stand.periods == 0 and not stand.events and not stand.held


def test_the_gate_moves_the_body_toward_the_triangle_until_the_centre_of_mass_is_inside():
    def follows(stand):  # the centre of mass goes where the body is wanted, 20 mm behind it
        stand.est.com = np.array([*(stand.desired[0][:2] - [0.02, 0.0]), 0.1])

    stand = Stand(follows)
    follows(stand)
    start = stand.desired[0][:2].copy()
    gate = LiftOffGate(RC)
    assert not gate.open(stand.est.com[:2], stand.est.feet[_others(0), :2])  # LF: COM behind
    assert finish(gate.wait(stand, 0)) is True
    (kind, leg, details), = stand.events
    assert kind == "lift-off gate" and leg == 0
    assert details["waited_s"] == pytest.approx(stand.periods * PERIOD)
    assert stand.held  # the body holds where it waited through the swing
    moved = np.hypot(*(stand.desired[0][:2] - start))
    assert 0 < moved <= RC.gate_speed * PERIOD * stand.periods + 1e-12
    assert gate.open(stand.est.com[:2], stand.est.feet[_others(0), :2])


def test_the_gate_gives_up_after_its_timeout_and_is_off_when_switched_off():
    stand = Stand()  # the centre of mass never comes: far behind the feet
    stand.est.com = np.array([0.0, 0.0, 0.1])
    assert finish(LiftOffGate(RC).wait(stand, 0)) is False
    assert stand.events[-1][0] == "lift-off gate timeout"
    assert stand.periods == pytest.approx(RC.gate_timeout / PERIOD, abs=1)
    off = Stand()
    off.est.com = np.array([0.0, 0.0, 0.1])
    assert finish(LiftOffGate(replace(RC, lift_off_gate=False)).wait(off, 0)) is True
    assert off.periods == 0


# ------------------------------------------------------------------ stance watch
def test_the_slip_reflex_sees_a_loaded_stance_foot_sliding_away():
    slip = SlipReflex(replace(RC, slip_reflex=True), touchdown_force=2.0)
    targets = np.zeros((4, 3))
    feet = targets + [[0.0, 0.0, 0.0], [0.0, -0.02, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
    fast, slow = np.array([0.0, 0.1, 0.0, 0.0]), np.array([0.0, 0.01, 0.0, 0.0])  # [m/s]
    stance, forces = np.ones(4, dtype=bool), np.full(4, 6.0)  # [N]
    assert slip.watch(feet, fast, targets, stance, forces) == 1
    assert slip.watch(feet, slow, targets, stance, forces) is None  # a leg giving, not a slide
    assert slip.watch(feet, fast, targets, stance, np.array([6, 1, 6, 6.0])) is None  # unloaded
    assert slip.watch(feet * 0.5, fast, targets, stance, forces) is None  # 10 mm: within reach
    off = SlipReflex(RC, touchdown_force=2.0)  # off by default
    assert off.watch(feet, fast, targets, stance, forces) is None


def test_the_tilt_reflex_sees_the_trunk_tip_past_its_threshold():
    tilt = TiltReflex(RC)
    level = np.zeros(3)
    assert tilt.watch(np.array([0.15, 0.0, 1.0]), level, False) == pytest.approx(0.15)
    assert tilt.watch(np.array([0.0, -0.1, 0.0]), level, False) is None
    assert tilt.watch(np.array([0.15, 0.0, 0.0]), level, True) is None  # recovering already
    assert TiltReflex(replace(RC, tilt_reflex=False)).watch(np.array([0.5, 0, 0]), level,
                                                            False) is None


# ------------------------------------------------------------------ touch-down check
class _Placing(Stand):
    """The foot of leg 0 follows its target exactly (a perfect servo) and feels the ground at
    z = 0."""

    def __init__(self, reflexes: ReflexConfig = RC) -> None:
        super().__init__(self._follow, reflexes)
        self.hmap = SimpleNamespace(height_at=lambda xy: np.zeros(len(xy)))

    @staticmethod
    def _follow(stand):
        stand.est.feet[0] = stand.legs.targets[0]

    def swing_path(self, centre, above, reach, after):
        """Straight from ``centre`` to over the contact point ``above``, then on down."""
        lift = self.legs.lift
        u = np.minimum(after / reach, 1.0)[:, None]
        path = centre + u * (above + lift - centre)
        path[:, 2] -= 0.1 * np.maximum(after - reach, 0.0)  # on down at touchdown_speed
        return path

    def touching_down(self, leg):
        return bool(self.est.feet[leg, 2] <= R.foot_radius + 1e-9)


def test_a_foot_far_off_its_foothold_is_put_on_the_next_best_candidate():
    stand = _Placing()
    foothold = np.array([0.45, 0.08, 0.0])
    candidates = np.array([foothold, [0.46, 0.08, 0.0], [0.45, 0.11, 0.0], [0.40, 0.2, 0.0]])
    plan = SimpleNamespace(foothold=foothold, candidates=candidates,
                           total=np.array([3.0, 2.5, 2.0, 1.0]))
    stand.est.feet[0] = foothold + [0.0, -0.03, R.foot_radius]  # landed 30 mm to the right
    finish(TouchdownCheck(RC).place(stand, 0, plan, True))
    (kind, leg, details), = stand.events
    assert kind == "touch-down re-placed" and leg == 0
    assert details == {"off_mm": pytest.approx(30.0), "ground": True}
    # candidate 1 is within replace_separation of the foothold tried: candidate 2 it is
    np.testing.assert_allclose(stand.est.feet[0, :2], candidates[2, :2], atol=1e-9)
    assert stand.touching_down(0)
    unchecked = _Placing(replace(RC, touchdown_check=False))
    unchecked.est.feet[0] = foothold + [0.0, -0.03, R.foot_radius]
    finish(TouchdownCheck(unchecked.config.reflexes).place(unchecked, 0, plan, True))
    assert unchecked.periods == 0 and not unchecked.events


# ------------------------------------------------------------------ recovery and re-basing
def test_recovery_waits_for_the_posture_and_accepts_one_it_cannot_reach():
    def levels(stand):  # the trunk rights itself by 0.02 rad a period
        stand.pose = (stand.pose[0], np.array([max(stand.pose[1][0] - 0.02, 0.0), 0.0, 0.0]))

    rights = Stand(levels)
    rights.pose = (BODY.copy(), np.array([0.2, 0.0, 0.0]))
    rights.alarm = ("tilt", None)
    finish(recover(rights))
    assert rights.alarm is None and not rights.events
    assert rights.periods == 8  # 0.2 rad down to below tilt_recovered (0.05 rad)
    stuck = Stand()  # the trunk stays 0.2 rad rolled (joints at their limits)
    stuck.pose = (BODY.copy(), np.array([0.2, 0.0, 0.0]))
    stuck.alarm = ("tilt", None)
    finish(recover(stuck))
    assert stuck.periods == pytest.approx(RC.recover_timeout / PERIOD, abs=1)
    (kind, _, details), = stuck.events
    assert kind == "posture accepted" and details["error_rad"] == pytest.approx(0.2)
    assert stuck.desired[1][0] == pytest.approx(0.2)  # the plan goes on from it


@pytest.mark.parametrize("slide, steps_first", [(0.006, True), (0.003, False)])
def test_a_slipped_foot_stands_where_it_stopped_and_steps_first_if_it_went_far(slide,
                                                                            steps_first):
    def slides(stand):  # the right front foot slides `slide` [m] a period for five periods
        if stand.periods <= 5:
            stand.est.feet = stand.est.feet.copy()
            stand.est.feet[1, 1] -= slide

    stand = Stand(slides, replace(RC, slip_reflex=True))
    before = stand.est.feet[1].copy()
    stand.alarm = ("slip", 1)
    finish(recover(stand))
    assert stand.periods == 6  # slid five periods, stood still the sixth
    np.testing.assert_allclose(stand.est.feet[1], before - [0.0, 5 * slide, 0.0])
    np.testing.assert_array_equal(stand.legs.down[1], stand.est.feet[1])  # taken where it is
    np.testing.assert_array_equal(stand.legs.anchor[1], stand.est.feet[1])
    # 30 mm is past replace_distance (25 mm): it steps first; 15 mm is not
    assert stand.replace == (1 if steps_first else None)
    assert stand.alarm is None and not stand.events


def test_re_basing_takes_the_stance_where_it_stands_when_the_body_is_far_off():
    assert Rebase(RC).due(BODY, BODY + [0.1, 0, 0]) is None  # off by default
    rebase = Rebase(replace(RC, rebase_distance=0.03))
    assert rebase.due(BODY, BODY + [0.02, 0.0, 0.0]) is None
    assert rebase.due(BODY, BODY + [0.03, 0.04, 0.0]) == pytest.approx(0.05)
    stand = Stand(reflexes=replace(RC, rebase_distance=0.03))
    stand.desired = (BODY + [0.06, 0.0, 0.0], np.zeros(3))
    stand.legs.anchor = stand.legs.anchor + [0.0, 0.01, 0.0]
    stand.legs.correction.position = np.array([0.01, -0.02, 0.003])
    stand.rebase.after_recovery(stand)
    np.testing.assert_allclose(stand.desired[0][:2], BODY[:2])
    np.testing.assert_allclose(stand.legs.anchor, stand.est.feet)
    np.testing.assert_allclose(stand.legs.correction.position, [0.0, 0.0, 0.003])
    assert [e[0] for e in stand.events] == ["re-based"]
    np.testing.assert_allclose(stand.est.feet,
                               body_to_world(legs_forward_kinematics(R, Q0), BODY, np.zeros(3)),
                               atol=1e-12)  # (the stand-in's feet: where its legs put them)
