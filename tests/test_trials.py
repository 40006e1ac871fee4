"""Learning from the robot's own trials: footholds labelled by what followed, as comparisons."""

import math

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG
from footfall.core.state import nominal_state
from footfall.data.runlog import RunRecord, RunStep
from footfall.data.store import DemoStore
from footfall.expert.corrections import correct_stored_runs
from footfall.features.family import Candidates
from footfall.learning.dataset import design_matrix, make_example, pair_example
from footfall.learning.model import FootholdModel
from footfall.learning.train import learn_model
from footfall.learning.trials import TrialFoothold, trial_footholds, trial_pairs
from test_corrections import TableExpert

LEGS = ("LH", "LF", "RH", "RF")


def test_pairs_rank_each_bad_foothold_below_good_ones_of_its_own_board_and_leg_group():
    board = np.array(["a"] * 6 + ["b"] * 4)
    front = np.array([True, True, True, False, False, False, True, True, False, False])
    bad = np.array([True, False, False, True, False, False, True, False, True, True])
    pairs = trial_pairs(board, front, bad, 4, np.random.default_rng(0))
    good, worse = pairs.T
    assert not bad[good].any() and bad[worse].all()
    assert (board[good] == board[worse]).all() and (front[good] == front[worse]).all()
    # each bad foothold against every good one of its cell (at most 4), each once
    assert sorted(map(tuple, pairs.tolist())) == [(1, 0), (2, 0), (4, 3), (5, 3), (7, 6)]
    one = trial_pairs(board, front, bad, 1, np.random.default_rng(0))
    assert one.shape == (3, 2) and np.array_equal(
        one, trial_pairs(board, front, bad, 1, np.random.default_rng(0)))
    # the hind footholds of board b all went wrong: nothing to compare them with
    assert not np.isin([8, 9], one).any()
    with pytest.raises(FootfallError, match="whole number >= 1"):
        trial_pairs(board, front, bad, 0, np.random.default_rng(0))


def _step_board():
    """A flat board 1 m long (x) and 0.6 m wide (y), 0.06 m higher for x >= 0.5 m (1 cm cells)."""
    z = np.zeros((100, 60))
    z[50:, :] = 0.06
    return HeightMap(z, 0.01)


def _trials(hmap, rng, n=120):
    """Footholds on the step board, each 4 cm ahead of its leg's nominal stance: those within
    2 cm of the riser went wrong, the rest not; front and hind legs alike."""
    x = rng.uniform(0.42, 0.58, n)
    out = []
    for k in range(n):
        leg = LEGS[k % 4]
        nominal = LITTLEDOG.nominal_foot(leg)[:2]
        state = nominal_state(hmap, (x[k] - nominal[0] - 0.04, 0.3), 0.0, leg)
        xy = np.array([[x[k], 0.3 + nominal[1]]])
        foothold = np.append(xy[0], hmap.height_at(xy)[0])
        out.append(TrialFoothold(hmap, state, foothold, abs(x[k] - 0.5) < 0.02,
                                 hmap.content_hash(), f"run {k % 5}", leg.endswith("F")))
    return out


def test_a_function_learned_from_trials_alone_ranks_what_went_wrong_below():
    hmap = _step_board()
    trials = _trials(hmap, np.random.default_rng(1))
    model = learn_model([], "terrain", "l1", trials=trials, cv=3, seed=0, selection="min")
    assert model.info["trial_footholds"] == len(trials) and model.info["trial_comparisons"] > 0
    held_out = _trials(hmap, np.random.default_rng(2))
    for group in ("front", "hind"):
        mine = [t for t in held_out if t.front == (group == "front")]
        score = np.array([_value(model, hmap, t) for t in mine])
        bad = np.array([t.bad for t in mine])
        assert bad.any() and (~bad).any()
        # AUC of the learned value: good footholds above bad ones
        auc = np.mean(score[~bad][:, None] > score[bad][None, :])
        assert auc > 0.9, (group, auc)


def test_the_template_library_draws_the_robots_footholds_into_its_slots():
    hmap = _step_board()
    trials = _trials(hmap, np.random.default_rng(1), n=40)
    model = learn_model([], "templates", "l1", trials=trials, cv=3, seed=0,
                        library_size=30, bandwidth_rms=(0.004,) * 3)
    # 10 a scale of the 40 footholds (not every one, as a demonstrated foothold would be)
    assert [f.info["library_counts"] for f in model.functions.values()] == [[10, 10, 10]] * 2
    values = [_value(model, hmap, t) for t in trials[:8]]
    assert np.isfinite(values).all()


def _value(model, hmap, t):
    """The model's value of a trial foothold in its own state."""
    c = Candidates.of_state(hmap, t.state, t.foothold[None, :], model.config)
    return float(model.reward_for(t.state.swing_leg).values(c)[0])


