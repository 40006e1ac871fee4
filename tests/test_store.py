"""The demonstration store: round trips, validation, corruption, atomicity, concurrency."""

import hashlib
import json
import sqlite3
import subprocess
import sys
import textwrap
from dataclasses import replace

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.state import nominal_state
from footfall.data import schema
from footfall.data.store import FORMAT, SCHEMA_VERSION, Demonstration, DemoStore


def terrain(seed=0, shape=(120, 80)):
    h = np.random.default_rng(seed).normal(size=shape) * 0.01
    h[3, 5] = np.nan  # a cell without data survives the trip
    return HeightMap(h, 0.005, (0.0025, -0.1975), metadata={"generator": "test", "seed": seed})


def demo(hmap, leg="LF", chosen=2, source="walker", expert=None, n=5, seed=0):
    rng = np.random.default_rng(seed)
    state = nominal_state(hmap, (0.3 + 0.01 * seed, 0.01), 0.05, leg)
    cand = np.column_stack([rng.uniform(0.3, 0.5, n), rng.uniform(-0.1, 0.1, n),
                            rng.normal(0, 0.01, n)])
    return Demonstration(hmap.content_hash(), state, cand, chosen, source,
                         {"noise": 0.1, "weights": [1.0, 2.5]} if expert is None else expert)


@pytest.fixture
def store_path(tmp_path):
    return tmp_path / "demos.sqlite"


@pytest.fixture
def filled(store_path):
    """A store with one terrain and three demonstrations; returns (path, terrain, demos)."""
    hm = terrain()
    demos = [demo(hm, "LF", 2, "walker", seed=1), demo(hm, "RH", 0, "run:7:step:3", seed=2),
             demo(hm, "LH", 4, "teacher", {}, seed=3)]
    with DemoStore(store_path, create=True) as store:
        store.add_demonstrations(demos, terrains=[hm])
    return store_path, hm, demos


def raw(path):
    return sqlite3.connect(path, isolation_level=None)


def contents(path):
    """Everything a reader of the store sees, as plain comparable data."""
    with DemoStore(path) as store:
        return ([(d.id, d.terrain_hash, d.state.to_vector().tobytes(), d.swing_leg,
                  d.candidates.tobytes(), d.chosen, d.source, d.expert)
                 for d in store.demonstrations()], store.terrain_hashes())


# ---------------------------------------------------------------- round trip
def test_round_trip_is_bit_identical(filled):
    path, hm, demos = filled
    with DemoStore(path) as store:
        back = store.demonstrations()
        assert [d.id for d in back] == [1, 2, 3]  # creation order
        for a, b in zip(demos, back):
            assert b.terrain_hash == hm.content_hash()
            assert b.state.to_vector().tobytes() == a.state.to_vector().tobytes()
            assert b.state.swing_leg == a.state.swing_leg
            assert b.candidates.dtype == np.float64 and b.candidates.shape == a.candidates.shape
            assert b.candidates.tobytes() == a.candidates.tobytes()
            assert (b.chosen, b.source, b.expert) == (a.chosen, a.source, a.expert)
            np.testing.assert_array_equal(b.foothold, a.candidates[a.chosen])
        t = store.terrain(hm.content_hash())
        assert t.content_hash() == hm.content_hash()
        assert t.heights.tobytes() == hm.heights.tobytes()  # NaN included
        assert (t.resolution, t.origin, t.frame, t.metadata) == \
            (hm.resolution, hm.origin, hm.frame, hm.metadata)
        assert store.count() == 3 and len(store) == 3
        assert store.schema_version == SCHEMA_VERSION


def test_expert_settings_are_json_copies():
    hm = terrain()
    settings = {"noise": 0.1, "pair": (1, 2)}
    d = demo(hm, expert=settings)
    settings["noise"] = 99.0
    assert d.expert == {"noise": 0.1, "pair": [1, 2]}
    with pytest.raises(FootfallError, match="JSON"):
        demo(hm, expert={"x": object()})
    with pytest.raises(FootfallError, match="JSON"):
        demo(hm, expert={"x": float("nan")})


