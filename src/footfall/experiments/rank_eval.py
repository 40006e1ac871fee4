"""Any scorer's agreement with the expert on a store's decisions (``footfall rank-eval``).

Here, above both, because the measure needs the scorer and the expert's judgement
(:mod:`footfall.learning.evaluation` explains the measures). The scorer is a learned model
file, or a named scorer that needs no training (:data:`footfall.features.scorer.SCORERS`: the
hand-tuned reward ``"hand-tuned"``; ``"expert"``, the judging expert's own value, the ceiling).
The judge is the synthetic expert that made the demonstrations, or the walking expert. The
decisions are the store's demonstrations -- each with the expert's choice -- or the steps of
its run logs, the states the robot itself visited, where the expert's best of each step's
candidate set is the choice to rank.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from footfall.control.footstep import FootstepConfig
from footfall.core.errors import FootfallError
from footfall.core.files import distinct_inputs
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG
from footfall.data.outcomes import FALL_HORIZON, OUTCOME_LABELS, stored_outcomes
from footfall.data.store import Demonstration, DemoStore
from footfall.expert.corrections import DEFAULT_MARGIN, SEVERE_SHORTFALL
from footfall.expert.grounding import outcome_auc
from footfall.expert.protocol import expert_settings
from footfall.expert.scorer import ExpertScorer, judge_name
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert, walking_expert
from footfall.features.scorer import SCORERS
from footfall.features.scoring import score_footholds
from footfall.features.template_library import reproduced_on
from footfall.learning.evaluation import (
    EveryLeg,
    PathBias,
    RankScores,
    best_picks,
    expert_values,
    rank_scores,
)
from footfall.learning.model import FootholdModel
from footfall.learning.train import store_demonstrations

DECISIONS = ("demonstrations", "runs")  # where the decisions to rank come from


@dataclass(frozen=True)
class ModelAgreement:
    """How well a scorer ranks a store's decisions like the expert."""

    model: str  # the model file as given, or the scorer's registered name
    feature_set: str  # the model's feature set ("-" for a named scorer)
    learner: str  # the model's learner ("-" for a named scorer)
    scores: RankScores  # top-1, percentile, reward loss, shares above the margin ...
    decisions: str = "demonstrations"  # one of DECISIONS
    outcomes: dict | None = None  # run decisions: outcome label -> AUC of the scorer's value
    # of the footholds the robot stood on (outcome_power)
    expert: str | None = None  # the judging expert's name (judge_name); None without one
    trained_here: int = 0  # the decisions' terrains its template libraries were drawn from:
    # more than 0, and the measure is not a held-out one (library_provenance)
    path_bias: float | None = None  # [hand-tuned reward/m] ranked as the planner picks with this
    # path bias; None: the scorer alone
    severe_terms: dict | None = None  # its severe shortfalls split by the expert's terms
    # (severe_by_term); None when not asked for

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON: the scorer, the scores' keys, the outcome AUCs (run decisions;
        else null), the judging expert, then where the decisions came from."""
        return {"model": self.model, "feature_set": self.feature_set, "learner": self.learner,
                **self.scores.as_dict(), "outcomes": self.outcomes, "expert": self.expert,
                "decisions": self.decisions, "trained_here": self.trained_here,
                "path_bias": self.path_bias, "severe_terms": self.severe_terms}


def library_provenance(model: FootholdModel, maps: Mapping[str, HeightMap], name: str) -> int:
    """How many of the terrains ``maps`` (hash -> map) the model's template libraries name as
    their sources (0: the decisions are held out from its templates).

    Where every terrain a leg group's library names is among ``maps``, each of its templates
    must be the patch its recorded source names on one of them
    (:func:`~footfall.features.template_library.reproduced_on`): a library that claims these terrains
    but whose templates none of them gives is refused.
    """
    named: set[str] = set()
    for group, f in model.functions.items():
        library = f.library
        if library is None or not library.terrain_hashes:
            continue
        named |= set(library.terrain_hashes)
        if not set(library.terrain_hashes) <= set(maps):
            continue  # templates from terrains not here: nothing to reproduce them on
        found = [np.zeros(c, dtype=bool) for c in library.counts]
        for h in library.terrain_hashes:
            found = [a | b for a, b in zip(found, reproduced_on(library, maps[h]))]
        missing = sum(int((~a).sum()) for a in found)
        if missing:
            raise FootfallError(f"{name}: {missing} of the {sum(library.counts)} templates of its "
                                f"{group} library are not the patches their sources name on the "
                                f"terrains it claims (held in this store): an edited model, or "
                                f"one of other terrains")
    return len(named & set(maps))


def judging_expert(demos: Sequence[Demonstration] | None) -> ExpertConfig:
    """Who judges a store's decisions: the synthetic expert that made every one of ``demos``
    if one did (its recorded settings, the defaults filling any it did not record), else the
    walking expert (the one that walks and corrects runs in the reproduction)."""
    synthetic = f"{SyntheticExpert.__module__}.{SyntheticExpert.__qualname__}"
    recorded = {json.dumps(d.expert.get("config"), sort_keys=True) for d in demos or ()
                if d.expert.get("class") == synthetic}
    if demos and len(recorded) == 1 and all(d.expert.get("class") == synthetic for d in demos):
        settings = json.loads(recorded.pop())
        if isinstance(settings, dict):
            try:
                return ExpertConfig(**settings)
            except (FootfallError, TypeError):
                pass  # settings of another footfall: judged by the walking expert
    return walking_expert(FootstepConfig().lead)


def rank_eval(model_path: str | os.PathLike | None, store_path: str | os.PathLike, *,
              reward: str | None = None, with_expert: bool = True,
              source: str | Sequence[str] | None = None, decisions: str = "demonstrations",
              run_key: str | None = None, margin: float = DEFAULT_MARGIN,
              expert_config: ExpertConfig | None = None,
              path_bias: float | None = None, by_term: bool = False) -> ModelAgreement:
    """Score the model at ``model_path`` -- or the named scorer ``reward`` -- on the store's
    decisions.

    ``decisions`` "demonstrations" ranks the store's demonstrations (``source``
    keeps those whose source starts with it); "runs" ranks the steps of its run
    logs (``run_key`` keeps the runs whose key starts with it), whose choice is
    the expert's best of the step's candidates. ``with_expert`` False skips the
    reward loss and its shares (they need the expert's values; NaN then, null
    in ``as_dict``); run decisions need the expert. ``margin`` [value units] is
    the correction margin the share above it counts (the reproduction corrects
    above its own, ``ReproduceConfig.margin``). The judging expert is
    ``expert_config``, or :func:`judging_expert` of the demonstrations (run
    decisions: the walking expert); the named scorer "expert" is its own value.
    ``path_bias`` [hand-tuned reward/m] ranks as the footstep planner picks and ``by_term``
    splits the severe shortfalls by the expert's terms (see :func:`rank_eval_many`).

    Raises
    ------
    FootfallError
        For both or neither of a model and a named scorer, an unreadable model
        or one for another robot (checked first), an unknown scorer name, or a
        store without such decisions.
    """
    if (model_path is None) == (reward is None):
        raise FootfallError("give a model file or --reward NAME, not both and not neither")
    return rank_eval_many([] if model_path is None else [model_path], store_path,
                          reward=reward, with_expert=with_expert, source=source,
                          decisions=decisions, run_key=run_key, margin=margin,
                          expert_config=expert_config, path_bias=path_bias,
                          by_term=by_term)[0]


def rank_eval_many(model_paths: Sequence[str | os.PathLike], store_path: str | os.PathLike, *,
                   reward: str | None = None, with_expert: bool = True,
                   source: str | Sequence[str] | None = None, decisions: str = "demonstrations",
                   run_key: str | None = None, margin: float = DEFAULT_MARGIN,
                   expert_config: ExpertConfig | None = None,
                   path_bias: float | None = None, by_term: bool = False
                   ) -> list[ModelAgreement]:
    """:func:`rank_eval` of several models (and the named scorer ``reward``, last, if given)
    on the same decisions: the store is read and the expert judges each decision once.
    ``path_bias`` [hand-tuned reward/m]: rank as the footstep planner picks, each scorer's
    values less this bias per metre from the judge's gait-nominal foothold
    (:class:`~footfall.learning.evaluation.PathBias`); None: the scorer alone. ``by_term``:
    each scorer's severe shortfalls split by the expert's terms (:func:`severe_by_term`).

    Raises
    ------
    FootfallError
        As :func:`rank_eval`; also for no scorer at all.
    """
    model_paths = distinct_inputs(model_paths, "model")
    if not model_paths and reward is None:
        raise FootfallError("give a model file or --reward NAME")
    if not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 0):
        raise FootfallError(f"the correction margin must be a number >= 0, got {margin!r}")
    if path_bias is not None:  # checked before the store is read
        PathBias(path_bias, 0.0)
    if decisions not in DECISIONS:
        raise FootfallError(f"decisions must be one of {', '.join(DECISIONS)}, got {decisions!r}")
    if by_term and not with_expert:
        raise FootfallError("the shortfall by the expert's terms needs the expert")
    if decisions == "runs" and not with_expert:
        raise FootfallError("run decisions are ranked against the expert's best: they need "
                            "the expert")
    scorers = []  # (scorer, name, feature set, learner)
    for path in model_paths:  # every model checked before the store is read
        model = FootholdModel.load(path)
        model.check_compatible(robot=LITTLEDOG)  # the robot whose states the store holds
        scorers.append((model, str(path), model.feature_set, model.learner))
    named = SCORERS.get(reward) if reward is not None else None  # an unknown name fails here
    if decisions == "demonstrations":
        demos, maps = store_demonstrations(store_path, source=source)
    judge = expert_config or judging_expert(demos if decisions == "demonstrations" else None)
    bias = None if path_bias is None else PathBias(path_bias, judge.stance_lead)
    expert = SyntheticExpert(judge, LITTLEDOG) if with_expert else None
    if reward is not None:  # "expert" is the judging expert's own value: the ceiling
        scorers.append((EveryLeg(ExpertScorer(SyntheticExpert(judge, LITTLEDOG),
                                              name=judge_name(judge))
                                 if reward == "expert" else named(None)), reward, "-", "-"))
    if decisions == "demonstrations":
        values = expert_values(demos, maps.__getitem__, expert) if expert else None
    else:
        demos, maps, values = run_decisions(store_path, expert, run_key)
    out = []
    for scorer, name, feature_set, learner in scorers:
        here = (library_provenance(scorer, maps, name) if isinstance(scorer, FootholdModel)
                else 0)
        scores = rank_scores(scorer, demos, maps.__getitem__, values=values,
                             margin=float(margin), severe_above=SEVERE_SHORTFALL,
                             path_bias=bias)
        outcomes = (outcome_power(scorer, store_path, run_key) if decisions == "runs" else None)
        terms = (severe_by_term(scorer, demos, maps, expert, values, scores.losses, bias)
                 if by_term else None)
        out.append(ModelAgreement(name, feature_set, learner, scores, decisions, outcomes,
                                  judge_name(judge) if with_expert else None, here,
                                  path_bias, terms))
    return out


def severe_by_term(scorer, demos: Sequence, maps: Mapping[str, HeightMap],
                   expert: SyntheticExpert, values: Sequence[np.ndarray],
                   losses: Sequence[float], path_bias: PathBias | None = None,
                   above: float = SEVERE_SHORTFALL) -> dict[str, Any]:
    """What the scorer's severe picks lose, term by term of the expert's value.

    For every decision whose shortfall ``losses[k]`` is above ``above`` [value units], the
    expert's best candidate against the scorer's pick (the mean over its tied best) in each of
    the expert's terms (:meth:`~footfall.expert.synthetic.SyntheticExpert.contributions`).
    Returns the number of such decisions, their summed shortfall [value units] and each
    term's share of it (the shares sum to 1; a term the pick is better in is negative),
    largest first.
    """
    severe = [k for k, loss in enumerate(losses) if loss > above]
    sub = [demos[k] for k in severe]
    totals: dict[str, float] = {}
    for k, d, picks in zip(severe, sub, best_picks(scorer, sub, maps.__getitem__, path_bias)):
        best = int(np.argmax(values[k]))
        parts = expert.contributions(maps[d.terrain_hash], d.state,
                                     d.candidates[np.r_[best, picks]])
        for term, v in parts.items():
            totals[term] = totals.get(term, 0.0) + float(v[0] - np.mean(v[1:]))
    whole = sum(totals.values())
    shares = {t: v / whole for t, v in sorted(totals.items(), key=lambda kv: -kv[1])
              if whole > 0}
    return {"decisions": len(severe), "shortfall": whole, "above": float(above),
            "terms": shares}


def outcome_power(model, store_path: str | os.PathLike, run_key: str | None = None,
                  horizon: int = FALL_HORIZON) -> dict[str, dict]:
    """How well ``model``'s value of each foothold the robot stood on predicts what followed.

    ``model`` as for :func:`~footfall.learning.evaluation.rank_scores`. For every
    outcome label (:mod:`footfall.data.outcomes`): the AUC of minus the value, with a
    95 % interval over boards (:func:`~footfall.expert.grounding.outcome_auc`), and how
    many footholds had the outcome. Runs whose key starts with ``run_key``.
    """
    values: list[float] = []
    boards: list[str] = []
    labels: dict[str, list] = {lab: [] for lab in OUTCOME_LABELS}
    with DemoStore(store_path, read_only=True) as store:
        for _, run, hmap, outcome in stored_outcomes(store, run_key, horizon):
            for k in np.flatnonzero(outcome.used):  # one foothold per step: its own state
                step = run.steps[k]
                values.append(float(score_footholds(hmap, step.state, step.foothold[None, :],
                                                    model.reward_for(step.swing_leg),
                                                    model.robot)[0]))
                boards.append(run.terrain_hash)
            for lab in OUTCOME_LABELS:
                labels[lab] += getattr(outcome, lab)[outcome.used].tolist()
    bad = -np.asarray(values, dtype=np.float64)
    out = {}
    for lab in OUTCOME_LABELS:
        a = outcome_auc(bad, np.asarray(labels[lab], dtype=bool), np.asarray(boards))
        out[lab] = {"auc": _number_or_none(a.auc), "ci": [_number_or_none(a.low),
                                                          _number_or_none(a.high)],
                    "positives": a.positives, "negatives": a.negatives}
    return out


def _number_or_none(v: float) -> float | None:
    return v if math.isfinite(v) else None


def run_decisions(store_path: str | os.PathLike, expert: SyntheticExpert,
                  run_key: str | None = None) -> tuple[list[Demonstration], dict, list]:
    """The steps of a store's run logs as decisions the expert makes.

    Each step of each run (those whose key starts with ``run_key``) with at
    least two candidates becomes a demonstration whose choice is the expert's
    best of the step's candidates (source ``run:<id>:step:<k>``).

    Returns
    -------
    (list of Demonstration, dict, list of arrays)
        The decisions in run and step order, {terrain hash: HeightMap}, and the
        expert's values of each decision's candidates.
    """
    with DemoStore(store_path, read_only=True) as store:  # evaluation only reads
        heads = store.runs(key_prefix=run_key)
        if not heads:
            which = "" if run_key is None else f" with a key starting {run_key!r}"
            raise FootfallError(f"{store_path}: no run logs{which} to take decisions from")
        maps = {h: store.terrain(h) for h in {head["terrain_hash"] for head in heads}}
        demos, values = [], []
        for head in heads:
            run = store.run(head["id"])
            hmap = maps[run.terrain_hash]
            for step in run.steps:
                if step.candidates.shape[0] < 2:
                    continue
                v = np.asarray(expert.values(hmap, step.state, step.candidates))
                demos.append(Demonstration(run.terrain_hash, step.state, step.candidates,
                                           int(np.argmax(v)), f"run:{run.id}:step:{step.k}",
                                           expert_settings(expert)))
                values.append(v)
    if not demos:
        raise FootfallError(f"{store_path}: the run logs hold no step with two candidates")
    return demos, maps, values