def test_a_comparisons_rows_are_its_two_footholds_each_in_its_own_state():
    hmap = _step_board()
    trials = _trials(hmap, np.random.default_rng(3), n=8)
    model = learn_model([], "terrain", "l1", trials=trials + _trials(
        hmap, np.random.default_rng(4)), cv=3, seed=0)
    families = model.functions["front"].families
    a, b = (make_example(hmap, t.state, t.foothold[None, :], 0, families, model.config)
            for t in trials[:2])
    pair = pair_example(a, b, unit="board:x")
    assert (pair.n, pair.chosen, pair.unit) == (2, 0, "board:x")
    np.testing.assert_array_equal(design_matrix(pair, families),
                                  np.concatenate([design_matrix(a, families),
                                                  design_matrix(b, families)]))
    with pytest.raises(FootfallError, match="two one-foothold examples"):
        pair_example(pair, a)


def _store_with_runs(path):
    """Two scripted runs on the step board: run 0 crossed (the feet of steps 1 and 2, a front
    and a hind one, slid 20 mm), run 1 fell during its last step."""
    hmap = _step_board()
    with DemoStore(path, create=True) as store:
        for r, (slips, result) in enumerate([
                ([0.001, 0.020, 0.020, 0.001, 0.001, 0.001], {"success": True}),
                ([0.001] * 7 + [math.nan], {"success": False, "reason": "fall: trunk tilted"})]):
            steps = []
            for k, slip in enumerate(slips):
                state = nominal_state(hmap, (0.2 + 0.02 * k, 0.3), 0.0, LEGS[k % 4])
                # 3 cm ahead of the leg's nominal stance, chosen; the expert's table prefers
                # candidate 1, 2 cm further
                ahead = np.append(LITTLEDOG.nominal_foot(LEGS[k % 4])[:2] + state.body_position[:2]
                                  + [0.03, 0.0], 0.0)
                cand = np.array([ahead, ahead + [0.02, 0.0, 0.0]])
                down = not math.isnan(slip)
                steps.append(RunStep(k, state, cand, np.zeros(2), 0, 0.5 * k,
                                     0.5 * k + 0.3 if down else math.nan,
                                     cand[0] if down else np.full(3, np.nan), slip))
            store.add_run(RunRecord(hmap.content_hash(), r, {}, result, tuple(steps),
                                    key=f"test/{r}"), terrains=[hmap])
    return hmap


def test_a_stores_runs_become_labelled_footholds(tmp_path):
    hmap = _store_with_runs(tmp_path / "runs.sqlite")
    tried = trial_footholds([tmp_path / "runs.sqlite"])
    assert len(tried) == 6 + 7  # the fallen run's last foot never landed
    bad = [t.bad for t in tried]
    # run 0: the feet that slid; run 1: the footholds of the fall's last 3 steps + its own
    assert bad == [False, True, True, False, False, False] + [False] * 4 + [True] * 3
    assert {t.board for t in tried} == {hmap.content_hash()}
    assert [t.front for t in tried[:4]] == [False, True, False, True]
    with DemoStore(tmp_path / "runs.sqlite", read_only=True) as store:
        first = store.run(store.runs()[0]["id"])
    np.testing.assert_array_equal(tried[2].foothold, first.steps[2].foothold)
    assert trial_footholds([tmp_path / "runs.sqlite"], key_prefix="test/1")[0].run.endswith("#2")


def test_the_experts_corrections_of_stored_runs_are_the_reproductions(tmp_path):
    _store_with_runs(tmp_path / "runs.sqlite")
    # Every step chose 2 value units below the expert's best: all are above a margin of 1, and
    # 6 of each run are labelled.
    done = correct_stored_runs([tmp_path / "runs.sqlite"], tmp_path / "d.sqlite", TableExpert(),
                               margin=1.0, per_run=6, seed=0)
    assert (done.runs, done.steps, done.above_margin, done.added) == (2, 14, 14, 12)
    with DemoStore(tmp_path / "d.sqlite", read_only=True) as store:
        demos = store.demonstrations()
    # (which 6: the largest shortfalls, equal here but for rounding)
    assert [d.source.rsplit(":step:")[0] for d in demos] == ["run:test/0"] * 6 + ["run:test/1"] * 6
    assert all(d.chosen == 1 for d in demos)
    none = correct_stored_runs([tmp_path / "runs.sqlite"], tmp_path / "e.sqlite", TableExpert(),
                               margin=2.5, per_run=6, seed=0)
    assert (none.runs, none.above_margin, none.added) == (2, 0, 0)  # within the margin: fine


def test_learn_from_trials_on_the_command_line(tmp_path, capsys):
    code, _, err = run(capsys, "learn", "--features", "terrain", "-o", tmp_path / "m.npz")
    assert_user_error(code, err, "--trials")
    code, _, err = run(capsys, "learn", "--trials", tmp_path / "none.sqlite", "--features",
                       "terrain", "-o", tmp_path / "m.npz")
    assert code == 2 and "none.sqlite" in err
    _store_with_runs(tmp_path / "runs.sqlite")
    code, out, err = run(capsys, "learn", "--trials", tmp_path / "runs.sqlite", "--features",
                         "terrain", "--cv", "2", "-o", tmp_path / "m.npz")
    assert code == 0, err
    assert "from 0 demonstrations and 13 footholds of its own runs" in out, out
    model = FootholdModel.load(tmp_path / "m.npz")
    assert (model.info["n_demonstrations"], model.info["trial_footholds"]) == (0, 13)
