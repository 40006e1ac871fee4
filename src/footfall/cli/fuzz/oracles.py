"""The fuzz's oracles: what an accepted input's result must be for a user to rely on it."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import Garbage
from footfall.core.files import checked_json
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG
from footfall.core.state import nominal_state
from footfall.data.store import DemoStore
from footfall.expert.collect import rough_x_range
from footfall.features.candidates import reachable_footholds
from footfall.features.scoring import score_footholds
from footfall.learning.train import store_demonstrations
from footfall.terrain.saving import summarise_map

HEIGHT_BOUND = 1e5  # [m] no height of an accepted map is this large
ORIGIN_BOUND = 1e6  # [m] nor its origin this far from the frame's


def check_map(hmap: Any) -> None:
    """An accepted height map must be one footfall can use: finite numbers, sane sizes."""
    if not isinstance(hmap, HeightMap):
        raise Garbage(f"not a HeightMap: {type(hmap).__name__}")
    h = hmap.heights
    if h.ndim != 2 or h.dtype.kind != "f":
        raise Garbage(f"heights of shape {h.shape} and dtype {h.dtype}")
    known = h[~np.isnan(h)]
    if known.size == 0 or not np.all(np.abs(known) < HEIGHT_BOUND):
        raise Garbage("heights missing, infinite or absurd")
    r, (ox, oy) = hmap.resolution, hmap.origin
    if not (math.isfinite(r) and 0 < r <= 10 and abs(ox) <= ORIGIN_BOUND
            and abs(oy) <= ORIGIN_BOUND):
        raise Garbage(f"resolution {r!r} or origin {hmap.origin!r}")
    checked_json(hmap.metadata, "metadata")
    summary = summarise_map(hmap, "fuzz.npz")
    json.dumps(summary.as_dict(), allow_nan=False)
    rough_x_range(hmap)
    hmap.height_at(np.array([[ox + r, oy + r]]))


def check_model(model: Any, bases: Bases) -> None:
    """An accepted model must rank footholds with finite rewards on a valid map -- once it is
    accepted as every command that uses a model accepts it: for the robot footfall walks
    (``check_compatible``; a model of another robot is refused there, in one line)."""
    model.check_compatible(robot=LITTLEDOG)
    hmap = HeightMap.load(bases.map)
    for leg in ("LF", "RH"):
        state = nominal_state(hmap, (0.3, 0.0), 0.0, leg)
        footholds = reachable_footholds(hmap, state)[::25]
        rewards = score_footholds(hmap, state, footholds, model.reward_for(leg), model.robot)
        valid = rewards[np.isfinite(rewards)]
        if np.isnan(rewards).any() or np.isposinf(rewards).any() or valid.size == 0:
            raise Garbage(f"{leg} rewards not finite: {rewards[:5]}")


def check_demonstrations(path: Path) -> None:
    """Every demonstration read from an accepted store holds finite numbers of the right shape."""
    demos, terrains = store_demonstrations(path)
    for hmap in terrains.values():
        check_map(hmap)
    for d in demos:
        c = np.asarray(d.candidates)
        if c.ndim != 2 or c.shape[1] != 3 or c.dtype != np.float64 or not np.isfinite(c).all():
            raise Garbage(f"demonstration {d.id}: candidates {c.shape} {c.dtype}")
        if not (isinstance(d.chosen, int) and 0 <= d.chosen < len(c)):
            raise Garbage(f"demonstration {d.id}: chosen {d.chosen!r} of {len(c)}")
        if d.terrain_hash not in terrains:
            raise Garbage(f"demonstration {d.id}: its terrain is missing")
        for name in ("body_position", "body_rpy", "feet"):
            a = np.asarray(getattr(d.state, name))
            if not np.isfinite(a).all():
                raise Garbage(f"demonstration {d.id}: state {name} not finite")


def check_runs(path: Path) -> None:
    """Every run log read from an accepted store holds finite times, positions and candidates,
    rewards that are numbers or -inf (an invalid candidate), and a choice among them."""
    with DemoStore(path, read_only=True) as store:
        records = [store.run(head["id"]) for head in store.runs()]
    for run in records:
        for step in run.steps:
            c, r = np.asarray(step.candidates), np.asarray(step.rewards)
            if not np.isfinite(c).all() or np.isnan(r).any() or np.isposinf(r).any():
                raise Garbage(f"run {run.id} step {step.k}: candidates or rewards not finite")
            if not (0 <= step.chosen < len(c)) or not math.isfinite(step.t_liftoff):
                raise Garbage(f"run {run.id} step {step.k}: chosen {step.chosen!r} or lift-off")
            touchdown = np.asarray(step.touchdown)
            if not (np.isfinite(touchdown).all() or np.isnan(touchdown).all()):
                raise Garbage(f"run {run.id} step {step.k}: touch-down half defined")
            if not (math.isnan(step.slip) or 0 <= step.slip < HEIGHT_BOUND):
                raise Garbage(f"run {run.id} step {step.k}: slip {step.slip!r}")

