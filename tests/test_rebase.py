"""Re-basing the stance after a recovery that leaves the body far from where it is wanted
(ReflexConfig.rebase_distance, footfall.control.reflexes.rebase.Rebase)."""

import numpy as np

from footfall.control.controller import Controller
from footfall.control.reflexes import ReflexConfig
from footfall.control.reflexes.recovery import recover
from scenes import staged


class Slid(Controller):
    """Stands 0.3 s with its anchors 10 mm to the left of its feet, then finds itself 60 mm
    behind where it is wanted (as when the whole robot has slid back off a step) and recovers
    as after an alarm. Records the body [m], the wanted body [m], the horizontal correction
    [m], the stance anchors and the feet [m] just after the recovery, and its events."""

    def step_phases(self, k):
        self.legs.anchor[:, 1] += 0.01
        for _ in range(30):
            yield from self.tick(*self.desired, None)
        self.desired[0][0] += 0.06
        yield from recover(self)
        self.body, self.wanted = self.pose[0].copy(), self.desired[0].copy()
        self.correction = self.legs.correction.position.copy()
        self.anchors_after = self.legs.anchor.copy()
        self.feet_after = self.est.feet.copy()
        return True


def _slide(rebase: float | None) -> Slid:
    run = staged(Slid, reflexes=ReflexConfig(rebase_distance=rebase))
    run.controller.events = run.record.result["events"]
    return run.controller


def test_a_body_far_from_where_it_is_wanted_is_taken_where_it_stands():
    kept, rebased = _slide(None), _slide(0.03)
    # without re-basing the body is still wanted 60 mm ahead, the anchors stay off the feet
    # and the correction keeps its pull
    assert kept.wanted[0] - kept.body[0] > 0.05
    assert abs(kept.correction[1]) > 0.002
    assert np.abs(kept.anchors_after - kept.feet_after)[:, 1].min() > 0.005
    # re-based: wanted where it stands, every stance foot anchored where it stands, the
    # horizontal correction cleared, and the event in the run log
    np.testing.assert_allclose(rebased.wanted[:2], rebased.body[:2], atol=1e-12)
    np.testing.assert_allclose(rebased.correction[:2], 0.0, atol=1e-12)
    np.testing.assert_allclose(rebased.anchors_after, rebased.feet_after, atol=1e-12)
    assert [e["event"] for e in rebased.events] == ["re-based"]
    assert rebased.events[0]["off_mm"] > 50.0
    assert not [e for e in kept.events if e["event"] == "re-based"]


def test_a_body_near_where_it_is_wanted_is_not_re_based():
    run = _slide(0.1)  # 60 mm is within this distance
    assert not [e for e in run.events if e["event"] == "re-based"]
    assert run.wanted[0] - run.body[0] > 0.05
