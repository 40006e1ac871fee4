"""A demonstration (paper §II-B): the foothold an expert chose among the candidates F, with the
robot's state at the decision and the terrain it stood on. Stored by
:class:`footfall.data.store.DemoStore`; made by the walker, corrections and the teacher.
"""

from __future__ import annotations

import hashlib
import numbers
import re
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import checked_json
from footfall.core.state import RobotState
from footfall.data.frozen import set_fields

_HASH_RE = re.compile(r"^[0-9a-f]{64}$")


@dataclass(frozen=True, eq=False)
class Demonstration:
    """One demonstrated foothold: in ``state`` on terrain ``terrain_hash``, ``chosen`` of F.

    Parameters
    ----------
    terrain_hash : str
        :meth:`HeightMap.content_hash` of the terrain (64 hex digits).
    state : RobotState
        The robot's state at the decision; ``state.swing_leg`` is the leg that moves.
    candidates : array of shape (n, 3)
        The candidate set F: x, y and terrain height z [m] of each reachable
        foothold, n >= 2, finite.
    chosen : int
        Index in ``candidates`` of the foothold the expert chose, in [0, n).
    source : str
        Where it came from: ``"walker"``, ``"run:<id>:step:<k>"``, ``"teacher"``.
    expert : dict
        JSON-serialisable settings of the expert that chose (a private copy is kept).
    id : int or None
        Row id in a :class:`DemoStore` (creation order); None until stored.
    values : array of shape (n,) or None
        The teacher's verdict on every candidate: its value of each [its value units, higher
        better], finite; None where it gave no values (a person's label).
    refused : array of shape (n,) of bool, or None
        The candidates the teacher refuses outright ("never here": a veto, a person's mark);
        never the chosen one. None: it said nothing of the others.
    judged : array of shape (n,) or None
        The values its refusals are relative to [value units, higher better], finite: a
        candidate is refused where it is more than the teacher's margin below the best of them
        (the synthetic expert's values behind the guarded teacher's veto; a teacher without a
        separate judge, its own values). None: not given (a person's marks).
    """

    terrain_hash: str
    state: RobotState
    candidates: np.ndarray  # (n, 3) [m] x, y, terrain height
    chosen: int  # index into candidates
    source: str = "walker"
    expert: dict = field(default_factory=dict)
    id: int | None = None
    values: np.ndarray | None = None  # (n,) the teacher's value of each candidate [its units]
    refused: np.ndarray | None = None  # (n,) bool: refused outright ("never here")
    judged: np.ndarray | None = None  # (n,) [value units] what the refusals are relative to

    def __post_init__(self) -> None:
        if not isinstance(self.terrain_hash, str) or not _HASH_RE.match(self.terrain_hash):
            raise FootfallError(f"terrain hash must be 64 lowercase hex digits, "
                                f"got {self.terrain_hash!r}")
        if not isinstance(self.state, RobotState):
            raise FootfallError(f"state must be a RobotState, got {type(self.state).__name__}")
        try:
            cand = np.array(self.candidates, dtype=np.float64)
        except (TypeError, ValueError):
            raise FootfallError("candidates must be an (n, 3) array of numbers") from None
        if cand.ndim != 2 or cand.shape[1] != 3 or cand.shape[0] < 2:
            raise FootfallError(f"candidates must have shape (n, 3) with n >= 2, got {cand.shape}")
        if not np.isfinite(cand).all():
            raise FootfallError("candidates must be finite")
        chosen = self.chosen
        if isinstance(chosen, bool) or not isinstance(chosen, numbers.Integral):
            raise FootfallError(f"chosen must be an integer index, got {chosen!r}")
        if not 0 <= int(chosen) < cand.shape[0]:
            raise FootfallError(f"chosen index {chosen} is outside the {cand.shape[0]} candidates")
        if not isinstance(self.source, str) or not self.source.strip():
            raise FootfallError(f"source must be a non-empty string, got {self.source!r}")
        if not isinstance(self.expert, dict):
            raise FootfallError(f"expert settings must be a dict, got {type(self.expert).__name__}")
        if self.id is not None and (isinstance(self.id, bool)
                                    or not isinstance(self.id, numbers.Integral)):
            raise FootfallError(f"id must be an integer or None, got {self.id!r}")
        values, refused = checked_verdict(self.values, self.refused, cand.shape[0], int(chosen))
        judged = checked_values(self.judged, cand.shape[0], "the judged values")
        set_fields(self, candidates=cand, chosen=int(chosen),
                   expert=checked_json(self.expert, "expert settings"),
                   id=None if self.id is None else int(self.id), values=values, refused=refused,
                   judged=judged)

    @property
    def has_verdict(self) -> bool:
        """Whether the teacher said more than its choice (values, refusals, judged values)."""
        return self.values is not None or self.refused is not None or self.judged is not None

    @property
    def swing_leg(self) -> str:
        """The leg that moves (``state.swing_leg``)."""
        return self.state.swing_leg

    @property
    def n_candidates(self) -> int:
        """Number of candidate footholds n."""
        return int(self.candidates.shape[0])

    @property
    def foothold(self) -> np.ndarray:
        """The chosen foothold, shape (3,): x, y, terrain height [m]."""
        return self.candidates[self.chosen]

    def content_hash(self) -> str:
        """The demonstration's identity: :func:`decision_hash` on its terrain. Two with the same
        hash are the same demonstration, whatever their id, source or expert settings."""
        return decision_hash(self.state, self.candidates, self.chosen, self.terrain_hash)