def test_filters_ids_and_summary(filled):
    path, hm, _ = filled
    other = terrain(seed=5)
    with DemoStore(path) as store:
        store.add_terrain(other)
        store.add_demonstration(demo(other, "RF", 1, "run:8:step:0", seed=4))
        assert [d.id for d in store.demonstrations(source_prefix="run:")] == [2, 4]
        assert store.demonstrations(source_prefix="run_") == []  # '_' is not a wildcard
        assert [d.id for d in store.demonstrations(terrain_hash=other.content_hash())] == [4]
        assert [d.id for d in store.demonstrations(ids=[4, 1])] == [4, 1]  # in the asked order
        assert store.count(source_prefix="teach") == 1
        with pytest.raises(FootfallError, match="demonstration 99 is not in the store"):
            store.demonstrations(ids=[1, 99])
        s = store.summary()
    assert s["format"] == FORMAT and s["demonstrations"] == 4 and s["terrains"] == 2
    assert s["by_terrain"] == {hm.content_hash(): 3, other.content_hash(): 1}
    assert s["by_leg"] == {"LF": 1, "RF": 1, "LH": 1, "RH": 1}
    assert s["by_source"] == {"run": 2, "teacher": 1, "walker": 1}
    assert s["candidates"] == {"min": 5, "mean": 5.0, "max": 5}
    assert (s["first_id"], s["last_id"]) == (1, 4)


def test_empty_store_summary(store_path):
    with DemoStore(store_path, create=True) as store:
        s = store.summary()
        assert store.demonstrations() == []
    assert s["demonstrations"] == 0 and s["by_terrain"] == {} and s["candidates"] is None
    assert s["by_leg"] == {"LF": 0, "RF": 0, "LH": 0, "RH": 0}


# ------------------------------------------------------------------- terrains
def test_terrain_is_stored_once(store_path):
    hm = terrain()
    relabelled = HeightMap(hm.heights, hm.resolution, hm.origin, metadata={"other": 1})
    with DemoStore(store_path, create=True) as store:
        assert store.add_terrain(hm) == hm.content_hash()
        assert store.add_terrain(hm) == hm.content_hash()
        store.add_demonstrations([demo(hm)], terrains=[hm, relabelled])
        assert store.terrain_hashes() == [hm.content_hash()]
        assert store.terrain(hm.content_hash()).metadata == hm.metadata  # the first one wins
    with raw(store_path) as con:
        assert con.execute("SELECT count(*) FROM terrains").fetchone() == (1,)


def test_terrain_hash_is_verified_on_load(filled):
    path, hm, _ = filled
    with raw(path) as con:  # one height changes: the stored blob no longer gives the hash
        blob = bytearray(con.execute("SELECT heights FROM terrains").fetchone()[0])
        blob[800] ^= 0x01
        con.execute("UPDATE terrains SET heights = ?", (bytes(blob),))
    with DemoStore(path) as store:
        with pytest.raises(FootfallError, match="corrupt.*content hash"):
            store.terrain(hm.content_hash())
        with pytest.raises(FootfallError, match=f"terrain {'0' * 64} is not in the store"):
            store.terrain("0" * 64)
    with raw(path) as con:  # a truncated blob is caught before hashing
        con.execute("UPDATE terrains SET heights = substr(heights, 1, 100)")
    with DemoStore(path) as store, pytest.raises(FootfallError, match="corrupt.*bytes"):
        store.terrain(hm.content_hash())


def test_demonstration_needs_its_terrain_in_the_store(store_path):
    with DemoStore(store_path, create=True) as store:
        with pytest.raises(FootfallError, match="not in the store; add it"):
            store.add_demonstration(demo(terrain()))
        assert store.count() == 0


