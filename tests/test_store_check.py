"""A damaged or tampered store is reported whole (``footfall store check``), refused at its bad
row by the commands that read it, and never written while it has objects footfall did not make;
seeds give distinct demonstrations and duplicates never straddle cross-validation folds."""

import json
import os
import shutil
import sqlite3

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.state import nominal_state
from footfall.data.check import check_store
from footfall.data.connection import read_only_uri
from footfall.data.runlog import RunRecord, RunStep
from footfall.data.store import DemoStore
from footfall.expert.collect import collect_demonstrations
from footfall.learning.dataset import Example, distinct_examples, stack
from footfall.learning.ranker import grouped_folds, pairwise_transform
from footfall.learning.train import store_demonstrations
from test_store import demo, terrain
from test_walker import ProgressExpert, bumpy

SPACING = 0.02  # [m] a coarse candidate lattice: fast walks


@pytest.fixture
def clean(tmp_path):
    """A sound store: one terrain, three demonstrations, one run of two steps."""
    path = tmp_path / "clean.sqlite"
    hm = terrain()
    state = nominal_state(hm, (0.3, 0.0), 0.0, "LF")
    cand = np.array([[0.3, 0.0, 0.0], [0.32, 0.01, 0.001], [0.34, 0.0, 0.0]])
    steps = tuple(RunStep(k, state, cand, np.array([0.1, -np.inf, 0.3]), 2, 0.5 * k)
                  for k in range(2))
    with DemoStore(path, create=True) as store:
        store.add_demonstrations([demo(hm, "LF", 2, seed=1), demo(hm, "RH", 0, seed=2),
                                  demo(hm, "LH", 4, seed=3)], terrains=[hm])
        store.add_run(RunRecord(hm.content_hash(), 7, {"a": 1}, {"success": True}, steps,
                                key="run-a"))
    return path


def tamper(path, *statements):
    """Run SQL on the file behind footfall's back; a statement may be (sql, parameters)."""
    con = sqlite3.connect(path, isolation_level=None)
    try:
        for sql in statements:
            con.execute(*((sql,) if isinstance(sql, str) else sql))
    finally:
        con.close()


def snapshot(path):
    con = sqlite3.connect(path)
    try:
        return (sorted(con.execute("SELECT type, name, sql FROM sqlite_master")),
                con.execute("SELECT count(*) FROM demonstrations").fetchone())
    finally:
        con.close()


# ------------------------------------------------------------ footfall store check
def test_a_clean_store_checks_ok_and_is_not_changed(clean, capsys):
    before = clean.read_bytes()
    code, out, err = run(capsys, "store", "check", clean)
    assert code == 0 and err == ""
    assert out.strip() == f"{clean}: ok (3 demonstrations, 1 terrains, 1 runs)"
    assert clean.read_bytes() == before
    code, out, _ = run(capsys, "store", "check", clean, "--json")
    report = json.loads(out)
    assert code == 0 and report["ok"] and report["problems"] == [] and report["run_steps"] == 2


