"""People against the synthetic expert and against each other: agreement figures tested with
scripted labelers of known noise, through the HTTP API, on the page's route and in
``footfall demos info --json``, their "never here" marks against the expert's refusals and each
other's (by hand and through the API); and the expert's judgement of a run kept in the store."""

import json

import numpy as np
import pytest
from scipy.stats import binomtest

from cli_helpers import run
from footfall.core.state import RobotState
from footfall.data.label import Label, Mark
from footfall.data.store import DemoStore
from footfall.expert.protocol import teacher_verdict
from footfall.expert.synthetic import SyntheticExpert
from footfall.teach import judging
from footfall.teach.agreement import (
    SAME_FOOTHOLD,
    agreement,
    agreement_lines,
    expert_verdicts,
    marks_agreement,
    same_choice,
)
from footfall.teach.client import ScriptedLabeler, TeachClient
from footfall.teach.judging import default_expert, expert_key
from footfall.teach.service import TeachService
from teach_helpers import serving, store_of_runs

RUNS, STEPS, CANDIDATES = 4, 10, 6  # store_of_runs: 6 candidates a step


@pytest.fixture(scope="module")
def labelled(tmp_path_factory):
    path = store_of_runs(tmp_path_factory.mktemp("agree") / "s.sqlite", runs=RUNS, steps=STEPS)
    expert = SyntheticExpert(default_expert())
    with serving(TeachService(path)) as (_, _, address), TeachClient(address) as client:
        for name, noise, seed in (("careful", 0.0, 0), ("also careful", 0.0, 1),
                                  ("half", 0.5, 2), ("careless", 1.0, 3)):
            labeler = ScriptedLabeler(client, expert, name=name, seed=seed, noise=noise)
            for run in client.runs():
                labeler.label_run(run["id"])
        _mark_run(client, expert, MARKED_RUN)
        figures = client._get("/api/agreement")
    return path, figures


MARKED_RUN = 1  # the run whose steps the scripted labelers also mark "never here"


def _mark_run(client, expert, run_id):
    """On every step of a run: "careful" marks each candidate the expert refuses, "careless"
    two candidates at random (never the one their own label names)."""
    rng = np.random.default_rng(5)
    board = None
    for k in range(STEPS):
        s = client.step(run_id, k, judge=False)
        board = board or client.terrain(s["terrain_hash"])
        state = RobotState.from_vector(np.array(s["state"]), s["leg"])
        _, refused, _ = teacher_verdict(expert, board, state, np.array(s["candidates"]))
        own = {label["labeler"]: label["chosen"] for label in s["labels"]}
        for i in np.flatnonzero(refused):
            if i != own["careful"]:
                client.mark(run_id, k, "careful", candidate=int(i))
        for i in rng.choice([c for c in range(CANDIDATES) if c != own["careless"]], 2,
                            replace=False):
            client.mark(run_id, k, "careless", candidate=int(i))


def test_a_careful_labeler_agrees_with_the_expert_and_with_another_careful_one(labelled):
    _, figures = labelled
    n = RUNS * STEPS
    assert figures["with_expert"]["careful"] == {"steps": n, "agree": n, "share": 1.0,
                                                 "exact": 1.0}
    assert figures["between"]["also careful | careful"]["share"] == 1.0


@pytest.mark.parametrize("name, noise", [("half", 0.5), ("careless", 1.0)])
def test_a_noisy_labelers_agreement_matches_its_noise(labelled, name, noise):
    # a careless step names one of the 6 candidates at random: right by chance 1 time in 6
    _, figures = labelled
    t = figures["with_expert"][name]
    expected = (1 - noise) + noise / CANDIDATES
    assert t["steps"] == RUNS * STEPS
    assert binomtest(round(t["exact"] * t["steps"]), t["steps"], expected).pvalue > 0.001
    assert t["share"] < 1.0
    between = figures["between"][f"careful | {name}"]
    assert between["steps"] == RUNS * STEPS and between["agree"] == t["agree"]


def test_demos_info_gives_the_same_figures(labelled, capsys):
    path, figures = labelled
    code, out, _ = run(capsys, "demos", "info", str(path), "--json")
    assert code == 0 and json.loads(out)["agreement"] == figures
    code, out, _ = run(capsys, "demos", "info", str(path))
    assert code == 0 and "careful agrees with the synthetic expert on 40 of 40 steps (100 %)" in out
    assert "careful's 'never here' marks: the synthetic expert also refuses" in out


