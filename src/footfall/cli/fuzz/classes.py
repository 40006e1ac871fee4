"""The fuzz target of the bad-input classes a new command could forget (docs/bad-input.md):
an output that is an existing file of another kind, an input given twice, an option given
twice, and settings or data that say nothing.

* ``kind``: a writer (``learn``, ``terrain make``, ``terrain board``, ``terrain import``,
  ``outcomes --fit``, ``demos collect``, ``demos correct``, ``walk --log``) given as its output
  an existing file of each kind (a board, a model, a store, expert settings, another
  program's file). It must refuse another footfall kind in one line and leave the file as it
  was; over its own kind, or another program's file of its suffix, it may write, and the file
  must then be of the writer's kind.
* ``twice``: a command that takes several stores or files given one of them twice -- by the
  same name, another path, a symbolic or a hard link: refused in one line.
* ``option``: a command with an option that takes one value given twice: refused in one line.
* ``nothing``: expert settings whose every weight is 0, or demonstrations whose candidates are
  one foothold: refused in one line.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import shutil
import sqlite3
from collections.abc import Callable
from pathlib import Path

import numpy as np
from hypothesis import strategies as st

from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import Garbage, cli_work
from footfall.cli.fuzz.targets import Target, register_target
from footfall.core.errors import FootfallError
from footfall.core.files import footfall_format
from footfall.data.demonstration import Demonstration
from footfall.data.store import DemoStore
from footfall.expert.synthetic import ExpertConfig

WRITERS = {  # name -> (arguments with {out} the output, the footfall kind it writes)
    "learn": (["learn", "{store}", "--features", "terrain", "--cv", "2", "-o", "{out}"],
              "footfall.model"),
    "terrain-make": (["terrain", "make", "flat", "--seed", "1", "-o", "{out}"],
                     "footfall.heightmap"),
    "terrain-board": (["terrain", "board", "flat", "--seed", "1", "-o", "{out}"],
                      "footfall.heightmap"),
    "terrain-import": (["terrain", "import", "{map}", "-o", "{out}"], "footfall.heightmap"),
    "outcomes": (["outcomes", "{store}", "--fit", "slid", "-o", "{out}"], "footfall.expert"),
    "demos-collect": (["demos", "collect", "--terrain", "{map}", "-n", "2", "--seed", "0",
                       "-o", "{out}"], "footfall.demostore"),
    "demos-correct": (["demos", "correct", "{store}", "-o", "{out}"], "footfall.demostore"),
    "walk-log": (["walk", "--terrain", "{flat}", "--seed", "0", "--log", "{out}"],
                 "footfall.demostore"),
}
EXISTING = ("map.npz", "model.npz", "store.sqlite", "expert.json", "other.json", "other.npz",
            "other.sqlite")
TWICE = {  # name -> arguments with {a} and {b} one file by two names
    "outcomes": ["outcomes", "{a}", "{b}"],
    "learn-trials": ["learn", "--trials", "{a}", "--trials", "{b}", "--features", "terrain",
                     "-o", "{scratch}/m.npz"],
    "demos-correct": ["demos", "correct", "{a}", "{b}", "-o", "{scratch}/d.sqlite"],
    "demos-collect": ["demos", "collect", "--terrain", "{ma}", "--terrain", "{mb}", "-n", "2",
                      "--seed", "0", "-o", "{scratch}/d.sqlite"],
    "rank-eval": ["rank-eval", "{mda}", "{mdb}", "{a}", "--no-expert"],
    "benchmark-terrain": ["benchmark-terrain", "--model", "x={mda}", "--model", "y={mdb}",
                          "--out", "{scratch}/suite"],
}
OPTIONS = (  # a command with an option that takes one value, given twice
    ["terrain", "make", "flat", "--seed", "1", "--seed", "2", "-o", "{scratch}/x.npz"],
    ["walk", "--terrain", "{flat}", "--seed", "0", "--seed", "1"],
    ["rank-eval", "--reward", "hand-tuned", "--reward", "expert", "{store}"],
    ["learn", "{store}", "--features", "terrain", "--features", "both", "-o", "{scratch}/m.npz"],
    ["demos", "correct", "{store}", "--margin", "1", "--margin", "2", "-o", "{scratch}/d.sqlite"],
    ["outcomes", "{store}", "--horizon", "1", "--horizon=2"],
)
class_cases = st.one_of(
    st.tuples(st.just("kind"), st.sampled_from(sorted(WRITERS)), st.sampled_from(EXISTING)),
    st.tuples(st.just("twice"), st.sampled_from(sorted(TWICE)),
              st.sampled_from(("same", "path", "symlink", "hardlink"))),
    st.tuples(st.just("option"), st.integers(0, len(OPTIONS) - 1), st.just("")),
    st.tuples(st.just("nothing"), st.sampled_from(("zero-expert", "one-foothold")), st.just("")),
)


def _existing(bases: Bases, name: str, path: Path) -> None:
    """A file of the kind ``name`` (see EXISTING) at ``path``."""
    sources = {"map.npz": bases.small_map, "model.npz": bases.model,
               "store.sqlite": bases.store}
    if name in sources:
        shutil.copyfile(sources[name], path)
    elif name == "expert.json":
        path.write_text(json.dumps({"format": "footfall.expert", "version": 1,
                                    "expert": ExpertConfig().to_dict()}))
    elif name == "other.json":
        path.write_text(json.dumps({"notes": "another program's"}))
    elif name == "other.npz":
        np.savez(path, x=np.arange(3))
    else:
        con = sqlite3.connect(path)
        con.execute("CREATE TABLE notes (x)")
        con.commit()
        con.close()


def _kind_work(bases: Bases, scratch: Path, writer: str, existing: str) -> None:
    args, writes = WRITERS[writer]
    out = scratch / f"out{Path(existing).suffix}"
    _existing(bases, existing, out)
    found = footfall_format(out)
    digest = hashlib.sha256(out.read_bytes()).hexdigest()
    other_kind = found is not None and found != writes
    argv = [a.format(out=out, store=bases.store, map=bases.small_map, flat=bases.flat)
            for a in args]
    try:
        cli_work(argv, must_refuse=other_kind, cwd=scratch)()
    except FootfallError:
        if hashlib.sha256(out.read_bytes()).hexdigest() != digest:
            raise Garbage(f"{writer} refused but changed {existing}") from None
        raise
    if footfall_format(out) != writes:
        raise Garbage(f"{writer} over {existing} left a {footfall_format(out)} file, not "
                      f"a {writes}")


def _twice_work(bases: Bases, scratch: Path, command: str, how: str) -> None:
    names = {}  # {a}/{b}: a store, {ma}/{mb}: a board, {mda}/{mdb}: a model; each one file
    for (one, two), source in ((("a", "b"), bases.store), (("ma", "mb"), bases.small_map),
                               (("mda", "mdb"), bases.model)):
        first = scratch / Path(source).name
        shutil.copyfile(source, first)
        other = {"same": first, "path": scratch / ".." / scratch.name / first.name,
                 "symlink": scratch / f"sym-{first.name}",
                 "hardlink": scratch / f"hard-{first.name}"}[how]
        if how == "symlink":
            other.symlink_to(first)
        elif how == "hardlink":
            os.link(first, other)
        names[one], names[two] = first, other
    _refused_because([a.format(scratch=scratch, **names) for a in TWICE[command]], scratch,
                     "is given twice", f"{command}: an input given twice ({how})")


def _refused_because(argv: list[str], scratch: Path, reason: str, what: str) -> None:
    """``footfall ARGV`` must be refused in one line that says ``reason`` (the refusal
    propagates, counted by the harness); refused for another reason, it is garbage."""
    try:
        cli_work(argv, must_refuse=True, cwd=scratch)()
    except FootfallError as exc:
        if reason not in str(exc):
            raise Garbage(f"{what} refused for another reason: {exc}") from None
        raise


def _nothing_work(bases: Bases, scratch: Path, what: str) -> None:
    if what == "zero-expert":
        zero = {f.name: 0.0 for f in dataclasses.fields(ExpertConfig)
                if f.name.startswith("w_")}
        path = scratch / "zero.json"
        path.write_text(json.dumps({"format": "footfall.expert", "version": 1,
                                    "expert": {**ExpertConfig().to_dict(), **zero}}))
        argv = ["rank-eval", "--reward", "hand-tuned", str(bases.store), "--expert-config",
                str(path)]
    else:
        store = scratch / "one.sqlite"
        with DemoStore(bases.store, read_only=True) as s:
            demos = s.demonstrations()
            maps = [s.terrain(h) for h in {d.terrain_hash for d in demos}]
        same = [Demonstration(d.terrain_hash, d.state, np.repeat(d.candidates[:1], 4, axis=0),
                              0, source="walker") for d in demos]
        with DemoStore(store, create=True) as s:
            s.add_demonstrations(same, terrains=maps)
        argv = ["learn", str(store), "--features", "terrain", "--cv", "2", "-o",
                str(scratch / "m.npz")]
    cli_work(argv, must_refuse=True, cwd=scratch)()


def _class_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    kind, what, how = case

    def work() -> None:
        if kind == "kind":
            _kind_work(bases, scratch, what, how)
        elif kind == "twice":
            _twice_work(bases, scratch, what, how)
        elif kind == "option":
            _refused_because([a.format(scratch=scratch, store=bases.store, flat=bases.flat)
                              for a in OPTIONS[what]], scratch, "is given twice",
                             "an option given twice")
        else:
            _nothing_work(bases, scratch, what)
    return work


register_target(Target("classes", class_cases, _class_work, seconds=60.0))
