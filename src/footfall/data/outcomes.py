"""What followed each foothold of a logged run: the robot's own labels of its footholds.

A run log (:class:`~footfall.data.runlog.RunRecord`) says where each planned
foothold was, where the foot touched down, how far it travelled in stance,
and how the run ended (with the flight recorder's account of a failure,
:func:`footfall.sim.explain.explain_run`). :func:`step_outcomes` turns that
into one row per step of outcome labels -- no expert involved:

* ``used``: the foot touched down (a foothold the robot stood on);
* ``placement_error`` [m]: touch-down foot centre from the plan, horizontally;
* ``slip`` [m]: the foot centre's travel from touch-down to its next lift-off
  (NaN where the run ended first);
* ``slid``: that travel exceeded :data:`STANCE_SLID`, or the run's failure was
  put down to this foot sliding while it stood here;
* ``missed``: the foot touched down more than :data:`MISSED` from the plan (the swing
  did not get there: caught on an edge, or the body was already going);
* ``next_missed``: the swing that left this foothold missed the leg's next one (a riser
  just ahead of a foothold, say, catches the foot as it lifts);
* ``fall``: the run fell (trunk tilted or touched the terrain) during this step
  or one of the next ``horizon`` steps -- with the default horizon of 3, within
  one crawl-gait cycle of the foot being put here;
* ``failed``: the same for any failure (a fall, stuck, out of time).

The step during which a run ended is its last logged step (a step is logged
when its foothold is chosen); a foothold chosen and never touched down is not
``used``, and the evaluations read only used footholds.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.data.runlog import RunRecord
from footfall.data.store import DemoStore

STANCE_SLID = 0.015  # [m] a stance foot this far from its touch-down point has slid (the ball
# rolls a few mm as the body passes over it); the flight recorder's threshold too
MISSED = 0.02  # [m] a foot touching down this far from its planned foothold missed it
FALL_HORIZON = 3  # [steps] a fall this many steps after a foothold still counts against it
OUTCOME_LABELS = ("slid", "missed", "next_missed", "fall", "failed")  # the boolean labels an evaluation can predict


@dataclass(frozen=True)
class StepOutcomes:
    """Outcome labels of the steps of one run, each an array of shape (n_steps,)."""

    used: np.ndarray  # bool: the foot touched down
    placement_error: np.ndarray  # [m] touch-down from the plan, horizontal (NaN: no touch-down)
    slip: np.ndarray  # [m] stance travel from touch-down to next lift-off (NaN: the run ended)
    slid: np.ndarray  # bool: slip > STANCE_SLID, or the failure's sliding stance foot stood here
    missed: np.ndarray  # bool: touched down more than MISSED from the plan
    next_missed: np.ndarray  # bool: the same leg's next foothold was missed
    fall: np.ndarray  # bool: the run fell during this step or one of the next `horizon`
    failed: np.ndarray  # bool: the run failed (any reason) during this step or the next `horizon`


def _failure_kind(result: dict) -> str | None:
    """'fall', 'other' (stuck, time limit, step limit) or None for a success."""
    if result.get("success"):
        return None
    return "fall" if str(result.get("reason", "")).startswith("fall") else "other"


def step_outcomes(run: RunRecord, horizon: int = FALL_HORIZON,
                  slid_threshold: float = STANCE_SLID) -> StepOutcomes:
    """The outcome labels of every step of ``run`` (see the module).

    Parameters
    ----------
    run : RunRecord
        A logged run with its result (``success``, ``reason``; a failure's
        ``explanation`` may name the stance foot that slid).
    horizon : int
        Steps after a foothold's own step during which a fall still counts
        against it (>= 0).
    slid_threshold : float
        [m] stance travel above which a foot has slid.
    """
    if isinstance(horizon, bool) or not isinstance(horizon, int) or horizon < 0:
        raise FootfallError(f"the outcome horizon is a whole number of steps >= 0, got {horizon!r}")
    if not (np.isfinite(slid_threshold) and slid_threshold > 0):
        raise FootfallError(f"the slid threshold is a distance > 0 [m], got {slid_threshold!r}")
    steps = run.steps
    n = len(steps)
    touchdown = np.array([s.touchdown for s in steps], dtype=np.float64).reshape(n, 3)
    planned = np.array([s.foothold for s in steps], dtype=np.float64).reshape(n, 3)
    used = np.isfinite(touchdown).all(axis=1)
    placement = np.where(used, np.hypot(*(touchdown[:, :2] - planned[:, :2]).T), np.nan)
    slip = np.array([s.slip for s in steps], dtype=np.float64)
    slid = np.nan_to_num(slip, nan=0.0) > slid_threshold

    kind = _failure_kind(run.result)
    near_end = (n - 1 - np.arange(n)) <= horizon  # the run ended during this step or the next h
    failed = near_end & (kind is not None)
    fall = near_end & (kind == "fall")
    # A failure put down to a sliding stance foot: that foot's last foothold before the end.
    explanation = run.result.get("explanation") or {}
    leg = (explanation.get("slip") or {}).get("leg") if kind is not None else None
    moved = (explanation.get("slip") or {}).get("moved_mm")
    if leg is not None and moved is not None and moved > 1e3 * slid_threshold:
        stood = [k for k in range(n) if used[k] and steps[k].swing_leg == leg]
        if stood:
            slid[stood[-1]] = True
    missed = np.nan_to_num(placement, nan=0.0) > MISSED
    next_missed = np.zeros(n, dtype=bool)
    legs = np.array([s.swing_leg for s in steps])
    for leg_name in np.unique(legs):  # the four legs' footholds, each in order
        mine = np.flatnonzero(legs == leg_name)
        next_missed[mine[:-1]] = missed[mine[1:]]
    return StepOutcomes(used, placement, slip, slid, missed, next_missed, fall, failed)


def stored_outcomes(store: DemoStore, key_prefix: str | None = None,
                    horizon: int = FALL_HORIZON
                    ) -> Iterator[tuple[dict, RunRecord, HeightMap, StepOutcomes]]:
    """Every run of an open store (key starting with ``key_prefix``), in creation order: its
    head (:meth:`DemoStore.runs`), the run, its board (each read once) and its outcome labels."""
    boards: dict[str, HeightMap] = {}
    for head in store.runs(key_prefix=key_prefix):
        run = store.run(head["id"])
        if run.terrain_hash not in boards:
            boards[run.terrain_hash] = store.terrain(run.terrain_hash)
        yield head, run, boards[run.terrain_hash], step_outcomes(run, horizon)
