"""The reproduction resumes after an interruption without repeating or losing anything."""

import json

import pytest

from footfall.core.errors import FootfallError
from footfall.data.store import DemoStore
from footfall.experiments.reproduce import ReproduceConfig, planned_seeds, run_reproduction
from footfall.expert.synthetic import ExpertConfig
from footfall.sim.episode import WALL_CLOCK_FIELDS, WalkConfig

TINY = ReproduceConfig(
    train_boards=((("rocky", 0.5),),), test_board=(("rocky", 0.6),), sweep_difficulties=(),
    rounds=2, target_demos=1000, corrections_per_run=None, margin=2.0, library_size=30,
    training_candidates=20, cv=2, final_bandwidth_rms=0.004, eval_runs=2, offline_demos=4,
    walk=WalkConfig(max_steps=8),  # eight steps a run: small, but every stage runs
    expert=ExpertConfig())  # the expert who values progress corrects most of eight steps (the
# walking expert, who wants the foot where this gait puts it, too few of them to learn from)


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


def test_the_reproduction_has_every_table(uninterrupted):
    r = _results(uninterrupted)
    assert set(r["table2"]) == {"terrain", "templates", "both", "flat", "expert", "default"}
    assert all(t["runs"] == TINY.eval_runs for t in r["table2"].values())
    with DemoStore(uninterrupted / "reproduce.sqlite") as store:  # the expert chose its own
        judged = [store.run(x["id"]) for x in store.runs(key_prefix="eval/expert/")]
        plain = [store.run(x["id"]) for x in store.runs(key_prefix="eval/default/")]
    assert judged and all(run.settings["judge"] == "SyntheticExpert.values" for run in judged)
    planned = planned_seeds(TINY)  # every run drew its seed from the stream of its purpose
    with DemoStore(uninterrupted / "reproduce.sqlite") as store:
        for prefix, purpose in (("correct/", "correction runs"), ("eval/", "evaluation runs")):
            seeds = {store.run(x["id"]).seed for x in store.runs(key_prefix=prefix)}
            assert seeds and seeds <= set(planned[purpose])
    assert r["boards"]["test"]["seed"] in planned["boards"]
    assert plain and all("judge" not in run.settings for run in plain)
    assert set(r["table1"]) == {"templates", "both"}
    assert r["demonstrations"]["n"] > 0
    assert set(r["ranking"]) == {"terrain", "templates", "both"}
    # The expert's verdict on every logged step of each test-board row.
    assert set(r["choices"]) == {"terrain", "templates", "both", "expert", "default"}
    with DemoStore(uninterrupted / "reproduce.sqlite") as store:
        for k, v in r["choices"].items():
            logged = sum(len(store.run(x["id"]).steps) for x in store.runs(key_prefix=f"eval/{k}/"))
            assert v["steps"] == logged > 0
            assert 0 <= v["median"] <= v["p90"] and v["mean"] >= 0
            assert 0 <= v["severe"] <= v["above_margin"] <= 1
    md = (uninterrupted / "report.md").read_text()
    assert "Table I" in md and "Table II" in md and "Wilson" in md
    assert "Expert choosing (reference)" in md and "Hand-tuned reward (reference)" in md
    assert "The expert's verdict on the robot's choices" in md


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

    from footfall.experiments.reproduce import _runs_by_key

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
