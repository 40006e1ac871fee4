"""The scale of a scorer (a reward): the unit in which its differences compare to another reward's.

Learned weights are logits of preference with no fixed unit, while the
footstep planner's path bias and the body path's clearance penalties are
stated in units of the hand-tuned reward. A reward's *spread* -- how much it
varies over a rough reference module -- converts between the two.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES
from footfall.core.state import RobotState, nominal_state
from footfall.features.candidates import reachable_footholds
from footfall.features.family import Candidates
from footfall.features.reward import default_reward
from footfall.features.scorer import FootholdScorer
from footfall.terrain import make_module

REFERENCE_MODULE = ("rocky", 0.5, 0)  # kind, difficulty, seed of the terrain module on which a
# reward's spread is measured (see reward_spread): rough enough that every feature varies
REFERENCE_YAW = 0.0  # [rad] heading the reference module is scored at (+x)
_UNIT_FLOOR = 1e-3  # [-] a reward that differs from the best by less than this fraction of the
# rewards' mean magnitude is float noise of the dense scoring (float32), not terrain


def reward_unit(rewards: list[np.ndarray]) -> float:
    """The reward unit of a map: std of the finite per-foothold rewards, pooled over arrays.

    Floored at ``1e-3`` of their mean magnitude, so that float noise on a
    uniform terrain is not mistaken for differences; 1.0 if the rewards are
    all equal to zero or there are none.
    """
    finite = np.concatenate([r[np.isfinite(r)] for r in rewards]) if rewards else np.zeros(0)
    if finite.size == 0:
        return 1.0
    unit = max(float(finite.std()), _UNIT_FLOOR * float(np.abs(finite).mean()))
    return unit if unit > 0 else 1.0


@lru_cache(maxsize=1)
def _reference_module() -> HeightMap:
    return make_module(*REFERENCE_MODULE)


@lru_cache(maxsize=1)
def _reference_states() -> tuple[RobotState, ...]:
    """The robot in its default stance at the reference module's centre, each leg swinging."""
    module = _reference_module()
    x0, x1, y0, y1 = module.bounds
    centre = (0.5 * (x0 + x1), 0.5 * (y0 + y1))
    return tuple(nominal_state(module, centre, REFERENCE_YAW, leg) for leg in LEG_NAMES)


_SPREADS: dict[str, float] = {}  # spread_key -> spread (a few rewards per process)


def spread_key(reward: FootholdScorer) -> str:
    """Digest of everything that sets a reward's spread: its terrain part and its state part."""
    return reward.key(state=False) + reward.key(state=True)


def reward_spread(reward: FootholdScorer) -> float:
    """The spread of a reward: the unit in which its differences compare to another reward's.

    The terrain part's standard deviation, scored densely (5 mm lattice,
    heading +x) over :data:`REFERENCE_MODULE`, combined in quadrature with the
    state part's standard deviation over reference candidate sets (the robot in
    its default stance at the module's centre, each leg swinging in turn, its
    whole candidate set F); the state part counts only for rewards that have
    one (pose weights). A learned reward's pose part can vary over F far more
    than its terrain part, and the path bias must hold against the whole of
    it. See :func:`reward_unit`. Cached by the reward's content, so equal
    rewards get the very same number.
    """
    key = spread_key(reward)
    if key not in _SPREADS:
        module = _reference_module()
        grid = reward.dense(module, spacing=0.005, yaw=REFERENCE_YAW)
        spread = reward_unit([np.asarray(grid.reward)[np.asarray(grid.valid)]])
        if reward.has_state_part:
            state_part = np.concatenate([reward.state_values(Candidates.of_state(
                module, state, reachable_footholds(module, state, spacing=0.005), reward.config))
                for state in _reference_states()])
            spread = math.hypot(spread, float(np.nanstd(state_part)))
        _SPREADS[key] = spread
    return _SPREADS[key]


def path_bias_weight(reward: FootholdScorer, bias_weight: float) -> float:
    """The footstep planner's path bias for ``reward`` [reward/m]: ``bias_weight`` [hand-tuned
    reward/m] scaled by the reward's spread over the hand-tuned reward's.

    A reward with the hand-tuned default's terrain and pose parts has the ratio 1 exactly, so
    its bias is ``bias_weight`` to the last bit without scoring the reference module at all (a
    module made and scored: ~0.5 s of CPU, once per process, that would only be divided by
    itself); other rewards are scaled by their cached spreads. A scorer with its own path
    preference (the expert's stance term) gets none.
    """
    if reward.own_path_preference:
        return 0.0
    reward = reward.spread_basis
    default = default_reward(reward.config)
    if spread_key(reward) == spread_key(default):
        return float(bias_weight)
    return float(bias_weight) * (reward_spread(reward) / reward_spread(default))
