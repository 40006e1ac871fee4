"""Kinds of supervision: a teacher's verdict as relevance levels, through every learner."""

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.learning.learner import LEARNERS, get_learner
from footfall.learning.ranker import pairwise_error
from footfall.learning.supervision import (
    GRADED_MARGIN,
    GRADED_SEVERE,
    SUPERVISIONS,
    get_supervision,
)
from footfall.learning.train import TrainingDemo, learn_model
from test_learners import lowest_foothold_demos


def test_the_levels_of_each_kind_by_hand():
    values = np.array([10.0, 9.0, 7.5, 0.5, -30.0, 9.5])
    refused = np.array([False, False, False, False, True, True])
    chosen = 1  # the teacher chose 9.0 over its best 10.0 (an imperfect or biased teacher)
    assert get_supervision("choice").levels(6, chosen, values, refused).tolist() == \
        [0, 1, 0, 0, 0, 0]
    assert get_supervision("refusals").levels(6, chosen, values, refused).tolist() == \
        [1, 2, 1, 1, 0, 0]
    # short of the best by 0, -, 2.5, 9.5, 40 (refused), 0.5 (refused)
    assert get_supervision("graded").levels(6, chosen, values, refused).tolist() == \
        [2, 3, 1, 1, 0, 0]
    assert (GRADED_MARGIN, GRADED_SEVERE) == (2.0, 10.0)  # the teacher's margin and severe
    # a kind given less than it reads uses what it has
    assert get_supervision("graded").levels(6, chosen, None, refused).tolist() == \
        [1, 2, 1, 1, 0, 0]
    assert get_supervision("refusals").levels(6, chosen, values, None).tolist() == \
        [0, 1, 0, 0, 0, 0]
    with pytest.raises(FootfallError, match="unknown supervision 'votes'; use one of choice"):
        get_supervision("votes")


