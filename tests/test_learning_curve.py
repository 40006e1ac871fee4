"""The learning curve: its draws' boards are disjoint from each other and from the test boards,
every prefix of a draw's demonstrations holds both leg groups, and a small curve is measured,
written and resumed."""

import json
import shutil

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.control.footstep import FootstepConfig
from footfall.core.errors import FootfallError
from footfall.core.robot import LITTLEDOG
from footfall.core.state import stance_target
from footfall.data.store import DemoStore
from footfall.experiments.curve_report import FORMAT as CURVE_FORMAT
from footfall.experiments.curve_report import compare_points, curve_table
from footfall.experiments.learning_curve import (
    CurveConfig,
    balanced_order,
    point_model_path,
    run_learning_curve,
)
from footfall.expert.synthetic import SyntheticExpert, walking_expert
from footfall.features.reward import default_reward
from footfall.learning.evaluation import EveryLeg, PathBias, rank_scores
from footfall.terrain import make_board


def _hashes(specs):
    return {make_board([(kind, d)], seed).content_hash() for kind, d, seed in specs}


def test_the_draws_use_disjoint_boards_and_never_the_test_boards():
    config = CurveConfig(train_kinds=("rocky", "steps"), train_difficulties=(0.5, 0.8),
                         test_difficulties=(0.6,), draws=3)
    draws = [_hashes(config.training_boards(k)) for k in range(3)]
    test = _hashes(config.test_boards())
    assert all(len(h) == 4 for h in draws) and len(test) == 2
    for k in range(3):
        assert not draws[k] & test
        for j in range(k):
            assert not draws[k] & draws[j]
    assert config.training_boards(1) == CurveConfig(
        train_kinds=("rocky", "steps"), train_difficulties=(0.5, 0.8)).training_boards(1)


def test_every_prefix_of_the_order_holds_both_leg_groups():
    front = np.random.default_rng(0).permutation(np.arange(50) < 20)  # 20 front, 30 hind
    order = balanced_order(front, np.random.default_rng(1))
    assert np.array_equal(np.sort(order), np.arange(50))
    for n in range(2, 41, 2):
        assert front[order[:n]].sum() == n // 2
    again = balanced_order(front, np.random.default_rng(1))
    assert np.array_equal(order, again)


TINY = CurveConfig(sizes=(10,), draws=1, feature_sets=("terrain",), learners=("l1",),
                   train_kinds=("rocky",), train_difficulties=(0.6,), test_difficulties=(0.6,),
                   test_decisions=8, library_size=30)


def test_a_small_curve_is_measured_written_and_resumed(tmp_path):
    logs = []
    summary = run_learning_curve(tmp_path, TINY, log=logs.append)
    (point,) = summary["points"]
    assert (point["draw"], point["n"], point["feature_set"], point["learner"]) == \
        (0, 10, "terrain", "l1")
    assert point["decisions"] == 8 and 0.0 <= point["above_margin"] <= 1.0
    assert len(point["losses"]) == 8  # every decision's shortfall, for paired comparisons
    assert np.mean(np.array(point["losses"]) > point["margin"]) == point["above_margin"]
    assert summary["lines"]["expert"]["above_margin"] == 0.0  # the ceiling: no shortfall
    assert 0.0 <= summary["lines"]["hand-tuned"]["above_margin"] <= 1.0
    assert (tmp_path / "learning-curve.png").stat().st_size > 0
    assert "| terrain | l1 | 10 | 1 |" in (tmp_path / "report.md").read_text()
    assert "template library 30 (every demonstrated foothold a template: more from 11 " \
        "demonstrations)" in (tmp_path / "report.md").read_text()
    assert curve_table(summary)[0]["above_margin"] == point["above_margin"]
    assert any("learned" in line for line in logs)

    logs.clear()
    again = run_learning_curve(tmp_path, TINY, log=logs.append)
    assert "resuming: 1 points measured" in logs and not any("learned" in s for s in logs)
    assert again["lines"] == summary["lines"] and (tmp_path / "test-values.npz").exists()
    assert again["points"] == summary["points"]
    stored = json.loads((tmp_path / "results.json").read_text())
    assert stored["format"] == "footfall.learning-curve" and stored["points"] == again["points"]

    with pytest.raises(FootfallError, match="holds a curve of other settings .test_decisions"):
        run_learning_curve(tmp_path, CurveConfig(**{**vars(TINY), "test_decisions": 9}))

    logs.clear()  # more sizes extend the curve: the measured point stays, the new one is added
    more = run_learning_curve(tmp_path, CurveConfig(**{**vars(TINY), "sizes": (10, 12)}),
                              log=logs.append)
    assert [p["n"] for p in more["points"]] == [10, 12] and more["points"][0] == point
    assert sum("learned" in line for line in logs) == 1

    stored = json.loads((tmp_path / "results.json").read_text())  # written before a setting
    del stored["config"]["search_radius"]  # existed: read as that setting's default
    (tmp_path / "results.json").write_text(json.dumps(stored))
    logs.clear()
    run_learning_curve(tmp_path, CurveConfig(**{**vars(TINY), "sizes": (10, 12)}),
                       log=logs.append)
    assert "resuming: 2 points measured" in logs and not any("learned" in s for s in logs)


