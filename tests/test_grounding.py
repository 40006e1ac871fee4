"""The expert against outcomes: AUC with board intervals, the linear weight features, the
outcome fit, expert settings files and ``footfall outcomes``."""

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.robot import LITTLEDOG
from footfall.core.state import nominal_state
from footfall.data.store import DemoStore
from footfall.experiments.batch import batch_run_keys, walk_config, walk_once
from footfall.expert.grounding import (
    BONUS_WEIGHTS,
    RISK_WEIGHTS,
    WEIGHTS,
    FootholdOutcomes,
    fit_outcomes,
    outcome_auc,
    weight_features,
    weighted_auc,
)
from footfall.expert.scorer import judge_name
from footfall.expert.settings_file import load_expert, save_expert
from footfall.expert.synthetic import SyntheticExpert, walking_expert
from footfall.expert.terms import EXPERT_TERM_NAMES
from footfall.features.candidates import reachable_footholds
from footfall.terrain.modules import make_board
from footfall.terrain.saving import save_board

LEAD = 0.05
EXPERT = replace(walking_expert(LEAD), w_riser=0.0)  # without its riser term: the fits below
# must find a riser risk planted in the outcomes


def test_auc_orders_and_its_interval_resamples_boards():
    rng = np.random.default_rng(0)
    boards = np.repeat(np.arange(10), 30)
    label = rng.random(300) < 0.2
    assert outcome_auc(label.astype(float), label, boards).auc == 1.0
    assert outcome_auc(-label.astype(float), label, boards).auc == 0.0
    noisy = label + rng.normal(0, 0.8, 300)
    a = outcome_auc(noisy, label, boards, seed=3)
    assert 0.5 < a.auc < 1.0 and a.low <= a.auc <= a.high
    assert (a.positives, a.negatives) == (label.sum(), (~label).sum())
    assert outcome_auc(noisy, label, boards, seed=3) == a  # seeded
    none = outcome_auc(noisy, np.zeros(300, bool), boards)
    assert math.isnan(none.auc) and none.positives == 0
    with pytest.raises(FootfallError):
        outcome_auc(noisy, label[:-1], boards)


def test_the_value_is_linear_in_the_weights():
    board = make_board([("rocky", 0.7)], 5)
    state = nominal_state(board, (0.9, 0.0), 0.2, "LH")
    cand = reachable_footholds(board, state)
    config = replace(EXPERT, w_riser=150.0)
    expert = SyntheticExpert(config)
    terms = expert.terms(board, state, cand)
    features = weight_features(terms, config, LITTLEDOG)
    total = sum(getattr(config, w) * features[w] for w in WEIGHTS)
    np.testing.assert_allclose(total, expert.values(board, state, cand), rtol=1e-12, atol=1e-9)
    assert all(np.all(features[w] >= 0) for w in BONUS_WEIGHTS)


