"""What the teaching server knows and does, without HTTP: a store's runs and steps as the page
shows them, the labels people give (paper §II-B) and their "never here" marks.

:class:`TeachService` opens the store once per server thread (SQLite
connections stay in their thread), keeps the synthetic expert's verdict on a
run once it has judged it, and turns the store's errors into the kinds the
server answers with (:class:`footfall.core.errors.NotFound` -> 404,
:class:`~footfall.data.label_queries.LabelConflict` and
:class:`~footfall.data.mark_queries.MarkConflict` -> 409, any other
:class:`FootfallError` -> 422).
"""

from __future__ import annotations

import os
import tempfile
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError, NotFound
from footfall.core.files import plain_json
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.data.inventory import terrain_label
from footfall.data.label import check_labeler
from footfall.data.runlog import RunRecord
from footfall.data.store import DemoStore
from footfall.expert.corrections import DEFAULT_MARGIN, source_of
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert
from footfall.sim.rollout import branch_lines
from footfall.teach.judging import default_expert, expert_key, judged_run, store_agreement
from footfall.teach.review import (
    SNAP_RADIUS,
    nearest_candidate,
    review_order,
    robot_pose,
    steps_to_fall,
    terrain_window,
)

JUDGED_RUNS = 32  # runs whose expert verdicts the service keeps in memory (and all in the store)
REFUSED_STEPS = 4096  # marked steps whose expert refusals the service keeps in memory