def test_worker_processes_collect_and_learn_what_one_process_does(tmp_path):
    config = CurveConfig(**{**vars(TINY), "draws": 2})
    logs = []
    one = run_learning_curve(tmp_path / "one", config, log=lambda _: None)
    two = run_learning_curve(tmp_path / "two", config, log=logs.append, processes=2)
    assert any("in 2 processes" in line for line in logs)
    assert sum("learned" in line for line in logs) == 2
    assert two["lines"] == one["lines"]
    strip = [{k: v for k, v in p.items() if k != "seconds"} for p in one["points"]]
    assert [{k: v for k, v in p.items() if k != "seconds"} for p in two["points"]] == strip
    for name in ("terrain-l1-10-draw0.npz", "terrain-l1-10-draw1.npz"):
        with np.load(tmp_path / "one" / "models" / name) as a, \
                np.load(tmp_path / "two" / "models" / name) as b:
            assert set(a.files) == set(b.files)
            assert all(np.array_equal(a[k], b[k]) for k in a.files if k != "meta")


def test_a_curve_on_the_walking_planners_f_holds_only_footholds_near_the_gait_nominal_one(
        tmp_path):
    config = CurveConfig(**{**vars(TINY), "search_radius": 0.03})
    summary = run_learning_curve(tmp_path, config, log=lambda _: None)
    assert summary["config"]["search_radius"] == 0.03
    assert "within 3 cm of the gait-nominal foothold" in (tmp_path / "report.md").read_text()
    lead = FootstepConfig().lead  # the walking expert's stance lead
    for name in ("test.sqlite", "draw0.sqlite"):
        with DemoStore(tmp_path / name) as store:
            demos = store.demonstrations()
        assert demos
        for d in demos:
            target = stance_target(d.state, LITTLEDOG, lead)
            assert np.hypot(*(d.candidates[:, :2] - target).T).max() <= 0.03 + 1e-9

    stored = json.loads((tmp_path / "results.json").read_text())
    del stored["config"]["search_radius"]  # a curve written before the setting existed: read
    (tmp_path / "old").mkdir()  # as its default (every reachable foothold), not this curve's
    (tmp_path / "old" / "results.json").write_text(json.dumps(stored))
    with pytest.raises(FootfallError, match="other settings .search_radius"):
        run_learning_curve(tmp_path / "old", config, log=lambda _: None)


