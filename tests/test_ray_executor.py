"""Batches of runs on a real Ray cluster: started here on loopback with 2 CPUs, as a user's would be.

The cluster is its own processes (``ray start --head --block``), reached by
address like a remote one; the driver (this process) is the only writer of
every store.
"""

import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.heightmap import HeightMap
from footfall.data.store import DemoStore
from footfall.experiments.executors import LOOPBACK_ENV, LocalPool, RayCluster, make_executor
from footfall.experiments.runs import RunJob, Runner
from footfall.sim.episode import WALL_CLOCK_FIELDS, WalkConfig
from maps import short_flat_board


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


READY = "Ray runtime started"  # what `ray start` prints once the head node serves


@pytest.fixture(scope="module")
def cluster():
    """A Ray head node with 2 CPUs on 127.0.0.1; its address. Stopped (every process) at the end."""
    port = _free_port()
    temp = tempfile.mkdtemp(prefix="ffray", dir="/tmp")  # short: Ray's socket paths are long
    # Token authentication, as Ray's clusters have by default; this driver holds the token.
    settings = {**LOOPBACK_ENV, "RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": secrets.token_hex(32)}
    env = {**os.environ, **settings}
    old = {k: os.environ.get(k) for k in settings}
    head = subprocess.Popen(
        [str(Path(sys.executable).parent / "ray"), "start", "--head", "--block",
         f"--port={port}", "--num-cpus=2", "--include-dashboard=false",
         "--object-store-memory=100000000", f"--temp-dir={temp}", "--disable-usage-stats"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        start_new_session=True)
    drain = threading.Thread(target=lambda: [None for _ in head.stdout], daemon=True)
    try:
        said = []
        for line in head.stdout:  # however long the start takes; ends if `ray start` exits
            said.append(line)
            if READY in line:
                break
        assert any(READY in line for line in said), "ray start exited:\n" + "".join(said)
        drain.start()  # keep reading what the head prints: it never blocks on a full pipe
        os.environ.update(settings)  # this driver, too, speaks to it on loopback
        yield f"127.0.0.1:{port}"
    finally:
        os.killpg(head.pid, signal.SIGINT)  # --block: on Ctrl-C the head stops its processes
        try:
            head.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(head.pid, signal.SIGKILL)
            head.wait()
        if drain.is_alive():
            drain.join()  # the head has exited: its output ends
        head.stdout.close()
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
        shutil.rmtree(temp, ignore_errors=True)  # the cluster's logs and sockets


def _stripped(record) -> tuple:
    """A run record as comparable plain data, without its wall-clock figures."""
    result = {k: v for k, v in record.result.items() if k not in WALL_CLOCK_FIELDS}
    steps = [(s.k, s.state.swing_leg, s.chosen, s.state.to_vector().tolist(),
              np.asarray(s.candidates).tolist(), np.asarray(s.rewards).tolist(),
              np.asarray(s.touchdown).tolist(), s.t_liftoff, s.t_touchdown,
              None if np.isnan(s.slip) else s.slip) for s in record.steps]
    return (record.key, record.terrain_hash, record.seed, json.dumps(record.settings,
                                                                     sort_keys=True),
            json.dumps(result, sort_keys=True), steps)


def _stored(path: Path) -> dict:
    with DemoStore(path) as store:
        return {r["key"]: _stripped(store.run(r["id"])) for r in store.runs()}


def _jobs(board: Path, n: int, config: WalkConfig = WalkConfig(start_setback=0.2)) -> list:
    return [RunJob(f"t/s{s}", str(board), None, s, config) for s in range(n)]


@pytest.fixture(scope="module")
def board(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("board") / "flat.npz"
    short_flat_board().save(path)
    return path


def _runner(store: DemoStore, board: Path, executor, on_run=None) -> Runner:
    hmap = HeightMap.load(board)
    return Runner(store, {hmap.content_hash(): hmap}, executor, on_run, lambda line: None)


# ---------------------------------------------------------------------- the tests
def test_walk_many_on_ray_equals_the_local_pool_record_for_record(cluster, tmp_path, capsys):
    flat = tmp_path / "flat.npz"
    assert run(capsys, "terrain", "board", "flat", "flat", "flat", "--seed", "1",
               "-o", flat)[0] == 0
    common = ["walk-many", "--terrain", flat, "--seed", "3", "--runs", "4", "--json"]
    code, local_out, _ = run(capsys, *common, "--log", tmp_path / "local.sqlite")
    assert code == 0
    code, ray_out, _ = run(capsys, *common, "--log", tmp_path / "ray.sqlite",
                           "--executor", "ray", "--ray-address", cluster)
    assert code == 0
    strip = lambda out: [{k: v for k, v in r.items() if k not in WALL_CLOCK_FIELDS}
                         for r in json.loads(out)["runs_detail"]]
    assert strip(local_out) == strip(ray_out)
    local, remote = _stored(tmp_path / "local.sqlite"), _stored(tmp_path / "ray.sqlite")
    assert len(local) == 4 and sorted(local) == sorted(remote)
    for key in local:
        assert local[key] == remote[key], key


def _walking_workers() -> list[int]:
    """Process ids of Ray workers walking a run now (Ray titles them after the task)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if (entry / "cmdline").read_bytes().startswith(b"ray::walk_shipped"):
                    found.append(int(entry.name))
            except OSError:
                continue
    return found


def test_a_killed_ray_worker_leaves_every_run_once_in_the_store(cluster, board, tmp_path):
    jobs = _jobs(board, 5)
    killed: list[int] = []
    stop = threading.Event()

    def killer() -> None:  # kill the first worker seen walking, once it is well into its run
        while not stop.is_set() and not killed:
            busy = _walking_workers()
            if busy:
                time.sleep(0.5)
                if busy[0] in _walking_workers():
                    os.kill(busy[0], signal.SIGKILL)
                    killed.append(busy[0])
            time.sleep(0.02)

    thread = threading.Thread(target=killer, daemon=True)
    with DemoStore(tmp_path / "ray.sqlite", create=True) as store:
        executor = RayCluster(address=cluster)
        thread.start()
        try:
            _runner(store, board, executor).run(jobs, "runs")
        finally:
            stop.set()
            thread.join()
            executor.close()
        keys = [r["key"] for r in store.runs()]
    assert killed, "no worker was killed: the test did not test"
    assert sorted(keys) == sorted(j.key for j in jobs)  # each run once, none lost
    with DemoStore(tmp_path / "local.sqlite", create=True) as store:
        _runner(store, board, LocalPool(2)).run(jobs, "runs")
    assert _stored(tmp_path / "ray.sqlite") == _stored(tmp_path / "local.sqlite")


class Counting:
    """An executor that counts the jobs it is given to walk."""

    def __init__(self, inner) -> None:
        self.inner, self.name, self.walked = inner, inner.name, []

    def map(self, jobs):
        self.walked += [j.key for j in jobs]
        return self.inner.map(jobs)

    def close(self) -> None:
        self.inner.close()


def test_an_interrupted_ray_driver_run_again_repeats_nothing_and_loses_nothing(cluster, board,
                                                                              tmp_path):
    jobs = _jobs(board, 5)
    stored: list[str] = []

    def interrupt_after_two(key: str) -> None:
        stored.append(key)
        if len(stored) == 2:
            raise KeyboardInterrupt  # as Ctrl-C in the driver, between two stored runs

    path = tmp_path / "ray.sqlite"
    executor = Counting(RayCluster(address=cluster))
    with DemoStore(path, create=True) as store:
        with pytest.raises(KeyboardInterrupt):
            _runner(store, board, executor, interrupt_after_two).run(jobs, "runs")
        executor.close()
        assert sorted(r["key"] for r in store.runs()) == sorted(stored)
    again = Counting(RayCluster(address=cluster))
    with DemoStore(path) as store:
        try:
            _runner(store, board, again).run(jobs, "runs")
        finally:
            again.close()
        keys = [r["key"] for r in store.runs()]
    assert sorted(again.walked) == sorted(set(j.key for j in jobs) - set(stored))  # no repeats
    assert sorted(keys) == sorted(j.key for j in jobs)  # nothing lost, each once
    with DemoStore(tmp_path / "local.sqlite", create=True) as store:
        _runner(store, board, LocalPool(2)).run(jobs, "runs")
    assert _stored(path) == _stored(tmp_path / "local.sqlite")


def test_ray_ships_the_files_so_a_node_needs_none_of_the_drivers(cluster, board, tmp_path):
    """A job's board is read by the driver and shipped: the worker walks a copy of its bytes."""
    moved = tmp_path / "board.npz"
    moved.write_bytes(board.read_bytes())
    executor = RayCluster(address=cluster)
    try:
        [(job, (record, demos))] = list(executor.map(
            [replace(_jobs(moved, 1, WalkConfig(start_setback=0.2, max_steps=2))[0])]))
    finally:
        executor.close()
    assert job.terrain == str(moved)  # the driver's job is unchanged
    assert record.terrain_hash == HeightMap.load(moved).content_hash() and len(record.steps) == 2


def test_bad_executor_settings_are_one_line_and_exit_2(tmp_path, capsys, board):
    code, _, err = run(capsys, "walk-many", "--terrain", board, "--seed", "0", "--runs", "2",
                       "--ray-address", "127.0.0.1:1")
    assert_user_error(code, err, "--ray-address is for --executor ray")
    code, _, err = run(capsys, "walk-many", "--terrain", board, "--seed", "0", "--runs", "2",
                       "--executor", "slurm")
    assert code == 2 and "slurm" in err
    port = _free_port()  # nothing listens there
    code, _, err = run(capsys, "walk-many", "--terrain", board, "--seed", "0", "--runs", "2",
                       "--executor", "ray", "--ray-address", f"127.0.0.1:{port}")
    assert_user_error(code, err, f"no Ray cluster answers at 127.0.0.1:{port}")
    code, _, err = run(capsys, "walk-many", "--terrain", board, "--seed", "0", "--runs", "2",
                       "--executor", "ray", "--ray-address", "nowhere")
    assert_user_error(code, err, "--ray-address must be HOST:PORT")
    with pytest.raises(Exception, match="unknown executor"):
        make_executor("slurm")
