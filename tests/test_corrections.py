"""Expert corrections of run logs: exactly the steps that fall short by the margin become demonstrations."""

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.state import nominal_state
from footfall.data.runlog import RunRecord, RunStep
from footfall.data.store import DemoStore
from footfall.expert.corrections import (
    corrections_to_demonstrations,
    inspect_run,
    source_of,
    step_verdicts,
    worst_corrections,
)
from test_store import terrain


class TableExpert:
    """An expert whose values are a table: candidate x coordinate [m] * 100 (1 unit per cm)."""

    config = None

    def values(self, hmap, state, candidates):
        return 100.0 * np.asarray(candidates)[:, 0]

    def choose(self, hmap, state, candidates, rng):
        return int(np.argmax(self.values(hmap, state, candidates)))


def _run(hm, chosen_x):
    """A run whose step k chose the candidate at x = chosen_x[k] of five at x = 0.30 ... 0.34 m."""
    xs = np.linspace(0.30, 0.34, 5)
    cand = np.column_stack([xs, np.zeros(5), np.zeros(5)])
    steps = []
    for k, x in enumerate(chosen_x):
        state = nominal_state(hm, (0.2, 0.0), 0.0, ("LH", "LF", "RH", "RF")[k % 4])
        steps.append(RunStep(k, state, cand, np.zeros(5), int(np.argmin(abs(xs - x))), 0.1 * k))
    return RunRecord(hm.content_hash(), 0, {}, {"success": True}, tuple(steps))


def test_corrects_exactly_the_steps_short_of_the_experts_best_by_more_than_the_margin():
    hm = terrain()
    # shortfalls in expert units (1 cm each step of x): 4, 0, 1, 3, 2
    run = _run(hm, [0.30, 0.34, 0.33, 0.31, 0.32])
    verdicts = inspect_run(run, hm, TableExpert(), margin=1.5)
    assert [v.shortfall for v in verdicts] == pytest.approx([4, 0, 1, 3, 2])
    assert [v.k for v in verdicts if v.label is not None] == [0, 3, 4]
    assert all(v.label == 4 for v in verdicts if v.label is not None)  # the expert's best
    # A shortfall equal to the margin is not a mistake.
    assert [v.k for v in inspect_run(run, hm, TableExpert(), margin=2.0)
            if v.label is not None] == [0, 3]
    demos = corrections_to_demonstrations(run, "correct/r0/train00", verdicts, TableExpert())
    assert [d.source for d in demos] == [source_of("correct/r0/train00", k) for k in (0, 3, 4)]
    assert [d.chosen for d in demos] == [4, 4, 4]
    assert all(np.array_equal(d.candidates, run.steps[0].candidates) for d in demos)


def test_step_verdicts_are_the_best_index_and_the_shortfall_of_every_step():
    hm = terrain()
    run = _run(hm, [0.30, 0.34, 0.33, 0.31, 0.32])
    best, shortfall = step_verdicts(run, hm, TableExpert())
    assert best.tolist() == [4] * 5
    np.testing.assert_allclose(shortfall, [4, 0, 1, 3, 2], atol=1e-9)
    with pytest.raises(FootfallError, match="another terrain"):
        step_verdicts(run, terrain(seed=1), TableExpert())


def test_a_capped_expert_labels_the_worst_mistakes_of_a_run():
    hm = terrain()
    run = _run(hm, [0.30, 0.34, 0.33, 0.31, 0.32])
    verdicts = worst_corrections(inspect_run(run, hm, TableExpert(), margin=1.5), 1.5, cap=2)
    assert [v.k for v in verdicts if v.label is not None] == [0, 3]  # shortfalls 4 and 3


def test_run_and_its_corrections_are_stored_in_one_transaction(tmp_path):
    hm = terrain()
    run = _run(hm, [0.30, 0.34])
    demos = corrections_to_demonstrations(run, "k", inspect_run(run, hm, TableExpert(), 0.5),
                                          TableExpert())
    with DemoStore(tmp_path / "s.sqlite", create=True) as store:
        store.add_run(RunRecord(run.terrain_hash, 0, {}, run.result, run.steps, key="k"),
                      terrains=[hm], demonstrations=demos)
        with pytest.raises(FootfallError, match="already in the store"):
            store.add_run(RunRecord(run.terrain_hash, 0, {}, run.result, run.steps, key="k"),
                          demonstrations=demos)
        assert [d.source for d in store.demonstrations()] == ["run:k:step:0"]  # nothing doubled