def test_a_curve_ranked_as_the_planner_picks_measures_the_same_models_with_the_path_bias(
        tmp_path):
    alone = run_learning_curve(tmp_path / "alone", TINY, log=lambda _: None)
    (tmp_path / "biased" / "models").mkdir(parents=True)  # the same stores and models
    for path in (tmp_path / "alone").glob("*.sqlite"):
        shutil.copy(path, tmp_path / "biased" / path.name)
    for path in (tmp_path / "alone" / "models").iterdir():
        shutil.copy(path, tmp_path / "biased" / "models" / path.name)
    logs = []
    config = CurveConfig(**{**vars(TINY), "path_bias": 60.0})
    biased = run_learning_curve(tmp_path / "biased", config, log=logs.append)
    assert not any("learned" in line for line in logs)  # measured anew, not learned anew
    assert biased["config"]["path_bias"] == 60.0
    assert biased["lines"]["expert"]["reward_loss"] == 0.0  # the expert carries its own
    assert biased["lines"]["hand-tuned"]["losses"] != alone["lines"]["hand-tuned"]["losses"]
    with DemoStore(tmp_path / "alone" / "test.sqlite") as store:
        demos = store.demonstrations()[:TINY.test_decisions]
        maps = {d.terrain_hash: store.terrain(d.terrain_hash) for d in demos}
    expert = SyntheticExpert(walking_expert(FootstepConfig().lead))
    hand = rank_scores(EveryLeg(default_reward()), demos, maps.__getitem__, expert,
                       margin=1.0, path_bias=PathBias(60.0, FootstepConfig().lead))
    assert biased["lines"]["hand-tuned"]["losses"] == pytest.approx(list(hand.losses))
    assert "as the footstep planner picks" in (tmp_path / "biased" / "report.md").read_text()
    with pytest.raises(FootfallError, match="differ in path_bias"):
        compare_points(alone, biased, 10, ("terrain", "l1"), ("terrain", "l1"))


@pytest.mark.parametrize("args, match", [
    (["--sizes", "10,abc"], "--sizes must be whole numbers"),
    (["--sizes", "50,25"], "sizes"),
    (["--draws", "0"], "--draws"),
    (["--learner", "lasso"], "lasso"),
])
def test_bad_curve_settings_are_one_line(tmp_path, capsys, args, match):
    code, _, err = run(capsys, "learning-curve", "--out", str(tmp_path / "c"), *args)
    assert_user_error(code, err, match)


def _curve(points, **config):
    base = {"train_kinds": ["rocky"], "train_difficulties": [0.6], "test_difficulties": [0.6],
            "test_decisions": 6, "seed": 0}
    return {"format": CURVE_FORMAT, "config": {**base, **config}, "points": [
        {"draw": d, "n": n, "feature_set": fs, "learner": ln, "losses": losses, "margin": 1.0}
        for d, n, fs, ln, losses in points]}


