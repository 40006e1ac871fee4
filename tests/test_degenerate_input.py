"""A teacher or data that say nothing are refused in one line, not turned into a result that
looks like one: expert settings whose every weight is 0 (every foothold valued alike, so the
hand-tuned reward would be judged flawless), demonstrations whose candidates are one
foothold (nothing to choose), a learning-curve point compared with itself (p = 1, +0.00)."""

import dataclasses
import json

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.state import nominal_state
from footfall.data.demonstration import Demonstration
from footfall.data.store import DemoStore
from footfall.experiments.curve_report import compare_points
from footfall.expert.settings_file import save_expert
from footfall.expert.synthetic import ExpertConfig, check_judges
from test_store import terrain


def test_expert_settings_whose_every_weight_is_zero_are_refused(tmp_path, capsys):
    zero = {f.name: 0.0 for f in dataclasses.fields(ExpertConfig) if f.name.startswith("w_")}
    with pytest.raises(FootfallError, match="every weight is 0"):
        check_judges(ExpertConfig(**zero), "settings")
    check_judges(ExpertConfig(**{**zero, "w_progress": 1.0}), "settings")  # one weight judges
    with pytest.raises(FootfallError, match="every weight is 0"):
        save_expert(tmp_path / "never.json", ExpertConfig(**zero), {})
    assert not (tmp_path / "never.json").exists()
    path = tmp_path / "zero.json"
    path.write_text(json.dumps({"format": "footfall.expert", "version": 1,
                                "expert": {**ExpertConfig().to_dict(), **zero}}))
    with DemoStore(tmp_path / "s.sqlite", create=True):
        pass
    code, _, err = run(capsys, "rank-eval", "--reward", "hand-tuned", tmp_path / "s.sqlite",
                       "--expert-config", path)
    assert_user_error(code, err, "every weight is 0")


def test_demonstrations_whose_candidates_are_one_foothold_are_refused(tmp_path, capsys):
    hm = terrain()
    state = nominal_state(hm, (0.2, 0.0), 0.0, "LF")
    same = np.tile([[0.3, 0.0, 0.0]], (6, 1))
    with DemoStore(tmp_path / "s.sqlite", create=True) as store:
        store.add_demonstrations([Demonstration(hm.content_hash(), state, same, k % 6,
                                                source="walker")
                                  for k in range(12)], terrains=[hm])
    code, _, err = run(capsys, "learn", tmp_path / "s.sqlite", "--features", "terrain", "-o",
                       tmp_path / "m.npz")
    assert_user_error(code, err, "candidates are one foothold")
    assert not (tmp_path / "m.npz").exists()


def test_a_curve_point_compared_with_itself_is_refused():
    curve = {"config": {}, "points": [{"draw": 0, "n": 10, "feature_set": "both",
                                       "learner": "l1", "losses": [0.0, 1.0]}]}
    with pytest.raises(FootfallError, match="the two points are one"):
        compare_points(curve, curve, 10, ("both", "l1"), ("both", "l1"))
    with pytest.raises(FootfallError, match="the two points are one"):
        compare_points(curve, json.loads(json.dumps(curve)), 10, ("both", "l1"), ("both", "l1"))


@pytest.mark.parametrize("sizes", ["5", "9", "1000000000"])
def test_a_curve_size_that_cannot_be_learned_is_refused_before_any_work(tmp_path, capsys,
                                                                        sizes):
    """Fewer demonstrations than each leg group's 5 folds need, or more than the max_count
    limit: refused when the settings are read, not after minutes of collecting."""
    code, _, err = run(capsys, "learning-curve", "--sizes", sizes, "--out", tmp_path / "c")
    assert_user_error(code, err, "sizes must be increasing whole numbers from 10")
    assert not (tmp_path / "c").exists()


def test_trials_where_nothing_went_wrong_are_refused_in_their_own_words():
    from footfall.learning.train import learn_model
    from footfall.learning.trials import TrialFoothold

    hm = terrain()
    state = nominal_state(hm, (0.2, 0.0), 0.0, "LF")
    fine = [TrialFoothold(hm, state, np.array([0.3, 0.01 * k, 0.0]), False, "run", "board",
                          True) for k in range(6)]
    with pytest.raises(FootfallError, match="none of the 6 footholds of the trial runs went "
                                            "wrong"):
        learn_model([], "terrain", trials=fine)
