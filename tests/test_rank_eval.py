"""``footfall rank-eval``: any scorer -- a model file, the hand-tuned reward, the expert's own
value -- measured by the same numbers, on demonstrations and on the steps of run logs."""

import json
import math
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.control.footstep import FootstepConfig
from footfall.core.errors import FootfallError
from footfall.core.robot import LITTLEDOG
from footfall.core.state import stance_target
from footfall.data.outcomes import OUTCOME_LABELS, step_outcomes
from footfall.data.store import DemoStore
from footfall.experiments.batch import walk_once
from footfall.experiments.rank_eval import judging_expert, rank_eval, severe_by_term
from footfall.expert.collect import collect_into_store
from footfall.expert.scorer import judge_name
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert, walking_expert
from footfall.features.reward import default_reward
from footfall.features.spread import path_bias_weight
from footfall.learning.evaluation import EveryLeg
from footfall.learning.train import learn_from_store, store_demonstrations
from footfall.terrain.saving import save_board


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """A store with 12 of the expert's demonstrations and one run walked with the hand-tuned
    reward on a rocky board; and a model learned from the demonstrations."""
    folder = tmp_path_factory.mktemp("rank_eval")
    board = folder / "board.npz"
    save_board(["rocky:0.5"], seed=3, path=board)
    path = folder / "store.sqlite"
    collect_into_store([board], path, n=12, seed=0)
    walk_once(board, 2, search_radius=0.03, log_path=path)
    model = folder / "model.npz"
    learn_from_store(path, model, "terrain", library_size=30, cv=3, Cs=4)
    return path, model


def test_the_expert_is_its_own_ceiling_and_the_hand_tuned_reward_falls_short(store):
    path, _ = store
    ceiling = rank_eval(None, path, reward="expert").scores
    assert ceiling.n == 12
    assert ceiling.reward_loss == 0 and ceiling.above_margin == 0 and ceiling.severe == 0
    assert (ceiling.margin, ceiling.severe_above) == (1.0, 10.0)  # [value units]
    hand = rank_eval(None, path, reward="hand-tuned").scores
    assert hand.n == 12 and hand.reward_loss > 0
    assert hand.above_margin == pytest.approx(sum(x > 1.0 for x in hand.losses) / 12)
    assert 0 <= hand.severe <= hand.above_margin <= 1
    two = rank_eval(None, path, reward="hand-tuned", margin=2.0).scores  # the reproduction's
    assert two.margin == 2.0 and two.losses == hand.losses
    assert two.above_margin == pytest.approx(sum(x > 2.0 for x in hand.losses) / 12)
    with pytest.raises(FootfallError, match="the correction margin must be a number >= 0"):
        rank_eval(None, path, reward="hand-tuned", margin=-1.0)


def test_run_decisions_are_the_steps_the_robot_took_ranked_against_the_experts_best(store):
    path, model = store
    with DemoStore(path, read_only=True) as s:
        steps = [st for st in s.run(s.runs()[0]["id"]).steps if st.candidates.shape[0] >= 2]
    ceiling = rank_eval(None, path, reward="expert", decisions="runs")
    assert ceiling.decisions == "runs" and ceiling.scores.n == len(steps) > 5
    assert ceiling.expert == "synthetic expert"  # runs are judged by the walking expert
    assert ceiling.scores.top1 == 1 and ceiling.scores.reward_loss == 0
    learned_eval = rank_eval(model, path, decisions="runs")
    learned = learned_eval.scores
    assert learned.n == len(steps) and learned.reward_loss >= 0
    assert math.isfinite(learned.above_margin)
    # what followed the footholds stood on: the run's own outcome labels, counted
    with DemoStore(path, read_only=True) as s:
        labels = step_outcomes(s.run(s.runs()[0]["id"]))
    assert set(learned_eval.outcomes) == set(OUTCOME_LABELS)
    for lab in OUTCOME_LABELS:
        o, y = learned_eval.outcomes[lab], getattr(labels, lab)[labels.used]
        assert (o["positives"], o["negatives"]) == (int(y.sum()), int((~y).sum()))
        assert (o["auc"] is None) == (y.all() or not y.any())
    assert rank_eval(model, path).outcomes is None  # demonstrations have no outcome
    with pytest.raises(FootfallError, match="no run logs with a key starting 'nothing/'"):
        rank_eval(None, path, reward="expert", decisions="runs", run_key="nothing/")


def test_the_command_ranks_a_model_or_a_named_scorer_and_refuses_bad_use(store, capsys):
    path, model = store
    # (the expert's values are the slow part: the library tests above measure with them)
    code, out, _ = run(capsys, "rank-eval", model, path, "--no-expert", "--json")
    assert code == 0
    result = json.loads(out)
    assert (result["feature_set"], result["decisions"], result["n"]) == \
        ("terrain", "demonstrations", 12)
    assert result["above_margin"] is None and result["severe_above"] == 10.0
    code, out, _ = run(capsys, "rank-eval", "--reward", "hand-tuned", path, "--no-expert")
    assert code == 0 and out.startswith("hand-tuned on 12 demonstrations: top-1 ")
    assert out.rstrip().endswith("above the margin n/a, severe n/a")
    # several scorers on the same decisions: each as it is alone, the named one last
    copy = Path(path).parent / "copy.npz"  # the same function in another file
    shutil.copyfile(model, copy)
    code, out, _ = run(capsys, "rank-eval", model, copy, "--reward", "hand-tuned", path,
                       "--no-expert", "--json")
    many = json.loads(out)
    assert code == 0 and [m["model"] for m in many] == [str(model), str(copy), "hand-tuned"]
    assert many[0] == {**many[1], "model": str(model)} and many[0] == result
    code, out, _ = run(capsys, "rank-eval", model, "--reward", "hand-tuned", path, "--no-expert")
    assert code == 0 and out.splitlines()[1].startswith("hand-tuned on 12 demonstrations")
    for args, message in [
            ([str(path)], "give MODEL.npz... STORE.sqlite"),
            (["--reward", "hand-tunde", str(path)], "unknown scorer 'hand-tunde'"),
            (["--reward", "hand-tuned", "--path-bias", "-1", str(path)],
             "Invalid value for '--path-bias'"),
            (["--reward", "expert", "--decisions", "runs", "--no-expert", str(path)],
             "run decisions are ranked against the expert's best")]:
        code, out, err = run(capsys, "rank-eval", *args)
        assert out == ""
        assert_user_error(code, err, message)


