"""The fuzz target of batches that race: two ``walk-many --log`` processes on one store at once.

The store is new (both create it) or one that exists; the two batches walk the same seeds,
overlapping ones, or seeds apart. Both must end with exit status 0 -- a run the other process
stored first is reused, not an error -- and the store must then hold every seed's run once.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

from hypothesis import strategies as st

from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import Garbage
from footfall.cli.fuzz.targets import Target, register_target
from footfall.data.store import DemoStore

FIRST_SEED = 70  # the first batch's seed; the second's is this plus the case's offset
race_cases = st.tuples(st.booleans(), st.sampled_from((0, 1, 100)), st.integers(1, 2))
"""(a new store, the second batch's seed offset: 0 the same runs, 1 overlapping, 100 apart,
runs per batch)."""
SECONDS = 150.0  # [s] both batches, each a few steps on a short flat board


def _batch(bases: Bases, store: Path, seed: int, runs: int) -> list[str]:
    return [sys.executable, "-c", "from footfall.cli.entry import main; raise SystemExit(main())",
            "walk-many", "--terrain", str(bases.flat), "--runs", str(runs), "--seed", str(seed),
            "--log", str(store), "--processes", "1"]


def _race_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    new, offset, runs = case

    def work() -> None:
        store = scratch / "wm.sqlite"
        if not new:
            shutil.copyfile(bases.store, store)
        env = {**os.environ, "OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
        seeds = (FIRST_SEED, FIRST_SEED + offset)
        procs = [subprocess.Popen(_batch(bases, store, s, runs), env=env, cwd=scratch,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
                 for s in seeds]
        try:
            errors = [p.communicate(timeout=SECONDS - 10)[1] for p in procs]
        finally:
            for p in procs:
                p.kill() if p.poll() is None else None
        for p, err in zip(procs, errors):
            if p.returncode != 0:
                raise Garbage(f"a batch beside another ended with status {p.returncode}: "
                              f"{err.strip().splitlines()[-1:] if err.strip() else ''}")
        wanted = sorted({s + i for s in seeds for i in range(runs)})
        with DemoStore(store, read_only=True) as s:
            got = sorted(s.run(r["id"]).seed for r in s.runs(key_prefix="walk-many/"))
        if got != wanted:
            raise Garbage(f"the store holds the runs of seeds {got}, not each of {wanted} once")
    return work


register_target(Target("concurrency", race_cases, _race_work, seconds=SECONDS))
