"""What footfall asks of an expert, and what it records about one with each demonstration.

An expert -- the synthetic one (:class:`footfall.expert.synthetic.SyntheticExpert`),
or any other -- values the candidate set F of a robot state and chooses one
foothold; the kinematic walker and the corrections of run logs need nothing more.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import plain_json
from footfall.core.heightmap import HeightMap
from footfall.core.state import RobotState


class Expert(Protocol):
    """An expert: values and a choice over the candidate set F of a state."""

    def choose(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray,
               rng: np.random.Generator) -> int:
        """Index of the chosen foothold in ``candidates`` (n, 3) [m]."""

    def values(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray) -> np.ndarray:
        """Noiseless value of each candidate, shape (n,), higher is better."""


REFUSED_SHORTFALL = 10.0  # [value units] an expert without a veto of its own refuses a candidate
# this far below its best: the severe shortfall of footfall.expert.corrections


def teacher_verdict(expert: Any, hmap: HeightMap, state: RobotState, candidates: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A teacher's verdict on every candidate (n, 3) [m]: its values (n,) [value units], the
    candidates it refuses outright (n,) bool and the values those refusals are relative to (n,)
    [value units] -- its own ``verdict`` if it has one (a veto by a judge of its own), else its
    values, refusing those more than :data:`REFUSED_SHORTFALL` below its best. Never the best."""
    own = getattr(expert, "verdict", None)
    if callable(own):
        values, refused, judged = (np.asarray(a) for a in own(hmap, state, candidates))
        values, judged = values.astype(np.float64), judged.astype(np.float64)
        refused = refused.astype(bool)
    else:
        values = judged = np.asarray(expert.values(hmap, state, candidates), dtype=np.float64)
        refused = values.max(initial=-np.inf) - values > REFUSED_SHORTFALL
    n = len(candidates)
    if values.shape != (n,) or refused.shape != (n,) or judged.shape != (n,):
        raise FootfallError(f"the teacher's verdict has shapes {values.shape}, {refused.shape} "
                            f"and {judged.shape} for {n} candidates")
    return values, refused, judged


def kept_verdict(values: np.ndarray, refused: np.ndarray, judged: np.ndarray | None,
                 chosen: int) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """A teacher's verdict as a demonstration keeps it (finite, the choice never refused): a
    candidate valued -inf (no foothold) refused and valued at the lowest finite value (its
    judged value too); the chosen candidate not refused (an imperfect teacher may choose a
    foothold its own veto refuses: its choice is its word)."""
    values = np.asarray(values, dtype=np.float64)
    finite = np.isfinite(values)
    if judged is not None:
        judged = np.asarray(judged, dtype=np.float64)
        finite &= np.isfinite(judged)
        judged = np.where(finite, judged, judged[finite].min(initial=0.0))
    refused = np.asarray(refused, dtype=bool) | ~finite
    values = np.where(finite, values, values[finite].min(initial=0.0))
    refused[chosen] = False
    return values, refused, judged


def values_each(expert: Any, hmap: HeightMap, states: Sequence[RobotState],
                candidates: np.ndarray) -> np.ndarray:
    """An expert's values of the same candidates (n, 3) [m] in each of ``states`` (one heading
    and swing leg: a planner's rollouts), (len(states), n): its own ``values_each`` if it has
    one (the same numbers, its terrain analysis made once), else ``values`` per state."""
    own = getattr(expert, "values_each", None)
    if callable(own):
        out = np.asarray(own(hmap, states, candidates), dtype=np.float64)
    else:
        out = np.stack([np.asarray(expert.values(hmap, s, candidates), dtype=np.float64)
                        for s in states]) if states else np.zeros((0, len(candidates)))
    if out.shape != (len(states), len(candidates)):
        raise FootfallError(f"the expert returned shape {out.shape} for {len(states)} states "
                            f"of {len(candidates)} footholds")
    return out


def expert_settings(expert: Any) -> dict:
    """JSON settings of an expert, recorded with each demonstration it makes.

    ``{"class": "<module>.<name>", "config": ...}``: the config is
    ``expert.to_dict()`` if the expert has it, else its ``config``
    attribute (through ``to_dict()`` or as a dataclass) if it has one.
    """
    cls = type(expert)
    settings: dict[str, Any] = {"class": f"{cls.__module__}.{cls.__qualname__}"}
    to_dict = getattr(expert, "to_dict", None)
    config = getattr(expert, "config", None)
    if callable(to_dict):
        settings["config"] = to_dict()
    elif config is not None:
        config_to_dict = getattr(config, "to_dict", None)
        settings["config"] = config_to_dict() if callable(config_to_dict) else config
    return plain_json(settings, nonfinite="keep", other="repr")
