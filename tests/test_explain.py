"""Why a run failed: the flight recorder, the support margin and the failure taxonomy."""

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.robot import LITTLEDOG
from footfall.sim.explain import (
    CAUSES,
    SLIP_MOVED,
    explain_run,
    explanation_lines,
    hull_margin,
)
from footfall.sim.trace import ROW_WIDTH, RunTrace, trace_row

MID_RANGE = np.array([[0.5 * (lo + hi) for lo, hi in leg.limits] for leg in LITTLEDOG.legs])
SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def test_hull_margin_is_the_signed_distance_inside_the_stance_feet():
    four = np.ones(4, dtype=bool)
    assert hull_margin(SQUARE, four, np.array([0.5, 0.5])) == pytest.approx(0.5)
    assert hull_margin(SQUARE, four, np.array([0.2, 0.5])) == pytest.approx(0.2)
    assert hull_margin(SQUARE, four, np.array([-0.2, 0.5])) == pytest.approx(-0.2)
    # the order of the feet does not matter (a crossed quadrilateral is still its hull)
    assert hull_margin(SQUARE[[0, 2, 1, 3]], four, np.array([0.5, 0.3])) == pytest.approx(0.3)
    # three stance feet: the triangle; its hypotenuse x + y = 1
    three = np.array([True, True, False, True])
    assert hull_margin(SQUARE, three, np.array([0.25, 0.5])) == pytest.approx(0.25 / np.sqrt(2))
    assert np.isnan(hull_margin(SQUARE, np.array([True, True, False, False]), np.zeros(2)))


def test_hull_margin_works_on_many_rows_at_once():
    rng = np.random.default_rng(0)
    feet = rng.uniform(-1, 1, (50, 4, 2))
    active = rng.random((50, 4)) > 0.2
    q = rng.uniform(-1, 1, (50, 2))
    many = hull_margin(feet, active, q)
    one_by_one = [hull_margin(feet[i], active[i], q[i]) for i in range(50)]
    np.testing.assert_allclose(many, one_by_one)


def test_the_trace_keeps_the_last_rows_in_time_order():
    trace = RunTrace(window=0.05, period=0.01)  # 5 rows
    feet = np.zeros((4, 3))
    for i in range(7):
        trace.record(trace_row(0.01 * i, np.zeros(3), np.zeros(3), np.zeros(3), feet, feet,
                               np.ones(4, bool), feet, feet, feet, None if i % 2 else 1))
    series = trace.series()
    np.testing.assert_allclose(series.time, [0.02, 0.03, 0.04, 0.05, 0.06])
    assert series.swing.tolist() == [1, -1, 1, -1, 1] and series.stance.all()
    assert trace_row(0.0, *[np.zeros(3)] * 3, feet, feet, np.ones(4, bool), feet, feet, feet,
                     None).shape == (ROW_WIDTH,)
    with pytest.raises(FootfallError):
        RunTrace(0.0, 0.01)


def test_an_infinite_trace_window_keeps_the_whole_run():
    # (WalkConfig.trace_window allows inf: the flight recorder over a whole run, for a diagnosis)
    trace = RunTrace(window=float("inf"), period=0.01)
    feet = np.zeros((4, 3))
    for i in range(2500):  # past the first buffer of 1 024 rows, and the second
        trace.record(trace_row(0.01 * i, np.zeros(3), np.zeros(3), np.zeros(3), feet, feet,
                               np.ones(4, bool), feet, feet, feet, None))
    np.testing.assert_allclose(trace.series().time, 0.01 * np.arange(2500))


