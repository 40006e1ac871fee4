"""``footfall benchmark-terrain``: a terrain suite's boards, runs, summary and resumption."""

import json
from dataclasses import replace

import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.data.store import DemoStore
from footfall.experiments.reproduce import reproduction_walk
from footfall.experiments.terrain_suite import (
    STORE_NAME,
    SUITES,
    SuiteConfig,
    run_suite,
    suite_jobs,
    suite_markdown,
)
from footfall.terrain.kinds import HELD_OUT_KINDS, PAPER_KINDS, TRAINING_KINDS

TINY = SuiteConfig(kinds=("stones", "scan"), boards=2, runs=1,
                   walk=replace(reproduction_walk(), max_steps=5))


def test_the_suites_keep_training_and_held_out_kinds_apart():
    assert set(SUITES["held-out"]) == set(HELD_OUT_KINDS)
    assert SUITES["training"] == TRAINING_KINDS
    assert set(PAPER_KINDS) - {"flat"} <= set(TRAINING_KINDS)
    assert not set(SUITES["held-out"]) & set(TRAINING_KINDS)


def test_board_seeds_are_distinct_and_a_kinds_boards_do_not_depend_on_the_others():
    full = SuiteConfig(boards=3).board_specs()
    seeds = [s for _, s, _ in full.values()]
    assert len(set(seeds)) == len(seeds) == 3 * len(HELD_OUT_KINDS)
    assert SuiteConfig(boards=3, kinds=("scan",)).board_specs() == {
        k: v for k, v in full.items() if k.startswith("scan-")}
    assert full["stones-b0"][0] == (("stones", 0.7), ("stones", 0.7))
    assert SuiteConfig(runs=4).run_seeds() == SuiteConfig(runs=4, kinds=("scan",)).run_seeds()


def test_a_kind_outside_the_suite_is_refused():
    with pytest.raises(FootfallError, match="the held-out suite has no kind rocky"):
        SuiteConfig(kinds=("rocky",))


@pytest.fixture(scope="module")
def walked(tmp_path_factory):
    out = tmp_path_factory.mktemp("suite")
    return out, run_suite(out, TINY, processes=1, log=lambda s: None)


def test_both_choosers_walk_every_board_with_the_same_seeds_and_are_paired(walked):
    out, summary = walked
    with DemoStore(out / STORE_NAME) as store:
        keys = sorted(r["key"] for r in store.runs())
    assert len(keys) == 2 * 2 * TINY.boards * TINY.runs
    units = {who: sorted(k.split("/", 1)[1] for k in keys if k.startswith(who + "/"))
             for who in ("expert", "hand")}
    assert units["expert"] == units["hand"]
    for kind in ("stones", "scan"):
        for who in ("expert", "hand"):
            s = summary["kinds"][kind][who]
            assert s["runs"] == TINY.boards * TINY.runs and 0 <= s["successes"] <= s["runs"]
            lo, hi = s["success_ci"]
            assert 0 <= lo <= s["success_rate"] <= hi <= 1
            assert sum(s["causes"].values()) <= s["runs"] - s["successes"]
        assert summary["paired"][kind]["pairs"] == TINY.boards * TINY.runs
    assert summary["pooled"]["hand"]["runs"] == 2 * TINY.boards * TINY.runs
    assert summary["paired"]["all"]["pairs"] == 2 * TINY.boards * TINY.runs
    md = (out / "suite.md").read_text()
    assert md == suite_markdown(summary) and "| **all** |" in md and "| stones |" in md


def test_a_rerun_walks_nothing_and_other_boards_are_refused(walked):
    out, summary = walked
    logged: list[str] = []
    again = run_suite(out, TINY, processes=1, log=logged.append)
    assert any("already stored" in line for line in logged)
    assert json.dumps(again, sort_keys=True) == json.dumps(summary, sort_keys=True)
    with pytest.raises(FootfallError, match="other settings"):
        run_suite(out, replace(TINY, boards=3), processes=1, log=lambda s: None)


def test_the_command_refuses_bad_kinds_in_one_line(tmp_path, capsys):
    assert_user_error(*run(capsys, "benchmark-terrain", "--kind", "rocky", "--out",
                           tmp_path)[::2], "has no kind rocky")


def test_a_variant_walks_its_change_and_is_not_mixed_with_the_defaults(walked, tmp_path):
    out, summary = walked
    variant = replace(TINY, variant="with-friction-check")
    jobs = suite_jobs(variant, {"stones-b0": tmp_path / "b.npz"})
    assert {j.walk.footstep.friction_safety for j in jobs} == {1.5}
    assert {j.walk.footstep.friction_safety for j in suite_jobs(
        TINY, {"stones-b0": tmp_path / "b.npz"})} == {None}
    assert suite_markdown({**summary, "config": variant.to_dict()}).startswith(
        "# The held-out terrain suite, with-friction-check: with footholds dropped")
    with pytest.raises(FootfallError, match="other settings"):
        run_suite(out, variant, processes=1, log=lambda s: None)
    with pytest.raises(FootfallError, match="controller variant"):
        replace(TINY, variant="no-such-variant")


def test_later_boards_are_the_same_boards_walked_alone():
    full = SuiteConfig(boards=6).board_specs()
    late = SuiteConfig(boards=6, first_board=4).board_specs()
    assert sorted(late) == sorted(k for k in full if k.endswith(("-b4", "-b5")))
    assert all(late[k] == full[k] for k in late)
    with pytest.raises(FootfallError, match="first board"):
        SuiteConfig(boards=2, first_board=2)


