"""A bounded reader of ``.npz`` archives: nothing is inflated before it is inspected.

``numpy.load`` trusts the file: a zip member whose ``.npy`` header declares a
huge array, a decompression bomb, an encrypted member or a mangled header
makes it allocate gigabytes or raise whatever the zip, zlib or header parser
raises. Here the archive's directory and every member's ``.npy`` header are
checked against the limits (:mod:`footfall.core.limits`) first, then exactly
the declared number of bytes is read, in chunks, so a lying header cannot
inflate more than it declared. Every problem becomes one
:class:`~footfall.core.errors.FootfallError` naming the file and the member.
"""

from __future__ import annotations

import math
import tokenize
import zipfile
import zlib
from pathlib import Path
from typing import IO, Callable

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.limits import Limits, current_limits
from footfall.core.paths import readable_file

MemberCheck = Callable[[str, tuple[int, ...], np.dtype], None]
"""``(name, shape, dtype)`` of an array about to be read; raises FootfallError to refuse it."""

ARRAY_KINDS = "biufcUS"  # dtype kinds an archive may hold: no objects, records or raw bytes
CHUNK = 1 << 20  # [bytes] read at a time
HEADER_ERRORS = (ValueError, SyntaxError, tokenize.TokenError, EOFError, KeyError, TypeError)
_ZIP_ERRORS = (zipfile.BadZipFile, zipfile.LargeZipFile, zlib.error, EOFError,
               NotImplementedError, RuntimeError, OSError, ValueError)


def read_npz_members(path: str | Path, check: MemberCheck | None = None
                     ) -> dict[str, np.ndarray]:
    """Every array of the ``.npz`` at ``path`` by name, read within the limits.

    Raises
    ------
    FootfallError
        Naming the file (and member): missing, unreadable, too large, not a
        zip archive, encrypted or oddly compressed members, duplicate or odd
        member names, a broken ``.npy`` header, an object/record dtype, an
        array above ``max_array_bytes``, a corrupt or truncated stream; or
        whatever ``check`` refuses.
    """
    p = readable_file(path)
    limits = current_limits()
    try:
        with open(p, "rb") as fh:
            if not zipfile.is_zipfile(fh):
                raise FootfallError(f"{p}: not a readable footfall .npz file (not a zip archive)")
            fh.seek(0)
            with zipfile.ZipFile(fh) as archive:
                members = _checked_members(p, archive, limits)
                return {name: _read_member(p, archive, info, name, limits, check)
                        for name, info in members}
    except FootfallError:
        raise
    except PermissionError:
        raise FootfallError(f"{p}: permission denied") from None
    except _ZIP_ERRORS as exc:
        raise FootfallError(f"{p}: not a readable footfall .npz file ({_describe(exc)})") from None


def _describe(exc: BaseException) -> str:
    return str(exc) or type(exc).__name__


def _checked_members(p: Path, archive: zipfile.ZipFile, limits: Limits
                     ) -> list[tuple[str, zipfile.ZipInfo]]:
    """The archive's members as (array name, info), after checking its directory."""
    members: list[tuple[str, zipfile.ZipInfo]] = []
    seen: set[str] = set()
    declared = 0
    for info in archive.infolist():
        member = info.filename
        stem = member[:-4]
        if (not member.endswith(".npy") or not stem or "/" in member or "\\" in member
                or stem.startswith(".") or any(ord(c) < 32 for c in member)):
            raise FootfallError(f"{p}: member {member!r} is not an array (.npy) of this archive")
        if stem in seen:
            raise FootfallError(f"{p}: member {member!r} occurs twice")
        seen.add(stem)
        if info.flag_bits & 0x1:
            raise FootfallError(f"{p}: member {member!r} is encrypted")
        if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            raise FootfallError(f"{p}: member {member!r} uses compression method "
                                f"{info.compress_type} (footfall reads stored or deflated only)")
        declared += info.file_size
        members.append((stem, info))
    if declared > limits.max_file_bytes:
        raise FootfallError(f"{p}: the archive would inflate to {declared} bytes, above the "
                            f"limit of {limits.max_file_bytes} (raise it with "
                            f"--limit max_file_bytes=N)")
    return members


