"""People's "never here" marks in the store: one transaction each, one per labeler and candidate
of a step, retries not doubled, never on the labeler's own label; a foothold label's
demonstration carries its labeler's marks as refused candidates, and ``footfall learn
--supervision refusals`` learns from them."""

import sqlite3

import numpy as np
import pytest

from cli_helpers import run
from footfall.core.errors import FootfallError, NotFound
from footfall.core.heightmap import HeightMap
from footfall.core.state import nominal_state
from footfall.data import codec
from footfall.data.label_queries import LabelConflict
from footfall.data.mark_queries import MarkConflict
from footfall.data.runlog import RunRecord, RunStep
from footfall.data.store import DemoStore
from footfall.features.candidates import reachable_footholds
from footfall.learning import train
from footfall.learning.model import FootholdModel
from footfall.learning.supervision import get_supervision
from test_runlog import _run
from test_store import terrain


@pytest.fixture
def store(tmp_path):
    hm = terrain()
    with DemoStore(tmp_path / "s.sqlite", create=True) as s:
        run_id = s.add_run(_run(hm, n_steps=4), terrains=[hm])
        yield s, run_id


def _others(s, run_id, k):
    """The candidates of step k that are not the robot's choice (6 candidates a step)."""
    chosen = s.run(run_id).steps[k].chosen
    return [i for i in range(6) if i != chosen]


def test_a_mark_round_trips_and_is_listed_by_step_run_and_all(store):
    s, run_id = store
    a, b = _others(s, run_id, 1)[:2]
    mark, new = s.add_mark(run_id, 1, "ada", a, request="m1", created=1.5e9)
    assert new and (mark.run_id, mark.k, mark.labeler, mark.candidate, mark.created,
                    mark.request) == (run_id, 1, "ada", a, 1.5e9, "m1")
    s.add_mark(run_id, 1, "bob", a)
    s.add_mark(run_id, 2, "ada", b)
    assert [m.to_dict() for m in s.marks(run_id, 1)][0] == mark.to_dict()
    assert [(m.k, m.labeler) for m in s.marks(run_id, 1)] == [(1, "ada"), (1, "bob")]
    assert len(s.marks(run_id)) == len(s.marks()) == 3
    assert [m.candidate for m in s.marks(labeler="ada")] == [a, b]
    assert s.mark_counts() == {"ada": 2, "bob": 1}
    assert len(s) == 0  # a mark alone makes no demonstration


def test_a_retried_request_and_a_second_mark_of_one_candidate_are_not_doubled(store):
    s, run_id = store
    a, b = _others(s, run_id, 0)[:2]
    first, new = s.add_mark(run_id, 0, "ada", a, request="r-1")
    again, new_again = s.add_mark(run_id, 0, "ada", a, request="r-1")
    twice, new_twice = s.add_mark(run_id, 0, "ada", a, request="r-2")  # marked already
    assert new and not new_again and not new_twice and first == again == twice
    assert len(s.marks()) == 1
    with pytest.raises(MarkConflict, match="request id 'r-1' was used for another mark"):
        s.add_mark(run_id, 0, "ada", b, request="r-1")
    assert len(s.marks()) == 1


@pytest.mark.parametrize("args, error, words", [
    ((0, "ada", 6), FootfallError, "candidate 6 is not in F (the step has 6 candidates)"),
    ((0, "ada", -1), FootfallError, "candidate -1 is not in F"),
    ((9, "ada", 0), NotFound, "has no step 9 (it has 4 steps)"),
    ((0, "", 0), FootfallError, "a labeler name is a non-empty string"),
    ((0, "ada", True), FootfallError, "a candidate index is an integer"),
])
def test_a_bad_mark_is_one_line_and_writes_nothing(store, args, error, words):
    s, run_id = store
    with pytest.raises(error, match=words.replace("(", r"\(").replace(")", r"\)")) as caught:
        s.add_mark(run_id, *args)
    assert "\n" not in str(caught.value) and s.marks() == []
    with pytest.raises(NotFound, match="run 99 is not in the store"):
        s.add_mark(99, 0, "ada", 0)


