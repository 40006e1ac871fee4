"""The expert against outcomes: does its value of a foothold predict what followed?

The robot's logged runs label every foothold it stood on with what followed
(:mod:`footfall.data.outcomes`: slid, missed, a fall within a gait cycle). This
module puts the expert's judgement of each of those footholds beside its
labels -- :func:`foothold_outcomes` builds one row per used foothold with the
expert's raw terms, each term's share of the value, the value, and the labels
-- and measures how well a score predicts a label: :func:`outcome_auc` is the
area under the ROC curve of a score for a label (1: every bad foothold scored
worse than every good one; 0.5: no better than chance; below 0.5: the score
prefers the footholds that went wrong), with a 95 % interval from resampling
whole boards (the footholds of one board share its few hard places and are
not independent). :func:`fit_outcomes` grounds the expert's risk weights in
one outcome (a constrained logistic fit on the weights' features: the value is
linear in its weights, :func:`weight_features`). :func:`failure_causes`
tallies how each method's runs failed (the flight recorder's taxonomy,
:data:`footfall.sim.explain.CAUSES`).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field, fields, replace

import numpy as np
from scipy.optimize import minimize

from footfall.core.errors import FootfallError
from footfall.core.robot import RobotDescription
from footfall.data.outcomes import FALL_HORIZON, OUTCOME_LABELS, stored_outcomes
from footfall.data.store import DemoStore
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert
from footfall.expert.terms import EXPERT_TERM_NAMES, contributions

AUC_RESAMPLES = 1000  # board resamples of an AUC's interval
WEIGHTS: tuple[str, ...] = tuple(f.name for f in fields(ExpertConfig) if f.name.startswith("w_"))
"""The expert's weights: its value is linear in them (:func:`weight_features`)."""
PREFERENCE_WEIGHTS = ("w_progress", "w_stance")  # what the gait wants, not what is risky
RISK_WEIGHTS = tuple(w for w in WEIGHTS if w not in PREFERENCE_WEIGHTS)
"""The weights an outcome fit sets: every term that may make a foothold go wrong."""
BONUS_WEIGHTS = ("w_hold", "w_stability")  # shares >= 0, the rest <= 0
PRICED_DETOUR = 0.03  # [m] a foothold that doubles the odds of a fall is worth moving the foot
# this far from where the gait wants it: the reproduction's candidate radius, all of F
FIT_L2_GRID = (1e-3, 1e-2, 1e-1, 1.0)  # [-] ridge penalties the outcome fit chooses from, on
# the coefficients of standardised features, by leave-one-board-out log-loss


TERM_WORSE_HIGHER: dict[str, bool] = {
    "slip_margin": False, "pinch": True, "trap_depth": True, "drop_off": True,
    "crown": True, "riser_ahead": True, "leg_clearance": False, "unknown": True, "progress": False,
    "stance_offset": True, "stability": False, "reach_margin": False, "joint_margin": False}
"""For each expert term: is more of it worse for the foothold (True) or better (False)?"""


def term_badness(table: FootholdOutcomes, name: str) -> np.ndarray:
    """The raw term ``name`` of every row, signed so that higher is worse (for :func:`outcome_auc`)."""
    return table.terms[name] if TERM_WORSE_HIGHER[name] else -table.terms[name]


def method_name(settings: dict) -> str:
    """Who chose a run's footholds: the judge's name, or the reward names joined."""
    if settings.get("judge"):
        return str(settings["judge"])
    reward = settings.get("reward", "reward")
    return " + ".join(reward) if isinstance(reward, list) else str(reward)


@dataclass(frozen=True)
class FootholdOutcomes:
    """The footholds the robot stood on, as rows: who chose, the expert's view, what followed.

    Every array has one entry per row (foothold); ``terms`` and ``parts`` map each
    expert term (:data:`~footfall.expert.terms.EXPERT_TERMS`) to its raw value (in its
    unit) and to its share of the value [value units].
    """

    method: np.ndarray  # (n,) str: who chose the run's footholds (method_name)
    board: np.ndarray  # (n,) str: the board's content hash
    run: np.ndarray  # (n,) int: run id in its store
    store: np.ndarray  # (n,) int: which of the stores the run came from (its position)
    k: np.ndarray  # (n,) int: step number in the run
    leg: np.ndarray  # (n,) str: the swing leg
    labels: dict[str, np.ndarray] = field(default_factory=dict)  # OUTCOME_LABELS -> (n,) bool
    slip: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (n,) [m] stance travel
    placement_error: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (n,) [m]
    terms: dict[str, np.ndarray] = field(default_factory=dict)  # raw terms, their units
    parts: dict[str, np.ndarray] = field(default_factory=dict)  # shares of the value [value]
    value: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (n,) [value units]

    def __len__(self) -> int:
        return int(self.method.shape[0])

    def select(self, mask: np.ndarray) -> FootholdOutcomes:
        """The rows where ``mask`` (n,) bool holds."""
        pick = np.asarray(mask, dtype=bool)
        return FootholdOutcomes(
            self.method[pick], self.board[pick], self.run[pick], self.store[pick],
            self.k[pick], self.leg[pick], {n: v[pick] for n, v in self.labels.items()},
            self.slip[pick], self.placement_error[pick],
            {n: v[pick] for n, v in self.terms.items()},
            {n: v[pick] for n, v in self.parts.items()}, self.value[pick])


