"""The template budget: a function learned from n demonstrations reads at most floor(share x n)
templates, those its learner relied on most, fitted again on them."""

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.experiments.reproduce import ReproduceConfig
from footfall.learning.learner import get_learner
from footfall.learning.train import learn_model
from test_learners import _toy, lowest_foothold_demos

SETTINGS = dict(cv=3, training_candidates=30, library_size=90, bandwidth_rms=(0.004,) * 3)


@pytest.fixture(scope="module")
def demos():
    return lowest_foothold_demos()  # 8 front, 8 hind


def _sources(model, group):
    """Every kept template of a group, as (scale, x, y, yaw, mirrored) rows."""
    lib = model.functions[group].library
    return {(s, *np.round(row, 9)) for s, src in enumerate(lib.sources) for row in src}


@pytest.mark.parametrize("learner", ["lambdarank", "l1"])
def test_a_budget_keeps_the_templates_the_learner_relied_on_most(demos, learner):
    free = learn_model(demos, "templates", learner, **SETTINGS)
    capped = learn_model(demos, "templates", learner, template_budget=0.25, **SETTINGS)
    assert capped.info["template_budget"] == 0.25 and free.info["template_budget"] is None
    over = False
    for group in ("front", "hind"):
        kept = sum(capped.templates_kept()[group]["kept"])
        assert kept <= 2  # floor(0.25 x 8 demonstrations); a refit may keep fewer
        over |= sum(free.templates_kept()[group]["kept"]) > 2
        # the budgeted function's templates are among those the free fit read
        assert _sources(capped, group) <= _sources(free, group)
        assert capped.templates_kept()[group]["library"] == free.templates_kept()[group]["library"]
    assert over  # the budget bit: without it some group reads more than 2 templates


def test_a_generous_budget_changes_nothing(demos):
    free = learn_model(demos, "templates", "lambdarank", **SETTINGS)
    loose = learn_model(demos, "templates", "lambdarank", template_budget=100.0, **SETTINGS)
    for group in ("front", "hind"):
        assert _sources(loose, group) == _sources(free, group)


@pytest.mark.parametrize("name", ["lambdarank", "l1"])
def test_a_learner_s_importance_is_zero_exactly_on_the_columns_it_does_not_read(name):
    X, y, groups = _toy(3, n_demos=40)
    learner = get_learner(name)
    fitted = learner.fit(X, y, groups, Cs=4, cv=3)
    importance = learner.importance(fitted)
    assert importance.shape == (X.shape[1],) and np.all(importance >= 0)
    reads = (fitted.forest_.used_columns(X.shape[1]) if name == "lambdarank"
             else fitted.coef_ != 0)
    np.testing.assert_array_equal(importance > 0, reads)


def test_a_learner_that_cannot_rank_its_columns_refuses_a_budget(demos):
    with pytest.raises(FootfallError, match="cannot rank its columns.*--template-budget none"):
        learn_model(demos, "templates", "kernel", template_budget=0.5, **SETTINGS)
    with pytest.raises(FootfallError, match="kernel.*cannot rank"):
        ReproduceConfig(learner="kernel")  # the reproduction's budget: refused before walking
    with pytest.raises(FootfallError, match="kernel.*cannot carry a learned veto"):
        ReproduceConfig(learner="kernel", template_budget=None)  # nor the teacher's veto
    config = ReproduceConfig(learner="kernel", template_budget=None, veto=False)
    assert config.template_budget is None and not config.veto


@pytest.mark.parametrize("bad", [0, -0.5, float("nan"), float("inf"), True, "half"])
def test_a_bad_budget_is_refused(demos, bad):
    with pytest.raises(FootfallError, match="template_budget"):
        learn_model(demos, "templates", "lambdarank", template_budget=bad, **SETTINGS)
