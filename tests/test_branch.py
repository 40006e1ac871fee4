"""Branching a run at a decision (footfall.sim.branch): the recorded choice forced gives the
recorded run bit for bit; another candidate gives another run from that step on."""

import json

import numpy as np
import pytest

from cli_helpers import run
from footfall.core.errors import FootfallError
from footfall.experiments.reproduce import ReproduceConfig
from footfall.features.reward import default_reward
from footfall.sim.branch import TapedWalk
from footfall.sim.episode import WALL_CLOCK_FIELDS, WalkConfig
from footfall.terrain import make_board, parse_board_spec


@pytest.fixture(scope="module")
def taped():
    """A rough run that is eventful: a step called off by the tilt reflex (so decisions and
    steps are numbered apart), two tilt alarms, and a fall at its end."""
    reward = default_reward()
    hmap = make_board([parse_board_spec("rocky:1.0")], seed=3)
    walk = TapedWalk(hmap, lambda leg: reward, 1, WalkConfig(max_steps=20))
    return walk, walk.run()


def same_run(a, b):
    """Two run logs equal bit for bit, but for the wall clock."""
    strip = lambda r: {k: v for k, v in r.result.items() if k not in WALL_CLOCK_FIELDS}  # noqa: E731
    assert strip(a) == strip(b)
    assert a.settings == b.settings and a.terrain_hash == b.terrain_hash
    assert len(a.steps) == len(b.steps)
    for sa, sb in zip(a.steps, b.steps):
        assert sa.state.swing_leg == sb.state.swing_leg and sa.chosen == sb.chosen
        np.testing.assert_array_equal(sa.state.to_vector(), sb.state.to_vector())
        np.testing.assert_array_equal(sa.candidates, sb.candidates)
        np.testing.assert_array_equal(sa.rewards, sb.rewards)
        np.testing.assert_array_equal(sa.touchdown, sb.touchdown)
        np.testing.assert_array_equal([sa.t_liftoff, sa.t_touchdown, sa.slip],  # NaN: none
                                      [sb.t_liftoff, sb.t_touchdown, sb.slip])


def test_the_taped_run_is_eventful_and_keeps_every_decision(taped):
    walk, record = taped
    tape = walk.tape
    assert not record.result["success"] and record.result["reason"].startswith("fall")
    assert record.result["reflexes"].get("tilt", 0) >= 1
    assert len(tape.decisions) > len(record.steps)  # a step planned and called off
    assert [d.index for d in tape.decisions] == list(range(len(tape.decisions)))
    periods = [d.periods for d in tape.decisions]
    assert periods == sorted(periods) and periods[-1] < len(tape.measurements)
    times = [d.physics[0] for d in tape.decisions]  # the integration state starts with time
    assert times == sorted(times) and times[0] > 0


@pytest.mark.parametrize("where", ["first", "middle", "last"])
def test_forcing_the_recorded_choice_gives_the_recorded_run_bit_for_bit(taped, where):
    walk, record = taped
    n = len(walk.tape.decisions)
    at = {"first": 0, "middle": n // 2, "last": n - 1}[where]
    same_run(walk.branch(at).record, record)
    chosen = walk.tape.decisions[at].plan.index
    same_run(walk.branch(at, first=chosen).record, record)  # the same candidate, planned again


def test_another_candidate_is_taken_there_and_the_run_goes_on_from_it(taped):
    walk, record = taped
    at = 4
    decision = walk.tape.decisions[at]
    k = len(decision.task.steps)  # the step this decision plans
    ranked = np.argsort(-decision.plan.value, kind="stable")
    other = int(ranked[1])
    assert other != decision.plan.index
    branch = walk.branch(at, first=other).record
    for sa, sb in zip(branch.steps[:k], record.steps[:k]):  # the steps before: the recorded
        assert sa.chosen == sb.chosen
        np.testing.assert_array_equal(sa.touchdown, sb.touchdown)
    assert branch.steps[k].chosen == other
    np.testing.assert_array_equal(branch.steps[k].candidates, record.steps[k].candidates)
    assert branch.result != record.result
    # the branch is itself a run: walked twice, the same
    same_run(walk.branch(at, first=other).record, branch)


def test_a_branch_refuses_what_the_run_does_not_have(taped):
    walk, _ = taped
    n = len(walk.tape.decisions)
    with pytest.raises(FootfallError, match="no decision"):
        walk.branch(n)
    with pytest.raises(FootfallError, match="no decision"):
        walk.branch(-1)
    size = walk.tape.decisions[0].plan.candidates.shape[0]
    with pytest.raises(FootfallError, match="first must be <"):
        walk.branch(0, first=size)


def test_the_branch_benchmark_times_both_ways_and_they_agree(capsys):
    code, out, _ = run(capsys, "bench", "branch", "--decisions", "1", "--tries", "1", "--json")
    assert code == 0
    result = json.loads(out)
    assert result["agree"] is True and len(result["branches"]) == 1
    row = result["branches"][0]
    assert 0 < row["physics_cpu_s"] < row["forked_cpu_s"] and row["replayed_cpu_s"] > 0


@pytest.mark.parametrize("kind", ReproduceConfig().test_kinds)
def test_every_test_kind_branches_bit_for_bit(kind):
    """A run on a board of each test kind (the reproduction's, at difficulty 1.0): branched at
    a middle decision with its recorded choice, the recorded run again."""
    reward = default_reward()
    hmap = make_board([parse_board_spec(f"{kind}:1.0")], seed=11)
    walk = TapedWalk(hmap, lambda leg: reward, 2, WalkConfig(max_steps=12))
    record = walk.run()
    same_run(walk.branch(len(walk.tape.decisions) // 2).record, record)