def _trace(slide: float = 0.0, com_x: float = 0.0, tilt_end: float = 0.7,
           airborne: float = 0.0):
    """Two seconds of a robot standing on a 0.2 x 0.16 m rectangle; the LF foot slides by
    ``slide`` [m] over the first second, the COM sits at ``com_x``; the trunk then rolls.
    The LF foot's force is 0 (in the air) in the first ``airborne`` [s]."""
    trace = RunTrace(window=2.0, period=0.01)
    feet0 = np.array([[0.1, 0.08, 0.01], [0.1, -0.08, 0.01], [-0.1, 0.08, 0.01],
                      [-0.1, -0.08, 0.01]])
    for i in range(200):
        t = 0.01 * i
        feet = feet0.copy()
        feet[0, 0] += slide * min(1.0, t)
        force = np.tile([0.0, 0.0, 6.0], (4, 1))
        force[0, 2] = 0.0 if t < airborne else 6.0
        roll = tilt_end * max(0.0, t - 1.0)
        trace.record(trace_row(t, np.array([com_x, 0.0, 0.15]), np.array([roll, 0.0, 0.0]),
                               np.array([com_x, 0.0, 0.15]), feet, force, np.ones(4, bool),
                               feet0, MID_RANGE, np.zeros((4, 3)), None))
    return trace.series()


def test_a_stance_foot_that_slid_before_the_tilt_is_the_cause():
    e = explain_run(_trace(slide=0.04), {"success": False, "reason": "fall: trunk tilted"},
                    LITTLEDOG)
    assert e["cause"] == "stance foot slipped" and e["slip"]["leg"] == "LF"
    assert e["slip"]["moved_mm"] > 1e3 * SLIP_MOVED
    assert e["tilt_began_s_before_end"] == pytest.approx(0.77, abs=0.02)
    assert e["cause"] in CAUSES and len(explanation_lines(e)) == 6


def test_a_foot_that_moved_in_the_air_is_a_touch_down_that_did_not_take():
    slid = explain_run(_trace(slide=0.04), {"success": False, "reason": "fall: trunk tilted"},
                       LITTLEDOG)
    assert slid["slip"]["on_ground_share"] == 1.0  # pressed 6 N all along: a slide
    fell = {"success": False, "reason": "fall: trunk tilted"}
    # LF reads no force for the first 0.4 s; it passes SLIP_MOVED (15 mm) at 0.38 s: in the air
    e = explain_run(_trace(slide=0.04, airborne=0.4), fell, LITTLEDOG)
    assert e["slip"]["leg"] == "LF" and e["slip"]["on_ground_share"] == 0.0
    assert e["cause"] == "touch-down did not take" and e["cause"] in CAUSES
    assert "on the ground 0 % of its stance" in explanation_lines(e)[1]
    # on the ground most of the way (in the air its first 0.1 s): a slide after all
    e = explain_run(_trace(slide=0.04, airborne=0.1), fell, LITTLEDOG)
    assert e["slip"]["on_ground_share"] == pytest.approx(29 / 39)  # rows 0.10 .. 0.38 s of 0 .. 0.38
    assert e["cause"] == "stance foot slipped"


def test_a_centre_of_mass_outside_the_feet_is_the_cause_without_a_slip():
    e = explain_run(_trace(com_x=0.15), {"success": False, "reason": "fall: trunk tilted"},
                    LITTLEDOG)
    assert e["cause"] == "centre of mass left the support"
    assert e["com_margin_min_mm"] == pytest.approx(-50.0, abs=0.5)


def test_causes_of_runs_that_did_not_fall():
    series = _trace()
    assert explain_run(series, {"success": True, "reason": "goal"}, LITTLEDOG)["cause"] is None
    assert explain_run(series, {"success": False, "reason": "stuck: no progress"},
                       LITTLEDOG)["cause"] == "no progress"
    standing = explain_run(_trace(tilt_end=0.0), {"success": False,
                                                  "reason": "fall: trunk touched the terrain"},
                           LITTLEDOG)
    assert standing["cause"] == "other" and standing["tilt_began_s_before_end"] is None


def test_cli_walk_refuses_an_explain_plot_it_cannot_write(tmp_path, capsys):
    board = tmp_path / "b.npz"
    code, _, _ = run(capsys, "terrain", "board", "flat", "--seed", "1", "-o", str(board))
    assert code == 0
    code, _, err = run(capsys, "walk", "--terrain", str(board), "--seed", "0",
                       "--explain-plot", str(tmp_path / "plot.txt"))
    assert_user_error(code, err, "--explain-plot")
