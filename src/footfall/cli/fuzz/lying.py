"""The fuzz target of files that look valid but lie: well-formed containers of wrong meaning.

A board whose module records lie off its map, whose resolution disagrees with its records, or
that was moved far from its frame's origin; a store whose labels, "never here" marks, sources or
step counts name what is not there; a model that cannot tell candidates apart, whose templates
are not the patches of the terrains it claims, or that names its terrains by no hash at all (one
that names terrains not in the store is ranked, and not said to be trained on them); a command
whose output is one of its inputs. Each lie must be refused in one line -- or, where it is
honest after all (no shift, the same resolution), be accepted -- and a refused command must
leave its input as it was.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import sqlite3
from collections.abc import Callable
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
from hypothesis import strategies as st

from footfall.cli.entry import main
from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import Garbage, cli_work
from footfall.cli.fuzz.targets import Target, register_target
from footfall.core.files import load_npz, save_npz
from footfall.core.heightmap import MAX_BOARD_OFFSET, HeightMap
from footfall.data.store import DemoStore
from footfall.experiments.batch import load_board
from footfall.learning import model as model_file

_SHIFTS = (0.0, 0.004, 0.5, 50.0, 1e6)  # [m] how far a lie moves records or a board
lying_cases = st.one_of(
    st.tuples(st.just("records"), st.sampled_from(_SHIFTS)),
    st.tuples(st.just("resolution"), st.sampled_from((1.0, 0.5, 2.0, 1.001))),
    st.tuples(st.just("moved"), st.sampled_from(_SHIFTS + (-2e3, 999.0))),
    st.tuples(st.just("store"), st.sampled_from(("chosen", "mark", "source", "n_steps"))),
    st.tuples(st.just("model"), st.sampled_from(("zero", "edited", "nowhere", "malformed"))),
    st.tuples(st.just("output"), st.sampled_from(("same", "hardlink", "symlink"))),
)


def _board(bases: Bases, path: Path, kind: str, amount: float) -> bool:
    """The base board saved to ``path`` with one lie of ``amount``; whether it is a lie a
    walk must refuse."""
    hm = HeightMap.load(bases.flat)
    meta = json.loads(json.dumps(hm.metadata))
    modules = meta.get("modules", [])
    origin, resolution = hm.origin, hm.resolution
    if kind == "records":  # the records move, the map does not
        for m in modules:
            m["x_start"] += amount
            m["x_end"] += amount
        lie = amount > 1e-9 and bool(modules)
    elif kind == "resolution":  # the array is said to be coarser or finer than it is
        resolution = hm.resolution * amount
        lie = amount != 1.0 and bool(modules)
    else:  # the board moved whole (its records are in its own frame: they stay)
        origin = (hm.origin[0] + amount, hm.origin[1])
        x0, x1 = origin[0], origin[0] + hm.heights.shape[0] * resolution
        lie = max(abs(x0), abs(x1)) > MAX_BOARD_OFFSET
    HeightMap(hm.heights, resolution, origin, hm.frame, meta).save(path)
    return lie


def _store(bases: Bases, path: Path, kind: str) -> None:
    """A copy of the base store with a reference to nothing (its run's first step labelled,
    or marked "never here", on a candidate it does not have, a demonstration from a run it
    does not hold, a run whose step count is not its steps')."""
    shutil.copyfile(bases.store, path)
    with DemoStore(path):  # a base store of an older footfall gains the newer tables
        pass
    con = sqlite3.connect(path, isolation_level=None)
    try:
        if kind == "chosen":  # a person's "fine" beyond the step's candidates
            con.execute("INSERT INTO labels (run_id, k, labeler, verdict, chosen, created) "
                        "SELECT run_id, k, 'fuzz', 'fine', 99999, 0 FROM run_steps LIMIT 1")
        elif kind == "mark":  # a person's "never here" beyond the step's candidates
            con.execute("INSERT INTO marks (run_id, k, labeler, candidate, created) "
                        "SELECT run_id, k, 'fuzz', 99999, 0 FROM run_steps LIMIT 1")
        elif kind == "source":
            con.execute("UPDATE demonstrations SET source = 'run:999:step:3' WHERE id = "
                        "(SELECT min(id) FROM demonstrations)")
        else:
            con.execute("UPDATE runs SET n_steps = n_steps + 1")
    finally:
        con.close()


def _model(bases: Bases, path: Path, kind: str) -> None:
    """The base model with every weight zero, its templates edited, or its terrains renamed."""
    _, arrays, meta = load_npz(bases.model, model_file.FORMAT, model_file.VERSION,
                               allow_nonfinite=True)
    if kind == "zero":
        arrays = {k: np.zeros_like(v) if k.endswith(".coef") else v for k, v in arrays.items()}
    elif kind == "edited":
        arrays = {k: v + 0.001 if k.endswith("_templates") else v for k, v in arrays.items()}
    else:  # a well-formed hash of no terrain, or no hash at all
        text = json.dumps(meta)
        for h in _library_hashes(meta):
            text = text.replace(h, "f" * 64 if kind == "nowhere" else "no-such-terrain")
        meta = json.loads(text)
    save_npz(path, model_file.FORMAT, model_file.VERSION, arrays, meta)


def _library_hashes(meta: dict) -> set[str]:
    return {h for g in meta["groups"].values() for fam in g["families"]
            for h in fam["params"].get("library", {}).get("terrain_hashes", [])}


def _rank(model: Path, store: Path) -> dict:
    """``footfall rank-eval MODEL STORE --no-expert --json``'s result (refusals raise)."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(["rank-eval", str(model), str(store), "--no-expert", "--json"])
    if code != 0:
        raise Garbage(f"rank-eval of a model it must rank ended with status {code}: "
                      f"{err.getvalue().strip()[:200]}")
    return json.loads(out.getvalue())


def _lying_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    kind, what = case

    def work() -> None:
        if kind in ("records", "resolution", "moved"):
            path = scratch / "board.npz"
            lie = _board(bases, path, kind, what)
            load_board(path)  # refusal raises FootfallError: the harness counts it
            if lie:
                raise Garbage(f"a board whose {kind} lie ({what}) was accepted")
        elif kind == "store":
            path = scratch / "store.sqlite"
            _store(bases, path, what)
            cli_work(["store", "check", str(path)], must_refuse=True)()
        elif kind == "model":
            path = scratch / "model.npz"
            _model(bases, path, what)
            if what in ("edited", "malformed"):  # templates not of the terrains it claims
                cli_work(["rank-eval", str(path), str(bases.store), "--no-expert"],
                         must_refuse=True)()
            scores = _rank(path, bases.store)
            if what == "zero" and not (scores["constant"] == 1.0 and scores["top1"] < 1.0):
                raise Garbage(f"an all-zero model scored top-1 {scores['top1']}, "
                              f"constant {scores['constant']}")
            if what == "nowhere" and scores["trained_here"] != 0:
                raise Garbage("a model of other terrains was said to be trained on these")
        else:
            _output_is_input(bases, scratch, what)
    return work


def _output_is_input(bases: Bases, scratch: Path, how: str) -> None:
    """``learn STORE -o OUT`` with OUT the store itself, a hard link or a symlink to it: must be
    refused, and the store must hold what it held."""
    store = scratch / "store.npz"  # a store under a model's name
    shutil.copyfile(bases.store, store)
    out = {"same": store, "hardlink": scratch / "link.npz", "symlink": scratch / "sym.npz"}[how]
    if how == "hardlink":
        os.link(store, out)
    elif how == "symlink":
        out.symlink_to(store)
    with DemoStore(bases.store, read_only=True) as s:
        before = len(s.demonstrations())
    try:
        cli_work(["learn", str(store), "--features", "terrain", "-o", str(out)],
                 must_refuse=True)()
    finally:  # refused or not, the input must hold what it held
        with DemoStore(store, read_only=True) as s:
            if len(s.demonstrations()) != before:
                raise Garbage(f"the input store lost demonstrations ({how})")


register_target(Target("lying-file", lying_cases, _lying_work, seconds=60.0))