def _table(n=4000, seed=0):
    """Footholds whose falls follow the riser ahead (and nothing else): 40 boards."""
    rng = np.random.default_rng(seed)
    phi = math.atan(LITTLEDOG.foot_friction)
    terms = {t: np.zeros(n) for t in EXPERT_TERM_NAMES}
    terms["slip_margin"] = phi + rng.normal(0, 0.05, n)
    terms["leg_clearance"] = np.full(n, 0.05)
    terms["stability"] = rng.uniform(0.02, 0.06, n)
    terms["reach_margin"] = np.full(n, 0.05)
    terms["joint_margin"] = np.full(n, 0.5)
    terms["stance_offset"] = rng.uniform(0, 0.03, n)
    terms["riser_ahead"] = rng.uniform(0, 0.04, n)
    fall = rng.random(n) < 1 / (1 + np.exp(-(-5 + 150 * terms["riser_ahead"])))
    parts = SyntheticExpert(EXPERT).utilities(terms)
    labels = {lab: fall.copy() for lab in ("slid", "missed", "next_missed", "fall", "failed")}
    return FootholdOutcomes(
        np.full(n, "m"), np.repeat(np.arange(40), n // 40).astype(str), np.arange(n),
        np.zeros(n, int), np.zeros(n, int), np.full(n, "LF"), labels, np.zeros(n), np.zeros(n),
        terms, parts, np.sum(np.stack(list(parts.values())), axis=0))


def test_the_fit_finds_the_planted_risk_and_only_adds_caution():
    table = _table()
    fit = fit_outcomes(table, EXPERT, LITTLEDOG, "fall")
    assert fit.coefficients["w_riser"] > 50  # per metre of riser: the planted 150, shrunk
    assert fit.config.w_riser > 0 and EXPERT.w_riser == 0
    for w in RISK_WEIGHTS:  # outcomes of chosen footholds add caution, never remove it
        assert getattr(fit.config, w) >= getattr(EXPERT, w)
    assert fit.scale == pytest.approx(0.03 * EXPERT.w_stance / math.log(2))
    assert fit.l2 in (1e-3, 1e-2, 1e-1, 1.0) and len(fit.cv_log_loss) == 4
    assert fit.config.w_stance == EXPERT.w_stance  # the gait's preference is not fitted
    assert fit.weights_before["w_riser"] == 0.0 and fit.positives == table.labels["fall"].sum()
    before = outcome_auc(-table.value, table.labels["fall"], table.board, resamples=0).auc
    after_value = sum(SyntheticExpert(fit.config).utilities(table.terms).values())
    after = outcome_auc(-after_value, table.labels["fall"], table.board, resamples=0).auc
    assert before < 0.6 < after
    assert fit_outcomes(table, EXPERT, LITTLEDOG, "fall") == fit  # deterministic
    with pytest.raises(FootfallError, match="unknown outcome"):
        fit_outcomes(table, EXPERT, LITTLEDOG, "tripped")
    never = replace(table, labels={**table.labels, "fall": np.zeros(len(table), bool)})
    with pytest.raises(FootfallError, match="both happen"):
        fit_outcomes(never, EXPERT, LITTLEDOG, "fall")


def test_expert_settings_files_round_trip_and_refuse_other_files(tmp_path):
    config = replace(EXPERT, w_riser=220.0, w_hold=0.0)
    path = tmp_path / "expert.json"
    save_expert(path, config, {"fit": {"label": "fall"}})
    assert load_expert(path) == config
    assert judge_name(config) != judge_name(walking_expert(LEAD)) == "synthetic expert"
    data = json.loads(path.read_text())
    for change, message in [({"format": "x"}, "not a footfall expert settings file"),
                            ({"version": 2}, "version 2"),
                            ({"expert": {**data["expert"], "w_riser": -1}}, "w_riser")]:
        (tmp_path / "bad.json").write_text(json.dumps({**data, **change}))
        with pytest.raises(FootfallError, match=message):
            load_expert(tmp_path / "bad.json")
    with pytest.raises(FootfallError, match="cannot read"):
        load_expert(tmp_path / "missing.json")


def test_a_batch_of_another_experts_runs_is_keyed_apart():
    board = make_board([("flat", 0.0)], 0)
    config = walk_config(None, True, 0.03)
    plain = batch_run_keys(board, None, True, config, [0])[0]
    assert batch_run_keys(board, None, True, config, [0], walking_expert(LEAD))[0] == plain
    other = batch_run_keys(board, None, True, config, [0], replace(EXPERT, w_riser=1.0))[0]
    assert other != plain and "/expert-" in other


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    """A store with hand-tuned runs over a rocky and a flat board, and a copy of the rocky one
    marked as a fall."""
    folder = tmp_path_factory.mktemp("outcomes")
    board = folder / "board.npz"
    save_board(["rocky:0.5"], seed=3, path=board)
    save_board(["flat", "flat"], seed=0, path=folder / "flat.npz")
    path = folder / "store.sqlite"
    walk_once(board, 2, search_radius=0.03, log_path=path)
    walk_once(folder / "flat.npz", 0, search_radius=0.03, log_path=path)
    with DemoStore(path) as store:
        record = store.run(store.runs()[0]["id"])
        store.add_run(replace(record, result={**record.result, "success": False,
                                              "reason": "fall: trunk tilted"}, key=None))
    return folder, path


def test_the_command_reports_causes_and_prediction_and_grounds_an_expert(logged, capsys):
    folder, path = logged
    code, out, _ = run(capsys, "outcomes", path, "--json")
    assert code == 0
    report = json.loads(out)
    method = report["methods"]["hand-tuned default"]
    assert (method["runs"], method["successes"]) == (3, 2)
    pooled = report["prediction"]["all"]
    assert pooled["boards"] == 2 and pooled["value"]["fall"]["positives"] == 4
    expert_file = folder / "grounded.json"
    code, out, _ = run(capsys, "outcomes", path, "--fit", "fall", "-o", expert_file)
    assert code == 0 and "grounded in 'fall' (4 of " in out
    grounded = load_expert(expert_file)
    assert grounded.w_stance == EXPERT.w_stance
    code, out, _ = run(capsys, "outcomes", path, "--expert-config", expert_file, "--json")
    assert code == 0 and json.loads(out)["expert"] == judge_name(grounded)
    for args, message in [(["-o", folder / "x.json"], "give --fit too"),
                          (["--expert-config", folder / "nope.json"], "cannot read"),
                          (["--horizon", "-1"], "--horizon")]:
        code, out, err = run(capsys, "outcomes", path, *args)
        assert_user_error(code, err, message)
    code, out, err = run(capsys, "walk", "--terrain", folder / "board.npz", "--seed", "0",
                         "--expert-config", expert_file)
    assert_user_error(code, err, "(--expert)")


def test_the_vectorised_auc_is_scikit_learns_under_any_weights():
    from sklearn.metrics import roc_auc_score

    rng = np.random.default_rng(1)
    score = np.round(rng.normal(size=200), 1)  # ties
    label = rng.random(200) < 0.3
    counts = rng.integers(0, 3, size=(5, 200)).astype(float)
    got = weighted_auc(score, label, np.vstack([np.ones(200), counts]))
    assert got[0] == pytest.approx(roc_auc_score(label, score), abs=1e-12)
    for row, c in zip(got[1:], counts):
        assert row == pytest.approx(roc_auc_score(label, score, sample_weight=c), abs=1e-12)
