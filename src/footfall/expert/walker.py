"""The kinematic walker: the synthetic expert's demonstrations without a simulator.

The body glides along a straight line across a board in the crawl gait while
an expert picks each swing leg's next foothold from the candidate set F; each
decision is a :class:`~footfall.data.store.Demonstration`. No dynamics, no balance.
One walk is :func:`walk_demonstrations`; spreading many over boards and lateral
paths is :mod:`footfall.expert.collect`.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import DEFAULT_STRIDE, LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.core.state import RobotState, nominal_state, stance_target
from footfall.data.store import Demonstration
from footfall.expert.protocol import Expert, expert_settings, kept_verdict, teacher_verdict
from footfall.features.candidates import DEFAULT_SPACING, reachable_footholds
from footfall.features.config import FeatureConfig

APPROACH = 0.12  # [m] flat approach walked before the recorded x range begins
EDGE_MARGIN = 0.15  # [m] the hips stay this far inside the board's x ends (start and stop)


def _check_rng(rng: Any) -> np.random.Generator:
    if not isinstance(rng, np.random.Generator):
        raise FootfallError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    return rng


def _finite(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise FootfallError(f"{what} must be a finite number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class WalkOptions:
    """How the kinematic walker walks, and the source it records with each demonstration."""

    stride: float = DEFAULT_STRIDE  # [m] body advance per gait cycle (four steps), > 0
    robot: RobotDescription = LITTLEDOG  # stance, gait order, kinematics
    spacing: float = DEFAULT_SPACING  # [m] candidate lattice spacing
    config: FeatureConfig | None = None  # candidates need enough data for these feature
    # patches; None: FeatureConfig(), so every candidate has valid features
    source: str = "walker"  # the source recorded with each demonstration
    search_radius: float | None = None  # [m] F: the reachable footholds within this of the
    # swing leg's gait-nominal foothold (stance_target), as the walking planner's F, or every
    # reachable one where fewer than two are that near; None: every reachable foothold
    lead: float = 0.0  # [m] how far ahead of the default stance the gait-nominal foothold lies

    def __post_init__(self) -> None:
        r = self.search_radius
        if r is not None and not (isinstance(r, numbers.Real) and math.isfinite(r) and r > 0):
            raise FootfallError(f"search_radius must be a positive number of metres or None, "
                                f"got {r!r}")
        if not (isinstance(self.lead, numbers.Real) and math.isfinite(self.lead)):
            raise FootfallError(f"lead must be a finite number of metres, got {self.lead!r}")


@dataclass(frozen=True)
class WalkPath:
    """Where one walk goes along the board, and which of its steps become demonstrations."""

    y: float = 0.0  # [m] lateral position of the body's path
    start_x: float | None = None  # [m] start of the body; None: the hind hips EDGE_MARGIN inside
    # the board's near x end (or, with x_range, an APPROACH before the front feet reach it)
    x_range: tuple[float, float] | None = None  # [m] record only steps whose chosen foothold has
    # x_range[0] <= x <= x_range[1] (e.g. the rough modules); the walk itself takes every step
    record_every: int = 1  # [steps] record only eligible steps (those x_range keeps) number
    record_phase: int = 0  # record_phase, record_phase + record_every, ... (counting from 0), to
    # spread a few demonstrations along the path; an odd record_every rotates them through the legs
    start_shift: float = 0.0  # [m] added to the start along x (a collection draws it per walk
    # from its seed, so that another seed walks through other states)


def walk_demonstrations(hmap: HeightMap, expert: Expert, rng: np.random.Generator, n_max: int,
                        path: WalkPath = WalkPath(), options: WalkOptions = WalkOptions(), *,
                        expert_info: dict | None = None,
                        progress: Callable[[Demonstration], None] | None = None
                        ) -> list[Demonstration]:
    """Walk straight along +x (heading 0) at lateral position ``path.y``, recording each choice.

    The robot starts standing in its nominal stance with the body at
    ``(path.start_x, path.y)``. Step k swings leg ``robot.gait_order[k % 4]``
    (crawl: LH, LF, RH, RF): the body first moves ``stride / 4`` forward, to
    where it is at touch-down, at height ``robot.nominal_height`` above the
    mean height of the four feet, which stay where they are; F is
    ``reachable_footholds(hmap, state, robot, spacing, config)`` for that
    state, the expert chooses from F, and the swing foot moves there.

    The walk stops when ``n_max`` demonstrations are recorded, when the front
    hips would come within ``EDGE_MARGIN`` of the board's far x end, or when
    the swing leg has fewer than two candidates (e.g. a hole under it).
    Feet are not checked for reach after touch-down: an expert that places a
    foot far behind its hip leaves it beyond reach later in the stance.

    Parameters
    ----------
    hmap : HeightMap
        The board; its frame's x axis is the walking direction.
    expert : Expert
        Its ``choose(hmap, state, candidates, rng) -> int`` chooses; its verdict on every
        candidate (:func:`~footfall.expert.protocol.teacher_verdict`) is kept with each
        demonstration.
    rng : numpy.random.Generator
        Passed to every ``expert.choose``; the same seed gives the same walk.
    n_max : int
        Most demonstrations to record (>= 0).
    path : WalkPath
        The lateral position, start and recorded steps of the walk.
    options : WalkOptions
        Stride, robot, candidate spacing and feature config, and the source recorded.
    expert_info : dict, optional
        Expert settings to record; default :func:`expert_settings` of ``expert``.
    progress : callable, optional
        Called with each recorded demonstration.

    Returns
    -------
    list of Demonstration
        In walking order, ``id`` None, all with ``terrain_hash = hmap.content_hash()``.

    Raises
    ------
    FootfallError
        For bad arguments, a start stance off the map or on cells without
        data, or an expert that returns an index outside F.
    """
    rng, stride, path = _checked_walk(hmap, rng, n_max, path, options)
    config = FeatureConfig() if options.config is None else options.config
    info = expert_settings(expert) if expert_info is None else dict(expert_info)
    start = _start_state(hmap, path, options.robot)
    terrain_hash = hmap.content_hash()
    x_range = path.x_range
    out: list[Demonstration] = []
    eligible = 0  # steps so far whose foothold x_range keeps
    steps = _walk(hmap, expert, rng, start, path, stride, options, config) if n_max > 0 else ()
    for state, candidates, choice in steps:
        foothold = candidates[choice]
        if x_range is None or x_range[0] <= foothold[0] <= x_range[1]:
            if eligible % path.record_every == path.record_phase:
                verdict = kept_verdict(*teacher_verdict(expert, hmap, state, candidates), choice)
                demo = Demonstration(terrain_hash, state, candidates, choice, options.source, info,
                                     values=verdict[0], refused=verdict[1], judged=verdict[2])
                out.append(demo)
                if progress is not None:
                    progress(demo)
                if len(out) >= n_max:
                    break  # before the next step: the expert draws from rng no more
            eligible += 1
    return out


def _walk(hmap: HeightMap, expert: Expert, rng: np.random.Generator, start: RobotState,
          path: WalkPath, stride: float, options: WalkOptions, config: FeatureConfig
          ) -> Iterator[tuple[RobotState, np.ndarray, int]]:
    """The walk's steps from the ``start`` stance, as (state at touch-down, candidates F (n, 3)
    [m], the expert's choice in F); each step's swing foot lands on its choice."""
    robot, x_range = options.robot, path.x_range
    feet = start.feet.copy()  # (4, 3) [m], in LEG_NAMES order
    goal = start.goal  # 1 km straight ahead along the path
    stop_x = hmap.bounds[1] - robot.hip_x - EDGE_MARGIN  # [m] last body x: the front hips stay on
    step = stride / 4  # [m] body advance per swing
    k = 0
    while True:
        body_x = path.start_x + (k + 1) * step  # [m] at the touch-down of step k
        if body_x > stop_x:
            return
        if x_range is not None and body_x - robot.hip_x - robot.max_reach > x_range[1]:
            return  # no foot can land in the recorded range any more
        leg = robot.gait_order[k % len(robot.gait_order)]
        body = np.array([body_x, path.y, feet[:, 2].mean() + robot.nominal_height])
        state = RobotState(feet, body, np.zeros(3), leg, goal)
        decision = _decide(hmap, expert, rng, state, options, config)
        if decision is None:
            return
        candidates, choice = decision
        yield state, candidates, choice
        feet[LEG_NAMES.index(leg)] = candidates[choice]  # the swing foot lands
        k += 1


def _checked_walk(hmap: HeightMap, rng: Any, n_max: Any, path: WalkPath, options: WalkOptions
                  ) -> tuple[np.random.Generator, float, WalkPath]:
    """The walker's arguments checked: the generator, the stride [m] and the path with its start
    (and every number) filled in; raises FootfallError for a bad one."""
    if not isinstance(hmap, HeightMap):
        raise FootfallError(f"the walker needs a HeightMap, got {type(hmap).__name__}")
    rng = _check_rng(rng)
    if isinstance(n_max, bool) or not isinstance(n_max, numbers.Integral) or n_max < 0:
        raise FootfallError(f"n_max must be a non-negative integer, got {n_max!r}")
    stride = _finite(options.stride, "stride")
    if stride <= 0:
        raise FootfallError(f"stride must be > 0 m, got {stride}")
    y = _finite(path.y, "y")
    robot, x_range = options.robot, path.x_range
    shift = _finite(path.start_shift, "start_shift")
    default_start = path.start_x is None
    start_x = (hmap.bounds[0] + robot.hip_x + EDGE_MARGIN if default_start
               else _finite(path.start_x, "start_x"))
    if x_range is not None:
        lo, hi = (_finite(v, "x_range") for v in x_range)
        if lo > hi:
            raise FootfallError(f"x_range must be (low, high), got {tuple(x_range)}")
        if default_start:
            # Steps long before the recorded range only cost time: start an
            # approach of APPROACH metres before the front feet reach it.
            start_x = max(start_x, lo - robot.hip_x - APPROACH)
        x_range = (lo, hi)
    start_x += shift
    every, phase = path.record_every, path.record_phase
    for value, what in ((every, "record_every"), (phase, "record_phase")):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 0:
            raise FootfallError(f"{what} must be a non-negative integer, got {value!r}")
    if not 0 <= phase < every:
        raise FootfallError(f"record_phase must be in [0, record_every), got {phase} "
                            f"with record_every {every}")
    return rng, stride, WalkPath(y, start_x, x_range, every, phase)  # start_x includes the shift


def _start_state(hmap: HeightMap, path: WalkPath, robot: RobotDescription) -> RobotState:
    """The nominal stance at the walk's start; raises FootfallError where a foot has no data."""
    state = nominal_state(hmap, (path.start_x, path.y), 0.0, robot.gait_order[0], robot=robot)
    if np.isnan(hmap.height_at(state.feet[:, :2])).any():
        raise FootfallError(f"walker start ({path.start_x:.3f}, {path.y:.3f}) m: the feet of the "
                            f"nominal stance are off the terrain or on cells without data")
    return state


def _decide(hmap: HeightMap, expert: Expert, rng: np.random.Generator, state: RobotState,
            options: WalkOptions, config: FeatureConfig) -> tuple[np.ndarray, int] | None:
    """The swing leg's candidates F (n, 3) [m] and the expert's choice among them; None where
    F has fewer than two (the walk stops)."""
    candidates = reachable_footholds(hmap, state, options.robot, options.spacing, config)
    if options.search_radius is not None:
        target = stance_target(state, options.robot, options.lead)
        near = np.sum((candidates[:, :2] - target) ** 2, axis=1) <= options.search_radius ** 2
        if np.count_nonzero(near) >= 2:
            candidates = candidates[near]
    if candidates.shape[0] < 2:
        return None
    choice = expert.choose(hmap, state, candidates, rng)
    if isinstance(choice, bool) or not isinstance(choice, numbers.Integral) \
            or not 0 <= choice < candidates.shape[0]:
        raise FootfallError(f"the expert chose {choice!r}, not an index into the "
                            f"{candidates.shape[0]} candidates")
    return candidates, int(choice)
