"""Stored runs labelled again by the rollout teacher (footfall.experiments.relabel,
``footfall demos correct --teacher rollout``): each run walked again from its log, checked to
retrace it, labelled as it goes; run by run, so a repeated command adds nothing twice."""

from dataclasses import replace

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.data.store import DemoStore
from footfall.experiments.executors import LocalPool
from footfall.experiments.relabel import relabel_runs, retraces
from footfall.experiments.runs import RunJob, Runner
from footfall.expert.synthetic import walking_expert
from footfall.sim.episode import WalkConfig
from footfall.sim.rollout import RolloutConfig
from footfall.terrain import make_board, parse_board_spec

SMALL = RolloutConfig(candidates=2, branches=1, horizon=1)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Two logged runs of the hand-tuned reward, three steps each, as walk-many --log keeps."""
    folder = tmp_path_factory.mktemp("runs")
    board = make_board([parse_board_spec("rocky:0.7")], seed=3)
    board.save(folder / "board.npz")
    config = WalkConfig(max_steps=3)
    with DemoStore(folder / "runs.sqlite", create=True) as store:
        runner = Runner(store, {board.content_hash(): board}, LocalPool(1), None, lambda s: None)
        runner.run([RunJob(f"walk/s{s}", str(folder / "board.npz"), None, s, config)
                    for s in (0, 1)], "runs")
    return folder / "runs.sqlite"


def test_runs_walked_again_are_labelled_once_and_a_repeat_adds_nothing(runs, tmp_path):
    expert = walking_expert(WalkConfig().footstep.lead)
    out = tmp_path / "labels.sqlite"
    told = []
    done = relabel_runs([runs], out, None, "rollout", expert, SMALL, todo=told.append)
    assert told == [2] and done.runs == 2 and done.skipped == 0
    assert done.steps == 6 and done.added == 6  # every step: three a run
    with DemoStore(out, read_only=True) as store, DemoStore(runs, read_only=True) as logged:
        demos = store.demonstrations()
        steps = {f"run:{h['key']}:step:{s.k}": s for h in logged.runs()
                 for s in logged.run(h["id"]).steps}
    assert sorted(d.source for d in demos) == sorted(steps)
    for d in demos:
        np.testing.assert_array_equal(d.candidates, steps[d.source].candidates)
        assert d.expert["class"].endswith("RolloutVerdict") and d.refused is not None
    again = relabel_runs([runs], out, None, "rollout", expert, SMALL)
    assert (again.runs, again.skipped, again.added) == (0, 2, 0)
    with DemoStore(out, read_only=True) as store:
        assert len(store.demonstrations()) == 6


def test_a_run_walked_by_another_function_is_refused_before_any_walking(runs, tmp_path):
    from test_bad_models import make_model

    model = tmp_path / "other.npz"
    make_model().save(model)
    with pytest.raises(FootfallError, match="give --model the function that walked it"):
        relabel_runs([runs], tmp_path / "x.sqlite", str(model), "rollout",
                     walking_expert(0.01), SMALL)
    assert not (tmp_path / "x.sqlite").exists()  # refused before anything was made
    with pytest.raises(FootfallError, match="no run logs"):
        relabel_runs([runs], tmp_path / "x.sqlite", None, "rollout", walking_expert(0.01),
                     SMALL, key_prefix="nothing/")


def test_a_walk_that_leaves_its_log_is_found_where_it_leaves(runs):
    with DemoStore(runs, read_only=True) as store:
        logged = store.run(store.runs()[0]["id"])
    assert retraces(logged, logged) is None
    steps = list(logged.steps)
    other = int(steps[1].chosen == 0)
    steps[1] = replace(steps[1], chosen=other)
    assert retraces(replace(logged, steps=tuple(steps)), logged) == 1
    assert retraces(replace(logged, steps=logged.steps[:2]), logged) == 2


def test_the_command_labels_by_walking_and_refuses_a_model_for_a_teacher_that_reads_logs(
        runs, tmp_path, capsys):
    out = tmp_path / "labels.sqlite"
    code, text, err = run(capsys, "demos", "correct", runs, "-o", out, "--teacher", "rollout",
                          "--every-step", "--run-key", "walk/s1", "--processes", "1")
    assert code == 0, err
    assert "added 3 labels" in text and "1 run walked again" in text
    code, text, err = run(capsys, "demos", "correct", runs, "-o", out, "--teacher", "rollout",
                          "--every-step", "--run-key", "walk/s1", "--processes", "1")
    assert code == 0 and "1 run already labelled there, skipped" in text
    code, _, err = run(capsys, "demos", "correct", runs, "-o", out, "--teacher", "accepted",
                       "--model", tmp_path / "m.npz")
    assert_user_error(code, err, "--model names the function that walked the runs")


def test_the_teaching_page_shows_the_branches_of_a_step_labelled_in_its_store(runs, tmp_path):
    """Labels written into the runs' own store: the teaching service gives, for a labelled
    step, what followed each candidate tried (in words) and the one taught."""
    import shutil

    from footfall.teach.service import TeachService

    store = tmp_path / "runs.sqlite"
    shutil.copy(runs, store)
    relabel_runs([store], store, None, "rollout", walking_expert(WalkConfig().footstep.lead),
                 SMALL, key_prefix="walk/s0")
    service = TeachService(store)
    try:
        run_id = next(r["id"] for r in service.runs() if r["key"] == "walk/s0")
        for k in range(3):
            shown = service.step(run_id, k, judge=False)
            branches = shown["branches"]
            tried = [t["candidate"] for t in branches["tried"]]
            assert branches["taught"] in tried
            assert [t["base"] for t in branches["tried"]] == [True] + [False] * (len(tried) - 1)
            assert all(len(t["outcomes"]) == SMALL.branches and all(t["outcomes"])
                       for t in branches["tried"])
        other = next(r["id"] for r in service.runs() if r["key"] == "walk/s1")
        assert service.step(other, 0, judge=False)["branches"] is None
    finally:
        service.close()
