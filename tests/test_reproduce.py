"""The reproduction resumes after an interruption without repeating or losing anything."""

import json
import shutil
from dataclasses import replace

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.data.store import DemoStore
from footfall.experiments.reproduce import ReproduceConfig, run_reproduction
from footfall.experiments.reproduce_learning import learn_functions
from footfall.experiments.workspace import open_workspace, planned_seeds
from footfall.expert.scorer import judge_name
from footfall.expert.synthetic import ExpertConfig
from footfall.features.family import PAPER_FEATURE_SETS
from footfall.learning.model import FootholdModel
from footfall.sim.episode import WALL_CLOCK_FIELDS, WalkConfig

TINY = ReproduceConfig(
    train_boards=((("rocky", 0.5),),), test_kinds=("rocky",), difficulties=(0.6,),
    calibration_boards=1, calibration_runs=1, calibration_level_runs=2, confirmation_runs=2,
    test_boards=2, sweep_runs=1, rounds=2, target_demos=1000, corrections_per_run=None, margin=2.0, library_size=30,
    training_candidates=20, cv=2, final_bandwidth_rms=0.004, eval_runs=1, offline_demos=4,
    walk=WalkConfig(max_steps=8),  # eight steps a run: small, but every stage runs
    expert=ExpertConfig(), teacher="expert", every_step=False, round_runs=1,
    supervision="choice", veto=False, library_capped=False)  # the paper's loop: the expert who
# values progress corrects most of eight steps (the walking expert, who wants the foot where this
# gait puts it, too few of them to learn from; the guarded teacher fewer still). The student's
# default loop -- every step labelled, graded, the veto -- is DAGGER's, below


def _stored(out):
    with DemoStore(out / "reproduce.sqlite") as store:
        runs = {r["key"]: {k: v for k, v in r["result"].items() if k not in WALL_CLOCK_FIELDS}
                for r in store.runs()}  # what the runs did, not how fast this computer was
        demos = sorted((d.source, d.chosen) for d in store.demonstrations())
    return runs, demos


def _results(out):
    r = json.loads((out / "results.json").read_text())
    r.pop("seconds_this_session")
    return r


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("whole")
    run_reproduction(out, TINY, processes=1, log=lambda s: None)
    return out


def test_resuming_after_an_interruption_repeats_nothing_and_loses_nothing(uninterrupted, tmp_path):
    first: list[str] = []

    def stop_after_three(key: str) -> None:
        first.append(key)
        if len(first) == 3:  # mid-way: after the corrections, before the evaluation is done
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_reproduction(tmp_path, TINY, processes=1, log=lambda s: None, on_run=stop_after_three)
    assert not (tmp_path / "report.md").exists()
    kept, _ = _stored(tmp_path)
    assert sorted(kept) == sorted(first)  # every finished run was kept

    second: list[str] = []
    run_reproduction(tmp_path, TINY, processes=1, log=lambda s: None, on_run=second.append)
    assert not set(first) & set(second)  # nothing repeated
    assert _stored(tmp_path) == _stored(uninterrupted)  # nothing lost, the same runs and labels
    assert _results(tmp_path) == _results(uninterrupted)
    for name in ("report.md", "report.html", "crossing.png", "models/both.npz"):
        assert (tmp_path / name).exists()
    html = (tmp_path / "report.html").read_text()
    assert "<table>" in html and "data:image/png;base64," in html and 'src="' not in html.replace(
        'src="data:', "")  # self-contained: every picture embedded


METHODS = {"terrain", "templates", "both", "expert", "default"}


def test_the_reproduction_has_every_table(uninterrupted):
    r = _results(uninterrupted)
    assert set(r["table2"]) == METHODS | {"flat"}  # the paper's one-board table: test0
    assert all(t["runs"] == TINY.eval_runs for t in r["table2"].values())
    with DemoStore(uninterrupted / "reproduce.sqlite") as store:  # the expert chose its own
        judged = [store.run(x["id"]) for x in store.runs(key_prefix="eval/test0/expert/")]
        plain = [store.run(x["id"]) for x in store.runs(key_prefix="eval/test0/default/")]
    assert judged and all(run.settings["judge"] == judge_name(TINY.expert) for run in judged)
    planned = planned_seeds(TINY)  # every run drew its seed from the stream of its purpose
    with DemoStore(uninterrupted / "reproduce.sqlite") as store:
        for prefix, purpose in (("correct/", "correction runs"), ("eval/", "evaluation runs"),
                                ("calibrate/", "calibration runs"), ("sweep/", "sweep runs"),
                                ("confirm/", "confirmation runs")):
            seeds = {store.run(x["id"]).seed for x in store.runs(key_prefix=prefix)}
            assert seeds and seeds <= set(planned[purpose])
    assert {r["boards"][f"test{b}"]["seed"] for b in range(2)} <= set(planned["boards"])
    assert plain and all("judge" not in run.settings for run in plain)
    assert set(r["table1"]) == {"templates", "both"}
    assert r["demonstrations"]["n"] > 0
    assert set(r["ranking"]) == {"terrain", "templates", "both"}
    # The expert's verdict on every logged step of each method's test-board runs.
    assert set(r["choices"]) == METHODS
    with DemoStore(uninterrupted / "reproduce.sqlite") as store:
        for k, v in r["choices"].items():
            logged = sum(len(store.run(x["id"]).steps) for b in ("test0", "test1")
                         for x in store.runs(key_prefix=f"eval/{b}/{k}/"))
            assert v["steps"] == logged > 0
            assert 0 <= v["median"] <= v["p90"] and v["mean"] >= 0
            assert 0 <= v["severe"] <= v["above_margin"] <= 1
    md = (uninterrupted / "report.md").read_text()
    assert "Table I" in md and "Table II" in md and "Wilson" in md
    assert "Teacher choosing (reference)" in md and "Hand-tuned reward (reference)" in md
    assert "The teacher (the synthetic expert) on" in md  # which teacher, in words
    assert "The expert's verdict on the robot's choices" in md


