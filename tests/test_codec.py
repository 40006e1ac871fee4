"""The store's array codec: bit-exact round trips, and every damaged column refused by name."""

import json
import re

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.data import codec

SPECIAL = np.array([0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, 1.7976931348623157e308])


@pytest.mark.parametrize("shape", [(0,), (3,), (20,), (5, 3), (0, 3), (2, 3, 4)])
def test_float64_round_trip_is_bit_exact(shape):
    a = np.random.default_rng(0).normal(size=shape)
    blob, shape_json, dtype = codec.encode(a)
    assert (json.loads(shape_json), dtype) == (list(shape), "<f8")
    assert blob == a.astype("<f8").tobytes()
    back = codec.decode(blob, shape_json, dtype, "it")
    assert back.dtype == np.float64 and back.shape == shape
    assert back.tobytes() == a.tobytes()
    assert not back.flags.writeable  # a view of the stored bytes: nobody edits it in place


def test_a_scalar_is_stored_as_one_number():
    blob, shape_json, dtype = codec.encode(np.float64(2.5))  # ascontiguousarray: ndim >= 1
    assert shape_json == "[1]"
    assert codec.decode(blob, shape_json, dtype, "it").tolist() == [2.5]


def test_special_values_survive():
    back = codec.decode(*codec.encode(SPECIAL), "it")
    assert back.tobytes() == SPECIAL.tobytes()  # NaN, signed zero, infinities, subnormals


@pytest.mark.parametrize("dtype", ["<f4", ">f8", "<i8", "u1", "?"])
def test_other_numbers_are_stored_as_little_endian_float64(dtype):
    a = np.arange(6).reshape(2, 3).astype(dtype)
    blob, shape_json, stored = codec.encode(a)
    assert (shape_json, stored) == ("[2, 3]", "<f8")
    np.testing.assert_array_equal(codec.decode(blob, shape_json, stored, "it"),
                                  a.astype(np.float64))


def test_a_non_contiguous_array_is_stored_in_row_major_order():
    a = np.arange(12.0).reshape(3, 4).T  # (4, 3), column-major view
    blob, shape_json, dtype = codec.encode(a)
    assert shape_json == "[4, 3]"
    np.testing.assert_array_equal(codec.decode(blob, shape_json, dtype, "it"), a)


@pytest.mark.parametrize("blob, match", [
    (np.zeros(14).tobytes(), r"its candidates holds 112 bytes, not the 15 numbers of shape \(5, 3\)"),
    (np.zeros(15).tobytes()[:-1], "holds 119 bytes"),
    (None, "holds no bytes"),
    ("text", "holds no bytes"),
])
def test_a_corrupt_blob_is_refused(blob, match):
    with pytest.raises(FootfallError, match=match):
        codec.decode(blob, "[5, 3]", "<f8", "its candidates")


@pytest.mark.parametrize("shape_json", ["[5, x]", "", None, "{}", "5", "[-1, 3]", "[2.5, 6]",
                                        "[true, 15]", '["5", 3]'])
def test_a_wrong_shape_is_refused(shape_json):
    with pytest.raises(FootfallError, match=re.escape(f"its state has a malformed shape {shape_json!r}")):
        codec.decode(np.zeros(15).tobytes(), shape_json, "<f8", "its state")


@pytest.mark.parametrize("dtype", ["<f4", ">f8", "float64", "|O", "", None])
def test_a_wrong_dtype_is_refused(dtype):
    with pytest.raises(FootfallError, match=re.escape(f"rewards has unsupported dtype {dtype!r}")):
        codec.decode(np.zeros(3).tobytes(), "[3]", dtype, "rewards")


def test_text_columns_are_checked():
    assert codec.text("walker", "its source") == "walker"
    for value in (None, b"walker", 3):
        with pytest.raises(FootfallError, match="its source is not text"):
            codec.text(value, "its source")