# ----------------------------------------------------------------- validation
@pytest.mark.parametrize("change, match", [
    ({"chosen": 5}, "outside the 5 candidates"),
    ({"chosen": -1}, "outside the 5 candidates"),
    ({"chosen": True}, "integer index"),
    ({"chosen": 1.0}, "integer index"),
    ({"candidates": np.zeros((1, 3))}, "n >= 2"),
    ({"candidates": np.zeros((4, 2))}, r"shape \(n, 3\)"),
    ({"candidates": np.full((4, 3), np.inf)}, "finite"),
    ({"terrain_hash": "abc"}, "64 lowercase hex"),
    ({"source": ""}, "source"),
    ({"state": "standing"}, "RobotState"),
])
def test_bad_demonstrations_are_rejected(change, match):
    d = demo(terrain())
    fields = {"terrain_hash": d.terrain_hash, "state": d.state, "candidates": d.candidates,
              "chosen": d.chosen, "source": d.source, "expert": d.expert}
    with pytest.raises(FootfallError, match=match):
        Demonstration(**{**fields, **change})


def test_chosen_index_is_checked_on_read(filled):
    path, _, _ = filled
    with raw(path) as con:
        with pytest.raises(sqlite3.IntegrityError):  # the schema refuses it too ...
            con.execute("UPDATE demonstrations SET chosen = 7 WHERE id = 2")
        con.execute("PRAGMA ignore_check_constraints = ON")  # ... unless forced
        con.execute("UPDATE demonstrations SET chosen = 7 WHERE id = 2")
    with DemoStore(path) as store:
        assert store.demonstrations(ids=[1])[0].chosen == 2  # the others are still readable
        with pytest.raises(FootfallError, match=r"demonstration 2 is corrupt.*chosen index 7"):
            store.demonstrations()


def test_bad_array_rows_are_corrupt(filled):
    path, _, _ = filled
    with raw(path) as con:
        con.execute("UPDATE demonstrations SET candidates_dtype = '|O' WHERE id = 3")
        con.execute("UPDATE demonstrations SET state = substr(state, 1, 24) WHERE id = 1")
    with DemoStore(path) as store:
        with pytest.raises(FootfallError, match="demonstration 3 is corrupt.*dtype"):
            store.demonstrations(ids=[3])
        with pytest.raises(FootfallError, match="demonstration 1 is corrupt.*bytes"):
            store.demonstrations(ids=[1])


# -------------------------------------------------------------- opening files
def test_missing_file_needs_create(store_path):
    with pytest.raises(FootfallError, match="no such file"):
        DemoStore(store_path)
    assert not store_path.exists()
    with pytest.raises(FootfallError, match="output directory does not exist"):
        DemoStore(store_path.parent / "nowhere" / "d.sqlite", create=True)


@pytest.mark.parametrize("create", [False, True])
def test_files_that_are_not_stores_are_refused_and_untouched(tmp_path, create):
    text = tmp_path / "notes.sqlite"
    text.write_text("hello, not a database\n")
    empty = tmp_path / "empty.sqlite"
    empty.write_bytes(b"")
    foreign = tmp_path / "foreign.sqlite"
    with raw(foreign) as con:
        con.execute("CREATE TABLE people (name TEXT)")
        con.execute("INSERT INTO people VALUES ('ada')")
    con.close()
    before = {p: p.read_bytes() for p in (text, empty, foreign)}
    for path, match in ((text, "not an SQLite database"), (empty, "empty file"),
                        (foreign, "not a footfall demonstration store")):
        with pytest.raises(FootfallError, match=match):
            DemoStore(path, create=create)
    with pytest.raises(FootfallError, match="not a file"):
        DemoStore(tmp_path, create=create)
    assert {p: p.read_bytes() for p in before} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in before)


