"""Reading a store's rows back, strictly: every column's SQLite type, every array, every number.

SQLite keeps whatever a row holds -- text in an INTEGER column, a blob where text belongs,
NaN in a REAL column -- so each value read is checked before it becomes a record. The queries
(:mod:`footfall.data.store`, :mod:`footfall.data.run_queries`) and the whole-store check
(:mod:`footfall.data.check`) decode rows with these functions only, so a row either query
would refuse is one the check reports, with the same message.

Each function raises :class:`FootfallError` with a message that names the column; the caller
prefixes the table and the row's key.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.limits import check_cells, current_limits
from footfall.core.robot import LEG_NAMES
from footfall.core.state import RobotState
from footfall.data import codec
from footfall.data.demonstration import Demonstration
from footfall.data.runlog import RunStep

DEMONSTRATION_COLUMNS = ("id, terrain_hash, swing_leg, state, state_shape, state_dtype, "
                         "candidates, candidates_shape, candidates_dtype, n_candidates, chosen, "
                         "source, expert")
VERDICT_COLUMNS = ("demonstration_id, teacher_values, values_shape, values_dtype, refused, "
                   "refused_shape, refused_dtype, judged, judged_shape, judged_dtype")
TERRAIN_COLUMNS = "hash, heights, shape, dtype, resolution, origin_x, origin_y, frame, metadata"
RUN_COLUMNS = "id, key, terrain_hash, seed, settings, result, n_steps"
STEP_COLUMNS = ("k, swing_leg, state, state_shape, state_dtype, candidates, candidates_shape, "
                "candidates_dtype, rewards, rewards_shape, rewards_dtype, chosen, t_liftoff, "
                "t_touchdown, touchdown, touchdown_shape, touchdown_dtype, slip")


# ------------------------------------------------------------------ one value
def integer(value: Any, what: str) -> int:
    """An INTEGER column's value: SQLite hands back text or a blob a damaged row holds."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise FootfallError(f"{what} is not an integer (got {_kind(value)})")
    return value


def real(value: Any, what: str, nullable: bool = False) -> float:
    """A REAL column's finite value (NaN if NULL where ``nullable``)."""
    if value is None and nullable:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise FootfallError(f"{what} is not a number (got {_kind(value)})")
    if not math.isfinite(value):
        raise FootfallError(f"{what} is not finite (got {value!r})")
    return float(value)


def json_object(value: Any, what: str) -> dict:
    """A TEXT column holding a JSON object: no NaN or infinity, within the metadata limits."""
    text = codec.text(value, what)
    limits = current_limits()
    if len(text) > limits.max_metadata_bytes:
        raise FootfallError(f"{what} is {len(text)} characters long, above the limit of "
                            f"{limits.max_metadata_bytes} (raise it with --limit "
                            f"max_metadata_bytes=N)")
    try:
        out = json.loads(text, parse_constant=_no_constant)
    except (ValueError, RecursionError):
        raise FootfallError(f"{what} is not valid JSON") from None
    if not isinstance(out, dict):
        raise FootfallError(f"{what} is not a JSON object")
    if _depth(out) > limits.max_metadata_depth:
        raise FootfallError(f"{what} is nested deeper than {limits.max_metadata_depth} levels")
    return out


def _no_constant(name: str) -> None:
    raise ValueError(f"{name} is not JSON")


def _depth(value: Any) -> int:
    if isinstance(value, dict):
        return 1 + max(map(_depth, value.values()), default=0)
    if isinstance(value, list):
        return 1 + max(map(_depth, value), default=0)
    return 0


def _kind(value: Any) -> str:
    """How a damaged value is named in a message: its SQLite storage class and a short repr."""
    kinds = {type(None): "NULL", int: "integer", float: "real", str: "text", bytes: "blob"}
    shown = repr(value) if not isinstance(value, bytes) else f"{len(value)} bytes"
    return f"{kinds.get(type(value), type(value).__name__)} {shown[:40]}"


def array(blob: Any, shape: Any, dtype: Any, what: str, finite: bool = True) -> np.ndarray:
    """An array from its three columns (:func:`codec.decode`), of finite numbers if ``finite``."""
    a = codec.decode(blob, codec.text(shape, f"{what} shape"), codec.text(dtype, f"{what} dtype"),
                     what)
    if finite and not np.isfinite(a).all():
        raise FootfallError(f"{what} holds non-finite numbers")
    return a


def leg(value: Any) -> str:
    """A swing leg's name: one of LEG_NAMES."""
    if value not in LEG_NAMES:
        raise FootfallError(f"swing_leg {_kind(value)} is not a leg ({', '.join(LEG_NAMES)})")
    return value


