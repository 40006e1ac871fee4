"""Demonstrations collected over boards: many walks of the kinematic walker, spread evenly.

:func:`collect_demonstrations` walks every board along lateral paths, round
after round, each walk of the kinematic walker (:mod:`footfall.expert.walker`)
recording an equal share of the demonstrations still missing;
:func:`collect_into_store` does so with the synthetic expert on terrain files
and adds the demonstrations to a store (``footfall demos collect``).
"""

from __future__ import annotations

import math
import numbers
import os
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import distinct_inputs, writable_path
from footfall.core.heightmap import HeightMap
from footfall.core.limits import check_count
from footfall.core.robot import DEFAULT_STRIDE, LITTLEDOG, RobotDescription
from footfall.data.schema import FORMAT as STORE_FORMAT
from footfall.data.schema import SUFFIXES as STORE_SUFFIXES
from footfall.data.store import Demonstration, DemoStore
from footfall.expert.protocol import Expert, expert_settings
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert
from footfall.expert.walker import EDGE_MARGIN, WalkOptions, WalkPath, walk_demonstrations
from footfall.features.candidates import DEFAULT_SPACING
from footfall.features.config import FeatureConfig

PATH_OFFSETS = (-0.15, -0.05, 0.05, 0.15)  # [m] lateral paths, relative to the board's centre
MAX_PATH_ROUNDS = 6  # rounds of ever denser lateral paths before collect gives up
PATH_HALF_WIDTH = 0.15  # [m] the lateral paths cover the board's centre +- this
MAX_START_SHIFT = 0.25  # [steps] a collection's walks start up to this much of a step late


def rough_x_range(hmap: HeightMap) -> tuple[float, float] | None:
    """The x range [m] of a board's non-flat modules, from its metadata.

    Returns
    -------
    (float, float) or None
        From the first non-flat module's ``x_start`` to the last one's
        ``x_end`` [m], in the map's frame; None if the metadata lists no
        modules or only flat ones (then the whole board counts).
    """
    modules = hmap.metadata.get("modules")
    if not isinstance(modules, list):
        return None
    rough = [m for m in modules if isinstance(m, dict) and m.get("kind") != "flat"
             and isinstance(m.get("x_start"), numbers.Real)
             and isinstance(m.get("x_end"), numbers.Real)]
    if not rough:
        return None
    return float(min(m["x_start"] for m in rough)), float(max(m["x_end"] for m in rough))


def estimated_steps(hmap: HeightMap, x_range: tuple[float, float] | None,
                    stride: float = DEFAULT_STRIDE, robot: RobotDescription = LITTLEDOG) -> int:
    """About how many steps of a default walk across ``hmap`` have footholds in ``x_range``.

    Assumes each foot lands half a stride ahead of its hip's position [m];
    ``x_range`` None counts every step.
    """
    x_min, x_max, _, _ = hmap.bounds
    start = x_min + robot.hip_x + EDGE_MARGIN  # [m] as in walk_demonstrations
    stop = x_max - robot.hip_x - EDGE_MARGIN
    step = stride / 4
    k = np.arange(max(math.floor((stop - start) / step + 1e-9), 0))
    hip_x = np.array([robot.leg(leg).hip[0] for leg in robot.gait_order])
    foot = start + (k + 1) * step + hip_x[k % len(hip_x)] + stride / 2
    if x_range is None:
        return int(k.size)
    return int(np.count_nonzero((foot >= x_range[0]) & (foot <= x_range[1])))


def _path_offsets(round_: int) -> list[float]:
    """Lateral offsets [m] of round ``round_``: PATH_OFFSETS, then midpoints of all before."""
    if round_ == 0:
        return list(PATH_OFFSETS)
    n = (len(PATH_OFFSETS) - 1) * 2 ** (round_ - 1)  # gaps between the earlier paths
    edges = np.linspace(-PATH_HALF_WIDTH, PATH_HALF_WIDTH, n + 1)
    return [round(float(o), 12) + 0.0 for o in 0.5 * (edges[:-1] + edges[1:])]


def lateral_paths(hmap: HeightMap, round_: int, robot: RobotDescription = LITTLEDOG
                  ) -> list[float]:
    """The lateral positions y [m] of the walker's paths in one round.

    Round 0: the board's centre plus :data:`PATH_OFFSETS`; round r > 0: the
    midpoints between all paths of the earlier rounds, so every round fills
    the gaps. Paths whose nominal feet would come within 0.05 m of the
    board's sides are dropped; if that drops all of round 0, it walks the
    centre line, and no later round repeats a path.
    """
    _, _, y_min, y_max = hmap.bounds
    centre = 0.5 * (y_min + y_max)
    half = 0.5 * (y_max - y_min) - robot.nominal_foot_y - 0.05  # [m] room for the feet
    earlier: list[float] = []
    for r in range(round_ + 1):
        kept = [o for o in _path_offsets(r) if abs(o) <= half
                and all(abs(o - e) > 1e-9 for e in earlier)]
        if r == 0 and not kept:
            kept = [0.0]
        if r < round_:
            earlier += kept
    return [centre + o for o in kept]


