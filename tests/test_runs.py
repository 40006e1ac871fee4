"""Table II's summary of many runs: success rate with its Wilson interval, slip of successful runs."""

import math

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.state import nominal_state
from footfall.core.stats import wilson_interval
from footfall.data.runlog import RunRecord, RunStep
from footfall.experiments.batch import summarise
from test_store import terrain


def _record(hm, success, slips, speed=5.0):
    steps = []
    for k, slip in enumerate(slips):
        state = nominal_state(hm, (0.2, 0.0), 0.0, ("LH", "LF", "RH", "RF")[k % 4])
        steps.append(RunStep(k, state, np.zeros((2, 3)), np.zeros(2), 0, 0.1 * k, 0.1 * k + 0.05,
                             np.zeros(3), slip))
    result = {"success": success, "reason": "goal" if success else "fall: trunk tilted",
              "speed_cm_s": speed, "speed_body_lengths_s": speed / 30.0}
    return RunRecord(hm.content_hash(), 0, {}, result, tuple(steps))


def test_summary_averages_slip_over_successful_runs_only():
    hm = terrain()
    records = [_record(hm, True, [0.010, 0.020, math.nan]),  # last foothold: never lifted again
               _record(hm, True, [0.030], speed=7.0),
               _record(hm, False, [0.500, 0.400])]  # a failed run's slip does not count
    s = summarise(records)
    assert (s.runs, s.successes) == (3, 2)
    assert s.success_rate == pytest.approx(2 / 3)
    assert s.success_ci == wilson_interval(2, 3)
    assert s.slip_count == 3
    assert s.slip_mean_mm == pytest.approx(20.0)
    assert s.slip_std_mm == pytest.approx(np.std([10.0, 20.0, 30.0]))
    assert s.speed_cm_s == pytest.approx(6.0)
    assert s.reasons == {"goal": 2, "fall: trunk tilted": 1}


def test_summary_without_a_success_has_no_slip():
    hm = terrain()
    s = summarise([_record(hm, False, [0.01])])
    assert s.successes == 0 and s.slip_mean_mm is None and s.speed_cm_s is None
    assert s.success_ci[0] == 0.0
    with pytest.raises(FootfallError, match="no runs"):
        summarise([])


def test_video_and_strip_are_written(tmp_path):
    import imageio.v2 as imageio

    from footfall.experiments.batch import save_strip, save_video

    frames = [np.full((64, 96, 3), 10 * i, np.uint8) for i in range(12)]
    save_video(frames, tmp_path / "run.mp4", fps=25.0)
    reader = imageio.get_reader(tmp_path / "run.mp4")
    assert reader.count_frames() == 12 and reader.get_meta_data()["fps"] == 25.0
    reader.close()
    save_strip([(0.5 * i, f) for i, f in enumerate(frames[:4])], tmp_path / "strip.png")
    assert (tmp_path / "strip.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob(".*.tmp*"))  # written through a temporary file and renamed


def test_a_board_file_is_made_once_and_never_mistaken_for_another_board(tmp_path):
    """A stage that chooses a board later (the test boards at the calibrated difficulty) must
    not resume on a file left with another difficulty or seed: one clear error instead."""
    from footfall.core.errors import FootfallError
    from footfall.experiments.runs import board_files

    spec = (("rocky", 0.6), ("steps", 0.6))
    path = board_files(tmp_path, {"test0": (spec, 11, True)})["test0"]
    made = path.stat().st_mtime_ns
    assert board_files(tmp_path, {"test0": (spec, 11, True)})["test0"].stat().st_mtime_ns == made
    flat = ((("flat", 0.0),) * 3)
    board_files(tmp_path, {"flat": (flat, 5, False)})
    board_files(tmp_path, {"flat": (flat, 5, False)})  # an all-flat board is itself too
    for other in ({"test0": ((("rocky", 0.8), ("steps", 0.8)), 11, True)},
                  {"test0": (spec, 12, True)}):
        with pytest.raises(FootfallError, match="holds another board than test0"):
            board_files(tmp_path, other)
