"""What followed the robot's footholds, against the expert's judgement (``footfall outcomes``).

Reads the run logs of one or more stores (e.g. ``walk-many --log``), labels every
foothold the robot stood on with what followed (:mod:`footfall.data.outcomes`),
and reports per method -- who chose the footholds -- the failures by cause and
how well the expert's value and each of its terms predict each outcome (AUC with
a 95 % interval over boards, :mod:`footfall.expert.grounding`). With ``fit``, it
grounds the expert's risk weights in one outcome (:func:`fit_outcomes`) and
reports the grounded value's AUC on the same footholds; measure it on other
boards by running again with the grounded settings as ``expert_config``.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from footfall.control.footstep import FootstepConfig
from footfall.core.errors import FootfallError
from footfall.core.files import distinct_inputs
from footfall.core.robot import LITTLEDOG
from footfall.data.outcomes import FALL_HORIZON, OUTCOME_LABELS
from footfall.expert.grounding import (
    AUC_RESAMPLES,
    FootholdOutcomes,
    OutcomeFit,
    failure_causes,
    fit_outcomes,
    foothold_outcomes,
    outcome_auc,
    term_badness,
)
from footfall.expert.scorer import judge_name
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert, walking_expert
from footfall.expert.terms import EXPERT_TERM_NAMES

ALL = "all"  # the pooled footholds of every method


def _auc_dict(badness: np.ndarray, label: np.ndarray, boards: np.ndarray,
              resamples: int) -> dict:
    a = outcome_auc(badness, label, boards, resamples=resamples)
    return {"auc": a.auc, "ci": [a.low, a.high], "positives": a.positives,
            "negatives": a.negatives}


def predictive_power(table: FootholdOutcomes, value: np.ndarray,
                     resamples: int = AUC_RESAMPLES) -> dict:
    """Per method (and ``"all"``) and outcome: the AUC of ``-value`` (n,) with its interval, and
    of each raw expert term (signed worse-higher; no interval)."""
    out = {}
    for method in [*sorted(set(table.method.tolist())), ALL]:
        rows = np.ones(len(table), dtype=bool) if method == ALL else table.method == method
        sub, v = table.select(rows), value[rows]
        out[method] = {
            "footholds": int(rows.sum()), "boards": int(np.unique(sub.board).size),
            "value": {lab: _auc_dict(-v, sub.labels[lab], sub.board, resamples)
                      for lab in OUTCOME_LABELS},
            "terms": {lab: {t: outcome_auc(term_badness(sub, t), sub.labels[lab], sub.board,
                                           resamples=0).auc for t in EXPERT_TERM_NAMES}
                      for lab in OUTCOME_LABELS}}
    return out


def outcome_report(store_paths: Sequence[str | os.PathLike],
                   expert_config: ExpertConfig | None = None, horizon: int = FALL_HORIZON,
                   fit: str | None = None, resamples: int = AUC_RESAMPLES
                   ) -> tuple[dict, OutcomeFit | None]:
    """The report of the module (plain JSON) and, with ``fit`` (an outcome label), the fit.

    ``expert_config`` is the expert that judges [default: the walking expert].

    Raises
    ------
    FootfallError
        For no store, stores without runs, or an unknown outcome to fit.
    """
    paths = [str(p) for p in distinct_inputs(store_paths, "run store")]
    if not paths:
        raise FootfallError("give at least one store with run logs")
    if fit is not None and fit not in OUTCOME_LABELS:
        raise FootfallError(f"unknown outcome {fit!r}; one of {', '.join(OUTCOME_LABELS)}")
    config = expert_config or walking_expert(FootstepConfig().lead)
    expert = SyntheticExpert(config, LITTLEDOG)
    table = foothold_outcomes(paths, expert, horizon)
    report = {"stores": paths, "expert": judge_name(config), "horizon": horizon,
              "methods": failure_causes(paths),
              "prediction": predictive_power(table, table.value, resamples)}
    fitted = None
    if fit is not None:
        fitted = fit_outcomes(table, config, LITTLEDOG, fit)
        grounded = SyntheticExpert(fitted.config, LITTLEDOG)
        value = np.sum(np.stack(list(grounded.utilities(table.terms).values())), axis=0)
        report["fit"] = {**fitted.as_dict(), "expert": judge_name(fitted.config),
                         "prediction_in_sample": predictive_power(table, value, resamples)}
    return report, fitted