def test_a_truncated_store_is_one_line(clean, capsys):
    data = clean.read_bytes()
    clean.write_bytes(data[:len(data) // 2])
    code, out, err = run(capsys, "store", "check", clean)
    assert_user_error(code, err, "corrupt demonstration store")
    assert len(out.strip().splitlines()) == 1
    for args in (("demos", "info", clean), ("learn", clean, "--features", "terrain", "-o",
                                             clean.parent / "m.npz")):
        code, _, err = run(capsys, *args)
        assert_user_error(code, err, "corrupt demonstration store")


CORRUPT_ROWS = [  # (statement, the problem's words: table, row key, column)
    ("UPDATE demonstrations SET chosen = 'abc' WHERE id = 2",
     "demonstrations row 2: chosen is not an integer (got text 'abc')"),
    ("UPDATE demonstrations SET source = x'0102' WHERE id = 3",
     "demonstrations row 3: source is not text"),
    ("UPDATE demonstrations SET source = CAST(x'ff00fe' AS TEXT) WHERE id = 3",
     "demonstrations row 3: source is not text"),  # not UTF-8: the query goes on
    ("UPDATE demonstrations SET candidates_dtype = '<U8' WHERE id = 1",
     "demonstrations row 1: candidates has unsupported dtype '<U8'"),
    ("UPDATE demonstrations SET n_candidates = 'five' WHERE id = 1",
     "demonstrations row 1: n_candidates is not an integer (got text 'five')"),
    ("UPDATE demonstrations SET n_candidates = 4 WHERE id = 2",
     "demonstrations row 2: n_candidates 4 does not match"),
    ("UPDATE demonstrations SET swing_leg = 'XX' WHERE id = 2",
     "demonstrations row 2: swing_leg text 'XX' is not a leg"),
    ("UPDATE demonstrations SET candidates = zeroblob(length(candidates)) WHERE id = 2",
     None),  # zeros are finite numbers: a sound row
    (("UPDATE demonstrations SET candidates = ? WHERE id = 2",
      (np.array([[0.3, 0.0, np.nan]] * 5).tobytes(),)),
     "demonstrations row 2: candidates holds non-finite numbers"),
    ("UPDATE demonstrations SET candidates = CAST(candidates AS TEXT) WHERE id = 2",
     "demonstrations row 2: candidates holds no bytes"),
    ("UPDATE demonstrations SET expert = '{\"noise\": NaN}' WHERE id = 1",
     "demonstrations row 1: expert is not valid JSON"),
    ("UPDATE runs SET n_steps = 'three' WHERE id = 1",
     "runs row 1: n_steps is not an integer (got text 'three')"),
    ("UPDATE runs SET n_steps = 3 WHERE id = 1",
     "runs row 1: n_steps is 3 but its steps are numbered 0..1"),
    ("UPDATE run_steps SET t_liftoff = 'soon' WHERE k = 1",
     "run_steps row (run 1, k 1): t_liftoff is not a number (got text 'soon')"),
    ("UPDATE terrains SET resolution = 'fine'",
     "is not a number (got text 'fine')"),
    # sources that name a run's step must name a stored one
    ("UPDATE demonstrations SET source = 'run:999:step:3' WHERE id = 1",
     "demonstrations row 1: its source 'run:999:step:3' names a run step that is not in the "
     "store"),
    ("UPDATE demonstrations SET source = 'run:run-a:step:2' WHERE id = 1",
     "demonstrations row 1: its source 'run:run-a:step:2' names a run step"),
    ("UPDATE demonstrations SET source = 'human:run:1:step:7' WHERE id = 2",
     "demonstrations row 2: its source 'human:run:1:step:7' names a run step"),
    ("UPDATE demonstrations SET source = 'run:run-a:step:1' WHERE id = 1", None),  # by key
    ("UPDATE demonstrations SET source = 'run:1:step:0' WHERE id = 1", None),  # by id
    ("UPDATE demonstrations SET source = 'human:run:1:step:1' WHERE id = 1", None),
    ("UPDATE demonstrations SET source = 'walker:test' WHERE id = 1", None),  # names no run
]


@pytest.mark.parametrize("statement, problem", CORRUPT_ROWS)
def test_a_corrupt_row_is_named_by_table_and_key(clean, capsys, statement, problem):
    tamper(clean, "PRAGMA ignore_check_constraints = ON", statement)
    before = clean.read_bytes()
    code, out, err = run(capsys, "store", "check", clean)
    assert clean.read_bytes() == before
    if problem is None:
        assert code == 0 and "ok" in out
        return
    assert_user_error(code, err, problem)
    assert any(problem in line for line in out.splitlines())
    code, _, err = run(capsys, "demos", "info", clean)  # it checks the file: every row
    assert_user_error(code, err, problem)


def test_a_label_beyond_its_step_s_candidates_is_a_problem(clean, capsys):
    with DemoStore(clean) as store:
        store.add_label(1, 1, "ada", "fine")
    assert run(capsys, "store", "check", clean)[0] == 0
    tamper(clean, "UPDATE labels SET chosen = 99999")
    code, _, err = run(capsys, "store", "check", clean)
    assert_user_error(code, err, "labels row 1: chosen 99999 is not one of its step's 3 "
                                 "candidates")


@pytest.mark.parametrize("statement, problem", [
    ("UPDATE marks SET candidate = 3", "marks row 1: candidate 3 is not one of its step's 3 "
                                       "candidates"),
    ("UPDATE marks SET k = 7", "marks row 1: run 1 has no step 7 in the store"),
    ("UPDATE marks SET run_id = 5", "marks row 1: run 5 has no step 1 in the store"),
    ("UPDATE marks SET candidate = 'x'", "marks row 1: candidate is not an integer (got text "
                                         "'x')"),
    ("UPDATE marks SET created = 'now'", "marks row 1: created is not a number"),
    ("UPDATE marks SET labeler = x'00'", "marks row 1: a labeler name is a non-empty string"),
    ("UPDATE marks SET candidate = 0", "marks row 1: candidate 0 is its labeler's own label of "
                                       "the step"),
])
def test_a_bad_mark_row_is_a_problem(clean, capsys, statement, problem):
    with DemoStore(clean) as store:
        store.add_label(1, 1, "ada", "foothold", 0)
        store.add_mark(1, 1, "ada", 1)
    assert run(capsys, "store", "check", clean)[0] == 0
    tamper(clean, "PRAGMA foreign_keys = OFF", statement)
    code, out, err = run(capsys, "store", "check", clean)
    assert_user_error(code, err, problem)
    assert sum("marks row" in line for line in out.splitlines()) == 1


def test_a_run_whose_steps_do_not_match_its_count_is_not_read_back(clean):
    tamper(clean, "DELETE FROM run_steps WHERE k = 1")
    with DemoStore(clean) as store, pytest.raises(FootfallError,
                                                  match="n_steps is 2 but 1 steps are stored"):
        store.run(1)


def test_readers_refuse_a_corrupt_row_with_its_key(clean, capsys):
    tamper(clean, "UPDATE demonstrations SET candidates_dtype = '<U8' WHERE id = 2")
    with pytest.raises(FootfallError, match=r"demonstration 2 is corrupt \(candidates has "
                                            r"unsupported dtype '<U8'\)"):
        store_demonstrations(clean)
    code, _, err = run(capsys, "learn", clean, "--features", "terrain", "-o",
                       clean.parent / "m.npz")
    assert_user_error(code, err, "demonstration 2 is corrupt")
    tamper(clean, "UPDATE demonstrations SET candidates_dtype = '<f8' WHERE id = 2",
           "UPDATE run_steps SET slip = 'far' WHERE k = 0")
    with DemoStore(clean, read_only=True) as store, \
            pytest.raises(FootfallError, match=r"run 1 is corrupt \(slip is not a number"):
        store.run(1)


def test_problems_are_listed_up_to_twenty_then_counted(clean, capsys):
    with DemoStore(clean) as store:
        hm = store.terrain(store.terrain_hashes()[0])
        store.add_demonstrations([demo(hm, "RF", 1, seed=10 + k) for k in range(25)])
    tamper(clean, "PRAGMA ignore_check_constraints = ON", "UPDATE demonstrations SET chosen = 'x'")
    code, out, err = run(capsys, "store", "check", clean)
    lines = out.strip().splitlines()
    assert_user_error(code, err, "demonstrations row 1: chosen is not an integer")
    assert "(and 27 more problems" in err
    assert len(lines) == 21 and lines[-1] == "... and 8 more"


@pytest.mark.parametrize("statement, named", [
    ("CREATE TRIGGER wipe AFTER INSERT ON demonstrations BEGIN DELETE FROM demonstrations; END",
     "trigger 'wipe' on table 'demonstrations' is not part of a footfall store"),
    ("CREATE VIEW everything AS SELECT * FROM demonstrations",
     "view 'everything' is not part of a footfall store"),
    ("CREATE TABLE notes (text TEXT)", "unknown table 'notes' is not part of a footfall store"),
    ("CREATE INDEX by_leg ON demonstrations (swing_leg)", "unknown index 'by_leg'"),
    ("DROP INDEX demonstrations_source", "index 'demonstrations_source' is missing"),
])
def test_objects_footfall_does_not_make_are_refused(clean, capsys, statement, named):
    tamper(clean, statement)
    code, _, err = run(capsys, "store", "check", clean)
    assert_user_error(code, err, named)
    before = snapshot(clean)
    for opened in (lambda: DemoStore(clean), lambda: DemoStore(clean, read_only=True)):
        with pytest.raises(FootfallError, match=named):
            opened()
    assert snapshot(clean) == before


# ----------------------------------------------------------------- writers
@pytest.fixture
def board_file(tmp_path):
    path = tmp_path / "board.npz"
    bumpy(length=0.6, modules=[{"kind": "flat", "x_start": 0.0, "x_end": 0.3},
                               {"kind": "rocky", "difficulty": 0.6, "x_start": 0.3,
                                "x_end": 0.6}]).save(path)
    return path


def test_collect_refuses_a_store_with_a_trigger_before_anything(clean, board_file, capsys,
                                                                 monkeypatch):
    tamper(clean, "CREATE TRIGGER wipe AFTER INSERT ON demonstrations "
                  "BEGIN DELETE FROM demonstrations; END")
    before = clean.read_bytes(), snapshot(clean)

    def walk(*args, **kwargs):
        raise AssertionError("walked before the store was checked")

    monkeypatch.setattr("footfall.expert.collect.collect_demonstrations", walk)
    code, out, err = run(capsys, "demos", "collect", "--terrain", board_file, "-n", 2,
                         "--seed", 0, "-o", clean)
    assert_user_error(code, err, "trigger 'wipe' on table 'demonstrations'")
    assert out == "" and (clean.read_bytes(), snapshot(clean)) == before


def test_walk_many_log_refuses_an_unknown_table(clean):
    from footfall.experiments.batch import _checked_log

    tamper(clean, "CREATE TABLE notes (text TEXT)")
    with pytest.raises(FootfallError, match="unknown table 'notes'"):
        _checked_log(clean)  # an existing log store is checked before any run


def test_collect_n_is_bounded_up_front(tmp_path, capsys):
    code, _, err = run(capsys, "demos", "collect", "--terrain", tmp_path / "missing.npz",
                       "-n", 10 ** 15, "--seed", 0, "-o", tmp_path / "d.sqlite")
    assert_user_error(code, err, "1000000000000000 is above the limit of 100000")
    assert not (tmp_path / "d.sqlite").exists()
    with pytest.raises(FootfallError, match="above the limit"):
        collect_demonstrations([bumpy()], ProgressExpert(), 10 ** 9, seed=0)


def test_sqlite_messages_become_one_line(clean):
    with DemoStore(clean) as store, pytest.raises(FootfallError) as caught, store._errors():
        raise sqlite3.OperationalError("CHECK constraint failed: chosen >= 0\n   AND chosen < 3")
    assert "\n" not in str(caught.value)
    assert str(caught.value).endswith("CHECK constraint failed: chosen >= 0 AND chosen < 3")


# ---------------------------------------------------------------- read-only
def test_readers_open_read_only(clean):
    with DemoStore(clean, read_only=True) as store:
        assert len(store.demonstrations()) == 3
        with pytest.raises(FootfallError, match="readonly"):
            store.add_demonstrations([store.demonstrations()[0]])
    with pytest.raises(FootfallError, match="cannot be created"):
        DemoStore(clean.parent / "new.sqlite", create=True, read_only=True)


def test_a_store_in_a_folder_that_cannot_be_written_is_read_immutable(clean, monkeypatch):
    for leftover in (f"{clean}-wal", f"{clean}-shm"):
        if os.path.exists(leftover):
            os.remove(leftover)
    assert read_only_uri(clean).endswith("?mode=ro")
    monkeypatch.setattr("footfall.data.connection.os.access", lambda path, mode: False)
    assert read_only_uri(clean).endswith("?immutable=1")
    with DemoStore(clean, read_only=True) as store:
        assert len(store.demonstrations()) == 3
    assert check_store(clean).ok
    assert sorted(os.listdir(clean.parent)) == ["clean.sqlite"]  # nothing made beside it


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes to any folder: chmod means nothing")
def test_a_store_in_a_read_only_folder_can_be_read(clean, tmp_path, capsys):
    folder = tmp_path / "ro"
    folder.mkdir()
    shutil.copy(clean, folder / "s.sqlite")
    folder.chmod(0o555)
    try:
        code, out, _ = run(capsys, "store", "check", folder / "s.sqlite")
        assert code == 0 and "ok (3 demonstrations" in out
        code, out, _ = run(capsys, "demos", "info", folder / "s.sqlite")
        assert code == 0 and "3 demonstrations on 1 terrain" in out
    finally:
        folder.chmod(0o755)


# ------------------------------------------------------------------- seeds
def test_seeds_give_distinct_demonstrations_and_the_same_seed_the_same(tmp_path):
    board = bumpy(length=0.6, width=0.61, seed=3)
    expert = ProgressExpert(noise=0.0)  # draws nothing: only the walks can differ

    def collect(seed):
        return collect_demonstrations([board], expert, 6, seed=seed, spacing=SPACING)

    path = tmp_path / "seeds.sqlite"
    with DemoStore(path, create=True) as store:
        for seed in range(4):
            store.add_demonstrations(collect(seed), terrains=[board])
        stored = store.demonstrations()
    assert len(stored) == 24
    assert len({d.content_hash() for d in stored}) == 24
    assert len({d.state.to_vector().tobytes() for d in stored}) == 24  # each its own state
    assert [d.content_hash() for d in collect(2)] == [d.content_hash() for d in stored[12:18]]


# ------------------------------------------------------------------- folds
class _Identity:
    """A stand-in feature family: the prepared array is the feature matrix."""

    @staticmethod
    def from_prepared(prepared):
        return prepared


def _example(rng, key, n=4):
    x = rng.normal(size=(n, 2))
    return Example((x,), n, 0, True, np.arange(n), key)


def test_duplicates_never_straddle_folds():
    rng = np.random.default_rng(0)
    originals = [_example(rng, f"demo{k}") for k in range(8)]
    # The store holds demos 0, 3 and 5 three times, in far-apart places (ids, groups).
    examples = originals + [originals[0], originals[3], originals[5]] * 2
    assert len(distinct_examples(examples)) == 8
    X, y, groups = stack(examples, [_Identity()])
    keys = np.concatenate([[e.key] * e.n for e in distinct_examples(examples)])
    assert X.shape[0] == 32 and np.unique(groups).size == 8
    _, _, pair_groups = pairwise_transform(X, y, groups)
    pair_keys = keys[np.searchsorted(groups, pair_groups)]
    for _, test in grouped_folds(pair_groups, 4):
        inside = set(pair_keys[test])
        outside = set(np.delete(pair_keys, test))
        assert not inside & outside  # a demonstration is tested in one fold and nowhere else
    keyless = [Example(e.prepared, e.n, e.chosen, e.front, e.rows) for e in examples[:3]] * 2
    assert len(distinct_examples(keyless)) == 6  # without a key, every example counts