def checked_verdict(values: object, refused: object, n: int, chosen: int
                    ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """A teacher's verdict on ``n`` candidates as read-only arrays: ``values`` (n,) finite
    [value units], ``refused`` (n,) bool without the ``chosen`` one; None stays None.

    Raises
    ------
    FootfallError
        For a wrong shape, a non-finite value, a refusal that is not 0 / 1, or the chosen
        candidate refused.
    """
    out_values, out_refused = checked_values(values, n, "the teacher's values"), None
    if refused is not None:
        try:
            raw = np.array(refused, dtype=np.float64)
        except (TypeError, ValueError):
            raise FootfallError("the refused candidates must be a mask of 0 / 1") from None
        if raw.shape != (n,) or not np.isin(raw, (0.0, 1.0)).all():
            raise FootfallError(f"the refused candidates must be a mask of {n} values 0 / 1, "
                                f"one per candidate")
        out_refused = raw.astype(bool)
        if out_refused[chosen]:
            raise FootfallError(f"the chosen candidate {chosen} is refused")
        out_refused.setflags(write=False)
    return out_values, out_refused


def checked_values(values: object, n: int, what: str) -> np.ndarray | None:
    """``values`` as a read-only (n,) float64 array of finite numbers [value units], one per
    candidate; None stays None.

    Raises
    ------
    FootfallError
        Naming ``what``, for a wrong shape or a value that is not a finite number.
    """
    if values is None:
        return None
    try:
        out = np.array(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise FootfallError(f"{what} must be numbers") from None
    if out.shape != (n,) or not np.isfinite(out).all():
        raise FootfallError(f"{what} must be {n} finite numbers, one per candidate, got shape "
                            f"{out.shape}")
    out.setflags(write=False)
    return out


def decision_hash(state: RobotState, candidates: np.ndarray, chosen: int,
                  terrain_hash: str = "") -> str:
    """SHA-256 of a foothold decision: the swing leg, the state vector, the candidates (n, 3)
    [m] as float64 and the chosen index (and the terrain's hash, if given)."""
    digest = hashlib.sha256()
    digest.update(f"{terrain_hash}|{state.swing_leg}|{int(chosen)}|".encode())
    digest.update(np.ascontiguousarray(state.to_vector(), dtype="<f8").tobytes())
    cand = np.ascontiguousarray(candidates, dtype="<f8")
    digest.update(repr(cand.shape).encode())
    digest.update(cand.tobytes())
    return digest.hexdigest()


def as_demonstrations(items: Iterable) -> list[Demonstration]:
    """``items`` as a list, each checked to be a :class:`Demonstration` (before a write begins)."""
    demos = list(items)
    for d in demos:
        if not isinstance(d, Demonstration):
            raise FootfallError(f"expected a Demonstration, got {type(d).__name__}")
    return demos