def foothold_outcomes(store_paths: Iterable[str], expert: SyntheticExpert,
                      horizon: int = FALL_HORIZON) -> FootholdOutcomes:
    """Every used foothold of every run in the stores, judged by ``expert`` (see the class).

    The expert judges the chosen foothold in the state the planner chose it in
    (the run log's state), on the board the run walked.

    Raises
    ------
    FootfallError
        If the stores hold no run with a used foothold.
    """
    cols: dict[str, list] = {n: [] for n in ("method", "board", "run", "store", "k", "leg",
                                             "slip", "placement_error")}
    labels: dict[str, list] = {n: [] for n in OUTCOME_LABELS}
    terms: dict[str, list] = {n: [] for n in EXPERT_TERM_NAMES}
    for index, path in enumerate(store_paths):
        with DemoStore(path) as store:
            for head, run, hmap, outcome in stored_outcomes(store, horizon=horizon):
                used = np.flatnonzero(outcome.used)
                for k in used:  # one expert call per foothold: the state differs per step
                    step = run.steps[k]
                    judged = expert.terms(hmap, step.state, step.foothold[None, :])
                    for name in EXPERT_TERM_NAMES:
                        terms[name].append(judged[name][0])
                method = method_name(run.settings)
                cols["method"] += [method] * used.size
                cols["board"] += [run.terrain_hash] * used.size
                cols["run"] += [int(head["id"])] * used.size
                cols["store"] += [index] * used.size
                cols["k"] += used.tolist()
                cols["leg"] += [run.steps[k].swing_leg for k in used]
                cols["slip"] += outcome.slip[used].tolist()
                cols["placement_error"] += outcome.placement_error[used].tolist()
                for name in OUTCOME_LABELS:
                    labels[name] += getattr(outcome, name)[used].tolist()
    if not cols["method"]:
        raise FootfallError("the stores hold no run with a foothold the robot stood on")
    raw = {n: np.asarray(v, dtype=np.float64) for n, v in terms.items()}
    parts = expert.utilities(raw)
    return FootholdOutcomes(
        np.asarray(cols["method"], dtype=str), np.asarray(cols["board"], dtype=str),
        np.asarray(cols["run"], dtype=np.int64), np.asarray(cols["store"], dtype=np.int64),
        np.asarray(cols["k"], dtype=np.int64), np.asarray(cols["leg"], dtype=str),
        {n: np.asarray(v, dtype=bool) for n, v in labels.items()},
        np.asarray(cols["slip"], dtype=np.float64),
        np.asarray(cols["placement_error"], dtype=np.float64),
        raw, parts, np.sum(np.stack(list(parts.values())), axis=0))


@dataclass(frozen=True)
class Auc:
    """Area under the ROC curve of a score for a label, with a board-resampled interval."""

    auc: float  # [-] P(a bad foothold scores worse than a good one); NaN without both kinds
    low: float  # [-] 2.5 % of the board-resampled AUCs
    high: float  # [-] 97.5 %
    positives: int  # footholds with the label
    negatives: int  # footholds without it


