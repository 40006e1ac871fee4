"""People's labels of run steps in the store: a foothold label is a demonstration with its
provenance, written in one transaction; one label per labeler and step; retries not doubled."""

import dataclasses

import numpy as np
import pytest

from footfall.core.errors import FootfallError, NotFound
from footfall.data.label import human_source
from footfall.data.label_queries import LabelConflict
from footfall.data.store import DemoStore
from test_runlog import _run
from test_store import terrain


@pytest.fixture
def store(tmp_path):
    hm = terrain()
    with DemoStore(tmp_path / "s.sqlite", create=True) as s:
        run_id = s.add_run(_run(hm, n_steps=4), terrains=[hm])
        yield s, run_id


def test_a_foothold_label_is_a_demonstration_with_its_provenance(store):
    s, run_id = store
    step = s.run(run_id).steps[2]
    label, new = s.add_label(run_id, 2, "ada", "foothold", 4, request="r1", created=1.5e9)
    assert new and label.chosen == 4 and label.created == 1.5e9 and label.request == "r1"
    (demo,) = s.demonstrations(source_prefix="human")
    assert demo.id == label.demonstration_id and demo.source == human_source(run_id, 2)
    assert demo.expert == {"kind": "human", "labeler": "ada"} and demo.chosen == 4
    assert demo.candidates.tobytes() == step.candidates.tobytes()
    assert demo.state.to_vector().tobytes() == step.state.to_vector().tobytes()
    assert demo.terrain_hash == s.run(run_id).terrain_hash
    assert s.summary()["by_source"] == {"human": 1}
    assert s.label_counts() == {"by_labeler": {"ada": {"foothold": 1, "fine": 0}},
                                "disagreements": 0}


def test_a_fine_verdict_is_on_the_robots_choice_and_makes_no_demonstration(store):
    s, run_id = store
    chosen = s.run(run_id).steps[0].chosen
    label, _ = s.add_label(run_id, 0, "ada", "fine")
    assert label.chosen == chosen and label.demonstration_id is None and len(s) == 0
    with pytest.raises(FootfallError, match="robot's own choice"):
        s.add_label(run_id, 0, "ada", "fine", (chosen + 1) % 6)


def test_a_labeler_relabelling_a_step_replaces_their_label_and_its_demonstration(store):
    s, run_id = store
    first, _ = s.add_label(run_id, 1, "ada", "foothold", 2)
    second, _ = s.add_label(run_id, 1, "ada", "foothold", 3)
    assert [x.id for x in s.labels(run_id, 1)] == [second.id]
    assert [d.id for d in s.demonstrations()] == [second.demonstration_id]
    assert second.demonstration_id != first.demonstration_id


def test_two_labelers_who_disagree_both_keep_their_label(store):
    s, run_id = store
    s.add_label(run_id, 1, "ada", "foothold", 2)
    s.add_label(run_id, 1, "grace", "foothold", 5)
    s.add_label(run_id, 3, "ada", "foothold", 0)
    s.add_label(run_id, 3, "grace", "foothold", 0)  # agree here
    assert sorted((x.labeler, x.chosen) for x in s.labels(run_id, 1)) == \
        [("ada", 2), ("grace", 5)]
    assert len(s) == 4 and s.label_counts()["disagreements"] == 1


def test_a_repeated_request_returns_the_first_label_and_writes_nothing(store):
    s, run_id = store
    a, new_a = s.add_label(run_id, 1, "ada", "foothold", 2, request="abc")
    b, new_b = s.add_label(run_id, 1, "ada", "foothold", 2, request="abc")
    assert new_a and not new_b and a == b and len(s) == 1
    with pytest.raises(LabelConflict, match="another label"):
        s.add_label(run_id, 2, "ada", "foothold", 2, request="abc")


def test_undo_removes_the_label_and_its_demonstration_but_only_the_labelers_own(store):
    s, run_id = store
    mine, _ = s.add_label(run_id, 1, "ada", "foothold", 2)
    theirs, _ = s.add_label(run_id, 1, "grace", "foothold", 4)
    with pytest.raises(NotFound, match="of labeler 'ada'"):
        s.remove_label(theirs.id, labeler="ada")
    assert s.remove_label(mine.id, labeler="ada") == mine
    assert [x.id for x in s.labels()] == [theirs.id]
    assert [d.id for d in s.demonstrations()] == [theirs.demonstration_id]
    with pytest.raises(NotFound):
        s.remove_label(mine.id)


@pytest.mark.parametrize("args, message", [
    ((99, 0, "ada", "foothold", 1), "run 99 is not in the store"),
    (("run", 0, "ada", "foothold", 1), "a run id is an integer"),
    ((None, 9, "ada", "foothold", 1), "a run id is an integer"),
    ((True, 0, "ada", "foothold", 1), "a run id is an integer"),
    ((1, 9, "ada", "foothold", 1), "run 1 has no step 9"),
    ((1, 0, "ada", "foothold", 6), "candidate 6 is not in F"),
    ((1, 0, "ada", "foothold", -1), "candidate -1 is not in F"),
    ((1, 0, "ada", "foothold", 1.0), "a candidate index is an integer"),
    ((1, 0, "ada", "foothold", None), "needs the index"),
    ((1, 0, "ada", "maybe", 1), "a verdict is one of"),
    ((1, 0, "", "foothold", 1), "labeler name"),
    ((1, 0, "a\nb", "foothold", 1), "labeler name"),
    ((1, 0, "x" * 65, "foothold", 1), "labeler name"),
    ((1, 0, 7, "foothold", 1), "labeler name"),
])
def test_bad_labels_are_refused_and_change_nothing(store, args, message):
    s, run_id = store
    assert run_id == 1
    with pytest.raises(FootfallError, match=message):
        s.add_label(*args)
    assert s.labels() == [] and len(s) == 0