def test_two_points_are_compared_decision_by_decision_over_their_shared_draws(tmp_path, capsys):
    a = [0.0, 2.0, 3.0, 0.5, 5.0, 0.0]  # above the margin (1.0): decisions 1, 2, 4
    b = [0.0, 0.0, 3.0, 2.0, 0.0, 0.0]  # decisions 2, 3
    curve = _curve([(0, 100, "both", "l1", a), (1, 100, "both", "l1", a),
                    (0, 100, "both", "kernel", b), (2, 100, "both", "kernel", b),
                    (1, 50, "both", "kernel", b)])
    r = compare_points(curve, curve, 100, ("both", "l1"), ("both", "kernel"))
    assert r["draws"] == [0]  # draw 1 has no kernel point at 100, draw 2 no l1 point
    assert r["a"]["above_margin"] == 0.5 and r["b"]["above_margin"] == pytest.approx(1 / 3)
    assert (r["a_only_above"], r["b_only_above"]) == (2, 1)
    assert r["p"] == pytest.approx(1.0)  # 2 against 1 separates nothing
    assert r["a"]["mean_shortfall"] == pytest.approx(10.5 / 6)
    assert r["b"]["mean_shortfall"] == pytest.approx(5.0 / 6)
    assert r["shortfall_difference"] == pytest.approx(5.5 / 6)
    lo, hi = r["shortfall_difference_ci"]  # differences 0, 2, 0, -1.5, 5, 0
    assert -1.5 <= lo < 5.5 / 6 < hi <= 5.0
    with pytest.raises(FootfallError, match="differ in seed"):
        compare_points(curve, _curve([], seed=1), 100, ("both", "l1"), ("both", "l1"))
    with pytest.raises(FootfallError, match="differ in search_radius"):  # other decisions
        compare_points(curve, _curve([], search_radius=0.03), 100, ("both", "l1"),
                       ("both", "l1"))
    with pytest.raises(FootfallError, match="no point both/svm at 100"):
        compare_points(curve, curve, 100, ("both", "l1"), ("both", "svm"))

    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "results.json").write_text(json.dumps(curve))
    code, out, _ = run(capsys, "curve-compare", str(tmp_path / "c"), "--size", "100",
                       "--other-learner", "kernel")
    assert code == 0 and "only 2, for the second only 1" in out
    assert "mean shortfall 1.75 against 0.83: first less second +0.92 [" in out
    sizes = compare_points(curve, curve, 100, ("both", "l1"), ("both", "kernel"), b_n=50)
    assert sizes["draws"] == [1] and (sizes["a"]["n"], sizes["b"]["n"]) == (100, 50)
    assert sizes["shortfall_difference"] == pytest.approx(5.5 / 6)  # the same losses as above
    code, out, _ = run(capsys, "curve-compare", str(tmp_path / "c"), "--size", "100",
                       "--other-learner", "kernel", "--other-size", "50")
    assert code == 0 and out.startswith("100 against 50 demonstrations, draws 1;")
    assert "both/kernel at 50: 0.333" in out
    lined = {**curve, "lines": {"hand-tuned": {"losses": b}}}  # each draw against the line
    r = compare_points(lined, lined, 100, ("both", "l1"), "hand-tuned")
    assert r["draws"] == [0, 1] and r["b"]["point"] == ["hand-tuned"]
    assert r["shortfall_difference"] == pytest.approx(5.5 / 6)
    assert (r["a_only_above"], r["b_only_above"]) == (4, 2)
    with pytest.raises(FootfallError, match="no line 'expert'"):
        compare_points(lined, lined, 100, ("both", "l1"), "expert")
    (tmp_path / "c" / "results.json").write_text(json.dumps(lined))
    code, out, _ = run(capsys, "curve-compare", str(tmp_path / "c"), "--size", "100",
                       "--other-line", "hand-tuned")
    assert code == 0 and out.startswith("100 demonstrations, draws 0, 1;")
    assert "  hand-tuned: 0.333 (per draw 0.333, 0.333)" in out
    code, _, err = run(capsys, "curve-compare", str(tmp_path / "c"), "--size", "100",
                       "--other-line", "hand-tuned", "--other-size", "50")
    assert_user_error(code, err, "--other-line compares with a line")
    shorter = _curve([(0, 100, "both", "l1", a[:4]), (0, 100, "both", "kernel", b)])
    with pytest.raises(FootfallError, match="different held-out decisions"):
        compare_points(shorter, shorter, 100, ("both", "l1"), ("both", "kernel"))
    code, _, err = run(capsys, "curve-compare", str(tmp_path / "none"), "--size", "100")
    assert_user_error(code, err, "not a learning curve's results")


def test_a_capped_curve_learns_every_point_from_at_most_its_library_size(tmp_path):
    from footfall.learning.model import FootholdModel

    config = CurveConfig(**{**vars(TINY), "sizes": (12,), "feature_sets": ("templates",),
                            "library_capped": True})  # 12 demonstrations, 10 templates a scale
    run_learning_curve(tmp_path, config, log=lambda _: None)
    model = FootholdModel.load(point_model_path(tmp_path, 0, 12, "templates", "l1"))
    assert model.info["library_capped"] is True
    assert "template library 30 (at most: from 11 demonstrations a random sample" in \
        (tmp_path / "report.md").read_text()
