"""Raw ``.npz`` archives, built and damaged without footfall's writer.

:func:`write_npz` writes members exactly as given (a crafted member can be raw bytes:
a broken header, a pickle, a header that declares a huge array); :func:`patch_zip`
damages an archive the way a broken download or a crafted file does (encrypted flags,
unknown compression methods, flipped and missing bytes). Pure functions of their input.
"""

from __future__ import annotations

import io
import json
import struct
import zipfile
from typing import Any

import numpy as np

from footfall.cli.fuzz.values import DEEP

_LOCAL = b"PK\x03\x04"
_CENTRAL = b"PK\x01\x02"


def npy_bytes(array: np.ndarray) -> bytes:
    """``array`` in ``.npy`` format (no pickle)."""
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.asanyarray(array), allow_pickle=False)
    return buf.getvalue()


def pickle_payload(marker: str) -> bytes:
    """A pickle (protocol 0, written by hand) that creates the file ``marker`` when loaded:
    ``open(marker, "w")``. No footfall loader may ever run it."""
    return b"cbuiltins\nopen\n(V" + marker.encode("raw_unicode_escape") + b"\nVw\ntR."


def pickle_member(marker: str) -> bytes:
    """An ``.npy`` member of object dtype whose data is :func:`pickle_payload`."""
    header = {"descr": "|O", "fortran_order": False, "shape": (1,)}
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    return buf.getvalue() + pickle_payload(marker)


def huge_member(shape: tuple[int, ...], data_bytes: int = 1 << 20) -> bytes:
    """An ``.npy`` member whose header declares ``shape`` float64 but holds only zeros of
    ``data_bytes``: read naively, it inflates to the declared size."""
    header = {"descr": "<f8", "fortran_order": False, "shape": shape}
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, header)
    return buf.getvalue() + bytes(data_bytes)


def meta_text(meta: Any) -> str:
    """JSON text of ``meta``, NaN and infinity as Python writes them, :data:`DEEP` nested deep."""
    text = json.dumps(meta, sort_keys=True, allow_nan=True)
    return text.replace(json.dumps(DEEP), "[" * 100_000 + "]" * 100_000)


def write_npz(members: dict[str, bytes | np.ndarray], compress: bool = True) -> bytes:
    """A zip archive of ``.npy`` members (arrays are encoded, bytes written as they are)."""
    buf = io.BytesIO()
    method = zipfile.ZIP_DEFLATED if compress else zipfile.ZIP_STORED
    with zipfile.ZipFile(buf, "w", compression=method) as zf:
        for name, value in members.items():
            data = value if isinstance(value, bytes) else npy_bytes(value)
            zf.writestr(name if name.endswith(".npy") else name + ".npy", data)
    return buf.getvalue()


def footfall_members(fmt: str, version: Any, arrays: dict[str, np.ndarray], meta: Any
                     ) -> dict[str, bytes | np.ndarray]:
    """The members of a footfall file (as :func:`footfall.core.files.save_npz` lays them out)."""
    members: dict[str, bytes | np.ndarray] = dict(arrays)
    members["format"] = np.array(fmt)
    members["version"] = version if isinstance(version, np.ndarray) else np.array(version)
    members["meta"] = np.array(meta_text(meta))
    return members


# A header field's offset in the local and the central directory header (None: left alone)
_HEADER_FIELDS = {"encrypt": (6, 8), "method": (8, 10), "crc": (14, None), "sizes": (22, 24)}
ZIP_EDITS = ("encrypt", "method", "flip", "truncate", "insert", "delete", "zero_run",
             "crc", "sizes", "comment")


def _headers(data: bytes, signature: bytes) -> list[int]:
    out, at = [], data.find(signature)
    while at >= 0:
        out.append(at)
        at = data.find(signature, at + 4)
    return out


def patch_zip(data: bytes, edit: str, k: int) -> bytes:
    """``data`` (a zip archive) damaged by ``edit`` (see :data:`ZIP_EDITS`) at a place chosen by ``k``."""
    b = bytearray(data)
    if not b:
        return bytes(b)
    i = k % len(b)
    local = [at for at in _headers(data, _LOCAL) if at + 30 <= len(b)]
    central = [at for at in _headers(data, _CENTRAL) if at + 46 <= len(b)]
    if edit in _HEADER_FIELDS and local:
        values = {"method": 99 if k % 2 else 12, "crc": k & 0xFFFFFFFF,
                  "sizes": (k * 7919) & 0xFFFFFFFF}
        for headers, offset in zip((local, central), _HEADER_FIELDS[edit]):
            for at in headers if offset is not None else ():
                if edit == "encrypt":
                    b[at + offset] |= 1  # general-purpose flag bit 0: encrypted
                else:
                    struct.pack_into("<H" if edit == "method" else "<I", b, at + offset,
                                     values[edit])
        return bytes(b)
    if edit == "truncate":
        return bytes(b[:i])
    if edit == "insert":
        return bytes(b[:i] + bytes([k % 256]) * (1 + k % 7) + b[i:])
    if edit == "delete":
        return bytes(b[:i] + b[i + 1 + k % 7:])
    if edit == "zero_run":
        n = min(len(b) - i, 1 + k % 64)
        b[i:i + n] = bytes(n)
        return bytes(b)
    if edit == "comment":
        return bytes(b) + b"trailing garbage" * (1 + k % 4)
    b[i] ^= 1 << (k % 8)  # flip
    return bytes(b)
