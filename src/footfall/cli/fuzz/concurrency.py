"""The fuzz target of commands that race: two processes into one store or one folder at once.

* Two ``walk-many --log`` batches on one store: new (both create it) or one that exists; the
  same seeds, overlapping ones, or seeds apart. Both must end with exit status 0 -- a run the
  other process stored first is reused, not an error -- and the store must then hold every
  seed's run once.
* Two ``demos correct`` of one store's runs into one output at once: both end with status 0,
  and the output holds each correction once.
* Two ``benchmark-terrain`` into one folder at once (a folder-owning command; every one holds
  its folder the same way): each ends with status 0, or 2 with the one line that the folder is
  in use; at least one walks, and the folder's store holds each run once.
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
race_cases = st.one_of(
    st.tuples(st.booleans(), st.sampled_from((0, 1, 100)), st.integers(1, 2)),
    st.tuples(st.sampled_from(("correct", "folder"))))
"""(a new store, the second batch's seed offset: 0 the same runs, 1 overlapping, 100 apart,
runs per batch); or two corrections of a store into one output, or two commands into one
folder."""
ENV = {"OMP_NUM_THREADS": "1", "MPLBACKEND": "Agg"}
SECONDS = 150.0  # [s] both batches, each a few steps on a short flat board


def _batch(bases: Bases, store: Path, seed: int, runs: int) -> list[str]:
    return [sys.executable, "-c", "from footfall.cli.entry import main; raise SystemExit(main())",
            "walk-many", "--terrain", str(bases.flat), "--runs", str(runs), "--seed", str(seed),
            "--log", str(store), "--processes", "1"]


def _footfall(*args: object) -> list[str]:
    return [sys.executable, "-c", "from footfall.cli.entry import main; raise SystemExit(main())",
            *map(str, args)]


def _both(commands: list[list[str]], scratch: Path) -> list[tuple[int, str]]:
    """Start the commands at once; their exit statuses and standard errors."""
    env = {**os.environ, **ENV}
    procs = [subprocess.Popen(c, env=env, cwd=scratch, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True) for c in commands]
    try:
        errors = [p.communicate(timeout=SECONDS - 10)[1] for p in procs]
    finally:
        for p in procs:
            p.kill() if p.poll() is None else None
    return [(p.returncode, err) for p, err in zip(procs, errors)]


def _corrections_race(bases: Bases, scratch: Path) -> None:
    out = scratch / "labels.sqlite"
    done = _both([_footfall("demos", "correct", bases.store, "--every-step", "-o", out)] * 2,
                 scratch)
    if any(code != 0 for code, _ in done):
        raise Garbage(f"two corrections at once: statuses {[c for c, _ in done]}: "
                      f"{[e.strip()[-200:] for _, e in done]}")
    with DemoStore(out, read_only=True) as s:
        sources = [d.source for d in s.demonstrations()]
    if not sources or len(sources) != len(set(sources)):
        raise Garbage(f"two corrections at once stored {len(sources)} labels of "
                      f"{len(set(sources))} steps")


def _folder_race(bases: Bases, scratch: Path) -> None:
    out = scratch / "suite"
    command = _footfall("benchmark-terrain", "--suite", "training", "--kind", "slope", "--who",
                        "hand", "--boards", "1", "--runs", "1", "--processes", "1", "--out", out)
    done = _both([command, command], scratch)
    for code, err in done:
        lines = err.strip().splitlines()
        if code not in (0, 2) or (code == 2 and (len(lines) != 1 or "is in use" not in err)):
            raise Garbage(f"a command beside another in one folder ended with status {code}: "
                          f"{lines[-1:]}")
    if all(code != 0 for code, _ in done):
        raise Garbage("two commands into one folder: neither walked")
    with DemoStore(out / "suite.sqlite", read_only=True) as s:
        keys = [r["key"] for r in s.runs()]
    if not keys or len(keys) != len(set(keys)):
        raise Garbage(f"two commands into one folder stored {len(keys)} runs of "
                      f"{len(set(keys))} keys")


def _race_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    if len(case) == 1:
        return lambda: (_corrections_race if case[0] == "correct" else _folder_race)(
            bases, scratch)
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
