"""The loaders and commands under fuzz, each with its inputs (a Hypothesis strategy) and its oracle.

A target turns one drawn case into a file or an argument list in a scratch directory, runs
the loader or command on it, and -- when it is accepted -- checks the result as a user
would rely on it (:class:`~footfall.cli.fuzz.harness.Garbage` if not). Register a
new one with :func:`register_target`.
"""

from __future__ import annotations

import json
import math
import shutil
import sqlite3
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import strategies as st

from footfall.cli.fuzz import craft, values
from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import Garbage, Outcome, cli_work, guarded

HEIGHT_BOUND = 1e5  # [m] no height of an accepted map is this large
ORIGIN_BOUND = 1e6  # [m] nor its origin this far from the frame's


@dataclass(frozen=True)
class Target:
    """A loader or command under fuzz."""

    name: str
    cases: st.SearchStrategy  # what one input is made from
    work: Callable[[Any, Bases, Path], Callable[[], None]]  # (case, bases, scratch) -> work
    seconds: float = 10.0  # [s] the time limit of one input


TARGETS: dict[str, Target] = {}


def register_target(target: Target) -> Target:
    """Add ``target`` to :data:`TARGETS` (by its name)."""
    TARGETS[target.name] = target
    return target


def run_case(target: Target, case: Any, bases: Bases, scratch: Path) -> Outcome:
    """Run one case of ``target`` in a fresh ``scratch`` directory and classify it."""
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)
    return guarded(target.name, repr(case)[:500], target.work(case, bases, scratch),
                   target.seconds)


# ------------------------------------------------------------------ oracles
def check_map(hmap: Any) -> None:
    """An accepted height map must be one footfall can use: finite numbers, sane sizes."""
    from footfall.core.files import checked_json
    from footfall.core.heightmap import HeightMap
    from footfall.expert.collect import rough_x_range
    from footfall.terrain.saving import summarise_map

    if not isinstance(hmap, HeightMap):
        raise Garbage(f"not a HeightMap: {type(hmap).__name__}")
    h = hmap.heights
    if h.ndim != 2 or h.dtype.kind != "f":
        raise Garbage(f"heights of shape {h.shape} and dtype {h.dtype}")
    known = h[~np.isnan(h)]
    if known.size == 0 or not np.all(np.abs(known) < HEIGHT_BOUND):
        raise Garbage("heights missing, infinite or absurd")
    r, (ox, oy) = hmap.resolution, hmap.origin
    if not (math.isfinite(r) and 0 < r <= 10 and abs(ox) <= ORIGIN_BOUND
            and abs(oy) <= ORIGIN_BOUND):
        raise Garbage(f"resolution {r!r} or origin {hmap.origin!r}")
    checked_json(hmap.metadata, "metadata")
    summary = summarise_map(hmap, "fuzz.npz")
    json.dumps(summary.as_dict(), allow_nan=False)
    rough_x_range(hmap)
    hmap.height_at(np.array([[ox + r, oy + r]]))


def check_model(model: Any, bases: Bases) -> None:
    """An accepted model must rank footholds with finite rewards on a valid map."""
    from footfall.core.heightmap import HeightMap
    from footfall.core.state import nominal_state
    from footfall.features.candidates import reachable_footholds
    from footfall.features.scoring import score_footholds

    hmap = HeightMap.load(bases.map)
    for leg in ("LF", "RH"):
        state = nominal_state(hmap, (0.3, 0.0), 0.0, leg)
        footholds = reachable_footholds(hmap, state)[::25]
        rewards = score_footholds(hmap, state, footholds, model.reward_for(leg), model.robot)
        valid = rewards[np.isfinite(rewards)]
        if np.isnan(rewards).any() or np.isposinf(rewards).any() or valid.size == 0:
            raise Garbage(f"{leg} rewards not finite: {rewards[:5]}")


def check_demonstrations(path: Path) -> None:
    """Every demonstration read from an accepted store holds finite numbers of the right shape."""
    from footfall.learning.train import store_demonstrations

    demos, terrains = store_demonstrations(path)
    for hmap in terrains.values():
        check_map(hmap)
    for d in demos:
        c = np.asarray(d.candidates)
        if c.ndim != 2 or c.shape[1] != 3 or c.dtype != np.float64 or not np.isfinite(c).all():
            raise Garbage(f"demonstration {d.id}: candidates {c.shape} {c.dtype}")
        if not (isinstance(d.chosen, int) and 0 <= d.chosen < len(c)):
            raise Garbage(f"demonstration {d.id}: chosen {d.chosen!r} of {len(c)}")
        if d.terrain_hash not in terrains:
            raise Garbage(f"demonstration {d.id}: its terrain is missing")
        for name in ("body_position", "body_rpy", "feet"):
            a = np.asarray(getattr(d.state, name))
            if not np.isfinite(a).all():
                raise Garbage(f"demonstration {d.id}: state {name} not finite")


