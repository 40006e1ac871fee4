"""Fuzz targets of footfall's files: height maps and model files (``.npz``), imported scans.

A case rebuilds a valid file with its JSON metadata, arrays, members or zip bytes damaged
(:mod:`.craft`, :mod:`.values`), or damages a scan's bytes, lines or array.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import strategies as st

from footfall.cli.fuzz import craft, values
from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import Garbage
from footfall.cli.fuzz.oracles import check_map, check_model
from footfall.cli.fuzz.targets import Target, register_target
from footfall.core.heightmap import HeightMap
from footfall.learning.model import FootholdModel
from footfall.terrain.scans import import_terrain


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
        path = build_npz(bases.small_map, case, scratch)
        try:
            check_map(HeightMap.load(path))
        finally:
            _no_pickle(scratch)
    return work


def _model_work(case: list, bases: Bases, scratch: Path) -> Callable[[], None]:
    def work() -> None:
        path = build_npz(bases.model, case, scratch)
        try:
            check_model(FootholdModel.load(path), bases)
        finally:
            _no_pickle(scratch)
    return work


register_target(Target("map-file", npz_cases, _map_work))
register_target(Target("model-file", npz_cases, _model_work))


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


# ------------------------------------------------- surveyed maps: bags, LAS / LAZ, GeoTIFF
_survey_options = st.fixed_dictionaries({}, optional={
    "topic": st.sampled_from(["/map", "/elevation_mapping/elevation_map", "", "/x"]),
    "layer": st.sampled_from(["elevation", "variance", "", "footfall_score"]),
    "message": st.integers(-3, 3),
    "time": st.one_of(st.sampled_from(values._SPECIAL_NUMBERS), st.floats()),
    "classes": st.lists(st.integers(0, 255), min_size=1, max_size=3).map(tuple),
    "statistic": st.sampled_from(["max", "min", "mean"]),
    "band": st.integers(1, 3),
    "bounds": st.tuples(*[st.sampled_from([-1e9, -0.1, 0.0, 0.05, 0.2, 1e9])] * 4),
    "resolution": st.one_of(st.sampled_from([0.005, 0.02]), st.sampled_from(
        values._SPECIAL_NUMBERS)),
})
survey_cases = st.tuples(st.sampled_from([".mcap", ".db3", ".las", ".laz", ".tif"]),
                         st.lists(st.tuples(st.sampled_from(["flip", "truncate", "insert",
                                                             "delete", "zero_run"]),
                                            st.integers(0, 2 ** 31 - 1)), max_size=3),
                         _survey_options)


def _survey_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    suffix, edits, options = case

    def work() -> None:
        path = scratch / f"survey{suffix}"
        data = bases.scans[suffix].read_bytes()
        for edit, k in edits:
            data = craft.patch_zip(data, edit, k)
        path.write_bytes(data)
        given = dict(options)
        if suffix in (".las", ".laz"):  # a cloud needs a cell size; mostly a usable one
            given.setdefault("resolution", 0.01)
        check_map(import_terrain(path, **given))
    return work


register_target(Target("survey-import", survey_cases, _survey_work))
