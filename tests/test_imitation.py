"""The imitation gap: a student's failed runs where its teacher crossed, judged step by step."""

import numpy as np
import pytest

from footfall.experiments.imitation import CAUSES, END_STEPS, imitation_gap, judge_gap_run
from test_corrections import VetoExpert, _run
from test_store import terrain


def _failed(run, reason="trunk tilted"):
    return type(run)(run.terrain_hash, run.seed, run.settings, {"success": False,
                                                                 "reason": reason},
                     run.steps, key="eval/test0/both/s3")


def test_a_scripted_pair_of_runs_is_an_imitation_error_or_accepted_throughout():
    hm = terrain()
    teacher = VetoExpert()  # best x = 0.34 m; refuses below 0.315 m; 1 value unit a cm
    crossed = _run(hm, [0.34] * 6)
    # parted at step 1 (0.33: 1 unit short, acceptable at margin 2), unacceptable at step 3
    # (0.31: refused), two steps before the run's last: in its last gait cycle
    erring = _failed(_run(hm, [0.34, 0.33, 0.34, 0.31, 0.34, 0.34]))
    g = judge_gap_run(erring, hm, teacher, margin=2.0)
    assert (g.parted, g.unacceptable, g.refused, g.cause) == (1, 3, True, CAUSES[0])
    assert (g.last_unacceptable, g.unacceptable_steps) == (3, 1)
    assert g.parted_shortfall == pytest.approx(1.0) and g.unacceptable_shortfall == \
        pytest.approx(3.0)
    # refused at steps 0 and 1, then END_STEPS acceptable steps before the end: earlier
    early = _failed(_run(hm, [0.31, 0.30] + [0.34] * END_STEPS))
    e = judge_gap_run(early, hm, teacher, margin=2.0)
    assert (e.unacceptable, e.last_unacceptable, e.unacceptable_steps, e.cause) == \
        (0, 1, 2, CAUSES[1])
    # one step later and the last refusal falls inside the last gait cycle
    assert judge_gap_run(_failed(_run(hm, [0.31, 0.34, 0.30] + [0.34] * (END_STEPS - 1))), hm,
                         teacher, margin=2.0).cause == CAUSES[0]
    # every foothold within the margin: a failure the teacher's choices could have met
    close = _failed(_run(hm, [0.34, 0.33, 0.32, 0.34, 0.33, 0.34]))
    h = judge_gap_run(close, hm, teacher, margin=2.0)
    assert (h.parted, h.unacceptable, h.last_unacceptable, h.cause) == (1, None, None,
                                                                         CAUSES[2])
    # the same student run is 2.5 units short at step 2 with a margin of 1.5: an error there
    assert judge_gap_run(close, hm, teacher, margin=1.5).unacceptable == 2
    both_crossed = _run(hm, [0.33] * 6)
    out = imitation_gap([(erring, crossed), (early, crossed), (close, crossed),
                         (both_crossed, crossed), (crossed, _failed(crossed))],
                        {hm.content_hash(): hm}, teacher, 2.0)
    assert (out["pairs"], out["student_only"], out["teacher_only"]) == (5, 1, 3)
    assert out["by_cause"] == {c: 1 for c in CAUSES} and out["refused"] == 2
    assert [r["cause"] for r in out["runs"]] == list(CAUSES)
    assert np.isfinite([out["runs"][0]["parted_shortfall"]]).all()
