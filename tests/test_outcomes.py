"""The robot's own labels of its footholds, on scripted runs whose endings are known."""

import math

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.state import nominal_state
from footfall.data.outcomes import MISSED, STANCE_SLID, step_outcomes
from footfall.data.runlog import RunRecord, RunStep

LEGS = ("LH", "LF", "RH", "RF")


def _scripted(slips, result, touched_last=False):
    """A run of len(slips) steps on flat ground; step k's planned foothold is (0.1 + 0.01 k, 0);
    each touches down 2 mm ahead of its plan but the last (unless ``touched_last``)."""
    hmap = HeightMap(np.zeros((50, 20)), 0.01)
    steps = []
    n = len(slips)
    for k, slip in enumerate(slips):
        state = nominal_state(hmap, (0.2, 0.1), 0.0, LEGS[k % 4])
        cand = np.array([[0.1 + 0.01 * k, 0.0, 0.0], [0.3, 0.05, 0.0]])
        down = k < n - 1 or touched_last
        steps.append(RunStep(k, state, cand, np.array([1.0, 0.0]), 0, 0.5 * k,
                             0.5 * k + 0.3 if down else math.nan,
                             cand[0] + [0.002, 0.0, 0.0] if down else np.full(3, np.nan),
                             slip))
    return RunRecord(hmap.content_hash(), 0, {}, result, tuple(steps))


def test_a_success_labels_only_the_feet_that_slid():
    run = _scripted([0.001, 0.020, 0.004, math.nan], {"success": True, "reason": "goal"},
                    touched_last=True)
    o = step_outcomes(run)
    assert o.used.tolist() == [True, True, True, True]
    np.testing.assert_allclose(o.placement_error, 0.002)
    assert o.slid.tolist() == [False, True, False, False]  # 20 mm > STANCE_SLID = 15 mm
    assert not o.fall.any() and not o.failed.any() and not o.missed.any()


def test_a_fall_counts_against_the_footholds_of_its_last_steps():
    slips = [0.001] * 7 + [math.nan]  # 8 steps; the fall came during step 7, whose foot never landed
    run = _scripted(slips, {"success": False, "reason": "fall: trunk tilted"})
    o = step_outcomes(run, horizon=3)
    assert o.used.tolist() == [True] * 7 + [False]
    assert np.isnan(o.placement_error[7])
    # Steps 4..7 are within 3 steps of the end (step 7 is the step the run ended in).
    assert o.fall.tolist() == [False] * 4 + [True] * 4
    assert o.failed.tolist() == o.fall.tolist()
    assert step_outcomes(run, horizon=0).fall.tolist() == [False] * 7 + [True]


def test_a_foot_that_lands_far_from_its_plan_missed_it():
    run = _scripted([0.001, 0.001, math.nan], {"success": True, "reason": "goal"},
                    touched_last=True)
    steps = list(run.steps)
    steps[1] = RunStep(1, steps[1].state, steps[1].candidates, steps[1].rewards, 0, 0.5, 0.8,
                       steps[1].candidates[0] + [0.0, MISSED + 0.001, 0.0], 0.001)
    o = step_outcomes(RunRecord(run.terrain_hash, 0, {}, run.result, tuple(steps)))
    assert o.missed.tolist() == [False, True, False]
    assert not o.next_missed.any()  # steps 0, 1, 2 swing three different legs
    assert o.placement_error[1] > MISSED


def test_the_foothold_a_missed_swing_left_from():
    run = _scripted([0.001] * 9 + [math.nan], {"success": True, "reason": "goal"},
                    touched_last=True)
    steps = list(run.steps)  # steps 1, 5, 9 swing LF; step 5's touch-down misses
    steps[5] = RunStep(5, steps[5].state, steps[5].candidates, steps[5].rewards, 0, 2.5, 2.8,
                       steps[5].candidates[0] + [0.05, 0.0, 0.0], 0.001)
    o = step_outcomes(RunRecord(run.terrain_hash, 0, {}, run.result, tuple(steps)))
    assert np.flatnonzero(o.missed).tolist() == [5]
    assert np.flatnonzero(o.next_missed).tolist() == [1]


def test_a_run_stuck_has_failed_but_not_fallen():
    run = _scripted([0.001] * 5, {"success": False, "reason": "stuck: no progress"})
    o = step_outcomes(run, horizon=1)
    assert not o.fall.any()
    assert o.failed.tolist() == [False, False, False, True, True]


def test_the_stance_foot_a_failure_is_put_down_to_has_slid_where_it_last_stood():
    # Steps 0..5 swing LH LF RH RF LH LF; the run fell in step 5 with the RH foot (last put down
    # in step 2) sliding 40 mm: that foothold slid, although its stance travel was never logged.
    slips = [0.001, 0.001, math.nan, 0.001, 0.001, math.nan]
    result = {"success": False, "reason": "fall: trunk tilted",
              "explanation": {"cause": "stance foot slipped",
                              "slip": {"leg": "RH", "moved_mm": 40.0}}}
    o = step_outcomes(_scripted(slips, result))
    assert o.slid.tolist() == [False, False, True, False, False, False]
    # A foot that moved less than the threshold is not called slid.
    result["explanation"]["slip"]["moved_mm"] = 1e3 * STANCE_SLID / 2
    assert not step_outcomes(_scripted(slips, result)).slid.any()


@pytest.mark.parametrize("kwargs", [{"horizon": -1}, {"horizon": 1.5}, {"horizon": True},
                                    {"slid_threshold": 0.0}, {"slid_threshold": math.nan}])
def test_bad_settings_are_refused(kwargs):
    run = _scripted([0.001, math.nan], {"success": True, "reason": "goal"})
    with pytest.raises(FootfallError):
        step_outcomes(run, **kwargs)
