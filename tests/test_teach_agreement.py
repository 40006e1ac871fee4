"""People against the synthetic expert and against each other: agreement figures tested with
scripted labelers of known noise, through the HTTP API, on the page's route and in
``footfall demos info --json``; and the expert's judgement of a run kept in the store."""

import json

import numpy as np
import pytest
from scipy.stats import binomtest

from cli_helpers import run
from footfall.data.label import Label
from footfall.data.store import DemoStore
from footfall.expert.synthetic import SyntheticExpert
from footfall.teach import judging
from footfall.teach.agreement import SAME_FOOTHOLD, agreement, expert_verdicts, same_choice
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
        figures = client._get("/api/agreement")
    return path, figures


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