def test_corrupt_store_is_refused(filled, tmp_path):
    path, _, _ = filled
    data = path.read_bytes()
    truncated = tmp_path / "truncated.sqlite"
    truncated.write_bytes(data[:len(data) // 3])
    scrambled = tmp_path / "scrambled.sqlite"  # SQLite header kept, the rest overwritten
    scrambled.write_bytes(data[:100] + bytes(np.random.default_rng(0).integers(
        0, 256, len(data) - 100, dtype=np.uint8)))
    for bad in (truncated, scrambled):
        with pytest.raises(FootfallError, match="corrupt demonstration store"), \
                DemoStore(bad) as store:
            store.check()
            store.demonstrations()


def test_newer_schema_and_other_formats_are_refused(filled):
    path, _, _ = filled
    with raw(path) as con:
        con.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'",
                    (str(SCHEMA_VERSION + 1),))
    with pytest.raises(FootfallError, match=f"schema version {SCHEMA_VERSION + 1} is newer"):
        DemoStore(path)
    with raw(path) as con:
        con.execute("UPDATE meta SET value = '1'  WHERE key = 'schema_version'")
        con.execute("UPDATE meta SET value = 'someone.else' WHERE key = 'format'")
    with pytest.raises(FootfallError, match="format 'someone.else'"):
        DemoStore(path)


def test_closed_store_says_so(filled):
    path, _, _ = filled
    store = DemoStore(path)
    store.close()
    store.close()  # idempotent
    with pytest.raises(FootfallError, match="is closed"):
        store.count()


# ---------------------------------------------------- atomicity, concurrency
def test_failure_inside_add_demonstrations_writes_nothing(filled, monkeypatch):
    path, hm, _ = filled
    before = contents(path)
    new_terrain = terrain(seed=9)
    good = [demo(hm, seed=10), demo(hm, seed=11)]
    with DemoStore(path) as store:
        # The third one's terrain is missing: found mid-transaction, after two inserts.
        with pytest.raises(FootfallError, match="not in the store"):
            store.add_demonstrations(good + [demo(terrain(seed=4))], terrains=[new_terrain])
        calls = []

        def explode(self, con, d, original=DemoStore._insert_demonstration):
            calls.append(d)
            if len(calls) == 2:
                raise RuntimeError("power cut")
            return original(self, con, d)

        monkeypatch.setattr(DemoStore, "_insert_demonstration", explode)
        with pytest.raises(RuntimeError, match="power cut"):
            store.add_demonstrations(good, terrains=[new_terrain])
        monkeypatch.undo()
        assert len(calls) == 2
        assert store.add_demonstrations(good) == [4, 5]  # the store still works
    after = contents(path)
    assert after[0][:3] == before[0] and after[1] == before[1]  # no new terrain


def test_writer_killed_mid_transaction_leaves_the_store_intact(filled):
    path, _, _ = filled
    before = contents(path)
    script = textwrap.dedent(f"""
        import os
        from footfall.data.store import DemoStore
        n = 0
        original = DemoStore._insert_demonstration
        def die(self, con, d):
            global n
            n += 1
            if n == 2:
                os._exit(17)  # no rollback, no close: like a crash
            return original(self, con, d)
        DemoStore._insert_demonstration = die
        with DemoStore({str(path)!r}) as store:
            demos = store.demonstrations()
            store.add_demonstrations(demos)
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=False)
    assert proc.returncode == 17, proc.stderr
    assert contents(path) == before
    with DemoStore(path) as store:
        store.check()


def test_wal_readers_see_committed_rows_only(filled):
    path, hm, _ = filled
    with raw(path) as con:
        assert con.execute("PRAGMA journal_mode").fetchone() == ("wal",)
    with DemoStore(path) as reader, DemoStore(path) as writer:
        assert reader.count() == 3
        writer.add_demonstration(demo(hm, seed=20))
        assert reader.count() == 4  # committed: visible to the other connection
        con = raw(path)
        con.execute("BEGIN IMMEDIATE")  # another writer, mid-transaction
        con.execute("DELETE FROM demonstrations")
        assert reader.count() == 4  # not blocked, and sees no uncommitted change
        assert len(reader.demonstrations()) == 4
        con.execute("ROLLBACK")
        con.close()
        assert reader.count() == 4


def test_parallel_writers_all_land(filled):
    path, _, _ = filled
    script = textwrap.dedent(f"""
        import sys
        from footfall.data.store import DemoStore
        with DemoStore({str(path)!r}) as store:
            template = store.demonstrations(ids=[1])[0]
            for k in range(8):  # one transaction each, interleaved with the other writers
                store.add_demonstration(template.__class__(
                    template.terrain_hash, template.state, template.candidates,
                    template.chosen, f"run:{{sys.argv[1]}}:step:{{k}}"))
    """)
    procs = [subprocess.Popen([sys.executable, "-c", script, str(w)], stderr=subprocess.PIPE,
                              text=True) for w in range(3)]
    for p in procs:
        _, err = p.communicate(timeout=60)
        assert p.returncode == 0, err
    with DemoStore(path) as store:
        runs = store.demonstrations(source_prefix="run:")
        assert store.count() == 3 + 24
        store.check()
    steps = {d.source for d in runs}
    assert steps >= {f"run:{w}:step:{k}" for w in range(3) for k in range(8)}
    for w in range(3):  # each writer's own rows are in its order
        ids = [d.id for d in runs if d.source.startswith(f"run:{w}:")]
        assert ids == sorted(ids) and len(ids) == 8


def test_store_file_is_self_describing(filled):
    path, _, _ = filled
    with raw(path) as con:
        meta = dict(con.execute("SELECT key, value FROM meta"))
        row = con.execute("SELECT state_shape, state_dtype, candidates_shape, candidates_dtype, "
                          "expert FROM demonstrations WHERE id = 1").fetchone()
    assert meta["format"] == FORMAT and meta["schema_version"] == str(SCHEMA_VERSION)
    assert "[m]" in meta["state_layout"]
    assert row[:4] == ("[20]", "<f8", "[5, 3]", "<f8")
    assert json.loads(row[4]) == {"noise": 0.1, "weights": [1.0, 2.5]}


# ------------------------------------------------------------ schema, migrations
def test_schema_text_is_unchanged():
    # SQLite keeps each CREATE statement's text in the file: a new store is byte-identical to
    # one written before only while this text is.
    text = "\n".join(schema.DEMONSTRATION_TABLES + schema.RUN_LOG_TABLES)
    assert hashlib.sha256(text.encode()).hexdigest() == \
        "74217367a37c2ccad35441dee48923bfcffa4b1f516c410db105860d4686801f"


def test_every_older_version_has_a_migration():
    assert sorted(schema.MIGRATIONS) == list(range(1, SCHEMA_VERSION))


def _objects(path):
    with raw(path) as con:
        objects = sorted(con.execute("SELECT type, name, tbl_name, sql FROM sqlite_master"))
        meta = dict(con.execute("SELECT key, value FROM meta"))
    con.close()
    return objects, meta


def _as_version_1(path):
    with raw(path) as con:
        con.execute("DROP TABLE marks")
        con.execute("DROP TABLE verdicts")
        con.execute("DROP TABLE judgements")
        con.execute("DROP TABLE replaced_labels")
        con.execute("DROP TABLE labels")
        con.execute("DROP TABLE run_steps")
        con.execute("DROP TABLE runs")
        con.execute("UPDATE meta SET value = '1' WHERE key = 'schema_version'")
    con.close()


def test_migrated_store_has_the_schema_of_a_new_one(filled, tmp_path):
    path, _, _ = filled
    before = contents(path)
    with DemoStore(tmp_path / "new.sqlite", create=True):
        pass
    _as_version_1(path)
    assert _objects(path)[1]["schema_version"] == "1"
    with DemoStore(path) as store:
        assert store.schema_version == SCHEMA_VERSION
    assert _objects(path) == _objects(tmp_path / "new.sqlite")
    assert contents(path) == before  # the demonstrations and terrains are untouched


@pytest.mark.parametrize("version, newer", [
    (2, ("marks", "verdicts", "judgements", "replaced_labels", "labels")),  # 3: people's labels
    (3, ("marks", "verdicts", "judgements", "replaced_labels")),  # 4: undo history, judgements
    (4, ("marks", "verdicts")),  # 5: the teachers' verdicts on the other candidates, marks
])
def test_an_older_store_gains_the_newer_tables_and_loses_nothing(filled, tmp_path, version,
                                                                 newer):
    path, _, _ = filled
    before = contents(path)
    with DemoStore(tmp_path / "new.sqlite", create=True):
        pass
    with raw(path) as con:
        for table in newer:
            con.execute(f"DROP TABLE {table}")
        con.execute("UPDATE meta SET value = ? WHERE key = 'schema_version'", (str(version),))
    con.close()
    with DemoStore(path, read_only=True) as store:  # read as it is: nothing refused
        assert store.schema_version == version and store.judgement(1, "any") is None
        assert store.marks() == [] and store.mark_counts() == {}  # no marks table: none
        if "labels" in newer:
            assert store.labels() == []
            assert store.summary()["labels"] == {"by_labeler": {}, "disagreements": 0}
    with DemoStore(path) as store:
        assert store.schema_version == SCHEMA_VERSION == 5
    assert _objects(path) == _objects(tmp_path / "new.sqlite")
    assert contents(path) == before


def test_migration_leaves_a_store_another_process_upgraded_alone(filled):
    path, _, _ = filled
    with raw(path) as con:
        before = sorted(con.execute("SELECT type, name, sql FROM sqlite_master"))
        con.execute("BEGIN IMMEDIATE")
        schema.migrate(con, 1)  # read as version 1, but version 2 by the time the lock is held
        con.execute("COMMIT")
        assert sorted(con.execute("SELECT type, name, sql FROM sqlite_master")) == before
        assert con.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone() \
            == (str(SCHEMA_VERSION),)
    con.close()



# ------------------------------------------------------------ teachers' verdicts
def test_a_teachers_verdict_round_trips_and_an_old_store_reads_without_one(store_path):
    hm = terrain()
    plain = demo(hm, "LF", 2, seed=1)
    values = np.array([0.5, -12.0, 3.25, 1.0, -1e3])
    refused = np.array([False, True, False, False, True])
    graded = replace(demo(hm, "RH", 2, seed=2), values=values, refused=refused)
    only_marks = replace(demo(hm, "LH", 0, seed=3), refused=np.eye(1, 5, 4, dtype=bool)[0])
    with DemoStore(store_path, create=True) as store:
        store.add_demonstrations([plain, graded, only_marks], terrains=[hm])
    with DemoStore(store_path, read_only=True) as store:
        a, b, c = store.demonstrations()
        assert a.values is None and a.refused is None and not a.has_verdict
        assert b.values.tobytes() == values.tobytes() and b.refused.tolist() == refused.tolist()
        assert c.values is None and c.refused.tolist() == [False] * 4 + [True]
        assert store.demonstrations(ids=[2])[0].refused.tolist() == refused.tolist()
    with raw(store_path) as con:  # the same store as version 4: its demonstrations, no verdicts
        con.execute("DROP TABLE marks")
        con.execute("DROP TABLE verdicts")
        con.execute("UPDATE meta SET value = '4' WHERE key = 'schema_version'")
    con.close()
    with DemoStore(store_path, read_only=True) as store:
        assert [d.has_verdict for d in store.demonstrations()] == [False] * 3
    with DemoStore(store_path) as store:  # opened to write: upgraded, the verdicts kept anew
        store.add_demonstration(graded)
        assert store.demonstrations(ids=[4])[0].values.tobytes() == values.tobytes()


@pytest.mark.parametrize("values, refused, match", [
    ([1.0, 2.0], None, "5 finite numbers"),
    ([1.0, np.inf, 0, 0, 0], None, "5 finite numbers"),
    (None, [0, 0, 1, 0, 0], "chosen candidate 2 is refused"),
    (None, [0, 0.5, 0, 0, 0], "mask of 5 values 0 / 1"),
    (None, [[0, 0, 0, 0, 0]], "mask of 5 values 0 / 1"),
])
def test_a_verdict_that_does_not_fit_its_candidates_is_refused(values, refused, match):
    with pytest.raises(FootfallError, match=match):
        replace(demo(terrain(), chosen=2), values=values, refused=refused)
