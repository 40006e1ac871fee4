"""The run log: what the robot chose at every step of a walking run, and what happened.

A :class:`RunRecord` holds one run of the simulated robot: the terrain (by
content hash), the seed, the settings, the outcome, and one :class:`RunStep`
per foothold decision -- the state, the swing leg, the candidate set F with
each candidate's reward, the chosen foothold, and then where the foot
actually touched down and how far it slipped. Runs live in the
demonstration store (:class:`footfall.data.store.DemoStore`), so that an expert
can later be shown a run and point out bad choices, which become
demonstrations in the same file; and so that a run can be replayed.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import checked_json
from footfall.core.state import RobotState
from footfall.data.frozen import set_fields


@dataclass(frozen=True, eq=False)
class RunStep:
    """One foothold decision of a run and its outcome."""

    k: int  # step number in the run, from 0
    state: RobotState  # the planner's state when it chose (feet, body pose, swing leg, goal)
    candidates: np.ndarray  # (n, 3) [m] candidate contact points x, y, terrain height z
    rewards: np.ndarray  # (n,) the reward function's value of each candidate (-inf: invalid)
    chosen: int  # index into candidates of the planned foothold
    t_liftoff: float  # [s] simulation time the swing began
    t_touchdown: float = math.nan  # [s] time the foot touched down (NaN: it never did)
    touchdown: np.ndarray = field(  # (3,) [m] foot-centre position at touch-down (NaN: none)
        default_factory=lambda: np.full(3, np.nan))
    slip: float = math.nan  # [m] foot-centre travel from touch-down to its next lift-off (NaN: run ended)

    def __post_init__(self) -> None:
        if not isinstance(self.state, RobotState):
            raise FootfallError("a run step needs a RobotState")
        cand = np.array(self.candidates, dtype=np.float64)
        rew = np.array(self.rewards, dtype=np.float64)
        td = np.array(self.touchdown, dtype=np.float64)
        if cand.ndim != 2 or cand.shape[1] != 3 or cand.shape[0] < 1:
            raise FootfallError(f"run step {self.k}: candidates must have shape (n, 3)")
        if rew.shape != (cand.shape[0],):
            raise FootfallError(f"run step {self.k}: one reward per candidate")
        if isinstance(self.chosen, bool) or not isinstance(self.chosen, numbers.Integral) \
                or not 0 <= self.chosen < cand.shape[0]:
            raise FootfallError(f"run step {self.k}: chosen index {self.chosen!r} outside "
                                f"the {cand.shape[0]} candidates")
        if td.shape != (3,):
            raise FootfallError(f"run step {self.k}: touch-down must have shape (3,)")
        set_fields(self, candidates=cand, rewards=rew, touchdown=td, chosen=int(self.chosen))

    @property
    def swing_leg(self) -> str:
        """The leg that swung."""
        return self.state.swing_leg

    @property
    def foothold(self) -> np.ndarray:
        """The planned contact point (3,) [m]."""
        return self.candidates[self.chosen]

    @property
    def placement_error(self) -> float:
        """Horizontal distance [m] of the touch-down foot centre from the plan (NaN: none)."""
        return float(np.hypot(*(self.touchdown[:2] - self.foothold[:2])))


@dataclass(frozen=True, eq=False)
class RunRecord:
    """One walking run: where, with what, how it ended, and every step."""

    terrain_hash: str  # HeightMap.content_hash() of the board the planner saw
    seed: int  # the run's seed (perturbations, noise)
    settings: dict  # JSON: reward / model, controller and perturbation settings
    result: dict  # JSON: success, reason, distance [m], time [s], slip statistics [m], ...
    steps: tuple[RunStep, ...] = ()
    key: str | None = None  # unique name of the run in a store (e.g. for resuming), optional
    id: int | None = None  # set by the store

    def __post_init__(self) -> None:
        if not isinstance(self.terrain_hash, str) or len(self.terrain_hash) != 64:
            raise FootfallError("a run needs the terrain's 64-hex-digit content hash")
        if isinstance(self.seed, bool) or not isinstance(self.seed, numbers.Integral):
            raise FootfallError(f"a run's seed is an integer, got {self.seed!r}")
        object.__setattr__(self, "settings", checked_json(self.settings, "run settings", object_only=True))
        object.__setattr__(self, "result", checked_json(self.result, "run result", object_only=True))
        steps = tuple(self.steps)
        for s in steps:
            if not isinstance(s, RunStep):
                raise FootfallError(f"expected RunStep, got {type(s).__name__}")
        if [s.k for s in steps] != list(range(len(steps))):
            raise FootfallError("run steps must be numbered 0, 1, 2, ... in order")
        object.__setattr__(self, "steps", steps)
        if self.key is not None and not isinstance(self.key, str):
            raise FootfallError("a run key is a string")

    def slips(self) -> np.ndarray:
        """Measured slips [m] of the steps whose foot swung again, (m,)."""
        s = np.array([st.slip for st in self.steps], dtype=np.float64)
        return s[np.isfinite(s)]
