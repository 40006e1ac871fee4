"""The verdicts on a reproduction's test-board runs: the expert's on every choice the robot made,
and the teacher's on every run a learned function failed and the teacher crossed (the imitation
gap, :mod:`footfall.experiments.imitation`). Both read the stored runs; the report shows them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.data.store import DemoStore
from footfall.experiments.imitation import imitation_gap
from footfall.expert.corrections import SEVERE_SHORTFALL, step_verdicts
from footfall.expert.synthetic import SyntheticExpert
from footfall.expert.teachers import state_judge
from footfall.features.family import PAPER_FEATURE_SETS

if TYPE_CHECKING:  # the settings' module runs the stages, which read these verdicts
    from footfall.experiments.reproduce import ReproduceConfig


def _runs_by_key(store: DemoStore, prefix: str) -> list[dict]:
    """The stored runs under ``prefix`` in key order: not in the order parallel workers finished."""
    return sorted(store.runs(key_prefix=prefix), key=lambda r: r["key"])


def choice_quality(store: DemoStore, maps: dict[str, HeightMap], config: ReproduceConfig,
                    test: list[str], log: Callable[[str], None]) -> dict:
    """The expert's verdict on every step of the runs on the ``test`` boards, per method.

    For the three functions and the two references: the steps judged, and the
    mean, median and 90th percentile of the shortfall [value units] of the
    robot's choice against the expert's best in the same F, with the fractions
    of steps above the correction margin and above :data:`SEVERE_SHORTFALL`.
    """
    expert = SyntheticExpert(config.expert)
    log("the expert's verdict on the choices of the test-board runs")
    out = {}
    for k in (*PAPER_FEATURE_SETS, "expert", "default"):  # every method of the test boards
        parts = []
        for row in (r for board in test for r in _runs_by_key(store, f"eval/{board}/{k}/")):
            run = store.run(row["id"])
            parts.append(step_verdicts(run, maps[run.terrain_hash], expert)[1])
        sf = np.concatenate(parts) if parts else np.zeros(0)
        out[k] = {"steps": int(sf.size), "severe_above": SEVERE_SHORTFALL}
        if sf.size:
            out[k].update(mean=float(sf.mean()), median=float(np.median(sf)),
                          p90=float(np.percentile(sf, 90)),
                          above_margin=float(np.mean(sf > config.margin)),
                          severe=float(np.mean(sf > SEVERE_SHORTFALL)))
    return out


def imitation_gaps(store: DemoStore, maps: dict[str, HeightMap], config: ReproduceConfig,
                   test: list[str], log: Callable[[str], None]) -> dict:
    """Per learned function, the test-board runs it failed and the teacher crossed (same board
    and seed), each judged by the teacher step by step (:mod:`footfall.experiments.imitation`)."""
    step = config.walk.footstep
    teacher = state_judge(config.teacher, config.expert, step.bias_weight, step.lead)
    log("the teacher's verdict on the learned functions' failed test-board runs")
    out = {}
    for fs in PAPER_FEATURE_SETS:
        pairs = []
        for board in test:
            teacher_runs = {r["key"].rsplit("/", 1)[1]: r
                            for r in _runs_by_key(store, f"eval/{board}/expert/")}
            for row in _runs_by_key(store, f"eval/{board}/{fs}/"):
                other = teacher_runs.get(row["key"].rsplit("/", 1)[1])
                if other is not None:
                    pairs.append((store.run(row["id"]), store.run(other["id"])))
        out[fs] = imitation_gap(pairs, maps, teacher, config.margin)
    return out
