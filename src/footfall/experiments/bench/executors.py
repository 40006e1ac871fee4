"""Benchmark of the executors: a batch of runs on a Ray cluster against the local process pool.

``bench_executors``: the same hand-tuned runs on the local pool and on a Ray
cluster started here on loopback (its start-up timed apart), in runs per
minute, with a check that both give the same records.
"""

from __future__ import annotations

import os
import platform
import tempfile
import time
from pathlib import Path

from footfall.experiments.batch import batch_jobs
from footfall.experiments.executors import LocalPool, RayCluster
from footfall.sim.episode import WALL_CLOCK_FIELDS
from footfall.terrain import make_board


def bench_executors(runs: int = 8, seed: int = 0, difficulty: float = 0.5,
                    processes: int = 2) -> dict:
    """Runs per minute of one batch on the local process pool and on a Ray cluster started here.

    ``runs`` hand-tuned runs over a flat | rocky | flat board, first on the
    local pool of ``processes`` workers (the baseline), then the same jobs on
    a Ray cluster of ``processes`` CPUs started in this process on loopback
    (its start-up timed apart). Both give the same records (checked).
    """
    out: dict = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
                 "runs": runs, "processes": processes}
    with tempfile.TemporaryDirectory() as folder:
        board = Path(folder) / "board.npz"
        make_board([("rocky", difficulty)], seed=seed).save(board)
        jobs = batch_jobs(board, None, runs, seed)
        results = {}
        ray = RayCluster(processes=processes)
        try:
            start = time.perf_counter()
            ray._connect()
            out["ray_start_s"] = time.perf_counter() - start
            for name, executor in (("local", LocalPool(processes)), ("ray", ray)):
                start = time.perf_counter()
                results[name] = {job.seed: rec for job, (rec, _) in executor.map(jobs)}
                wall = time.perf_counter() - start
                out[name] = {"wall_s": wall, "runs_per_minute": 60.0 * runs / wall}
        finally:
            ray.close()
    strip = lambda rec: {k: v for k, v in rec.result.items() if k not in WALL_CLOCK_FIELDS}
    out["same_records"] = all(strip(results["local"][s]) == strip(results["ray"][s])
                              for s in results["local"])
    out["successes"] = sum(bool(r.result["success"]) for r in results["local"].values())
    out["ray_over_local"] = out["ray"]["runs_per_minute"] / out["local"]["runs_per_minute"]
    return out


def format_executors(r: dict) -> str:
    """Human-readable lines of :func:`bench_executors`."""
    return "\n".join([
        f"{r['runs']} runs on a rocky board ({r['successes']} crossed), {r['processes']} "
        f"processes each:",
        f"local process pool: {r['local']['runs_per_minute']:.1f} runs/min "
        f"({r['local']['wall_s']:.1f} s)",
        f"Ray cluster started here: {r['ray']['runs_per_minute']:.1f} runs/min "
        f"({r['ray']['wall_s']:.1f} s, after {r['ray_start_s']:.1f} s to start it)",
        f"Ray / local pool: {r['ray_over_local']:.2f}; the same records on both: "
        f"{'yes' if r['same_records'] else 'NO'}"])