def test_a_mark_on_ones_own_label_and_a_label_of_ones_mark_are_conflicts(store):
    s, run_id = store
    robot = s.run(run_id).steps[0].chosen
    a, b = _others(s, run_id, 0)[:2]
    s.add_label(run_id, 0, "ada", "foothold", a)
    with pytest.raises(MarkConflict, match=f"candidate {a} is ada's own foothold label on this "
                                           "step: undo that label before marking it"):
        s.add_mark(run_id, 0, "ada", a)
    s.add_mark(run_id, 0, "bob", a)  # another labeler may refuse ada's foothold
    s.add_mark(run_id, 0, "ada", b)
    with pytest.raises(LabelConflict, match=f"ada marked candidate {b} 'never here' on this "
                                            "step: undo that mark first"):
        s.add_label(run_id, 0, "ada", "foothold", b)
    s.add_mark(run_id, 0, "ada", robot)  # the robot's choice refused
    with pytest.raises(LabelConflict, match="marked the robot's choice"):
        s.add_label(run_id, 0, "ada", "fine")
    assert [(x.labeler, x.chosen) for x in s.labels()] == [("ada", a)]
    s.add_label(run_id, 1, "cy", "fine")
    with pytest.raises(MarkConflict, match="the robot's choice, which cy called fine"):
        s.add_mark(run_id, 1, "cy", s.run(run_id).steps[1].chosen)


def test_removing_a_mark_is_ones_own_and_frees_the_candidate_for_a_label(store):
    s, run_id = store
    a = _others(s, run_id, 2)[0]
    mark, _ = s.add_mark(run_id, 2, "ada", a)
    with pytest.raises(NotFound, match=f"mark {mark.id} is not in the store \\(of labeler 'bob'"):
        s.remove_mark(mark.id, "bob")
    assert s.remove_mark(mark.id, "ada") == mark and s.marks() == []
    with pytest.raises(NotFound):
        s.remove_mark(mark.id, "ada")
    label, new = s.add_label(run_id, 2, "ada", "foothold", a)
    assert new and label.chosen == a


def test_an_undo_that_would_restore_a_marked_label_is_refused_and_changes_nothing(store):
    s, run_id = store
    a, b = _others(s, run_id, 3)[:2]
    s.add_label(run_id, 3, "ada", "foothold", a)
    second, _ = s.add_label(run_id, 3, "ada", "foothold", b)  # a kept aside
    s.add_mark(run_id, 3, "ada", a)
    before = (s.labels(), len(s))
    with pytest.raises(LabelConflict, match=f"would bring back ada's label of candidate {a}"):
        s.undo_label(second.id, "ada")
    assert (s.labels(), len(s)) == before
    (mark,) = s.marks()
    s.remove_mark(mark.id, "ada")  # the mark undone first: the label undoes
    removed, restored = s.undo_label(second.id, "ada")
    assert removed.id == second.id and restored.chosen == a


def test_a_foothold_labels_demonstration_carries_its_labelers_marks_as_refused(store):
    s, run_id = store
    a, b, c, d = _others(s, run_id, 1)[:4]
    robot = s.run(run_id).steps[1].chosen
    label, _ = s.add_label(run_id, 1, "ada", "foothold", a)
    s.add_mark(run_id, 1, "ada", b)
    s.add_mark(run_id, 1, "ada", robot)
    s.add_mark(run_id, 1, "bob", c)  # bob's mark: not ada's verdict
    s.add_label(run_id, 2, "ada", "fine")  # marks on a fine step make no demonstration
    s.add_mark(run_id, 2, "ada", _others(s, run_id, 2)[0])
    s.add_mark(run_id, 3, "ada", _others(s, run_id, 3)[0])  # nor on an unlabelled step
    (demo,) = s.demonstrations(source_prefix="human")
    assert demo.id == label.demonstration_id and demo.chosen == a
    assert np.flatnonzero(demo.refused).tolist() == sorted([b, robot])
    assert demo.values is None and s.demonstrations(ids=[demo.id])[0].refused.tolist() == \
        demo.refused.tolist()
    # a verdict stored with the demonstration joins the marks: their union is refused
    mask = np.zeros(6, dtype=bool)
    mask[d] = True
    con = sqlite3.connect(s.path, isolation_level=None)
    con.execute("INSERT INTO verdicts (demonstration_id, refused, refused_shape, refused_dtype) "
                "VALUES (?, ?, ?, ?)", (demo.id, *codec.encode(mask.astype(np.uint8))))
    con.close()
    (demo,) = s.demonstrations(source_prefix="human")
    assert np.flatnonzero(demo.refused).tolist() == sorted([b, d, robot])