# ------------------------------------------------------------------- records
def demonstration(row: tuple) -> Demonstration:
    """A :class:`Demonstration` from its ``demonstrations`` row (DEMONSTRATION_COLUMNS)."""
    (id_, terrain_hash, swing_leg, st, st_s, st_d, c, c_s, c_d, n, chosen, source, expert) = row
    state = RobotState.from_vector(array(st, st_s, st_d, "state"), leg(swing_leg))
    candidates = array(c, c_s, c_d, "candidates")
    n = integer(n, "n_candidates")
    if candidates.ndim != 2 or n != candidates.shape[0]:
        raise FootfallError(f"n_candidates {n} does not match the candidates' shape "
                            f"{candidates.shape}")
    return Demonstration(codec.text(terrain_hash, "terrain_hash"), state, candidates,
                         integer(chosen, "chosen"), codec.text(source, "source"),
                         json_object(expert, "expert"), integer(id_, "id"))


def verdict(row: tuple) -> tuple[int, np.ndarray | None, np.ndarray | None, np.ndarray | None]:
    """A demonstration's id and its teacher's values (n,), refusals (n,) and judged values (n,)
    (each None where NULL) from its ``verdicts`` row (VERDICT_COLUMNS); checked against the
    demonstration when the two are joined (:meth:`Demonstration.__post_init__`)."""
    id_, v, v_s, v_d, r, r_s, r_d, j, j_s, j_d = row
    values = None if v is None else array(v, v_s, v_d, "teacher_values")
    refused = None if r is None else array(r, r_s, r_d, "refused")
    judged = None if j is None else array(j, j_s, j_d, "judged")
    return integer(id_, "demonstration_id"), values, refused, judged


def terrain(row: tuple) -> HeightMap:
    """A :class:`HeightMap` from its ``terrains`` row (TERRAIN_COLUMNS), checked against its hash."""
    digest, blob, shape, dtype, resolution, ox, oy, frame, metadata = row
    shape_text = codec.text(shape, "shape")
    try:
        dims = json.loads(shape_text)
    except ValueError:
        dims = None
    if not (isinstance(dims, list) and len(dims) == 2
            and all(isinstance(d, int) and not isinstance(d, bool) and d >= 1 for d in dims)):
        raise FootfallError(f"shape {shape_text[:40]!r} is not [nx, ny] of whole numbers >= 1")
    check_cells(tuple(dims), "heights")
    heights = codec.decode(blob, shape_text, codec.text(dtype, "dtype"), "heights")
    hmap = HeightMap(heights, real(resolution, "resolution"),
                     (real(ox, "origin_x"), real(oy, "origin_y")), codec.text(frame, "frame"),
                     json_object(metadata, "metadata"))
    if hmap.content_hash() != digest:
        raise FootfallError("its content hash does not match its heights and geometry")
    return hmap


def run_head(row: tuple) -> dict[str, Any]:
    """A run's row (RUN_COLUMNS) as the dict :meth:`RunQueries.runs` returns."""
    id_, key, terrain_hash, seed, settings, result, n_steps = row
    n_steps = integer(n_steps, "n_steps")
    if n_steps < 0:
        raise FootfallError(f"n_steps is negative ({n_steps})")
    return {"id": integer(id_, "id"),
            "key": None if key is None else codec.text(key, "key"),
            "terrain_hash": codec.text(terrain_hash, "terrain_hash"),
            "seed": integer(seed, "seed"), "settings": json_object(settings, "settings"),
            "result": json_object(result, "result"), "n_steps": n_steps}


MAX_SLIP = 1e3  # [m] no stance foot of a run travels this far: a larger slip is a damaged row


def run_step(row: tuple) -> RunStep:
    """A run step from its ``run_steps`` row (STEP_COLUMNS)."""
    k, swing_leg, st, st_s, st_d, c, c_s, c_d, r, r_s, r_d, chosen, t0, t1, td, td_s, td_d, \
        slip = row
    state = RobotState.from_vector(array(st, st_s, st_d, "state"), leg(swing_leg))
    rewards = array(r, r_s, r_d, "rewards", finite=False)
    if np.isnan(rewards).any() or (rewards == np.inf).any():
        raise FootfallError("rewards hold NaN or +inf (only -inf marks an invalid candidate)")
    touchdown = array(td, td_s, td_d, "touchdown", finite=False)
    if np.isinf(touchdown).any():
        raise FootfallError("touchdown holds an infinite coordinate")
    travel = real(slip, "slip", nullable=True)
    if not (math.isnan(travel) or 0.0 <= travel <= MAX_SLIP):
        raise FootfallError(f"slip must be a distance from 0 to {MAX_SLIP:g} m, got {travel!r}")
    return RunStep(integer(k, "k"), state, array(c, c_s, c_d, "candidates"), rewards,
                   integer(chosen, "chosen"), real(t0, "t_liftoff"),
                   real(t1, "t_touchdown", nullable=True), touchdown, travel)