@pytest.mark.parametrize("request_id", ["", "a b", "x" * 65, 5, "é"])
def test_bad_request_ids_are_refused(store, request_id):
    s, run_id = store
    with pytest.raises(FootfallError, match="request id"):
        s.add_label(run_id, 0, "ada", "foothold", 1, request=request_id)
    assert s.labels() == []


def test_learning_reads_several_sources(store, tmp_path):
    s, run_id = store
    s.add_label(run_id, 1, "ada", "foothold", 2)
    assert len(s.demonstrations(source_prefix=["human", "walker"])) == 1
    assert s.count(source_prefix=("walker",)) == 0
    with pytest.raises(FootfallError, match="source filter"):
        s.demonstrations(source_prefix=[])


def test_the_store_check_reads_every_label_and_its_references(store, tmp_path):
    import sqlite3

    from footfall.data.check import check_store

    s, run_id = store
    s.add_label(run_id, 1, "ada", "foothold", 2)
    s.add_label(run_id, 2, "ada", "fine")
    assert check_store(s.path).ok and check_store(s.path).labels == 2
    con = sqlite3.connect(s.path, isolation_level=None)
    con.execute("PRAGMA foreign_keys = OFF")  # damage it as another program could
    con.execute("DELETE FROM demonstrations")
    con.execute("UPDATE labels SET labeler = 'x\ny' WHERE verdict = 'fine'")
    con.close()
    problems = check_store(s.path).problems
    assert any("a 'foothold' label without its demonstration" in p for p in problems)
    assert any("labels row 2" in p and "labeler name" in p for p in problems)


def test_undo_walks_back_through_the_labelers_history_of_a_step(store):
    s, run_id = store
    a, _ = s.add_label(run_id, 1, "ada", "foothold", 2)
    b, _ = s.add_label(run_id, 1, "ada", "foothold", 4)
    c, _ = s.add_label(run_id, 1, "ada", "fine")
    theirs, _ = s.add_label(run_id, 1, "grace", "foothold", 3)
    assert [(x.labeler, x.verdict, x.chosen) for x in s.labels(run_id, 1)] == \
        [("ada", "fine", c.chosen), ("grace", "foothold", 3)]
    assert len(s.demonstrations()) == 1  # only grace's: ada's current label is "fine"
    removed, restored = s.undo_label(c.id, labeler="ada")
    assert removed == c  # b back in place: its id and fields, with a new demonstration
    assert dataclasses.replace(restored, demonstration_id=b.demonstration_id) == b
    demos = s.demonstrations()
    assert sorted(d.chosen for d in demos) == [3, 4]
    assert next(x for x in s.labels(run_id, 1) if x.labeler == "ada").demonstration_id in \
        {d.id for d in demos}
    removed, restored = s.undo_label(b.id, labeler="ada")
    assert (removed.chosen, restored.id, restored.chosen) == (4, a.id, 2)
    removed, restored = s.undo_label(a.id, labeler="ada")
    assert restored is None and [x.labeler for x in s.labels(run_id, 1)] == ["grace"]
    assert [d.chosen for d in s.demonstrations()] == [3]


def test_the_same_verdict_again_changes_nothing_and_keeps_no_history(store):
    s, run_id = store
    a, new_a = s.add_label(run_id, 1, "ada", "foothold", 2, request="r1")
    b, new_b = s.add_label(run_id, 1, "ada", "foothold", 2, request="r2")
    assert new_a and not new_b and a == b and len(s) == 1
    assert s.undo_label(a.id, labeler="ada")[1] is None


def test_a_retried_request_of_a_replaced_label_is_not_stored_again(store):
    s, run_id = store
    a, _ = s.add_label(run_id, 1, "ada", "foothold", 2, request="first")
    s.add_label(run_id, 1, "ada", "foothold", 4, request="second")
    again, new = s.add_label(run_id, 1, "ada", "foothold", 2, request="first")
    assert not new and again.id == a.id
    assert [x.chosen for x in s.labels(run_id, 1)] == [4]


def test_a_judgement_is_kept_per_run_and_expert(store):
    s, run_id = store
    assert s.judgement(run_id, "expert-a") is None
    s.keep_judgement(run_id, "expert-a", np.array([1, 0, 5]), np.array([0.5, np.nan, 2.0]))
    best, shortfall = s.judgement(run_id, "expert-a")
    assert best.tolist() == [1, 0, 5] and np.isnan(shortfall[1])
    assert shortfall[[0, 2]].tolist() == [0.5, 2.0]
    assert s.judgement(run_id, "expert-b") is None
    s.keep_judgement(run_id, "expert-a", np.array([2, 2, 2]), np.zeros(3))
    assert s.judgement(run_id, "expert-a")[0].tolist() == [2, 2, 2]
    with pytest.raises(FootfallError, match="one best index"):
        s.keep_judgement(run_id, "expert-a", np.array([1]), np.zeros(2))