class TeachService:
    """A store's runs for people to label.

    Parameters
    ----------
    store : path
        The demonstration store (it must exist; it is upgraded to the current
        schema when opened, which adds the labels table to an older store).
    labeler : str, optional
        The name labels are given under when a request names nobody.
    expert : ExpertConfig, optional
        The synthetic expert whose disagreement orders the steps (default:
        :func:`default_expert`).
    """

    def __init__(self, store: str | os.PathLike, labeler: str | None = None,
                 expert: ExpertConfig | None = None,
                 robot: RobotDescription = LITTLEDOG) -> None:
        self.path = Path(store)
        self.labeler = None if labeler is None else check_labeler(labeler)
        self.robot = robot
        self._expert = SyntheticExpert(expert or default_expert(), robot)
        self._expert_key = expert_key(self._expert)
        self._expert_lock = threading.Lock()  # the expert keeps a cache: one judgement at a time
        self._judged: OrderedDict[int, tuple[np.ndarray, np.ndarray]] = OrderedDict()
        self._refusals: dict[tuple[int, int], np.ndarray] = {}  # the expert's, per marked step
        self._local = threading.local()
        self._opened: list[DemoStore] = []
        self._opened_lock = threading.Lock()
        with DemoStore(self.path):  # refuse a missing or foreign file now; upgrade an old one
            pass

    # --------------------------------------------------------------- the store
    def store(self) -> DemoStore:
        """This thread's connection to the store."""
        store = getattr(self._local, "store", None)
        if store is None:
            store = DemoStore(self.path, any_thread=True)  # closed by close(), from another thread
            self._local.store = store
            with self._opened_lock:
                self._opened.append(store)
        return store

    def close(self) -> None:
        """Close every thread's connection (the server has stopped)."""
        with self._opened_lock:
            for store in self._opened:
                store.close()
            self._opened.clear()

    # --------------------------------------------------------------------- runs
    def runs(self) -> list[dict[str, Any]]:
        """Every stored run, a line each: id, key, board, who chose (reward, model or judge),
        outcome (``failure``: as ``walk-many`` names it), slip, steps, labels, and the steps
        each labeler labelled (``labelled_by``)."""
        store = self.store()
        boards = {h: terrain_label(t) for h, t in store.terrain_info().items()}
        labelled: dict[int, int] = {}
        by: dict[int, dict[str, int]] = {}
        for label in store.labels():
            labelled[label.run_id] = labelled.get(label.run_id, 0) + 1
            mine = by.setdefault(label.run_id, {})
            mine[label.labeler] = mine.get(label.labeler, 0) + 1
        return [{"id": r["id"], "key": r["key"], "board": boards.get(r["terrain_hash"], "?"),
                 "chooser": _chooser(r["settings"]),
                 "success": bool(r["result"].get("success")),
                 "reason": r["result"].get("reason"), "failure": failure(r["result"]),
                 "distance_m": r["result"].get("distance"),
                 "slip_mean_mm": r["result"].get("slip_mean_mm"),
                 "steps": r["n_steps"], "labels": labelled.get(r["id"], 0),
                 "labelled_by": by.get(r["id"], {})}
                for r in store.runs()]

    def run(self, run_id: int, judge: bool = True) -> dict[str, Any]:
        """A run's steps, each with its slip, closeness to a fall and the expert's disagreement,
        and the order most worth a look (:func:`footfall.teach.review.review_order`).

        ``judge=False`` leaves the synthetic expert out (its verdict on a run's
        every step takes seconds the first time): the order then rests on the
        slips and the fall alone, and ``expert_best`` and ``shortfall`` are None.
        """
        run = self._run(run_id)
        n = len(run.steps)
        best, shortfall = self._verdicts(run) if judge else \
            (np.full(n, -1), np.full(n, np.nan))
        fell = str(run.result.get("reason", "")).startswith("fall")
        to_fall = steps_to_fall(len(run.steps), fell)
        slips = np.array([s.slip for s in run.steps], dtype=np.float64)
        labelers: dict[int, list[str]] = {}
        for label in self.store().labels(run_id=run.id):
            labelers.setdefault(label.k, []).append(label.labeler)
        steps = [{"k": s.k, "leg": s.swing_leg, "slip_mm": _mm(s.slip),
                  "steps_to_fall": int(to_fall[i]) if to_fall[i] >= 0 else None,
                  "expert_best": int(best[i]) if judge else None,
                  "shortfall": float(shortfall[i]),
                  "candidates": len(s.candidates), "labels": len(labelers.get(s.k, [])),
                  "labelers": labelers.get(s.k, [])}
                 for i, s in enumerate(run.steps)]
        return plain_json({"id": run.id, "key": run.key, "seed": run.seed,
                           "result": run.result, "failure": failure(run.result),
                           "steps": steps, "judged": judge,
                           "order": review_order(slips, to_fall, shortfall).tolist()},
                          nonfinite="null")

    def step(self, run_id: int, k: int, judge: bool = True) -> dict[str, Any]:
        """Everything the page draws of step ``k``: the terrain around it, the robot, F with the
        robot's rewards, its choice, what followed, the expert's best, the labels and "never
        here" marks given and the distance [m] a point snaps to a candidate within; and the
        planner's state vector (``RobotState.to_vector``: feet, body position, roll pitch
        yaw, goal) and the board's hash, for a scripted labeler (``judge=False``: without the
        expert's verdict, which costs a fraction of a second a step)."""
        run = self._run(run_id)
        step = self._step(run, k)
        best, shortfall = self._step_verdict(run, k) if judge else (None, None)
        fell = str(run.result.get("reason", "")).startswith("fall")
        to_fall = int(steps_to_fall(len(run.steps), fell)[k])
        hmap = self.store().terrain(run.terrain_hash)
        return plain_json({
            "run": run.id, "k": step.k, "steps": len(run.steps), "leg": step.swing_leg,
            "terrain_hash": run.terrain_hash, "state": step.state.to_vector(),
            "robot": robot_pose(step.state, self.robot),
            "terrain": terrain_window(hmap, step.foothold[:2]),
            "candidates": step.candidates,
            "rewards": [None if not np.isfinite(r) else float(r) for r in step.rewards],
            "chosen": step.chosen, "touchdown": step.touchdown, "slip_mm": _mm(step.slip),
            "steps_to_fall": to_fall if to_fall >= 0 else None,
            "reason": run.result.get("reason"), "failure": failure(run.result),
            "expert_best": best, "shortfall": shortfall,
            "labels": [label.to_dict() for label in self.store().labels(run_id=run.id, k=k)],
            "marks": [mark.to_dict() for mark in self.store().marks(run_id=run.id, k=k)],
            "snap_m": SNAP_RADIUS, "branches": self._branches(run, k),
        }, nonfinite="null")

    def _branches(self, run: RunRecord, k: int) -> dict[str, Any] | None:
        """What would have happened at step ``k``: the rollout teacher's branches of it, where
        this store holds its label of the step (``demos correct --teacher rollout``, a
        reproduction it taught) -- per candidate tried what followed, and the one it taught;
        None where it holds none."""
        if run.key is None:
            return None
        source = source_of(run.key, k)
        for d in self.store().demonstrations(source_prefix=source):
            if d.source == source and isinstance(d.expert.get("verdict"), dict):
                return {"taught": d.chosen, "tried": branch_lines(d.expert["verdict"])}
        return None

    def terrain_file(self, terrain_hash: str) -> bytes:
        """A stored board whole, as footfall's height-map file (``HeightMap.save``: a versioned,
        self-describing .npz), for a scripted labeler that judges as the synthetic expert does."""
        hmap = self.store().terrain(terrain_hash)
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "board.npz"
            hmap.save(path)
            return path.read_bytes()

    # ------------------------------------------------------------------- labels
    def label(self, run_id: int, k: int, verdict: str, labeler: str | None,
              candidate: int | None = None, point: list[float] | None = None,
              request: str | None = None) -> tuple[dict[str, Any], bool]:
        """Store a label; a clicked ``point`` (x, y [m]) labels the nearest candidate of F.
        Labelling the robot's own choice as the foothold is the verdict "fine" (it makes no
        demonstration: the robot chose as the person would have).

        Returns the label and whether it was new (False: a repeated request).
        """
        name = labeler if labeler is not None else self.labeler
        if name is None:
            raise FootfallError("who is labelling? give a labeler name")
        if verdict == "foothold":
            step = self._step(self._run(run_id), k)
            if candidate is None:
                if point is None:
                    raise FootfallError("a foothold label needs a candidate index or a point")
                candidate = nearest_candidate(step.candidates, np.asarray(point))
                if candidate is None:
                    raise FootfallError("no candidate of F lies near that point")
            if candidate == step.chosen:
                verdict, candidate = "fine", None
        label, new = self.store().add_label(run_id, k, name, verdict, candidate, request)
        return label.to_dict(), new

    def undo(self, label_id: int, labeler: str | None) -> dict[str, Any]:
        """Undo one of ``labeler``'s labels (and its demonstration), restoring the label it had
        replaced: ``{"removed": label, "restored": label or None}``."""
        name = labeler if labeler is not None else self.labeler
        if name is None:
            raise FootfallError("whose label? give a labeler name")
        removed, restored = self.store().undo_label(label_id, labeler=name)
        return {"removed": removed.to_dict(),
                "restored": None if restored is None else restored.to_dict()}

    def step_labels(self, run_id: int, k: int) -> dict[str, list[dict[str, Any]]]:
        """The labels and marks of step ``k`` of a run now (the page polls them: others label
        too): ``{"labels": [...], "marks": [...]}``."""
        store = self.store()
        labels = store.step_labels(run_id, k)  # NotFound for an unknown run or step
        return {"labels": [label.to_dict() for label in labels],
                "marks": [mark.to_dict() for mark in store.marks(run_id=run_id, k=k)]}

    # -------------------------------------------------------------------- marks
    def mark(self, run_id: int, k: int, labeler: str | None, candidate: int | None = None,
             point: list[float] | None = None, request: str | None = None
             ) -> tuple[dict[str, Any], bool]:
        """Mark a candidate of step ``k``'s F "never here"; a ``point`` (x, y [m]) marks the
        nearest candidate within the labels' snapping distance. Returns the mark and whether it
        was new (False: a repeated request, or a candidate already marked)."""
        name = labeler if labeler is not None else self.labeler
        if name is None:
            raise FootfallError("who is marking? give a labeler name")
        if candidate is None:
            if point is None:
                raise FootfallError("a mark needs a candidate index or a point")
            step = self._step(self._run(run_id), k)
            candidate = nearest_candidate(step.candidates, np.asarray(point))
            if candidate is None:
                raise FootfallError("no candidate of F lies near that point")
        mark, new = self.store().add_mark(run_id, k, name, candidate, request)
        return mark.to_dict(), new

    def unmark(self, mark_id: int, labeler: str | None) -> dict[str, Any]:
        """Remove one of ``labeler``'s marks: ``{"removed": mark}``."""
        name = labeler if labeler is not None else self.labeler
        if name is None:
            raise FootfallError("whose mark? give a labeler name")
        return {"removed": self.store().remove_mark(mark_id, name).to_dict()}

    def agreement(self, margin: float = DEFAULT_MARGIN) -> dict[str, Any]:
        """How often each labeler agrees with the synthetic expert and with each other labeler,
        in labels and in marks (:func:`footfall.teach.judging.store_agreement`)."""
        with self._expert_lock:
            if len(self._refusals) > REFUSED_STEPS:
                self._refusals.clear()
            return store_agreement(self.store(), self._expert, margin, self._refusals)

    def counts(self) -> dict[str, Any]:
        """Labels by labeler, disagreements, marks by labeler, and demonstrations by source."""
        store = self.store()
        summary = store.summary()
        return {"labels": summary["labels"], "marks": store.mark_counts(),
                "by_source": summary["by_source"], "runs": summary["runs"]}

    # ------------------------------------------------------------------ helpers
    def _run(self, run_id: int) -> RunRecord:
        return self.store().run(run_id)

    @staticmethod
    def _step(run: RunRecord, k: int):
        if not 0 <= k < len(run.steps):
            raise NotFound(f"run {run.id} has no step {k} (it has {len(run.steps)} steps)")
        return run.steps[k]

    def _step_verdict(self, run: RunRecord, k: int) -> tuple[int, float]:
        """The expert's best index in step ``k``'s F and the robot's shortfall [value units]:
        from the run's verdicts if judged, else this step alone (a fraction of a second)."""
        with self._expert_lock:
            hit = self._judged.get(run.id)
            if hit is not None:
                return int(hit[0][k]), float(hit[1][k])
            step = run.steps[k]
            hmap = self.store().terrain(run.terrain_hash)
            values = np.asarray(self._expert.values(hmap, step.state, step.candidates),
                                dtype=np.float64)
        best = int(np.argmax(values))
        return best, float(values[best] - values[step.chosen])

    def _verdicts(self, run: RunRecord) -> tuple[np.ndarray, np.ndarray]:
        """The expert's best index and the robot's shortfall at every step, judged once per
        store (kept in it: :func:`footfall.teach.judging.judged_run`)."""
        with self._expert_lock:
            hit = self._judged.get(run.id)
            if hit is None:
                hit = judged_run(self.store(), run, self._expert, self._expert_key)
                self._judged[run.id] = hit
                if len(self._judged) > JUDGED_RUNS:
                    self._judged.popitem(last=False)
            else:
                self._judged.move_to_end(run.id)
            return hit


def failure(result: dict) -> str | None:
    """What a failed run is put down to, as ``walk-many`` reports it: the cause of its
    explanation (:data:`footfall.sim.explain.CAUSES`) when the run was explained, else the
    reason it ended; None for a run that crossed."""
    if result.get("success"):
        return None
    cause = (result.get("explanation") or {}).get("cause")
    return str(cause) if cause else str(result.get("reason") or "failed")


def _chooser(settings: dict) -> str:
    """Who chose the run's footholds: the judge (the synthetic expert), or the reward's name(s)
    as the run recorded them ("-" for a run logged before runs named their reward)."""
    if "judge" in settings:
        return f"judge: {str(settings['judge']).split('.')[0]}"  # e.g. SyntheticExpert
    names = settings.get("reward")
    if isinstance(names, str):
        return names
    return ", ".join(map(str, names)) if isinstance(names, list) and names else "-"


def _mm(metres: float) -> float | None:
    return None if not np.isfinite(metres) else 1000.0 * float(metres)