def collect_demonstrations(hmaps: Sequence[HeightMap], expert: Expert, n: int, seed: int,
                           rough_only: bool = True, stride: float = DEFAULT_STRIDE,
                           robot: RobotDescription = LITTLEDOG, spacing: float = DEFAULT_SPACING,
                           config: FeatureConfig | None = None, source: str = "walker",
                           progress: Callable[[Demonstration], None] | None = None,
                           max_rounds: int = MAX_PATH_ROUNDS, search_radius: float | None = None,
                           lead: float = 0.0) -> list[Demonstration]:
    """About ``n`` demonstrations spread evenly over terrains and lateral paths.

    In round r every terrain is walked along each path of
    :func:`lateral_paths` (round r), each walk recording an equal share of
    the demonstrations still missing. Rounds continue, with new paths
    between the old ones, until ``n`` are collected, a round adds none, or
    after ``max_rounds`` rounds; so fewer than ``n`` come back only
    when the terrains are too short for them. A walk whose share is smaller
    than the eligible steps on its path (:func:`estimated_steps`) records
    every m-th of them (m odd, so the legs take turns), so that a small
    ``n`` is spread along the rough modules and over all four legs rather
    than taken from where they begin.

    Parameters
    ----------
    hmaps : sequence of HeightMap
        The terrains (duplicates, by content hash, are walked once).
    expert : Expert
        Chooses every foothold.
    n : int
        Demonstrations wanted (>= 1).
    seed : int
        Each walk gets its own generators, seeded from ``(seed, terrain,
        round, path)``: one for the expert, one for where the walk starts
        along x (up to :data:`MAX_START_SHIFT` of a step after the default
        start), so that every seed walks through other states -- even with
        an expert that draws nothing -- and the same arguments give the same result.
    rough_only : bool
        Record only footholds on a board's non-flat modules
        (:func:`rough_x_range`; boards without module metadata count whole).
    stride, robot, spacing, config, source, search_radius, lead
        As for :class:`WalkOptions` (``search_radius`` [m]: F as the walking planner's).
    progress : callable, optional
        As for :func:`walk_demonstrations`.
    max_rounds : int
        Most rounds of lateral paths (>= 1).

    Returns
    -------
    list of Demonstration
        At most ``n``, in walking order.
    """
    n = check_count(n, "the number of demonstrations", minimum=1)
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise FootfallError(f"seed must be a non-negative integer, got {seed!r}")
    unique: dict[str, HeightMap] = {}
    for hmap in hmaps:
        unique.setdefault(hmap.content_hash(), hmap)
    terrains = list(unique.values())
    if not terrains:
        raise FootfallError("collecting demonstrations needs at least one terrain")
    options = WalkOptions(stride, robot, spacing, config, source, search_radius, lead)
    info = expert_settings(expert)
    out: list[Demonstration] = []
    for round_ in range(max_rounds):
        walks = _round_walks(terrains, round_, robot)
        before = len(out)
        for w, (t, j, y) in enumerate(walks):
            remaining = n - len(out)
            if remaining <= 0:
                break
            quota = -(-remaining // (len(walks) - w))  # an equal share; later walks make up
            path = _spread_path(terrains[t], y, quota, w, rough_only, options,
                                _start_shift(seed, (t, round_, j), stride))
            rng = np.random.default_rng(np.random.SeedSequence(int(seed),
                                                               spawn_key=(t, round_, j)))
            out += walk_demonstrations(terrains[t], expert, rng, quota, path, options,
                                       expert_info=info, progress=progress)
        if len(out) >= n or len(out) == before:
            break
    return out[:n]


def _start_shift(seed: int, walk: tuple[int, int, int], stride: float) -> float:
    """Where walk ``walk`` (terrain, round, path) starts after the default start [m]: drawn from
    its own stream of ``seed`` (not the expert's), in [0, MAX_START_SHIFT * stride / 4)."""
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(*walk, 1)))
    return float(rng.uniform(0.0, MAX_START_SHIFT * stride / 4))