def _graded_toy(seed: int, n_demos: int = 40, n: int = 15, d: int = 6):
    """Demonstrations graded by a known value 2 x0 - x1 [value units x 5]: the chosen is the
    best, the levels by its shortfall."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n_demos * n, d))
    groups = np.repeat(np.arange(n_demos), n)
    value = 5.0 * (X @ np.array([2.0, -1.0, 0, 0, 0, 0])).reshape(n_demos, n)
    graded = get_supervision("graded")
    y = np.concatenate([graded.levels(n, int(np.argmax(v)), v, None) for v in value])
    return X, y, groups


@pytest.mark.parametrize("name", sorted(set(LEARNERS) - {"ridge"}))
def test_every_learner_learns_a_graded_ranking_the_same_way_twice(name):
    X, y, groups = _graded_toy(3)
    assert set(np.unique(y)) == {0, 1, 2, 3}
    learner = get_learner(name)
    fitted = learner.fit(X, y, groups, Cs=4, cv=3)
    scores = fitted.decision_function(X)
    np.testing.assert_array_equal(scores, learner.fit(X, y, groups, Cs=4, cv=3)
                                  .decision_function(X))
    assert 0.0 <= fitted.cv_error_ < 0.25  # held-out pairs between the levels
    assert pairwise_error(scores, y, groups) < 0.15


def _with_verdicts(demos: list[TrainingDemo]) -> list[TrainingDemo]:
    """The lowest-foothold demonstrations with the teacher's values (minus the height in mm)
    and refusals (the highest quarter of each F)."""
    out = []
    for d in demos:
        values = -1000.0 * d.candidates[:, 2]
        refused = values < np.quantile(values, 0.25)
        out.append(TrainingDemo(d.hmap, d.state, d.candidates, d.chosen, values=values,
                                refused=refused))
    return out


@pytest.mark.parametrize("kind", SUPERVISIONS.names())
def test_learn_model_reads_each_kind_of_supervision(kind):
    demos = _with_verdicts(lowest_foothold_demos())
    model = learn_model(demos, "terrain", "lambdarank", cv=3, training_candidates=30, seed=7,
                        supervision=kind)
    if kind == "choice":
        assert "supervision" not in model.info  # the paper's models are described as before
    else:
        assert model.info["supervision"] == kind and model.info["with_verdict"] == len(demos)
    # the levels reach the learner: a graded model is not the choice model
    choice = learn_model(demos, "terrain", "lambdarank", cv=3, training_candidates=30, seed=7)
    d = demos[0]
    from footfall.features.family import Candidates

    c = Candidates.of_state(d.hmap, d.state, d.candidates, model.config)
    same = np.array_equal(model.reward_for("LF").values(c), choice.reward_for("LF").values(c))
    assert same == (kind == "choice")


def test_a_learned_veto_is_lightgbms_log_odds_and_keeps_its_refusals_out():
    import lightgbm

    from footfall.learning.veto import VETO_PARAMS, fit_veto

    rng = np.random.default_rng(5)
    X = rng.normal(size=(600, 4))
    refused = X[:, 0] + 0.3 * rng.normal(size=600) > 0.5  # the teacher refuses by column 0
    groups = np.repeat(np.arange(40), 15)
    veto = fit_veto(X, refused, groups, cv=3, seed=1)
    booster = lightgbm.train({**VETO_PARAMS, "seed": 1}, lightgbm.Dataset(
        X, refused.astype(float), params={**VETO_PARAMS, "seed": 1}), veto.trees)
    np.testing.assert_allclose(veto.forest.predict(X), booster.predict(X, raw_score=True),
                               rtol=1e-9, atol=1e-9)
    assert veto.cv_error < 0.2 and veto.refused_share == pytest.approx(refused.mean())
    assert veto.forest.used_columns(4)[0]  # it reads the column that decides
    with pytest.raises(FootfallError, match="refuse no candidate"):
        fit_veto(X, np.zeros(600, dtype=bool), groups, cv=3)


def test_a_model_with_a_veto_scores_refused_candidates_down_and_round_trips(tmp_path):
    from footfall.features.family import Candidates
    from footfall.learning.function import VETO_PENALTY
    from footfall.learning.model import FootholdModel

    demos = _with_verdicts(lowest_foothold_demos())
    model = learn_model(demos, "terrain+pose", "lambdarank", cv=3, training_candidates=30,
                        seed=7, supervision="graded", veto=True)
    assert model.info["veto"] and model.functions["front"].veto is not None
    assert model.functions["front"].info["veto_trees"] > 0
    path = tmp_path / "vetoed.npz"
    model.save(path)
    back = FootholdModel.load(path)
    d = demos[1]
    c = Candidates.of_state(d.hmap, d.state, d.candidates, model.config)
    scorer = back.reward_for(d.state.swing_leg)
    values = scorer.values(c)
    np.testing.assert_array_equal(values, model.reward_for(d.state.swing_leg).values(c))
    plain = scorer.spread_basis.values(c)  # the ranker alone: the path bias's basis
    assert scorer.spread_basis is not scorer and np.ptp(plain) < VETO_PENALTY
    down = values < plain - VETO_PENALTY / 2
    assert down.any() and not down.all()
    # the veto takes down mostly what the teacher refused (the highest quarter)
    assert d.refused[down].mean() > 0.5
    with pytest.raises(FootfallError, match="cannot carry a learned veto"):
        learn_model(demos, "terrain", "l1", cv=3, veto=True)


def test_a_relative_veto_refuses_what_lies_far_below_the_best_of_its_own_set(tmp_path):
    from footfall.features.family import Candidates
    from footfall.learning.function import VETO_PENALTY
    from footfall.learning.model import FootholdModel

    demos = []
    for d in lowest_foothold_demos():  # the teacher's judge: minus the height [mm]; it refuses
        judged = -1000.0 * d.candidates[:, 2]  # what lies more than 10 mm above the lowest
        demos.append(TrainingDemo(d.hmap, d.state, d.candidates, d.chosen, values=judged,
                                  refused=judged.max() - judged > 10.0, judged=judged))
    model = learn_model(demos, "terrain+pose", "lambdarank", cv=3, training_candidates=40,
                        seed=7, supervision="graded", veto=True)
    f = model.functions["front"]
    # the margin is the largest shortfall the teacher accepted among the training rows
    assert f.veto_margin is not None and 0.0 < f.veto_margin <= 10.0
    model.save(tmp_path / "relative.npz")
    back = FootholdModel.load(tmp_path / "relative.npz")
    assert back.functions["front"].veto_margin == f.veto_margin
    d = demos[1]
    scorer = back.reward_for(d.state.swing_leg)
    function = scorer.function
    c = Candidates.of_state(d.hmap, d.state, d.candidates, model.config)
    judged = function.veto.predict(np.hstack([c.columns(fam) for fam in function.families]))
    refused = scorer.values(c) < scorer.spread_basis.values(c) - VETO_PENALTY / 2
    np.testing.assert_array_equal(refused, judged.max() - judged > function.veto_margin)
    assert refused.any()
    # relative to its own set: the candidates it refused, scored without the others, keep
    # their best standing
    alone = scorer.values(Candidates.of_state(d.hmap, d.state, d.candidates[refused],
                                              model.config))
    assert alone.max() > -VETO_PENALTY / 2


def test_a_veto_reads_what_its_supervision_reads():
    """Refusals alone (a person's marks) give the absolute veto even where the teacher's judged
    values are stored beside them; grades give the veto relative to them."""
    demos = []
    for d in lowest_foothold_demos():
        judged = -1000.0 * d.candidates[:, 2]
        demos.append(TrainingDemo(d.hmap, d.state, d.candidates, d.chosen, values=judged,
                                  refused=judged.max() - judged > 10.0, judged=judged))
    margins = {sup: learn_model(demos, "terrain+pose", "lambdarank", cv=3,
                                training_candidates=30, seed=7, supervision=sup,
                                veto=True).functions["front"].veto_margin
               for sup in ("refusals", "graded")}
    assert margins["refusals"] is None and margins["graded"] is not None


def test_a_veto_is_learned_on_the_columns_the_ranker_kept_within_its_template_budget():
    """A budget fits the ranker again on the templates it relied on most; the veto is fitted
    on those same columns, and the function reads what either reads."""
    demos = _with_verdicts(lowest_foothold_demos())
    demos = [TrainingDemo(d.hmap, d.state, d.candidates, d.chosen, values=d.values,
                          refused=d.refused, judged=d.values) for d in demos]
    model = learn_model(demos, "both", "lambdarank", cv=3, training_candidates=30, seed=7,
                        library_size=30, supervision="graded", veto=True, template_budget=0.2)
    from footfall.features.family import Candidates

    for f in model.functions.values():
        assert f.veto is not None and f.veto_margin is not None
        used = f.forest.used_columns(f.n_columns) | f.veto.used_columns(f.n_columns)
        widths = [len(fam.columns()) for fam in f.families]
        k = [fam.name for fam in f.families].index("templates")
        start = sum(widths[:k])
        assert used[start:start + widths[k]].all()  # every kept template is read by one of them
    d = demos[2]
    scorer = model.reward_for(d.state.swing_leg)
    values = scorer.values(Candidates.of_state(d.hmap, d.state, d.candidates, model.config))
    assert np.isfinite(values).all() and np.ptp(values) > 0
    # LightGBM on two threads (the reproduction's rounds) grows the same trees and veto
    threaded = learn_model(demos, "both", "lambdarank", cv=3, training_candidates=30, seed=7,
                           library_size=30, supervision="graded", veto=True,
                           template_budget=0.2, threads=2)
    for group, f in model.functions.items():
        mine, theirs = f.arrays(), threaded.functions[group].arrays()
        assert mine.keys() == theirs.keys() and any("veto" in k for k in mine)
        for k in mine:
            np.testing.assert_array_equal(mine[k], theirs[k], err_msg=k)
