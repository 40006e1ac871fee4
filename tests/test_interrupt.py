"""An interrupted command stops its worker processes: Ctrl-C, and SIGTERM as Ctrl-C."""

import multiprocessing
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from footfall.core.compute import worker_pool
from footfall.terrain.saving import save_board


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie waiting to be reaped does not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def _workers(pid: int) -> list[int]:
    """The spawned worker processes among ``pid``'s children (not the resource tracker)."""
    try:
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except OSError:
        return []
    found = []
    for child in map(int, children):
        try:
            cmdline = Path(f"/proc/{child}/cmdline").read_bytes().decode(errors="replace")
        except OSError:
            continue
        if "multiprocessing" in cmdline and "resource_tracker" not in cmdline:
            found.append(child)
    return found


pytestmark = pytest.mark.skipif(not Path("/proc/self/task").exists(),
                                reason="reads the process tree from /proc")


def test_a_pool_left_by_an_exception_stops_its_busy_workers():
    with pytest.raises(RuntimeError, match="stop"):
        with worker_pool(2) as pool:
            busy = [pool.submit(time.sleep, 600) for _ in range(2)]
            while not all(f.running() for f in busy):
                time.sleep(0.05)
            workers = [p.pid for p in multiprocessing.active_children()]
            assert workers
            raise RuntimeError("stop")
    assert not any(_alive(pid) for pid in workers)
    with worker_pool(2) as pool:  # left normally: the work is done, the pool closed
        assert list(pool.map(abs, [-1, -2])) == [1, 2]


def test_sigterm_interrupts_a_command_and_stops_its_workers(tmp_path):
    board = tmp_path / "board.npz"
    save_board(["rocky:0.5"], seed=3, path=board)
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    command = subprocess.Popen(
        [sys.executable, "-m", "footfall.cli", "walk-many", "--terrain", str(board),
         "--runs", "40", "--seed", "0", "--processes", "2"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        workers: list[int] = []
        deadline = time.monotonic() + 120
        while len(workers) < 2 and command.poll() is None and time.monotonic() < deadline:
            time.sleep(0.2)
            workers = _workers(command.pid)
        assert len(workers) == 2, "the command did not start its two workers"
        command.send_signal(signal.SIGTERM)
        _, err = command.communicate(timeout=60)
    finally:
        if command.poll() is None:
            command.kill()
    assert command.returncode == 130 and err.strip().endswith("footfall: interrupted")
    for _ in range(50):  # the workers were told to stop before the driver exited
        if not any(_alive(pid) for pid in workers):
            break
        time.sleep(0.1)
    assert not any(_alive(pid) for pid in workers)