def _round_walks(terrains: Sequence[HeightMap], round_: int, robot: RobotDescription
                 ) -> list[tuple[int, int, float]]:
    """The walks of one round as (terrain index, path index, y [m]): path by path, terrain by
    terrain, so that the shares even out over the terrains."""
    paths = [lateral_paths(hmap, round_, robot) for hmap in terrains]
    return [(t, j, ys[j]) for j in range(max(map(len, paths)))
            for t, ys in enumerate(paths) if j < len(ys)]


def _spread_path(hmap: HeightMap, y: float, quota: int, w: int, rough_only: bool,
                 options: WalkOptions, start_shift: float = 0.0) -> WalkPath:
    """The path of walk ``w`` of a round at ``y`` [m], recording ``quota`` of its eligible steps.

    A small share is spread along the path: every m-th eligible step, m odd so
    that the legs take turns, each walk starting at another phase.
    """
    x_range = rough_x_range(hmap) if rough_only else None
    every = max(estimated_steps(hmap, x_range, options.stride, options.robot) // quota, 1)
    if every % 2 == 0:
        every -= 1
    return WalkPath(y=y, x_range=x_range, record_every=every,
                    record_phase=(every // 2 + w) % every, start_shift=start_shift)


RECORDED_STEPS = ("rough", "all")  # a collection records the steps on non-flat modules, or all


@dataclass(frozen=True)
class CollectedDemonstrations:
    """What one collection added to a demonstration store."""

    store: str  # the store's path
    requested: int  # demonstrations asked for
    added: int  # demonstrations added (fewer when the terrains are too short)
    first_id: int  # id of the first demonstration added
    last_id: int  # id of the last one
    added_by_terrain: dict[str, int]  # {terrain hash: demonstrations added}, in walking order
    added_by_leg: dict[str, int]  # {swing leg: demonstrations added}, in walking order
    expert: dict[str, Any]  # the expert's settings, recorded with each demonstration
    seed: int  # the collection's seed
    steps: str  # which steps were recorded: one of RECORDED_STEPS
    total: int  # demonstrations in the store afterwards
    terrains: int  # terrains in the store afterwards

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON, in field order."""
        return dict(vars(self))


def collect_into_store(terrains: Sequence[str | os.PathLike], path: str | os.PathLike, n: int,
                       seed: int, *, noise: float | None = None,
                       second_best: float | None = None, steps: str = "rough",
                       progress: Callable[[Demonstration], None] | None = None,
                       ) -> CollectedDemonstrations:
    """Add the synthetic expert's foothold choices on terrain files to a store (created if missing).

    :func:`collect_demonstrations` spreads the ``n`` demonstrations over the
    terrains and their lateral paths. ``noise`` [value units] and
    ``second_best`` (the probability of picking the second-best foothold)
    override the expert's defaults; ``steps`` is ``"rough"`` (footholds on
    a board's non-flat modules only) or ``"all"``. The store is written in one
    transaction at the end: a failure leaves it as it was.

    Raises
    ------
    FootfallError
        For a bad output path, a terrain file or an existing store that cannot
        be read (all checked before walking), or when no demonstration was recorded.
    """
    n = check_count(n, "the number of demonstrations", minimum=1)  # before any file is read
    if steps not in RECORDED_STEPS:
        raise FootfallError(f"steps must be one of {', '.join(RECORDED_STEPS)}, got {steps!r}")
    terrains = distinct_inputs(terrains, "terrain")
    out = writable_path(path, STORE_SUFFIXES, what="store", kind="store", inputs=terrains,
                         writes=STORE_FORMAT)
    hmaps = [HeightMap.load(p) for p in terrains]
    if out.exists():
        with DemoStore(out):  # refuse a bad store before walking, not after
            pass
    settings = {k: v for k, v in (("noise", noise), ("second_best_prob", second_best))
                if v is not None}
    expert = SyntheticExpert(config=ExpertConfig(**settings))
    collected = collect_demonstrations(hmaps, expert, n, seed, rough_only=steps == "rough",
                                       progress=progress)
    if not collected:
        raise FootfallError("the walker recorded no demonstrations on these terrains "
                            "(too short, or no rough modules on its paths: try --steps all)")
    used = {d.terrain_hash for d in collected}
    with DemoStore(out, create=True) as store:
        ids = store.add_demonstrations(collected, terrains=[h for h in hmaps
                                                            if h.content_hash() in used])
        summary = store.summary()
    return CollectedDemonstrations(
        str(out), n, len(ids), ids[0], ids[-1], dict(Counter(d.terrain_hash for d in collected)),
        dict(Counter(d.swing_leg for d in collected)), collected[0].expert, seed, steps,
        summary["demonstrations"], summary["terrains"])