def test_the_judgement_of_a_run_is_kept_and_read_back_by_the_next_server(labelled, monkeypatch):
    path, _ = labelled
    key = expert_key(SyntheticExpert(default_expert()))
    with DemoStore(path, read_only=True) as store:
        kept = store.judgement(1, key)
    assert kept is not None and kept[0].shape == (STEPS,)

    def judge_again(*args):
        raise AssertionError("a kept judgement was judged again")

    monkeypatch.setattr(judging, "step_verdicts", judge_again)
    with serving(TeachService(path)) as (_, _, address), TeachClient(address) as client:
        run = client.run(1)
    assert [s["expert_best"] for s in run["steps"]] == kept[0].tolist()


def _label(verdict, chosen, labeler="a"):
    return Label(1, 1, 0, labeler, verdict, chosen, None, 0.0, None)


def test_same_choice_is_fine_alike_or_footholds_within_a_centimetre():
    f = np.array([[0, 0, 0], [0.5 * SAME_FOOTHOLD, 0, 0], [3 * SAME_FOOTHOLD, 0, 0]])
    assert same_choice(_label("foothold", 0), _label("foothold", 1), f)
    assert not same_choice(_label("foothold", 0), _label("foothold", 2), f)
    assert same_choice(_label("fine", 2), -1, f) and not same_choice(_label("fine", 2), 2, f)
    assert expert_verdicts(np.array([3, 4, 5]), np.array([0.5, 2.0, np.nan]), 1.0).tolist() \
        == [-1, 4, -1]
    figures = agreement([_label("foothold", 0, "a"), _label("foothold", 1, "b")],
                        lambda run, k: 2, lambda run, k: f)
    assert figures["with_expert"]["a"] == {"steps": 1, "agree": 0, "share": 0.0, "exact": 0.0}
    assert figures["between"]["a | b"] == {"steps": 1, "agree": 1, "share": 1.0, "exact": 0.0}


def test_marks_agree_with_the_expert_when_it_refuses_them_too(labelled):
    path, figures = labelled
    with DemoStore(path, read_only=True) as store:
        careful = store.marks(labeler="careful")
        careless_steps = {m.k for m in store.marks(labeler="careless")}
    assert careful, "the expert refuses some candidates of the marked run"
    steps = len({m.k for m in careful})
    marks = figures["marks"]
    assert marks["with_expert"]["careful"] == {"steps": steps, "marks": len(careful),
                                               "refused": len(careful), "share": 1.0}
    assert marks["with_expert"]["careless"]["marks"] == 2 * STEPS
    assert marks["between"]["careful | careless"]["steps"] == len(careless_steps & {
        m.k for m in careful})
    assert set(marks["with_expert"]) == {"careful", "careless"}  # the others marked nothing


def _mark(k, labeler, candidate):
    return Mark(0, 1, k, labeler, candidate, 0.0, None)


def test_marks_agreement_by_hand():
    f = np.array([[0, 0, 0], [0.5 * SAME_FOOTHOLD, 0, 0], [5 * SAME_FOOTHOLD, 0, 0],
                  [10 * SAME_FOOTHOLD, 0, 0]])
    marks = [_mark(0, "a", 0), _mark(0, "a", 2), _mark(0, "b", 1), _mark(0, "b", 3),
             _mark(1, "a", 3), _mark(2, "b", 2)]
    refusals = {0: np.array([False, False, True, True]), 1: np.zeros(4, dtype=bool), 2: None}
    figures = marks_agreement(marks, lambda run, k: refusals[k], lambda run, k: f)
    # a: steps 0 and 1 judged, 3 marks, of which the expert refuses candidate 2 of step 0
    assert figures["with_expert"]["a"] == {"steps": 2, "marks": 3, "refused": 1, "share": 1 / 3}
    # b: step 2 is not judged; on step 0 the expert refuses 3, not 1
    assert figures["with_expert"]["b"] == {"steps": 1, "marks": 2, "refused": 1, "share": 0.5}
    # both marked step 0 only: a's 0 and b's 1 lie 5 mm apart (the same foothold), 2 and 3 do not
    assert figures["between"] == {"a | b": {"steps": 1, "marks": 4, "shared": 2, "share": 0.5}}
    lines = agreement_lines({"with_expert": {}, "between": {}, "marks": figures})
    assert lines == ["  a's 'never here' marks: the synthetic expert also refuses 1 of 3 (33 %)",
                     "  b's 'never here' marks: the synthetic expert also refuses 1 of 2 (50 %)",
                     "  a | b mark the same candidates: 2 of 4 marks on 1 steps (50 %)"]
    assert marks_agreement([], lambda run, k: None, lambda run, k: f)["with_expert"] == {}