def npy_header(fh: IO[bytes]) -> tuple[tuple[int, ...], bool, np.dtype]:
    """(shape, fortran_order, dtype) from the ``.npy`` header at ``fh``, nothing more read.

    Raises one of :data:`HEADER_ERRORS` for a header that is not one (versions 1.0 and 2.0
    are read; 3.0 is refused).
    """
    fmt = np.lib.format
    version = fmt.read_magic(fh)
    if version == (1, 0):
        return fmt.read_array_header_1_0(fh)
    if version == (2, 0):
        return fmt.read_array_header_2_0(fh)
    raise ValueError(f"unsupported .npy format version {version}")


def _read_header(p: Path, member: str, fh: IO[bytes]
                 ) -> tuple[tuple[int, ...], bool, np.dtype]:
    """(shape, fortran_order, dtype) from a member's ``.npy`` header, checked."""
    try:
        shape, fortran, dtype = npy_header(fh)
    except HEADER_ERRORS as exc:
        raise FootfallError(f"{p}: member {member!r} has a broken .npy header "
                            f"({_describe(exc)})") from None
    if (dtype.kind not in ARRAY_KINDS or dtype.hasobject or dtype.names is not None
            or dtype.subdtype is not None or dtype.itemsize == 0):
        raise FootfallError(f"{p}: member {member!r} holds dtype {dtype} "
                            f"(objects, records and raw bytes are refused)")
    if not all(isinstance(n, int) and n >= 0 for n in shape):
        raise FootfallError(f"{p}: member {member!r} has an invalid shape {shape!r}")
    return tuple(shape), bool(fortran), dtype


def _read_member(p: Path, archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str,
                 limits: Limits, check: MemberCheck | None) -> np.ndarray:
    """One member's array: header checked, then exactly the declared bytes read."""
    try:
        return _read_member_stream(p, archive, info, name, limits, check)
    except FootfallError:
        raise
    except _ZIP_ERRORS as exc:
        raise FootfallError(f"{p}: member {info.filename!r} is corrupt ({_describe(exc)})"
                            ) from None


def _read_member_stream(p: Path, archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str,
                        limits: Limits, check: MemberCheck | None) -> np.ndarray:
    member = info.filename
    with archive.open(info) as fh:
        shape, fortran, dtype = _read_header(p, member, fh)
        nbytes = math.prod(shape) * dtype.itemsize
        if nbytes > limits.max_array_bytes:
            raise FootfallError(f"{p}: member {member!r} declares {nbytes} bytes "
                                f"(shape {shape}, dtype {dtype}), above the limit of "
                                f"{limits.max_array_bytes} (raise it with "
                                f"--limit max_array_bytes=N)")
        if check is not None:
            try:
                check(name, shape, dtype)
            except FootfallError as exc:
                raise FootfallError(f"{p}: {exc}") from None
        buffer = _read_exactly(p, member, fh, nbytes)
        if fh.read(1):  # also makes zipfile check the member's CRC
            raise FootfallError(f"{p}: member {member!r} holds more data than its header "
                                f"declares")
    return np.frombuffer(buffer, dtype=dtype).reshape(shape, order="F" if fortran else "C")


def _read_exactly(p: Path, member: str, fh: IO[bytes], nbytes: int) -> bytearray:
    buffer = bytearray(nbytes)
    view = memoryview(buffer)
    done = 0
    while done < nbytes:
        chunk = fh.read(min(CHUNK, nbytes - done))
        if not chunk:
            raise FootfallError(f"{p}: member {member!r} is truncated ({done} of {nbytes} "
                                f"bytes)")
        view[done:done + len(chunk)] = chunk
        done += len(chunk)
    return buffer
