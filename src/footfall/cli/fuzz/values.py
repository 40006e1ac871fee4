"""Hostile values, as Hypothesis strategies: what a broken or crafted file or argument holds."""

from __future__ import annotations

import math
import warnings

import numpy as np
from hypothesis import strategies as st

DEEP = "__fuzz_deep__"  # a JSON value replaced by lists nested 100 000 deep when written

_SPECIAL_NUMBERS = (math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-300, 0.0, -0.0, -1.0,
                    0.5, 1.0, 1e6, 10 ** 30, -(10 ** 30), 2 ** 63, -1, 0, 1, 3)
_SPECIAL_TEXT = ("", "abc", "nan", "1e400", "$\\frac$", "0", "-1", "None", "../../etc/passwd",
                 "x" * 1000, "\n\r\t", "\x00", "é∂ƒ")
argument_text = st.text(st.characters(blacklist_characters="\x00"), max_size=8)  # argv has no NUL

json_scalar = st.one_of(
    st.sampled_from(_SPECIAL_NUMBERS), st.sampled_from(_SPECIAL_TEXT),
    st.sampled_from([None, True, False]), st.floats(), st.integers(), st.text(max_size=12))
json_value = st.one_of(
    json_scalar,
    st.just(DEEP),
    st.recursive(json_scalar, lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=4)),
        max_leaves=8))

# How an array in a file can be wrong: (transformation, parameter)
ARRAY_EDITS = ("nan", "inf", "huge", "complex", "text", "bool", "int", "int8", "float16",
               "float32", "bigendian", "empty", "scalar", "ravel", "extra_dim", "drop_last",
               "transpose", "zeros", "negative", "tiny")
array_edit = st.tuples(st.sampled_from(ARRAY_EDITS), st.integers(0, 2 ** 31 - 1))


def edit_array(a: np.ndarray, edit: tuple[str, int]) -> np.ndarray:
    """``a`` changed by ``edit`` (see :data:`ARRAY_EDITS`); a pure function."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # casting 1e300 to float16 is the point
        return _edit_array(a, edit)


def _edit_array(a: np.ndarray, edit: tuple[str, int]) -> np.ndarray:
    kind, k = edit
    a = np.array(a)
    flat = a.reshape(-1).copy() if a.size else np.zeros(1)
    i = k % flat.size
    if kind in ("nan", "inf", "huge", "negative", "tiny"):
        numeric = flat.dtype.kind in "fiub"
        value = {"nan": np.nan, "inf": np.inf, "huge": 1e300, "tiny": 1e-300,
                 "negative": -abs(float(flat[i])) - 1.0 if numeric else -1.0}[kind]
        f = flat.astype(np.float64) if numeric else np.zeros(flat.size)
        f[i] = value
        return f.reshape(a.shape) if a.size else f
    conversions = {"complex": np.complex128, "bool": np.bool_, "int": np.int64, "int8": np.int8,
                   "float16": np.float16, "float32": np.float32, "bigendian": ">f8"}
    if kind in conversions:
        try:
            return a.astype(conversions[kind])
        except (TypeError, ValueError):
            return np.zeros(a.shape, conversions[kind])
    if kind == "text":
        return a.astype(str) if a.size else np.array("abc")
    if kind == "empty":
        return a.reshape(-1)[:0]
    if kind == "scalar":
        return np.array(flat[i])
    if kind == "ravel":
        return a.reshape(-1)
    if kind == "extra_dim":
        return a[None]
    if kind == "drop_last":
        return a[..., :-1] if a.ndim else a
    if kind == "transpose":
        return a.T.copy()
    return np.zeros_like(a)


sql_value = st.one_of(
    st.sampled_from([None, 0, -1, 2 ** 63 - 1, -(2 ** 63), 1.5, math.inf, -math.inf, 1e300,
                     "", "abc", "[1, 2]", "[-1]", "[1e30, 1e30]", "<f4", "|O", "nan", "LF",
                     b"", b"\x00" * 8, b"\xff" * 24]),
    st.integers(), st.floats(allow_nan=False), st.text(max_size=12), st.binary(max_size=64))

# Command-line tokens: values a numeric or path option must refuse
BAD_NUMBERS = ("nan", "inf", "-inf", "1e400", "abc", "", "0x10", "1,5", "--")
BAD_COUNTS = ("-1", "1.5", "abc", "", "nan", "1e3", "99999999999999999999", "1000000000000")
BAD_SEEDS = ("-1", "abc", "1.5", "", "99999999999999999999999", "nan")
BAD_OUTPUT = ("{missing}/dir/out{suffix}", "{dir}", "{dir}/out.txt", "{dir}/out",
              "/proc/version", "/dev/null/x{suffix}")
BAD_INPUT = ("{missing}", "{dir}", "{empty}", "{text}", "{map}", "{model}", "{store}",
             "/dev/zero", "/proc/self/mem")