def test_an_older_store_reads_without_marks_and_gains_the_table(tmp_path):
    hm = terrain()
    path = tmp_path / "v4.sqlite"
    with DemoStore(path, create=True) as s:
        run_id = s.add_run(_run(hm, n_steps=2), terrains=[hm])
        s.add_label(run_id, 0, "ada", "foothold", _others(s, run_id, 0)[0])
    con = sqlite3.connect(path, isolation_level=None)  # the same store as version 4
    con.execute("DROP TABLE marks")
    con.execute("DROP TABLE verdicts")
    con.execute("UPDATE meta SET value = '4' WHERE key = 'schema_version'")
    con.close()
    with DemoStore(path, read_only=True) as s:
        assert s.schema_version == 4 and s.marks() == [] and s.mark_counts() == {}
        assert s.demonstrations()[0].refused is None
        with pytest.raises(FootfallError, match="marks need version 5"):
            s.add_mark(run_id, 0, "ada", 1)
    with DemoStore(path) as s:  # opened to write: upgraded, marks kept
        b = _others(s, run_id, 0)[1]
        s.add_mark(run_id, 0, "ada", b)
        assert s.schema_version == 5
        assert np.flatnonzero(s.demonstrations()[0].refused).tolist() == [b]


# ------------------------------------------------------------------------- learning
def _reachable_run(hm, key, seed, n_steps=8, n=8):
    """A logged run whose every step's F is n footholds the robot can reach (the pose features
    are finite on them)."""
    rng = np.random.default_rng(seed)
    steps = []
    for k in range(n_steps):
        state = nominal_state(hm, (0.25 + 0.03 * k, 0.0), 0.0, ("LH", "LF", "RH", "RF")[k % 4])
        f = reachable_footholds(hm, state)
        cand = f[rng.choice(len(f), n, replace=False)]
        rewards = rng.normal(size=n)
        steps.append(RunStep(k, state, cand, rewards, int(np.argmax(rewards)), 0.5 * k,
                             0.5 * k + 0.3, cand[0] + 0.001, 0.001))
    return RunRecord(hm.content_hash(), seed, {"reward": "default"},
                     {"success": True, "reason": "goal"}, tuple(steps), key)


def test_learn_with_refusals_reads_the_marks_of_peoples_labels(tmp_path, capsys, monkeypatch):
    hm = HeightMap(np.random.default_rng(0).normal(size=(160, 120)) * 0.003, 0.005, (0.0, -0.3))
    path = tmp_path / "marked.sqlite"
    marked = {}
    with DemoStore(path, create=True) as s:
        for r in range(2):
            run_id = s.add_run(_reachable_run(hm, f"t/{r}", r), terrains=[hm] if r == 0 else [])
            for step in s.run(run_id).steps:
                others = [i for i in range(8) if i != step.chosen]
                label, _ = s.add_label(run_id, step.k, "ada", "foothold", others[0])
                s.add_mark(run_id, step.k, "ada", others[1])
                s.add_mark(run_id, step.k, "ada", step.chosen)  # the robot's choice refused
                marked[label.demonstration_id] = sorted([others[1], step.chosen])
    seen = []
    real = train.learn_model

    def spy(demos, *args, **kwargs):  # the training demonstrations, as the learner gets them
        seen.append((list(demos), kwargs.get("supervision")))
        return real(demos, *args, **kwargs)

    monkeypatch.setattr(train, "learn_model", spy)
    code, out, err = run(capsys, "learn", path, "--features", "terrain", "--source", "human",
                         "--supervision", "refusals", "--cv", "2", "-o", tmp_path / "m.npz")
    assert code == 0, err
    ((demos, supervision),) = seen
    assert supervision == "refusals" and len(demos) == len(marked) == 16
    with DemoStore(path, read_only=True) as s:
        ids = [d.id for d in s.demonstrations(source_prefix="human")]
    for demo_id, d in zip(ids, demos):  # learn_from_store keeps the store's order
        assert np.flatnonzero(d.refused).tolist() == marked[demo_id]
        assert d.levels(get_supervision("refusals")).tolist().count(0) == 2
    info = FootholdModel.load(tmp_path / "m.npz").info
    assert info["supervision"] == "refusals" and info["with_verdict"] == 16