def test_the_unseen_terrain_stage_is_calibrated_pooled_paired_and_swept(uninterrupted):
    r = _results(uninterrupted)
    cal = r["calibration"]  # one level, one expert run a board: the rule's record
    # the rule rests on its one level: walked on a second board to calibration_level_runs (2)
    assert list(cal["levels"]) == ["0.6"] and cal["levels"]["0.6"]["runs"] == 2
    assert {b for b in r["boards"] if b.startswith("cal")} == {"cal0.6-0", "cal0.6-1"}
    assert r["test_difficulty"] == 0.6 and "90%" in cal["rule"]
    # the choice confirmed on two fresh boards (one run each), the only level there is
    assert cal["selected"] == 0.6 and list(cal["confirmations"]) == ["0.6"]
    assert cal["confirmations"]["0.6"]["runs"] == 2
    assert {b for b in r["boards"] if b.startswith("confirm")} == {"confirm0.6-0", "confirm0.6-1"}
    assert "confirmed on fresh boards" in cal["rule"]
    with DemoStore(uninterrupted / "reproduce.sqlite") as store:
        confirm = [x["result"]["success"] for x in store.runs(key_prefix="confirm/0.6/")]
    assert cal["confirmations"]["0.6"]["successes"] == sum(map(bool, confirm)) and len(confirm) == 2
    held = cal["held_on_test"]  # the test boards held against the confirmation, not the choice
    assert held["against"] == "confirmation"
    assert held["calibration"] == [cal["confirmations"]["0.6"]["successes"], 2]
    assert r["boards"]["test0"]["modules"] == [["rocky", 0.6]]
    assert set(r["table2_boards"]) == {"test0", "test1"}
    for k in METHODS:  # pooled = the two boards' runs together
        per = [r["table2_boards"][b][k] for b in ("test0", "test1")]
        pooled = r["table2_pooled"][k]
        assert pooled["runs"] == sum(t["runs"] for t in per) == 2 * TINY.eval_runs
        assert pooled["successes"] == sum(t["successes"] for t in per)
        assert pooled["distance_mean_m"] > 0
    assert r["table2"]["both"] == r["table2_boards"]["test0"]["both"]
    pairs = {(c["a"], c["b"]): c for c in r["pairs"]}
    assert len(pairs) == 10 and ("both", "templates") in pairs and ("templates", "terrain") in pairs
    outcome = {}
    with DemoStore(uninterrupted / "reproduce.sqlite") as store:
        for x in store.runs(key_prefix="eval/test"):
            _, board, method, seed = x["key"].split("/")
            outcome[method, board, seed] = x["result"]["success"]
    for (a, b), c in pairs.items():  # the discordant pairs, counted from the store
        units = {(board, seed) for m, board, seed in outcome if m == a}
        assert c["pairs"] == len(units) == 2 * TINY.eval_runs
        assert c["a_only"] == sum(outcome[a, u[0], u[1]] and not outcome[b, u[0], u[1]]
                                  for u in units)
        assert c["b_only"] == sum(outcome[b, u[0], u[1]] and not outcome[a, u[0], u[1]]
                                  for u in units)
        assert 0 < c["p_value"] <= 1
        assert c["success_verdict"] in ("held", "reversed", "not separated")
    assert set(r["sweep"]) == {"0.6"} and set(r["sweep"]["0.6"]) == METHODS  # always walked
    md = (uninterrupted / "report.md").read_text()
    for heading in ("The test difficulty, by a rule", "the paper's one-board table",
                    "Table II pooled over the 2 test boards", "Paired comparisons",
                    "Success against difficulty"):
        assert heading in md