def weighted_auc(score: np.ndarray, label: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """AUCs of ``score`` (n,) for ``label`` (n,) under each row of ``weights`` (r, n) >= 0.

    Each row counts every foothold that many times (a resample); ties count one half.
    Vectorised over the rows: one sort, then sums per distinct score. NaN where a row
    weighs no positive or no negative.
    """
    order = np.argsort(score, kind="stable")
    s, y = score[order], label[order]
    w = np.asarray(weights, dtype=np.float64)[:, order]
    starts = np.flatnonzero(np.r_[True, s[1:] != s[:-1]])  # first row of each distinct score
    pos = np.add.reduceat(w * y, starts, axis=1)  # (r, g)
    neg = np.add.reduceat(w * ~y, starts, axis=1)
    below = np.cumsum(neg, axis=1) - neg  # negatives scoring strictly lower
    total = pos.sum(axis=1) * neg.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(total > 0, (pos * (below + 0.5 * neg)).sum(axis=1) / total, np.nan)


def outcome_auc(badness: np.ndarray, label: np.ndarray, boards: np.ndarray,
                resamples: int = AUC_RESAMPLES, seed: int = 0) -> Auc:
    """How well ``badness`` (n,) (higher: worse, e.g. minus a value) predicts ``label`` (n,).

    The interval resamples whole boards (``boards`` (n,) ids) with replacement
    (``resamples`` times, seeded): a board's footholds are not independent.
    """
    score = np.asarray(badness, dtype=np.float64)
    y = np.asarray(label, dtype=bool)
    b = np.asarray(boards)
    if not (score.shape == y.shape == b.shape and score.ndim == 1):
        raise FootfallError("a score, a label and a board per foothold, all of shape (n,)")
    pos, neg = int(y.sum()), int((~y).sum())
    if pos == 0 or neg == 0:
        return Auc(float("nan"), float("nan"), float("nan"), pos, neg)
    auc = float(weighted_auc(score, y, np.ones((1, y.size)))[0])
    low = high = float("nan")
    if resamples > 0:
        names, idx = np.unique(b, return_inverse=True)
        rng = np.random.default_rng(seed)
        draws = rng.integers(0, names.size, size=(resamples, names.size))
        counts = np.zeros((resamples, names.size))
        np.add.at(counts, (np.arange(resamples)[:, None], draws), 1.0)
        aucs = np.concatenate([weighted_auc(score, y, counts[i:i + 100, idx])
                               for i in range(0, resamples, 100)])  # 100 resamples at a time
        aucs = aucs[np.isfinite(aucs)]
        if aucs.size:
            low, high = (float(v) for v in np.quantile(aucs, [0.025, 0.975]))
    return Auc(auc, low, high, pos, neg)


def failure_causes(store_paths: Iterable[str]) -> dict[str, dict]:
    """Per method: runs, successes, and the failures by cause (the flight recorder's taxonomy)."""
    out: dict[str, dict] = {}
    for path in store_paths:
        with DemoStore(path) as store:
            for info in store.runs():
                entry = out.setdefault(method_name(info["settings"]),
                                       {"runs": 0, "successes": 0, "causes": Counter()})
                result = info["result"]
                entry["runs"] += 1
                if result.get("success"):
                    entry["successes"] += 1
                else:
                    cause = (result.get("explanation") or {}).get("cause") or "other"
                    entry["causes"][cause] += 1
    return {m: {**e, "causes": dict(e["causes"].most_common())} for m, e in sorted(out.items())}


def weight_features(terms: dict[str, np.ndarray], config: ExpertConfig,
                    robot: RobotDescription) -> dict[str, np.ndarray]:
    """What each weight multiplies: ``value = sum over w of config.w * features[w]`` (n,).

    The expert's utilities are hinges of its terms times a weight each
    (:meth:`SyntheticExpert.utilities`), so its value is linear in the weights;
    the feature of weight ``w`` is the value with that weight 1 and every other 0
    [value units per unit of the weight]. Penalties are <= 0, bonuses >= 0.
    """
    zero = replace(config, **{w: 0.0 for w in WEIGHTS})
    return {w: sum(contributions(terms, replace(zero, **{w: 1.0}), robot).values())
            for w in WEIGHTS}


@dataclass(frozen=True)
class OutcomeFit:
    """A logistic model of a bad outcome from the expert's weighted features, and the expert
    whose risk weights it sets (see :func:`fit_outcomes`)."""

    label: str  # the outcome fitted (one of OUTCOME_LABELS)
    coefficients: dict[str, float]  # RISK_WEIGHTS -> log-odds of the outcome per unit of the
    # weight's feature, sign flipped (>= 0: more of that share of the value, less risk)
    intercept: float  # [-] log-odds at features 0
    scale: float  # [value units per log-odds] the grounded weights are scale * coefficients
    config: ExpertConfig  # the grounded expert: risk weights from the fit, the rest as given
    l2: float  # [-] the ridge penalty chosen
    cv_log_loss: dict[str, float]  # each penalty of the grid -> leave-one-board-out log-loss
    weights_before: dict[str, float]  # every weight of the config the fit started from
    footholds: int  # footholds fitted
    positives: int  # of them with the outcome

    def as_dict(self) -> dict:
        """Plain data for JSON."""
        return {"label": self.label, "coefficients": self.coefficients,
                "weights_before": dict(self.weights_before),
                "intercept": self.intercept, "scale": self.scale, "l2": self.l2,
                "cv_log_loss": self.cv_log_loss,
                "weights": {w: getattr(self.config, w) for w in WEIGHTS},
                "footholds": self.footholds, "positives": self.positives}


def odds_price(config: ExpertConfig) -> float:
    """[value units per unit log-odds] what the grounded expert pays to lower a fall's log-odds
    by one: doubling the odds costs as much as a foothold PRICED_DETOUR [m] from the
    gait-nominal one (``config.w_stance`` value units per metre)."""
    return PRICED_DETOUR * config.w_stance / math.log(2.0)


def fit_outcomes(table: FootholdOutcomes, config: ExpertConfig, robot: RobotDescription,
                 label: str = "fall", l2_grid: tuple[float, ...] = FIT_L2_GRID) -> OutcomeFit:
    """Ground the expert's risk weights in what followed the footholds of ``table``.

    The model: ``P(label) = sigmoid(b - sum over risk weights w of beta_w * feature_w)``
    with every ``beta_w >= 0`` (a share of the value never makes a foothold safer by
    being lower), fitted by maximum likelihood with a ridge penalty on the betas of
    standardised features (L-BFGS-B, deterministic); the penalty is the one of
    ``l2_grid`` with the least log-loss over held-out boards, each board left out in turn
    (the footholds of a board share its hard places). The grounded expert
    keeps ``config``'s preference weights (progress, stance offset) and every
    threshold, and sets each risk weight to the larger of ``scale * beta_w`` and its weight
    in ``config``: the outcomes of the footholds the robots chose say nothing of the
    footholds every chooser avoided (nor of the margins every chooser kept), so they can
    add caution but not remove it. ``scale`` [value units per log-odds] is fixed by a rule,
    not fitted (:func:`odds_price`).

    Raises
    ------
    FootfallError
        For an unknown label, one that never (or always) happened in ``table``, or the
        footholds of fewer than two boards.
    """
    if label not in OUTCOME_LABELS:
        raise FootfallError(f"unknown outcome {label!r}; one of {', '.join(OUTCOME_LABELS)}")
    y = table.labels[label].astype(np.float64)
    if y.sum() == 0 or y.sum() == y.size:
        raise FootfallError(f"'{label}' must both happen and not happen among the footholds")
    features = weight_features(table.terms, config, robot)
    x = np.column_stack([features[w] for w in RISK_WEIGHTS])  # (n, k) [value per unit weight]
    spread = x.std(axis=0)
    spread = np.where(spread > 0, spread, 1.0)
    z = x / spread

    boards = np.unique(table.board)
    if boards.size < 2:
        raise FootfallError("the outcome fit needs the footholds of at least two boards")
    held = [table.board == b for b in boards]
    cv = [np.mean([_log_loss(_logistic_fit(z[~h], y[~h], l2), z[h], y[h]) for h in held])
          for l2 in l2_grid]
    l2 = float(l2_grid[int(np.argmin(cv))])
    theta = _logistic_fit(z, y, l2)
    beta = theta[1:] / spread  # per unit of the raw feature
    scale = odds_price(config)
    grounded = replace(config, **{w: max(float(scale * c), getattr(config, w))
                                  for w, c in zip(RISK_WEIGHTS, beta)})
    return OutcomeFit(label, {w: float(c) for w, c in zip(RISK_WEIGHTS, beta)},
                      float(theta[0]), scale, grounded, l2, dict(zip(map(str, l2_grid), cv)),
                      {w: float(getattr(config, w)) for w in WEIGHTS}, int(y.size), int(y.sum()))


def _logistic_fit(z: np.ndarray, y: np.ndarray, l2: float) -> np.ndarray:
    """(b, beta >= 0) of ``P(y) = sigmoid(b - z @ beta)`` with the ridge ``l2`` on beta."""
    def loss(theta: np.ndarray) -> tuple[float, np.ndarray]:
        logit = theta[0] - z @ theta[1:]
        p = 0.5 * (1.0 + np.tanh(0.5 * logit))  # the logistic function, without overflow
        g = p - y
        grad = np.concatenate([[g.mean()], -(z.T @ g) / y.size + 2 * l2 * theta[1:]])
        nll = np.mean(np.logaddexp(0.0, logit) - y * logit)
        return float(nll + l2 * theta[1:] @ theta[1:]), grad

    rate = min(max(y.mean(), 1e-6), 1 - 1e-6)
    start = np.concatenate([[np.log(rate / (1.0 - rate))], np.zeros(z.shape[1])])
    bounds = [(None, None)] + [(0.0, None)] * z.shape[1]
    return minimize(loss, start, jac=True, method="L-BFGS-B", bounds=bounds).x


def _log_loss(theta: np.ndarray, z: np.ndarray, y: np.ndarray) -> float:
    """Mean negative log-likelihood of ``y`` under the fitted ``theta``."""
    logit = theta[0] - z @ theta[1:]
    return float(np.mean(np.logaddexp(0.0, logit) - y * logit))