# ------------------------------------------------------------------ footfall .npz files
def _json_paths(value: Any, at: tuple = ()) -> list[tuple]:
    out = [at]
    if isinstance(value, dict):
        for k, v in value.items():
            out += _json_paths(v, at + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            out += _json_paths(v, at + (i,))
    return out


def edit_json(meta: Any, selector: int, op: str, new: Any) -> Any:
    """``meta`` with the node chosen by ``selector`` replaced, deleted or wrapped (``op``)."""
    meta = json.loads(json.dumps(meta))
    paths = _json_paths(meta)
    path = paths[selector % len(paths)]
    if not path:
        return new if op == "replace" else [meta]
    parent = meta
    for key in path[:-1]:
        parent = parent[key]
    key = path[-1]
    if op == "delete":
        del parent[key]
    elif op == "wrap":
        parent[key] = [parent[key]]
    elif op == "add" and isinstance(parent, dict):
        parent[f"{key}_extra"] = new
    else:
        parent[key] = new
    return meta


_npz_mutation = st.one_of(
    st.tuples(st.just("meta"), st.integers(0, 10 ** 6),
              st.sampled_from(["replace", "replace", "delete", "wrap", "add"]), values.json_value),
    st.tuples(st.just("array"), st.integers(0, 10 ** 6), values.array_edit),
    st.tuples(st.just("member"), st.integers(0, 10 ** 6),
              st.sampled_from(["drop", "pickle", "huge", "broken_header", "rename", "extra",
                               "format", "version"]), values.json_scalar),
    st.tuples(st.just("zip"), st.sampled_from(craft.ZIP_EDITS), st.integers(0, 2 ** 31 - 1)),
)
npz_cases = st.lists(_npz_mutation, min_size=1, max_size=3)


def _read_base(path: Path) -> tuple[str, Any, dict[str, np.ndarray], Any]:
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    return (str(arrays.pop("format")), int(arrays.pop("version")), arrays,
            json.loads(str(arrays.pop("meta"))))


def _member_edit(members: dict, selector: int, op: str, scalar: Any, scratch: Path) -> None:
    names = sorted(members)
    name = names[selector % len(names)]
    if op == "drop":
        members.pop(name)
    elif op == "pickle":
        members[name] = craft.pickle_member(str(scratch / "PICKLE_RAN"))
    elif op == "huge":
        members[name] = craft.huge_member((1 << 20, 1 << 18))
    elif op == "broken_header":
        members[name] = b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (3," \
                        + b" " * 40 + b"\n"
    elif op == "rename":
        members["../" + name] = members.pop(name)
    elif op == "extra":
        members["extra"] = np.zeros(3)
    elif op == "format":
        members["format"] = np.array(scalar if isinstance(scalar, str) else str(scalar))
    else:  # version
        try:
            version = np.array(scalar)
        except (ValueError, TypeError, OverflowError):
            version = np.array(str(scalar))
        members["version"] = version if version.dtype != object else np.array(str(scalar))


def build_npz(base: Path, mutations: list, scratch: Path) -> Path:
    """A copy of the footfall file ``base`` with ``mutations`` applied, written raw."""
    fmt, version, arrays, meta = _read_base(base)
    zip_edits = []
    members: dict[str, Any] = {}
    for m in mutations:
        if m[0] == "meta":
            meta = edit_json(meta, m[1], m[2], m[3])
        elif m[0] == "array" and arrays:
            name = sorted(arrays)[m[1] % len(arrays)]
            arrays[name] = values.edit_array(arrays[name], m[2])
    members = craft.footfall_members(fmt, version, arrays, meta)
    for m in mutations:
        if m[0] == "member":
            _member_edit(members, m[1], m[2], m[3], scratch)
        elif m[0] == "zip":
            zip_edits.append(m)
    data = craft.write_npz(members)
    for _, edit, k in zip_edits:
        data = craft.patch_zip(data, edit, k)
    out = scratch / "input.npz"
    out.write_bytes(data)
    return out


def _no_pickle(scratch: Path) -> None:
    if (scratch / "PICKLE_RAN").exists():
        raise Garbage("a pickle in the file was run")


def _map_work(case: list, bases: Bases, scratch: Path) -> Callable[[], None]:
    def work() -> None:
        from footfall.core.heightmap import HeightMap

        path = build_npz(bases.small_map, case, scratch)
        try:
            check_map(HeightMap.load(path))
        finally:
            _no_pickle(scratch)
    return work


def _model_work(case: list, bases: Bases, scratch: Path) -> Callable[[], None]:
    def work() -> None:
        from footfall.learning.model import FootholdModel

        path = build_npz(bases.model, case, scratch)
        try:
            check_model(FootholdModel.load(path), bases)
        finally:
            _no_pickle(scratch)
    return work


register_target(Target("map-file", npz_cases, _map_work))
register_target(Target("model-file", npz_cases, _model_work))


# ------------------------------------------------------------------ stores
_TABLES = ("meta", "terrains", "demonstrations", "runs", "steps")
FOREIGN_DDL = {
    "trigger": "CREATE TRIGGER fuzz_t AFTER INSERT ON demonstrations BEGIN "
               "DELETE FROM demonstrations; END",
    "view": "CREATE VIEW fuzz_v AS SELECT 1",
    "table": "CREATE TABLE fuzz_table (x)",
    "index": "CREATE INDEX fuzz_i ON demonstrations (chosen)",
}
_store_mutation = st.one_of(
    st.tuples(st.just("cell"), st.sampled_from(_TABLES), st.integers(0, 10 ** 6),
              st.integers(0, 10 ** 6), values.sql_value),
    st.tuples(st.just("ddl"), st.sampled_from(sorted(FOREIGN_DDL))),
    st.tuples(st.just("drop"), st.sampled_from(_TABLES)),
    st.tuples(st.just("bytes"), st.sampled_from(["flip", "truncate", "zero_run"]),
              st.integers(0, 2 ** 31 - 1)),
)
store_cases = st.tuples(st.lists(_store_mutation, min_size=1, max_size=3),
                        st.sampled_from(["read", "check", "info", "collect"]))


def _edit_store(path: Path, mutations: list) -> bool:
    """Apply the SQL mutations to the store at ``path``; whether a foreign object was added."""
    foreign = False
    con = sqlite3.connect(path, isolation_level=None)
    try:
        for m in mutations:
            if m[0] == "cell":
                _, table, row, column, value = m
                cols = [r[1] for r in con.execute(f"PRAGMA table_info({table})")]
                ids = [r[0] for r in con.execute(f"SELECT rowid FROM {table}")]
                if cols and ids:
                    con.execute(f"UPDATE {table} SET {cols[column % len(cols)]} = ? "
                                f"WHERE rowid = ?", (value, ids[row % len(ids)]))
            elif m[0] == "ddl":
                con.execute(FOREIGN_DDL[m[1]])
                foreign = True
            elif m[0] == "drop":
                con.execute("PRAGMA foreign_keys = OFF")
                con.execute(f"DROP TABLE IF EXISTS {m[1]}")
    except (sqlite3.Error, OverflowError):
        pass  # a mutation SQLite refuses is simply not made
    finally:
        con.close()
    return foreign


def _store_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    mutations, action = case

    def work() -> None:
        path = scratch / "store.sqlite"
        shutil.copyfile(bases.store, path)
        foreign = _edit_store(path, [m for m in mutations if m[0] != "bytes"])
        for _, edit, k in (m for m in mutations if m[0] == "bytes"):
            path.write_bytes(craft.patch_zip(path.read_bytes(), edit, k))
        if action == "read":
            check_demonstrations(path)
        elif action == "check":  # a store the check passes must read as valid
            cli_work(["store", "check", str(path)], must_refuse=foreign)()
            check_demonstrations(path)
        elif action == "info":
            cli_work(["demos", "info", str(path)], must_refuse=False)()
        else:
            cli_work(["demos", "collect", "--terrain", str(bases.map), "-n", "1", "--seed", "3",
                      "-o", str(path)], must_refuse=foreign)()
    return work


register_target(Target("store", store_cases, _store_work, seconds=20.0))


# ------------------------------------------------------------------ imported scans
_scan_mutation = st.one_of(
    st.tuples(st.just("bytes"), st.sampled_from(["flip", "truncate", "insert", "delete",
                                                 "zero_run"]), st.integers(0, 2 ** 31 - 1)),
    st.tuples(st.just("line"), st.integers(0, 10 ** 6),
              st.sampled_from(["nan nan nan", "1e400 0 0", "a b c", "1 2", "1 2 3 4 5",
                               "-1e300 1e300 0", "", "element vertex 999999999999",
                               "format binary_little_endian 1.0", "property list uchar int x"])),
    st.tuples(st.just("array"), values.array_edit),
)
_number_arg = st.one_of(st.none(), st.sampled_from([0.005, 0.001, 1e-3, 0.02]),
                        st.sampled_from(values._SPECIAL_NUMBERS), st.floats())
scan_cases = st.tuples(st.sampled_from([".npy", ".png", ".ply", ".xyz"]),
                       st.lists(_scan_mutation, max_size=3), _number_arg, _number_arg,
                       _number_arg)


def _mutated_scan(source: Path, mutations: list, out: Path) -> None:
    data = source.read_bytes()
    for m in mutations:
        if m[0] == "array" and source.suffix == ".npy":
            array = np.load(source, allow_pickle=False)
            data = craft.npy_bytes(values.edit_array(array, m[1]))
        elif m[0] == "line" and source.suffix in (".ply", ".xyz"):
            lines = data.split(b"\n")
            lines[m[1] % len(lines)] = m[2].encode()
            data = b"\n".join(lines)
        elif m[0] == "bytes":
            data = craft.patch_zip(data, m[1], m[2])
    out.write_bytes(data)


def _scan_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    suffix, mutations, resolution, z_scale, nodata = case

    def work() -> None:
        from footfall.terrain.scans import import_terrain

        path = scratch / f"scan{suffix}"
        _mutated_scan(bases.scans[suffix], mutations, path)
        if resolution is None and suffix in (".npy", ".png"):
            res = 0.008
        else:
            res = resolution
        z = 1e-5 if z_scale is None and suffix == ".png" else z_scale
        check_map(import_terrain(path, resolution=res, z_scale=z, nodata=nodata))
    return work


register_target(Target("scan-import", scan_cases, _scan_work))