def test_the_judge_is_the_expert_that_demonstrated_else_the_walking_expert(store):
    path, _ = store
    with DemoStore(path, read_only=True) as s:
        demos = s.demonstrations()
    made_by = ExpertConfig(**demos[0].expert["config"])
    assert judging_expert(demos) == made_by  # collect's expert
    assert rank_eval(None, path, reward="expert").expert == judge_name(made_by)
    someone = replace(demos[0], expert={"class": "people", "labeler": "ada"})
    assert judging_expert([*demos, someone]) == walking_expert(FootstepConfig().lead)
    assert judging_expert(None) == walking_expert(FootstepConfig().lead)
    other = replace(made_by, w_riser=50.0)
    assert rank_eval(None, path, reward="expert", expert_config=other).expert == judge_name(other)


def test_a_path_bias_ranks_as_the_planner_picks(store):
    """With the planner's path bias each scorer's values lose weight x spread ratio per metre
    from the judge's gait-nominal foothold; the expert, which carries its own, loses none."""
    path, _ = store
    alone = rank_eval(None, path, reward="hand-tuned").scores
    assert rank_eval(None, path, reward="hand-tuned", path_bias=0.0).scores.losses == alone.losses
    # a bias far larger than any reward difference: every pick is the candidate nearest the
    # gait-nominal foothold, and its loss is the expert's shortfall there
    pulled = rank_eval(None, path, reward="hand-tuned", path_bias=1e9)
    assert pulled.path_bias == 1e9 and pulled.as_dict()["path_bias"] == 1e9
    demos, maps = store_demonstrations(path)
    judge = judging_expert(demos)
    expert = SyntheticExpert(judge, LITTLEDOG)
    expected = []
    for d in demos:
        v = expert.values(maps[d.terrain_hash], d.state, d.candidates)
        gap = np.hypot(*(d.candidates[:, :2] - stance_target(d.state, LITTLEDOG,
                                                                judge.stance_lead)).T)
        nearest = np.flatnonzero(gap == gap.min())
        expected.append(v.max() - v[nearest].mean())
    np.testing.assert_allclose(pulled.scores.losses, expected, atol=1e-9)
    assert pulled.scores.losses != alone.losses
    ceiling = rank_eval(None, path, reward="expert", path_bias=60.0).scores
    assert ceiling.reward_loss == 0  # the expert walks and is ranked without the bias
    with pytest.raises(FootfallError, match="path bias's weight must be a finite number >= 0"):
        rank_eval(None, path, reward="hand-tuned", path_bias=-1.0)


def test_the_path_bias_is_scaled_to_a_rewards_spread():
    hand = default_reward()
    assert path_bias_weight(hand, 60.0) == 60.0  # the hand-tuned reward: exactly, unscored
    assert path_bias_weight(hand.scaled(2.0, name="twice"), 60.0) == pytest.approx(120.0)


def test_severe_shortfalls_split_by_the_experts_terms_add_up_to_the_shortfall(store, capsys):
    path, _ = store
    demos, maps = store_demonstrations(path)
    expert = SyntheticExpert(judging_expert(demos), LITTLEDOG)
    values = [expert.values(maps[d.terrain_hash], d.state, d.candidates) for d in demos]
    hand = rank_eval(None, path, reward="hand-tuned").scores
    above = float(np.median(hand.losses))  # half the decisions, whatever this board gives
    split = severe_by_term(EveryLeg(default_reward()), demos, maps, expert, values,
                           hand.losses, above=above)
    worse = [x for x in hand.losses if x > above]
    assert split["decisions"] == len(worse) > 0 and split["above"] == above
    # the terms add up to the value: their differences add up to the shortfall
    assert split["shortfall"] == pytest.approx(sum(worse))
    assert sum(split["terms"].values()) == pytest.approx(1.0)
    assert set(split["terms"]) <= set(expert.contributions(maps[demos[0].terrain_hash],
                                                           demos[0].state,
                                                           demos[0].candidates[:1]))
    asked = rank_eval(None, path, reward="hand-tuned", by_term=True)
    assert asked.as_dict()["severe_terms"]["above"] == 10.0  # the severe threshold
    assert rank_eval(None, path, reward="hand-tuned").severe_terms is None
    with pytest.raises(FootfallError, match="needs the expert"):
        rank_eval(None, path, reward="hand-tuned", by_term=True, with_expert=False)
    code, out, _ = run(capsys, "rank-eval", "--reward", "hand-tuned", path, "--by-term",
                       "--path-bias", "60")
    assert code == 0 and "as the planner picks (path bias 60 /m)" in out
    assert ("by the expert's term: " in out) == (asked.severe_terms["decisions"] > 0)