def test_bad_margin_and_another_terrain_are_refused():
    hm = terrain()
    run = _run(hm, [0.30])
    with pytest.raises(FootfallError, match="margin"):
        inspect_run(run, hm, TableExpert(), margin=-1.0)
    with pytest.raises(FootfallError, match="another terrain"):
        inspect_run(run, terrain(seed=1), TableExpert())


class VetoExpert(TableExpert):
    """The table expert with a veto: it refuses every candidate below x = 0.315 m."""

    def verdict(self, hmap, state, candidates):
        values = self.values(hmap, state, candidates)
        return values, np.asarray(candidates)[:, 0] < 0.315, values - 100.0  # judged: its own


def test_every_step_is_labelled_for_dagger_with_the_teachers_verdict():
    hm = terrain()
    run = _run(hm, [0.30, 0.34, 0.33, 0.31, 0.32])  # shortfalls 4, 0, 1, 3, 2
    verdicts = inspect_run(run, hm, VetoExpert(), margin=1.5, every_step=True)
    assert [v.k for v in verdicts if v.label is not None] == [0, 1, 2, 3, 4]
    assert [v.k for v in worst_corrections(verdicts, 1.5, 2, every_step=True)
            if v.label is not None] == [0, 3]  # the cap still keeps the worst
    demos = corrections_to_demonstrations(run, "r", worst_corrections(verdicts, 1.5, None, True),
                                          VetoExpert())
    assert len(demos) == 5 and all(d.chosen == 4 for d in demos)  # where it chose as the teacher
    np.testing.assert_allclose(demos[1].values, [30, 31, 32, 33, 34])
    assert demos[1].refused.tolist() == [True, True, False, False, False]
    np.testing.assert_allclose(demos[1].judged, [-70, -69, -68, -67, -66])
    # without a veto of its own, a teacher refuses what it values more than 10 below its best
    plain = inspect_run(run, hm, TableExpert(), margin=1.5, every_step=True)
    assert not any(v.refused.any() for v in plain)
    # a step whose label its own veto refuses keeps the label: the refusal is cleared
    class Stubborn(VetoExpert):
        def choose(self, hmap, state, candidates, rng):
            return 0
    (d0,) = corrections_to_demonstrations(run, "r", inspect_run(run, hm, Stubborn(), 1.5)[:1],
                                          Stubborn())
    assert d0.chosen == 0 and d0.refused.tolist() == [False, True, False, False, False]


def test_corrections_of_a_store_made_again_or_at_once_are_each_stored_once(tmp_path):
    """``demos correct`` run twice, or twice at once, stores each correction once and says
    how many it skipped; another teacher's label of the same step is another label."""
    import threading
    from dataclasses import replace

    from footfall.expert.corrections import correct_stored_runs

    hm = terrain()
    runs = tmp_path / "runs.sqlite"
    with DemoStore(runs, create=True) as store:
        for i in range(3):
            store.add_run(replace(_run(hm, [0.30, 0.34, 0.30]), key=f"r{i}"), terrains=[hm])
    out = tmp_path / "labels.sqlite"
    first = correct_stored_runs([runs], out, TableExpert(), 0.5, None, 0)
    again = correct_stored_runs([runs], out, TableExpert(), 0.5, None, 0)
    assert (first.added, first.skipped, again.added, again.skipped) == (6, 0, 0, 6)
    at_once = tmp_path / "at-once.sqlite"
    done = []
    workers = [threading.Thread(target=lambda: done.append(
        correct_stored_runs([runs], at_once, TableExpert(), 0.5, None, 0))) for _ in range(2)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    assert sorted((d.added, d.skipped) for d in done) == [(0, 6), (6, 0)]
    with DemoStore(at_once, read_only=True) as store:
        sources = [d.source for d in store.demonstrations()]
    assert len(sources) == len(set(sources)) == 6

    class OtherExpert(TableExpert):
        config = {"another": True}

    other = correct_stored_runs([runs], out, OtherExpert(), 0.5, None, 0)
    assert (other.added, other.skipped) == (6, 0)  # the same steps, another teacher's word
