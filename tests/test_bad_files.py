"""Bad files never crash, hang or slip through: each becomes one clear FootfallError line.

Issue 17, the files part: crafted .npz archives (corrupt, encrypted, oddly compressed,
decompression bombs, lying headers, hostile metadata), height maps with garbage geometry,
imports above the size limits, user strings in plots, output paths and interrupted writes.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import struct
import time
import tracemalloc
import warnings
import zipfile

import numpy as np
import pytest
from PIL import Image

from cli_helpers import assert_user_error, run
from footfall.core.atomic import atomic_path, remove_stale_temporaries
from footfall.core.errors import FootfallError
from footfall.core.files import json_depth, load_npz, writable_path
from footfall.core.heightmap import HeightMap, module_records
from footfall.core.limits import Limits, use_limits
from footfall.core.npz import read_npz_members
from footfall.terrain.scans import import_terrain

ROOT = os.geteuid() == 0 if hasattr(os, "geteuid") else False


# ------------------------------------------------------------------ crafting files
def npy_bytes(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.asanyarray(array), allow_pickle=False)
    return buf.getvalue()


def npy_with_header(header: str, data: bytes = b"") -> bytes:
    """A .npy (format 1.0) with a raw header text, padded as numpy pads it."""
    text = header.encode("latin1")
    pad = (64 - (10 + len(text) + 1) % 64) % 64
    text += b" " * pad + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(text)) + text + data


def map_members(heights=None, meta=None, fmt="footfall.heightmap", version=1) -> dict:
    """The members of a height-map archive as save_npz writes them (bytes of each .npy)."""
    heights = np.zeros((4, 4)) if heights is None else heights
    meta = {"resolution": 0.01, "origin": [0.0, 0.0], "frame": "world",
            "metadata": {}} if meta is None else meta
    meta_text = meta if isinstance(meta, str) else json.dumps(meta)
    return {"heights.npy": npy_bytes(heights), "format.npy": npy_bytes(np.array(fmt)),
            "version.npy": npy_bytes(np.asarray(version)), "meta.npy": npy_bytes(np.array(meta_text))}


def write_zip(path, members: dict, method=zipfile.ZIP_DEFLATED) -> None:
    with zipfile.ZipFile(path, "w", compression=method) as zf:
        for name, data in members.items():
            zf.writestr(name, data)


def patch_headers(path, offset_local: int, offset_central: int, value: int) -> None:
    """Overwrite a 2-byte field of every local and central zip header."""
    data = bytearray(path.read_bytes())
    for sig, off in ((b"PK\x03\x04", offset_local), (b"PK\x01\x02", offset_central)):
        start = 0
        while (i := data.find(sig, start)) >= 0:
            data[i + off:i + off + 2] = struct.pack("<H", value)
            start = i + 4
    path.write_bytes(bytes(data))


def load_error(path, match: str) -> str:
    with pytest.raises(FootfallError, match=match) as info:
        HeightMap.load(path)
    message = str(info.value)
    assert str(path) in message and "\n" not in message
    return message


@pytest.fixture
def good_map(tmp_path):
    path = tmp_path / "good.npz"
    HeightMap(np.random.default_rng(0).uniform(0, 0.05, (30, 20)), 0.01).save(path)
    return path


# ------------------------------------------------------------------------ archives
def test_corrupt_deflate_stream(tmp_path):
    path = tmp_path / "corrupt.npz"
    write_zip(path, map_members(np.random.default_rng(1).normal(size=(64, 64))))
    with zipfile.ZipFile(path) as zf:
        info = zf.getinfo("heights.npy")
    data = bytearray(path.read_bytes())
    start = info.header_offset + 30 + len(info.filename) + len(info.extra)
    data[start + 50:start + 250] = b"\xff" * 200
    path.write_bytes(bytes(data))
    load_error(path, "member 'heights.npy' (is corrupt|is truncated)")


def test_encrypted_member(tmp_path):
    path = tmp_path / "encrypted.npz"
    write_zip(path, map_members())
    patch_headers(path, 6, 8, 0x1)  # general purpose flag bit 0: encrypted
    load_error(path, "member 'heights.npy' is encrypted")


def test_unknown_compression_method(tmp_path):
    path = tmp_path / "method.npz"
    write_zip(path, map_members())
    patch_headers(path, 8, 10, 99)  # compression method 99 (AE-x)
    load_error(path, "compression method 99")


@pytest.mark.parametrize("name", ["../evil.npy", "dir/heights.npy", "notes.txt", ".npy"])
def test_odd_member_names(tmp_path, name):
    path = tmp_path / "names.npz"
    write_zip(path, {**map_members(), name: npy_bytes(np.zeros(2))})
    load_error(path, "is not an array")


def test_duplicate_member(tmp_path):
    path = tmp_path / "twice.npz"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # zipfile: "Duplicate name"
        with zipfile.ZipFile(path, "w") as zf:
            for name, data in map_members().items():
                zf.writestr(name, data)
            zf.writestr("heights.npy", npy_bytes(np.ones((4, 4))))
    load_error(path, "'heights.npy' occurs twice")


@pytest.mark.parametrize("header", [
    "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 4 }",  # SyntaxError
    "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 4), 'x': '''}",  # TokenError
    "{'descr': 'not a dtype', 'fortran_order': False, 'shape': (4, 4), }",
    "[1, 2, 3]",
])
def test_broken_npy_header_in_an_archive(tmp_path, header):
    path = tmp_path / "header.npz"
    write_zip(path, {**map_members(), "heights.npy": npy_with_header(header, b"\0" * 128)})
    load_error(path, "member 'heights.npy' has a broken .npy header")


@pytest.mark.parametrize("dtype", ["O", "V8", "[('a', '<f8')]"])
def test_object_record_and_void_members_are_refused(tmp_path, dtype):
    path = tmp_path / "objects.npz"
    header = f"{{'descr': {dtype if dtype.startswith('[') else repr(dtype)}, " \
             f"'fortran_order': False, 'shape': (2, 2), }}"
    write_zip(path, {**map_members(), "heights.npy": npy_with_header(header, b"\0" * 64)})
    load_error(path, "holds dtype")


def test_decompression_bomb_fails_fast_without_allocating(tmp_path):
    """A member declaring an 80 GB array is refused from its header, before reading."""
    path = tmp_path / "bomb.npz"
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (100000, 100000), }"
    write_zip(path, {**map_members(), "heights.npy": npy_with_header(header, b"\0" * 4096)})
    tracemalloc.start()
    try:
        message = load_error(path, "member 'heights.npy' declares 80000000000 bytes")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20 << 20 and "max_array_bytes" in message


def test_a_lying_header_cannot_inflate_more_than_it_declares(tmp_path):
    """The header says 4 x 4; the stream inflates to 8 MB of zeros: read 128 bytes, then refused."""
    path = tmp_path / "liar.npz"
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 4), }"
    write_zip(path, {**map_members(), "heights.npy": npy_with_header(header, bytes(8 << 20))})
    with use_limits(Limits(max_file_bytes=1 << 30)):
        load_error(path, "holds more data than its header declares")


def test_declared_total_size_above_the_file_limit(tmp_path):
    path = tmp_path / "big.npz"
    write_zip(path, map_members(np.zeros((400, 400))))  # 1.3 MB of zeros, a few kB on disk
    assert path.stat().st_size < 50_000
    with use_limits(Limits(max_file_bytes=100_000)):
        load_error(path, "would inflate to .* above the limit of 100000")


def test_file_above_the_file_limit_is_refused_by_its_size(good_map):
    with use_limits(Limits(max_file_bytes=100)):
        load_error(good_map, "bytes, above the limit of 100 .*max_file_bytes")


def test_truncated_member(tmp_path):
    path = tmp_path / "short.npz"
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (40, 40), }"
    write_zip(path, {**map_members(), "heights.npy": npy_with_header(header, b"\0" * 100)})
    load_error(path, "member 'heights.npy' is truncated")


@pytest.mark.skipif(ROOT, reason="root reads any file: permissions cannot be tested")
def test_unreadable_file_says_permission_denied(good_map, capsys, tmp_path):
    good_map.chmod(0)
    try:
        load_error(good_map, "permission denied")
        code, _, err = run(capsys, "terrain", "show", good_map, "-o", tmp_path / "r.png")
        assert_user_error(code, err, "permission denied")
    finally:
        good_map.chmod(0o644)


def test_unreadable_file_check_when_root(good_map, monkeypatch):
    """As root the permission test cannot run; os.access saying no must still be reported."""
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, mode, **kw: False if str(p) == str(good_map)
                        else real(p, mode, **kw))
    load_error(good_map, "permission denied")


# ---------------------------------------------------------------------- the header
@pytest.mark.parametrize("version, match", [
    (np.array("1"), "version must be an integer"),
    (np.array(True), "version must be an integer"),
    (np.array(1.5), "version must be an integer"),
    (np.array([1, 2]), "version must be an integer"),
])
def test_version_must_be_an_integer_scalar(tmp_path, version, match):
    path = tmp_path / "version.npz"
    write_zip(path, {**map_members(), "version.npy": npy_bytes(version)})
    load_error(path, match)


def test_format_must_be_a_string(tmp_path):
    path = tmp_path / "format.npz"
    write_zip(path, {**map_members(), "format.npy": npy_bytes(np.array([1, 2]))})
    load_error(path, "format must be a string")


def test_deeply_nested_metadata(tmp_path):
    path = tmp_path / "deep.npz"
    deep = '{"resolution": 0.01, "origin": [0, 0], "frame": "w", "metadata": {"x": ' \
           + "[" * 100_000 + "]" * 100_000 + "}}"
    write_zip(path, map_members(meta=deep))
    load_error(path, "nested 100002 levels deep, above the limit of 32")


def test_json_depth_ignores_brackets_in_strings():
    assert json_depth('{"a": "[[[[{{{", "b": [[1], {"c": "\\"]["}]}') == 3


@pytest.mark.parametrize("constant", ["NaN", "Infinity", "-Infinity", "1e400"])
def test_nan_and_infinity_in_metadata(tmp_path, constant):
    path = tmp_path / "nan.npz"
    write_zip(path, map_members(meta='{"resolution": 0.01, "origin": [0, 0], "frame": "w", '
                                     f'"metadata": {{"x": {constant}}}}}'))
    load_error(path, "meta is not valid JSON")


def test_metadata_longer_than_the_limit(tmp_path):
    path = tmp_path / "long.npz"
    write_zip(path, map_members(meta={"resolution": 0.01, "origin": [0, 0], "frame": "w",
                                      "metadata": {"x": "y" * 5000}}))
    with use_limits(Limits(max_metadata_bytes=1000)):
        load_error(path, "meta is 5.* bytes long, above the limit of 1000")


@pytest.mark.parametrize("meta, match", [
    ([1, 2], "meta must be a JSON object"),
    ({"origin": [0, 0], "frame": "w"}, "meta lacks resolution"),
    ({"resolution": "abc", "origin": [0, 0], "frame": "w"},
     "resolution must be > 0.* got 'abc'"),
    ({"resolution": True, "origin": [0, 0], "frame": "w"}, "resolution must be > 0.* got True"),
    ({"resolution": 1e300, "origin": [0, 0], "frame": "w"},
     r"resolution must be > 0: a finite number of 1e-05 .. 10 m/cell, got 1e\+300"),
    ({"resolution": 1e-300, "origin": [0, 0], "frame": "w"}, "resolution must be > 0"),
    ({"resolution": 0.01, "origin": [1e300, 0], "frame": "w"},
     r"origin must be within \+-1e\+06 m"),
    ({"resolution": 0.01, "origin": [999_999.99, 0], "frame": "w"},
     "reaches beyond 1e\\+06 m"),
    ({"resolution": 0.01, "origin": "ab", "frame": "w"}, "meta.origin must be a list"),
    ({"resolution": 0.01, "origin": [0, "1"], "frame": "w"}, "origin y .* must be a number"),
    ({"resolution": 0.01, "origin": [0, 0, 0], "frame": "w"}, "origin must be two"),
    ({"resolution": 0.01, "origin": [0, 0], "frame": 5}, "frame must be a name"),
    ({"resolution": 0.01, "origin": [0, 0], "frame": "w", "metadata": []},
     "metadata must be a JSON object, got list"),
])
def test_bad_geometry_in_the_header(tmp_path, meta, match):
    path = tmp_path / "geometry.npz"
    write_zip(path, map_members(meta=meta))
    load_error(path, match)


@pytest.mark.parametrize("heights, match", [
    (np.zeros((4, 4), dtype=complex), "heights must be float32 or float64 .* complex128"),
    (np.zeros((4, 4), dtype=bool), "heights must be float32 or float64 .* bool"),
    (np.array([["a", "b"], ["c", "d"]]), "heights must be float32 or float64"),
    (np.zeros((4, 4), dtype=np.int64), "heights must be float32 or float64 .* int64"),
    (np.zeros((2, 2, 2)), "heights must be 2-D"),
    (np.full((4, 4), 1e300), r"heights beyond \+-100000 m \(largest 1e\+300 m\)"),
    (np.array([[np.inf, 0.0], [0.0, 0.0]]), "infinite heights"),
])
def test_bad_heights_arrays(tmp_path, heights, match):
    path = tmp_path / "heights.npz"
    write_zip(path, map_members(heights))
    load_error(path, match)


def test_a_map_above_the_cell_limit_is_refused_before_reading(tmp_path):
    path = tmp_path / "cells.npz"
    write_zip(path, map_members(np.zeros((100, 100))))
    with use_limits(Limits(max_map_cells=1000)):
        load_error(path, "has 1e\\+04 cells, above the limit of 1000|would have 1e\\+04 cells")


def test_float32_heights_load(tmp_path):
    path = tmp_path / "f32.npz"
    write_zip(path, map_members(np.ones((4, 4), dtype=np.float32)))
    assert HeightMap.load(path).heights.dtype == np.float64


def test_the_safe_reader_round_trips_every_dtype_save_npz_writes(tmp_path):
    from footfall.core.files import save_npz

    arrays = {"f": np.arange(6.0).reshape(2, 3), "i": np.arange(4, dtype=">i4"),
              "b": np.array([True, False]), "e": np.zeros((0, 3)),
              "fortran": np.asfortranarray(np.arange(6).reshape(2, 3))}
    save_npz(tmp_path / "a.npz", "x", 1, arrays, {"k": [1, {"n": None}]})
    version, back, meta = load_npz(tmp_path / "a.npz", "x", 1)
    assert version == 1 and meta == {"k": [1, {"n": None}]}
    for name, a in arrays.items():
        np.testing.assert_array_equal(back[name], a)
        assert back[name].dtype == a.dtype and back[name].flags.writeable
    assert set(read_npz_members(tmp_path / "a.npz")) == set(arrays) | {"format", "version",
                                                                          "meta"}


# ------------------------------------------------------------------ module records
@pytest.mark.parametrize("modules, match", [
    ("flat", r"metadata.modules must be a list"),
    ([1, 2], r"metadata.modules\[0\] must be a module record"),
    ([{"kind": "flat", "x_start": 0.0}], r"metadata.modules\[0\] lacks x_end"),
    ([{"kind": 3, "x_start": 0.0, "x_end": 0.6}], r"modules\[0\].kind must be a string"),
    ([{"kind": "flat", "x_start": "0", "x_end": 0.6}], r"modules\[0\].x_start must be a number"),
    ([{"kind": "flat", "x_start": 0.0, "x_end": True}], r"modules\[0\].x_end must be a number"),
    ([{"kind": "flat", "x_start": 0.6, "x_end": 0.0}], "x_start 0.6 must be below x_end 0"),
    ([{"kind": "flat", "x_start": 0, "x_end": 1, "seed": 1.5}], r"\.seed must be a whole"),
    ([{"kind": "flat", "x_start": 0, "x_end": 1, "difficulty": 7}],
     r"\.difficulty must be in \[0, 1\]"),
])
def test_module_records_of_the_wrong_type(modules, match):
    with pytest.raises(FootfallError, match=match):
        module_records({"modules": modules})


def test_module_records_of_a_made_board_pass():
    from footfall.terrain import make_module

    records = module_records(make_module("flat", 0.0, 1).metadata)
    assert records[0]["kind"] == "flat"
    assert module_records({}) == [] and module_records({"other": 1}) == []


def test_walk_refuses_a_board_with_bad_module_records(tmp_path, capsys):
    path = tmp_path / "board.npz"
    HeightMap(np.zeros((60, 40)), 0.01, metadata={"modules": [1, 2]}).save(path)
    code, _, err = run(capsys, "walk", "--terrain", path, "--seed", "0")
    assert_user_error(code, err, f"{path}: metadata.modules[0] must be a module record")


# ---------------------------------------------------------------------------- CLI
def test_terrain_show_of_a_bad_file_is_one_line(tmp_path, capsys):
    path = tmp_path / "huge.npz"
    write_zip(path, map_members(meta={"resolution": 0.01, "origin": [1e300, 0], "frame": "w"}))
    code, _, err = run(capsys, "terrain", "show", path, "-o", tmp_path / "r.png")
    assert_user_error(code, err, "origin must be within")
    code, _, err = run(capsys, "terrain", "import", path, "-o", tmp_path / "i.npz")
    assert_user_error(code, err, "origin must be within")


def test_mathtext_in_a_file_name_is_drawn_as_text(good_map, tmp_path, capsys):
    odd = tmp_path / "title$\\frac$_{x}^.npz"
    shutil.copy(good_map, odd)
    code, out, err = run(capsys, "terrain", "show", odd, "-o", tmp_path / "r.png")
    assert code == 0, err
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"


def test_walk_video_with_an_unknown_suffix_fails_before_walking(good_map, tmp_path, capsys,
                                                                monkeypatch):
    import footfall.experiments.batch as batch

    def no_walk(*args, **kwargs):
        raise AssertionError("the walk started")

    monkeypatch.setattr(batch, "Walk", no_walk)  # what `footfall walk` runs
    code, _, err = run(capsys, "walk", "--terrain", good_map, "--seed", "0", "--video",
                       tmp_path / "out.txt")
    assert_user_error(code, err, "--video: ")
    assert "unknown video format '.txt' (use .mp4)" in err
    code, _, err = run(capsys, "walk", "--terrain", good_map, "--seed", "0", "--snapshots",
                       tmp_path / "strip.jpg")
    assert_user_error(code, err, "--snapshots: ")
    assert "unknown picture format '.jpg' (use .png)" in err
    with pytest.raises(FootfallError, match="video: .*unknown video format"):
        batch.walk_once(good_map, 0, video=tmp_path / "v.gif")


@pytest.mark.parametrize("args", [
    ["terrain", "make", "flat", "--seed", "1", "-o", "{tmp}/m.txt"],
    ["terrain", "board", "flat", "--seed", "1", "-o", "{tmp}/b.png"],
    ["terrain", "import", "{good}", "-o", "{tmp}/i"],
    ["terrain", "show", "{good}", "-o", "{tmp}/r.npz"],
])
def test_terrain_outputs_need_a_known_suffix(args, good_map, tmp_path, capsys):
    args = [a.format(tmp=tmp_path, good=good_map) for a in args]
    code, _, err = run(capsys, *args)
    assert_user_error(code, err, "unknown")
    assert "format" in err and "(use ." in err


def test_output_directory_without_write_permission(tmp_path, monkeypatch):
    real = os.access
    monkeypatch.setattr(os, "access", lambda p, mode, **kw: False if str(p) == str(tmp_path)
                        else real(p, mode, **kw))
    with pytest.raises(FootfallError, match="cannot write to directory .*permission denied"):
        writable_path(tmp_path / "x.npz")


# ------------------------------------------------------------------------ imports
def test_broken_npy_header_tokenize_error(tmp_path):
    path = tmp_path / "broken.npy"
    path.write_bytes(npy_with_header("{'descr': '<f8', 'shape': (3, 3), 'x': '''}", b"\0" * 72))
    with pytest.raises(FootfallError, match="not a readable .npy array"):
        import_terrain(path, resolution=0.01)


def test_npy_above_the_cell_limit_is_refused_from_its_header(tmp_path):
    path = tmp_path / "huge.npy"
    path.write_bytes(npy_with_header(
        "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000, 1000000), }", b"\0" * 64))
    tracemalloc.start()
    try:
        with pytest.raises(FootfallError, match=r"has 1000000000000 cells, above the limit"):
            import_terrain(path, resolution=0.01)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20 << 20


def test_png_above_the_cell_limit_is_one_line_without_pillow_warning(tmp_path, capsys,
                                                                     monkeypatch):
    monkeypatch.setenv("FOOTFALL_MAX_MAP_CELLS", "50000000")  # --limit sets it: undone after
    path = tmp_path / "big.png"
    Image.fromarray(np.zeros((300, 300), dtype=np.uint16)).save(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # Pillow's DecompressionBombWarning would be a 2nd line
        with use_limits(Limits(max_map_cells=50_000)):  # Pillow warns only: our check refuses
            with pytest.raises(FootfallError, match="PNG image has 90000 cells, above the limit"):
                import_terrain(path, resolution=0.01, z_scale=0.001)
        with use_limits(Limits(max_map_cells=1000)):  # above twice the limit: Pillow's error
            with pytest.raises(FootfallError, match="more pixels than the limit of 1000"):
                import_terrain(path, resolution=0.01, z_scale=0.001)
    code, _, err = run(capsys, "--limit", "max_map_cells=1000", "terrain", "import", path,
                       "--resolution", "0.01", "--z-scale", "0.001", "-o", tmp_path / "o.npz")
    assert_user_error(code, err, "the PNG image has more pixels than the limit of 1000")


def test_ply_declaring_too_many_points(tmp_path):
    path = tmp_path / "many.ply"
    path.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 99999999999\n"
                     b"property float x\nproperty float y\nproperty float z\nend_header\n"
                     + b"\0" * 120)
    with pytest.raises(FootfallError, match="declares 99999999999 items, above the limit"):
        import_terrain(path, resolution=0.01)


def test_xyz_with_more_points_than_the_limit(tmp_path):
    path = tmp_path / "many.xyz"
    path.write_text("".join(f"{i * 0.01} {i * 0.02} 0.1\n" for i in range(50)))
    with use_limits(Limits(max_scan_points=10)):
        with pytest.raises(FootfallError, match="more than 10 points"):
            import_terrain(path, resolution=0.01)


@pytest.mark.parametrize("make, kwargs, match", [
    (lambda p: np.save(p / "a.npy", np.full((4, 4), 1e300)), {"resolution": 0.01},
     r"heights beyond \+-100000 m \(largest 1e\+300 m\)"),
    (lambda p: np.save(p / "a.npy", np.full((4, 4), 1e300)),
     {"resolution": 0.01, "z_scale": 1e300}, "infinite heights"),
    (lambda p: (p / "a.xyz").write_text("0 0 1e300\n1 1 1e300\n"),
     {"resolution": 0.1, "z_scale": 1e10}, "infinite heights"),
    (lambda p: (p / "a.xyz").write_text("1e300 0 1\n-1e300 1 1\n"), {"resolution": 0.1},
     r"beyond \+-1e\+06 m"),
])
def test_extreme_values_are_refused_without_numpy_warnings(tmp_path, make, kwargs, match):
    make(tmp_path)
    path = next(tmp_path.glob("a.*"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an overflow warning would print a second line
        with pytest.raises(FootfallError, match=match):
            import_terrain(path, **kwargs)


def test_extreme_resolution_of_an_import(tmp_path):
    path = tmp_path / "a.npy"
    np.save(path, np.zeros((4, 4)))
    with pytest.raises(FootfallError, match="resolution must be > 0: a finite number"):
        import_terrain(path, resolution=1e300)


# ----------------------------------------------------------- interrupted writes
def test_stale_temporaries_of_dead_writers_are_removed(tmp_path):
    target = tmp_path / "map.npz"
    dead = tmp_path / ".map.npz.999999999.abcd1234.tmp.npz"  # above any Linux pid
    live = tmp_path / f".map.npz.{os.getpid()}.efgh5678.tmp.npz"  # this (live) process
    legacy_old = tmp_path / ".map.npz.ijkl9012.tmp.npz"  # older footfall: no pid, 2 h old
    legacy_new = tmp_path / ".map.npz.mnop3456.tmp.npz"  # no pid, just written
    other = tmp_path / ".other.npz.999999999.abcd1234.tmp.npz"  # another target's
    for f in (dead, live, legacy_old, legacy_new, other):
        f.write_bytes(b"partial")
    old = time.time() - 7200
    os.utime(legacy_old, (old, old))
    HeightMap(np.zeros((3, 3)), 0.01).save(target)
    assert target.is_file()
    assert not dead.exists() and not legacy_old.exists()
    assert live.exists() and legacy_new.exists() and other.exists()
    assert remove_stale_temporaries(target) == []


def test_temporary_files_name_their_writer(tmp_path):
    with atomic_path(tmp_path / "x.png") as tmp:
        assert tmp.name.startswith(f".x.png.{os.getpid()}.") and tmp.name.endswith(".tmp.png")
        assert remove_stale_temporaries(tmp_path / "x.png") == []  # a live writer's file stays
        tmp.write_bytes(b"x")
    assert (tmp_path / "x.png").read_bytes() == b"x"


def test_demos_collect_on_a_real_decompression_bomb_fails_fast(tmp_path, capsys):
    """A 600 KB map that truly inflates to 512 MB of heights (8000 x 8000, above the cell limit):
    ``demos collect`` refuses it from the header, without inflating it (issue 17's hang)."""
    path = tmp_path / "bomb.npz"
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': (8000, 8000), }"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, data in map_members().items():
            if name != "heights.npy":
                zf.writestr(name, data)
        with zf.open("heights.npy", "w", force_zip64=True) as member:
            member.write(npy_with_header(header))
            chunk = bytes(1 << 20)
            for _ in range(512):
                member.write(chunk)
    assert path.stat().st_size < 2 << 20
    tracemalloc.start()
    try:
        code, _, err = run(capsys, "demos", "collect", "--terrain", path, "-n", "1", "--seed", "0",
                           "-o", tmp_path / "demos.sqlite")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert_user_error(code, err, "6.4e+07 cells, above the limit of 50000000")
    assert peak < 50 << 20
    assert not (tmp_path / "demos.sqlite").exists()


def test_a_nodata_beyond_the_raw_dtype_matches_nothing_without_a_warning(tmp_path):
    """Found by the fuzz: float16 heights with nodata 8e15 printed NumPy's overflow warning."""
    path = tmp_path / "half.npy"
    np.save(path, np.full((8, 8), 0.5, dtype=np.float16))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hmap = import_terrain(path, resolution=0.01, nodata=8.2e15)
    assert np.all(hmap.heights == 0.5)