def test_another_configuration_in_the_same_folder_is_refused(uninterrupted):
    with pytest.raises(FootfallError, match="other settings"):
        run_reproduction(uninterrupted, ReproduceConfig.quick(seed=1), processes=1,
                         log=lambda s: None)


def test_a_round_learns_only_when_both_leg_groups_have_enough_corrections():
    from types import SimpleNamespace

    from footfall.experiments.reproduce import _short_groups

    demos = [SimpleNamespace(state=SimpleNamespace(swing_leg=leg))
             for leg in ("LF", "RH", "LH", "RH")]
    assert _short_groups(demos, 2) == ["front"]
    assert _short_groups(demos, 1) == []
    assert _short_groups([], 1) == ["front", "hind"]


def test_the_default_reproduction_walks_with_the_walking_expert_and_a_local_f():
    from footfall.experiments.reproduce import REPRODUCTION_SEARCH_RADIUS
    from footfall.expert.synthetic import walking_expert

    config = ReproduceConfig()
    assert config.expert == walking_expert(config.walk.footstep.lead)
    assert config.expert.w_progress == 0.0 and config.expert.w_stance > 0.0
    assert config.expert.stance_lead == config.walk.footstep.lead
    assert config.walk.footstep.search_radius == REPRODUCTION_SEARCH_RADIUS
    assert WalkConfig().footstep.search_radius is None  # plain walks: every reachable foothold


def test_tables_do_not_depend_on_the_order_in_which_runs_finished():
    from types import SimpleNamespace

    from footfall.experiments.judged_runs import _runs_by_key

    rows = [{"key": "eval/both/s5002", "id": 1}, {"key": "eval/both/s5000", "id": 2},
            {"key": "eval/both/s5001", "id": 3}]
    store = SimpleNamespace(runs=lambda key_prefix: [r for r in rows
                                                     if r["key"].startswith(key_prefix)])
    assert [r["id"] for r in _runs_by_key(store, "eval/both/")] == [2, 3, 1]


def test_extra_rounds_are_walked_while_a_leg_group_is_short_then_a_clear_error(tmp_path):
    """A leg group short of corrections gets extra rounds; if still short, one clear error."""
    from dataclasses import replace

    never_enough = replace(TINY, rounds=1, extra_rounds=1, cv=1000)  # no group ever reaches 1000
    walked: list[str] = []
    with pytest.raises(FootfallError, match=r"after 2 correction rounds the front and hind legs "
                                            r"have fewer than 1000 corrections"):
        run_reproduction(tmp_path, never_enough, processes=1, log=lambda s: None,
                         on_run=walked.append)
    assert sorted(walked) == ["correct/r0/train00", "correct/r1/train00"]
    with pytest.raises(FootfallError, match="extra_rounds"):
        replace(TINY, extra_rounds=-1)


def test_the_learner_and_folds_options_reach_the_reproductions_settings(tmp_path, capsys):
    from cli_helpers import assert_user_error, run
    from footfall.cli.experiments import _reproduce_config

    config = _reproduce_config(3, True, None, "lambdarank", "run")
    assert (config.learner, config.folds, config.seed) == ("lambdarank", "run", 3)
    assert config == ReproduceConfig(**{**vars(ReproduceConfig.quick(3)), "learner": "lambdarank",
                                        "folds": "run"})
    assert _reproduce_config(0, False, None) == ReproduceConfig(seed=0)
    assert (ReproduceConfig().learner, ReproduceConfig().folds) == ("lambdarank", "demonstration")
    for command in (["reproduce"], ["study", "--seeds", "0"]):
        code, _, err = run(capsys, *command, "--learner", "lasso", "--out", tmp_path / "r")
        assert_user_error(code, err, "lasso")
    with pytest.raises(FootfallError, match="learner must be a registered learner"):
        ReproduceConfig(learner="lasso")


def _without_seconds(value):
    """JSON settings less every "seconds" field (a learning time: this computer's speed)."""
    if isinstance(value, dict):
        return {k: _without_seconds(v) for k, v in value.items() if k != "seconds"}
    if isinstance(value, list):
        return [_without_seconds(v) for v in value]
    return value


def _model_contents(path):
    """A saved model's arrays, and its settings less its learning time."""
    with np.load(path, allow_pickle=False) as f:
        arrays = {k: f[k] for k in f.files}
    meta = _without_seconds(json.loads(str(arrays.pop("meta"))))
    return arrays, meta