def test_two_walks_are_paired_run_by_run():
    from footfall.experiments.terrain_suite import compare_suites, comparison_markdown

    these = {"expert/stones/b0/s1": True, "expert/stones/b0/s2": True,
             "expert/scan/b0/s1": False, "hand/stones/b0/s1": True, "expert/scan/b0/s9": True}
    those = {"expert/stones/b0/s1": False, "expert/stones/b0/s2": True,
             "expert/scan/b0/s1": True, "hand/stones/b0/s1": True}  # s9 not walked there
    c = compare_suites(these, those, ("stones", "scan"), ("expert", "hand"))
    assert c["expert"]["stones"] == {"runs": 2, "these": 2, "those": 1, "won": 1, "lost": 0,
                                     "p_value": 1.0}
    assert (c["expert"]["all"]["runs"], c["expert"]["all"]["won"],
            c["expert"]["all"]["lost"]) == (3, 1, 1)
    assert c["hand"]["all"]["runs"] == 1 and c["hand"]["scan"]["runs"] == 0
    table = comparison_markdown(c, "old")
    assert "| stones | 2 / 1 of 2, +1 / -0 (1) | 1 / 1 of 1, +0 / -0 (1) |" in table


def test_the_command_pairs_with_another_folder_and_refuses_one_that_is_not_a_suite(
        walked, tmp_path, capsys):
    out, _ = walked
    code, _, err = run(capsys, "benchmark-terrain", "--kind", "stones", "--out", tmp_path / "x",
                       "--against", tmp_path / "nothing")
    assert_user_error(code, err, "not a terrain suite's folder")
    assert not (tmp_path / "x").exists()  # refused before anything was walked


def test_the_command_walks_boards_of_the_difficulty_asked_into_their_own_folder(
        monkeypatch, tmp_path, capsys):
    import footfall.cli.experiments as cli

    seen = {}

    def fake_run_suite(folder, config, **kwargs):
        seen.update(folder=folder, config=config)
        raise FootfallError("stopped before walking")

    monkeypatch.setattr(cli, "run_suite", fake_run_suite)
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, "benchmark-terrain", "--suite", "training", "--kind", "ridges",
                       "--difficulty", "1")
    assert_user_error(code, err, "stopped before walking")
    assert str(seen["folder"]) == "out/suite-training-d1"
    assert seen["config"].difficulty == 1.0
    assert set(seen["config"].board_specs().values()) == {
        ((("ridges", 1.0), ("ridges", 1.0)), s, True)
        for _, s, _ in SuiteConfig(suite="training", kinds=("ridges",)).board_specs().values()}
    code, _, err = run(capsys, "benchmark-terrain", "--difficulty", "1.5")
    assert code == 2 and "1.5" in err and "Traceback" not in err


def test_a_learned_function_walks_as_a_chooser_paired_with_the_hand_tuned_reward(walked,
                                                                               tmp_path):
    """A model chooser walks the same boards and seeds under ``model:NAME``, is paired with the
    hand-tuned reward, and its name keeps to its file in the folder."""
    from footfall.learning.train import learn_model
    from test_learners import lowest_foothold_demos

    out, _ = walked
    model = learn_model(lowest_foothold_demos(), "terrain", "l1", cv=3, Cs=3, seed=1)
    model.save(tmp_path / "m.npz")
    with_model = replace(TINY, models=(("m", str(tmp_path / "m.npz")),),
                         who=("expert", "hand", "model:m"))
    summary = run_suite(out, with_model, processes=1, log=lambda s: None)
    with DemoStore(out / STORE_NAME) as store:
        keys = {r["key"] for r in store.runs()}
    mine = sorted(k.split("/", 1)[1] for k in keys if k.startswith("model:m/"))
    assert mine == sorted(k.split("/", 1)[1] for k in keys if k.startswith("hand/"))
    paired = summary["paired_models"]["model:m"]
    assert paired["all"]["pairs"] == 2 * TINY.boards * TINY.runs
    assert "Paired, m against the hand-tuned reward" in suite_markdown(summary)
    other = learn_model(lowest_foothold_demos(), "terrain", "l1", cv=3, Cs=3, seed=2)
    other.save(tmp_path / "other.npz")
    with pytest.raises(FootfallError, match="another model named 'm'"):
        run_suite(out, replace(with_model, models=(("m", str(tmp_path / "other.npz")),)),
                  processes=1, log=lambda s: None)
    with pytest.raises(FootfallError, match="'model:NAME' of a model given"):
        replace(TINY, who=("hand", "model:x"))


def test_the_reproductions_teacher_walks_as_a_chooser_paired_with_the_hand_tuned_reward(walked):
    """``--who teacher``: the hand-tuned reward among the footholds the expert accepts chooses
    every foothold, on the same boards and seeds, paired with the hand-tuned reward."""
    out, _ = walked
    with_teacher = replace(TINY, who=("hand", "teacher"))
    paths = {name: out / "terrain" / f"{name}.npz" for name in with_teacher.board_specs()}
    jobs = [j for j in suite_jobs(with_teacher, paths) if j.key.startswith("teacher/")]
    assert jobs and all(j.judge and j.teacher == "accepted" and j.model is None for j in jobs)
    summary = run_suite(out, with_teacher, processes=1, log=lambda s: None)
    with DemoStore(out / STORE_NAME) as store:
        keys = {r["key"] for r in store.runs()}
    mine = sorted(k.split("/", 1)[1] for k in keys if k.startswith("teacher/"))
    assert mine == sorted(k.split("/", 1)[1] for k in keys if k.startswith("hand/"))
    assert summary["paired_models"]["teacher"]["all"]["pairs"] == 2 * TINY.boards * TINY.runs
    assert "Paired, the teacher against the hand-tuned reward" in suite_markdown(summary)
    assert SuiteConfig().who == ("expert", "hand")  # the teacher's runs only when asked for
