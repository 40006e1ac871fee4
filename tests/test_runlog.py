"""Run logs in the store: round trip, atomicity, keys, and upgrading a version-1 store."""

import json
import math
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.state import nominal_state
from footfall.data.runlog import RunRecord, RunStep
from footfall.data.store import SCHEMA_VERSION, DemoStore
from test_store import demo, terrain


def _run(hmap, n_steps=3, key="table2:flat:0", seed=4):
    rng = np.random.default_rng(seed)
    steps = []
    for k in range(n_steps):
        leg = ("LH", "LF", "RH", "RF")[k % 4]
        state = nominal_state(hmap, (0.2 + 0.02 * k, 0.0), 0.0, leg)
        cand = np.column_stack([rng.uniform(0.2, 0.4, 6), rng.uniform(-0.1, 0.1, 6),
                                np.zeros(6)])
        rewards = rng.normal(size=6)
        rewards[1] = -np.inf  # an invalid candidate keeps its -inf
        last = k == n_steps - 1
        steps.append(RunStep(k, state, cand, rewards, int(np.argmax(rewards)), 0.5 * k,
                             math.nan if last else 0.5 * k + 0.3,
                             np.full(3, np.nan) if last else cand[0] + 0.001,
                             math.nan if last else 0.002 * k))
    return RunRecord(hmap.content_hash(), seed, {"reward": "default", "gait": {"swing": 0.3}},
                     {"success": True, "reason": "goal", "distance": 1.2}, tuple(steps), key)


def test_run_round_trip_is_bit_identical(tmp_path):
    hm = terrain()
    run = _run(hm)
    with DemoStore(tmp_path / "s.sqlite", create=True) as store:
        run_id = store.add_run(run, terrains=[hm])
        back = store.run(run_id)
        listed = store.runs()
    assert back.id == run_id and back.key == run.key and back.seed == run.seed
    assert back.settings == run.settings and back.result == run.result
    assert len(back.steps) == 3
    for a, b in zip(run.steps, back.steps):
        assert a.swing_leg == b.swing_leg and a.chosen == b.chosen
        assert a.state.to_vector().tobytes() == b.state.to_vector().tobytes()
        assert a.candidates.tobytes() == b.candidates.tobytes()
        assert a.rewards.tobytes() == b.rewards.tobytes()
        assert a.touchdown.tobytes() == b.touchdown.tobytes()
        assert (a.slip == b.slip) or (math.isnan(a.slip) and math.isnan(b.slip))
    assert back.slips().tolist() == [0.0, 0.002]
    assert [r["n_steps"] for r in listed] == [3] and listed[0]["result"]["success"] is True


def test_runs_filter_by_key_and_keys_are_unique(tmp_path):
    hm = terrain()
    with DemoStore(tmp_path / "s.sqlite", create=True) as store:
        store.add_terrain(hm)
        store.add_run(_run(hm, key="a:1"))
        store.add_run(_run(hm, key="b:1"))
        store.add_run(_run(hm, key=None))
        with pytest.raises(FootfallError, match="already in the store"):
            store.add_run(_run(hm, key="a:1"))
        assert [r["key"] for r in store.runs("a:")] == ["a:1"]
        assert len(store.runs()) == 3


def test_a_failed_run_write_leaves_nothing(tmp_path):
    hm = terrain()
    with DemoStore(tmp_path / "s.sqlite", create=True) as store:
        with pytest.raises(FootfallError, match="not in the store"):
            store.add_run(_run(hm))  # its terrain was never added
        assert store.runs() == []
        assert store.terrain_hashes() == []


def test_bad_run_steps_are_rejected():
    hm = terrain()
    state = nominal_state(hm, (0.3, 0.0), 0.0, "LF")
    with pytest.raises(FootfallError, match="outside"):
        RunStep(0, state, np.zeros((3, 3)), np.zeros(3), 3, 0.0)
    with pytest.raises(FootfallError, match="one reward per candidate"):
        RunStep(0, state, np.zeros((3, 3)), np.zeros(2), 0, 0.0)
    with pytest.raises(FootfallError, match="numbered"):
        RunRecord(hm.content_hash(), 0, {}, {}, (RunStep(1, state, np.zeros((2, 3)),
                                                         np.zeros(2), 0, 0.0),))
    with pytest.raises(FootfallError, match="without NaN"):
        RunRecord(hm.content_hash(), 0, {}, {"slip": float("nan")})


def test_a_version_1_store_is_upgraded_in_place_without_losing_anything(tmp_path):
    path = tmp_path / "old.sqlite"
    hm = terrain()
    with DemoStore(path, create=True) as store:
        store.add_demonstrations([demo(hm)], terrains=[hm])
    con = sqlite3.connect(path, isolation_level=None)  # make it look like a version-1 file
    con.execute("DROP TABLE marks")
    con.execute("DROP TABLE verdicts")
    con.execute("DROP TABLE judgements")
    con.execute("DROP TABLE replaced_labels")
    con.execute("DROP TABLE labels")
    con.execute("DROP TABLE run_steps")
    con.execute("DROP TABLE runs")
    con.execute("UPDATE meta SET value = '1' WHERE key = 'schema_version'")
    con.close()
    with DemoStore(path) as store:
        assert store.schema_version == SCHEMA_VERSION == 5
        assert len(store.demonstrations()) == 1
        store.add_run(_run(hm))
        assert len(store.runs()) == 1


def test_four_processes_creating_and_appending_to_one_new_store_lose_and_double_nothing(
        tmp_path):
    # All four start on a store that does not exist yet, at once (a start file releases them):
    # each creates it, stores two runs of its own and the same six runs as the others (two
    # batches walking the same runs). No process fails, every run is stored once, and each
    # shared run is stored by exactly one process and found stored by the other three.
    path, start = tmp_path / "new.sqlite", tmp_path / "go"
    script = textwrap.dedent(f"""
        import json, sys, time
        from pathlib import Path
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_runlog import _run
        from test_store import terrain
        from footfall.data.store import DemoStore
        w = int(sys.argv[1])
        hm = terrain()
        runs = [_run(hm, key=f"shared:{{k}}", seed=k) for k in range(6)]
        runs += [_run(hm, key=f"own:{{w}}:{{k}}", seed=10 + k) for k in range(2)]
        while not Path({str(start)!r}).exists():
            time.sleep(0.001)
        added = []
        with DemoStore({str(path)!r}, create=True) as store:
            for run in runs:
                added.append(store.add_run_if_new(run, terrains=[hm])[1])
        print(json.dumps(added))
    """)
    procs = [subprocess.Popen([sys.executable, "-c", script, str(w)], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for w in range(4)]
    time.sleep(2.0)  # every process imported and waiting
    start.touch()
    added = []
    for p in procs:
        out, err = p.communicate(timeout=120)
        assert p.returncode == 0, err
        added.append(json.loads(out))
    assert [a[6:] for a in added] == [[True, True]] * 4  # each its own runs
    assert [sum(a[k] for a in added) for k in range(6)] == [1] * 6  # each shared run once
    with DemoStore(path) as store:
        keys = [r["key"] for r in store.runs()]
        store.check()
    assert sorted(keys) == sorted([f"shared:{k}" for k in range(6)]
                                  + [f"own:{w}:{k}" for w in range(4) for k in range(2)])
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".new")] == []