def test_the_three_functions_learned_in_worker_processes_are_the_same_bits(uninterrupted,
                                                                          tmp_path):
    out = tmp_path / "copy"
    shutil.copytree(uninterrupted, out)
    for fs in PAPER_FEATURE_SETS:
        (out / "models" / f"{fs}.npz").unlink()
    ws = open_workspace(out, TINY)
    sources = FootholdModel.load(uninterrupted / "models" / "both.npz").info["sources"]
    with DemoStore(out / "reproduce.sqlite", read_only=True) as store:
        by_source = {d.source: d for d in store.demonstrations()}
    lines = []
    learn_functions(ws, [by_source[s] for s in sources], lines.append, processes=2,
                    store_path=out / "reproduce.sqlite")
    assert [line for line in lines if line.startswith("learning ")] == [
        f"learning {fs} (learner {TINY.learner}, {TINY.selection} on its path, folds by "
        f"{TINY.folds})" for fs in PAPER_FEATURE_SETS]  # the workers' logs in the sets' order
    for fs in PAPER_FEATURE_SETS:
        learned, saved = (_model_contents(folder / "models" / f"{fs}.npz")
                          for folder in (out, uninterrupted))
        assert learned[1] == saved[1]
        assert learned[0].keys() == saved[0].keys()
        for k in saved[0]:
            np.testing.assert_array_equal(learned[0][k], saved[0][k])


DAGGER = replace(TINY, every_step=ReproduceConfig().every_step,  # the student's defaults
                 round_runs=ReproduceConfig().round_runs, supervision=ReproduceConfig().supervision,
                 veto=ReproduceConfig().veto, library_capped=ReproduceConfig().library_capped,
                 teacher=ReproduceConfig().teacher, expert=None)


def _rounds(out, config, on_run=None):
    from footfall.experiments.executors import LocalPool
    from footfall.experiments.reproduce import STORE_NAME, correction_rounds
    from footfall.experiments.runs import Runner

    ws = open_workspace(out, config)
    with DemoStore(out / STORE_NAME, create=True) as store:
        return correction_rounds(ws, Runner(store, ws.by_hash, LocalPool(1), on_run,
                                            lambda s: None))


def test_dagger_labels_every_step_of_the_students_runs_and_resumes(tmp_path):
    """The teacher labels every step of every run of each round (two a board), with its
    verdict on every candidate; the labels grow round by round; a stopped round resumes to the
    same labels."""
    whole = _rounds(tmp_path / "whole", DAGGER)
    with DemoStore(tmp_path / "whole" / "reproduce.sqlite") as store:
        runs = {r["key"]: r["n_steps"] for r in store.runs()}
    assert sorted(runs) == ["correct/r0/train00", "correct/r0/train00/s1",
                            "correct/r1/train00", "correct/r1/train00/s1"]
    totals = [r["demonstrations_total"] for r in whole.rounds]
    assert totals == [runs["correct/r0/train00"] + runs["correct/r0/train00/s1"], len(whole.demos)]
    assert 0 < totals[0] < totals[1]  # the student's own states added to the teacher's
    assert whole.rounds[1]["reward"] == "models/round1.npz"  # round 1 walked the student
    assert DAGGER.every_step and DAGGER.veto and DAGGER.supervision == "graded"
    assert all(d.values is not None and d.refused is not None for d in whole.demos)
    assert any(d.refused.any() for d in whole.demos)  # the veto says "never here" somewhere
    first: list[str] = []

    def stop_after_three(key: str) -> None:
        first.append(key)
        if len(first) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _rounds(tmp_path / "again", DAGGER, stop_after_three)
    resumed = _rounds(tmp_path / "again", DAGGER)
    assert [(d.source, d.chosen, d.values.tobytes()) for d in resumed.demos] == \
        [(d.source, d.chosen, d.values.tobytes()) for d in whole.demos]


def test_the_rollout_teacher_teaches_and_walks_in_a_reproduction(tmp_path):
    """``reproduce --teacher rollout``: its labels of every step of the correction runs (its
    verdicts, no values), its own runs as the reference line (with its settings logged), and on
    a state alone -- the offline ranking -- its base, the accepted teacher."""
    from footfall.sim.rollout import RolloutConfig

    rollout = RolloutConfig(candidates=1, branches=1, horizon=0)  # the smallest teacher
    config = replace(TINY, teacher="rollout", expert=None, every_step=True,
                     supervision="refusals", veto=True, rollout=rollout)
    results = run_reproduction(tmp_path, config, processes=1, log=lambda s: None)
    with DemoStore(tmp_path / "reproduce.sqlite") as store:
        labels = store.demonstrations(source_prefix="run:correct/")
        teacher_runs = store.runs(key_prefix="eval/")
        settings = [store.run(r["id"]).settings for r in teacher_runs
                    if "/expert/" in r["key"]]
    assert labels and all(d.expert["class"].endswith("RolloutVerdict") and d.values is None
                          for d in labels)
    assert settings and all(s["teacher"]["rollout"] == rollout.to_dict() for s in settings)
    assert json.loads((tmp_path / "config.json").read_text())["rollout"] == rollout.to_dict()
    assert results["ranking"] and (tmp_path / "report.md").exists()
