"""Learning a foothold model from demonstrations, end to end (paper §II-C, §III-B).

For a feature set, each feature family is fitted to the training
demonstrations (the template library is built from them), the families'
bandwidth-free data are computed once, and for the front and the hind legs
the families tune their own hyperparameters (each scale's RBF bandwidth,
which the paper tuned by hand) by the same grouped cross-validation that
chooses lambda. The ranking function is then fitted, and families drop the
columns the L1 learner left at zero (templates without weight).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import distinct_inputs, writable_path
from footfall.core.heightmap import HeightMap
from footfall.core.limits import check_count
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.core.validate import require_int
from footfall.data.store import Demonstration, DemoStore
from footfall.features.config import FeatureConfig
from footfall.features.family import FeatureFamily, check_family_options
from footfall.features.template_library import DEFAULT_LIBRARY_SIZE
from footfall.learning.dataset import (
    DEFAULT_TRAINING_CANDIDATES,
    Example,
    check_feature_set,
    check_informative,
    create_families,
    distinct_examples,
    make_example,
    pair_example,
    stack,
    stack_units,
    training_rows,
)
from footfall.learning.function import RankingFunction, check_function
from footfall.learning.learner import Learner, get_learner
from footfall.learning.model import FORMAT as MODEL_FORMAT
from footfall.learning.model import LEG_GROUPS, FootholdModel
from footfall.learning.supervision import Supervision, get_supervision
from footfall.learning.trials import DEFAULT_PAIRS, TrialFoothold, trial_footholds, trial_pairs
from footfall.learning.veto import Veto, fit_veto


@dataclass(frozen=True)
class TrainingDemo:
    """What the learner sees of a demonstration: terrain, state, candidates, choice, and where
    it came from (for folds grouped by run or board)."""

    hmap: HeightMap
    state: RobotState
    candidates: np.ndarray  # (n, 3) [m]
    chosen: int
    source: str = ""  # the demonstration's source ("run:<key>:step:<k>", "walker:train", ...)
    terrain: str = ""  # its terrain's content hash ("" : computed from hmap when needed)
    values: np.ndarray | None = None  # (n,) the teacher's value of each candidate [its units]
    refused: np.ndarray | None = None  # (n,) bool: candidates the teacher refused outright
    judged: np.ndarray | None = None  # (n,) [value units] what its refusals are relative to

    @classmethod
    def of(cls, demo: Demonstration, hmap: HeightMap) -> TrainingDemo:
        """A stored demonstration on its terrain ``hmap``, with its teacher's verdict."""
        return cls(hmap, demo.state, demo.candidates, demo.chosen, demo.source,
                   demo.terrain_hash, demo.values, demo.refused, demo.judged)

    def levels(self, supervision: Supervision) -> np.ndarray | None:
        """(n,) relevance levels of the candidates by ``supervision``; None for a choice
        (the paper's one-hot levels, made where they are needed)."""
        if supervision.name == "choice":
            return None
        return supervision.levels(self.candidates.shape[0], self.chosen, self.values,
                                  self.refused)


FOLDS = ("demonstration", "run", "board")
"""What cross-validation folds never split: one demonstration (the paper's folds), one run
(the steps of one walk: a correction's run, or a kinematic walk's board), or one board."""


def fold_unit(demo: TrainingDemo, folds: str) -> str:
    """The fold unit of a demonstration ("" for folds by demonstration: each its own).

    ``run``: corrections of one walking run ("run:<key>:step:<k>" -> "run:<key>"); the
    kinematic walker's demonstrations carry no walk of their own, so their unit is their
    board. ``board``: the terrain's content hash.
    """
    if folds not in FOLDS:
        raise FootfallError(f"unknown fold grouping {folds!r}; use one of {', '.join(FOLDS)}")
    if folds == "demonstration":
        return ""
    board = "board:" + (demo.terrain or demo.hmap.content_hash())
    if folds == "run" and demo.source.startswith("run:") and ":step:" in demo.source:
        return demo.source.rsplit(":step:", 1)[0]  # a run key may itself hold colons
    return board


def _fit(examples: list[Example], families: Sequence[FeatureFamily], learner: Learner, Cs,
         cv: int, selection: str = "1se", columns: np.ndarray | None = None) -> Any:
    """The learner fitted to the examples' design matrix (only ``columns``, a (d,) bool mask
    of the families' columns, if given)."""
    X, y, groups = stack(examples, families)
    if columns is not None:
        X = X[:, columns]
    units = stack_units(examples)
    if units is None:
        return learner.fit(X, y, groups, Cs=Cs, cv=cv, selection=selection)
    return learner.fit(X, y, groups, Cs=Cs, cv=cv, selection=selection, units=units)


def _tune(examples: list[Example], families: tuple[FeatureFamily, ...], learner: Learner, Cs,
          cv: int, log: Callable[[str], None]) -> tuple[FeatureFamily, ...]:
    """Each family's hyperparameters by the cross-validation error of the whole model (those
    that only re-map a column monotonically fixed instead, for a learner that reads only the
    order of each column's values: :attr:`Learner.order_only`)."""
    tuned = list(families)
    for k, family in enumerate(families):
        def error(variant: FeatureFamily, k: int = k) -> float:
            trial = tuple(tuned[:k]) + (variant,) + tuple(tuned[k + 1:])
            return float(_fit(examples, trial, learner, Cs, cv).cv_error_)
        tuned[k] = family.tune(error, log, order_only=learner.order_only)
    return tuple(tuned)


def check_budget(learner: Learner, template_budget: float | None) -> None:
    """Refuse a template budget that is not a positive share, or for a learner that cannot
    rank its columns (the kernel ranker)."""
    if template_budget is not None and (isinstance(template_budget, bool) or not (
            isinstance(template_budget, (int, float)) and 0 < template_budget < math.inf)):
        raise FootfallError(f"template_budget must be a share of the demonstrations above 0, "
                            f"got {template_budget!r}")
    if template_budget is not None and not learner.ranks_columns:
        raise FootfallError(f"learner {learner.name!r} cannot rank its columns, so it cannot keep "
                            f"to a template budget; give it none (--template-budget none)")


def _within_budget(fitted: Any, examples: list[Example], families: tuple[FeatureFamily, ...],
                   learner: Learner, Cs, cv: int, selection: str, budget: float | None,
                   log: Callable[[str], None]
                   ) -> tuple[Any, tuple[FeatureFamily, ...], np.ndarray | None]:
    """The fit, or if it reads more templates than ``budget`` x its demonstrations allow, a fit
    on the templates the learner relied on most (its :meth:`Learner.importance`), keeping
    floor(budget x n); the fitted estimator, the families it was fitted on and the mask (d,) of
    the prepared columns it read (None: all of them)."""
    if budget is None or not any(f.name == "templates" for f in families):
        return fitted, families, None
    allowed = int(math.floor(budget * len(examples)))
    importance = learner.importance(fitted)
    reduced, masks, start = list(families), [], 0
    for k, family in enumerate(families):
        stop = start + len(family.columns())
        keep = np.ones(stop - start, dtype=bool)
        if family.name == "templates":
            weight = np.asarray(importance[start:stop], dtype=np.float64)
            used = int(np.count_nonzero(weight > 0))
            if used <= allowed:
                return fitted, families, None
            keep[:] = False
            keep[np.argsort(-weight, kind="stable")[:allowed]] = True
            reduced[k] = family.select(keep)[0]  # the kept templates, in the library's order
            log(f"  {used} templates read, more than the budget {allowed} "
                f"({budget:g} x {len(examples)}): fitting again on the first {allowed}")
        masks.append(keep)
        start = stop
    # the prepared data hold every library template's distances: fit on the kept columns
    mask = np.concatenate(masks)
    return _fit(examples, families, learner, Cs, cv, selection, mask), tuple(reduced), mask


def _fit_families(unfitted: tuple[FeatureFamily, ...], demos: Sequence[TrainingDemo],
                  trials: Sequence[TrialFoothold], family_options: dict | None,
                  library_size: int, library_capped: bool,
                  bandwidth_rms: Sequence[float] | None, config: FeatureConfig,
                  robot: RobotDescription, rng: np.random.Generator,
                  log: Callable[[str], None]) -> tuple[FeatureFamily, ...]:
    """Each family fitted (a template library built) on the demonstrations, then on trial
    footholds, each alone, drawn at random to fill the library's slots: every demonstrated
    foothold is a template, and the robot's own thousands would swamp the library."""
    check_family_options(unfitted, family_options or {})
    check_informative([d.candidates for d in demos], [t.bad for t in trials])  # before any work
    options = {name: dict(opts) for name, opts in (family_options or {}).items()}
    if any(f.name == "templates" for f in unfitted):
        options["templates"] = {"library_size": library_size, "bandwidth_rms": bandwidth_rms,
                                "capped": library_capped, **options.get("templates", {})}
    slots = max(0, library_size // len(config.scales) - len(demos))
    sample = [trials[i] for i in np.sort(rng.choice(len(trials), min(slots, len(trials)),
                                                    replace=False))] if trials else []
    seen = ([d.hmap for d in demos] + [t.hmap for t in sample],
            [d.state for d in demos] + [t.state for t in sample],
            [d.candidates for d in demos] + [t.foothold[None, :] for t in sample],
            [d.chosen for d in demos] + [0] * len(sample))
    return tuple(f.fit(*seen, rng, robot=robot, log=log, **options.get(f.name, {}))
                 for f in unfitted)


def _finite(prepared: Any) -> bool:
    """Whether every number in a family's prepared data (arrays, nested in tuples) is finite."""
    if isinstance(prepared, (tuple, list)):
        return all(_finite(p) for p in prepared)
    return bool(np.isfinite(np.asarray(prepared, dtype=np.float64)).all())


def _trial_examples(trials: Sequence[TrialFoothold], families: tuple[FeatureFamily, ...],
                    config: FeatureConfig, robot: RobotDescription, pairs: int, folds: str,
                    rng: np.random.Generator, log: Callable[[str], None]) -> list[Example]:
    """The trials' comparisons (:func:`trial_pairs`) as two-row examples; a fold never splits
    the comparisons of one run's foothold that went wrong (with ``folds`` board: a board's)."""
    if not trials:
        return []
    single, kept = [], []
    for t in trials:  # one foothold at a time: each was chosen in a state of its own
        try:
            example = make_example(t.hmap, t.state, t.foothold[None, :], 0, families, config,
                                   robot=robot)
        except FootfallError:  # too little terrain data around it for the features
            continue
        if _finite(example.prepared):  # else: out of the leg's reach (no joint margin)
            single.append(example)
            kept.append(t)
    index = trial_pairs(np.array([t.board for t in kept], dtype=str),
                        np.array([t.front for t in kept], dtype=bool),
                        np.array([t.bad for t in kept], dtype=bool), pairs, rng)
    log(f"trials: {len(kept)} footholds stood on ({sum(t.bad for t in kept)} went wrong), "
        f"{len(index)} comparisons")
    return [pair_example(single[g], single[b], unit=("board:" + kept[b].board if folds == "board"
                                                     else "trial:" + kept[b].run))
            for g, b in index]


def _fit_veto(examples: list[Example], families: tuple[FeatureFamily, ...],
              columns: np.ndarray | None, cv: int, selection: str, seed: int, threads: int,
              log: Callable[[str], None]) -> Veto | None:
    """The veto (:mod:`footfall.learning.veto`) of the examples whose teacher gave refusals,
    on the families' columns (only ``columns``, a (d,) bool mask, if given), with their fold
    units; None where the teacher refused none of their candidates, or all (nothing to learn:
    the function walks without a veto)."""
    told = distinct_examples([e for e in examples if e.refused is not None])
    if not told:
        raise FootfallError("a veto is learned from the teacher's refusals; no demonstration "
                            "carries them")
    share = float(np.mean(np.concatenate([e.refused for e in told])))
    if share in (0.0, 1.0):
        log(f"  no veto: the teacher refused {'none' if share == 0 else 'all'} of these "
            f"demonstrations' candidates")
        return None
    X, _, groups = stack(told, families)
    if columns is not None:
        X = X[:, columns]
    refused = np.concatenate([e.refused for e in told])
    judged = shortfall = None
    if all(e.judged is not None for e in told):  # the values the refusals are relative to
        judged = np.concatenate([e.judged for e in told])
        shortfall = np.concatenate([e.judged_best - e.judged for e in told])
    units = stack_units(told)
    veto = fit_veto(X, refused, groups, cv=cv, selection=selection, units=units, seed=seed,
                    judged=judged, shortfall=shortfall, threads=threads)
    log(f"  veto{'' if veto.margin is None else f' (relative, margin {veto.margin:.3g})'}: "
        f"{veto.trees} trees, cv error {veto.cv_error:.4f} "
        f"({100 * veto.refused_share:.0f} % of {refused.size} candidates refused)")
    return veto


def _demo_examples(demos: Sequence[TrainingDemo], families: tuple[FeatureFamily, ...],
                   config: FeatureConfig, robot: RobotDescription, kind: Supervision,
                   veto: bool, training_candidates: int, folds: str,
                   rng: np.random.Generator) -> list[Example]:
    """Each demonstration's chosen candidate and up to ``training_candidates`` others, with
    their levels by ``kind`` (and the teacher's refusals for a ``veto``: with the values they
    are relative to only where ``kind`` reads values -- a veto reads what its supervision
    does, so refusals alone give the absolute veto a person's marks would), one at a time:
    each is vectorised over its candidates."""
    examples = []
    relative = veto and "values" in kind.reads
    for d in demos:
        rows = training_rows(d.candidates.shape[0], d.chosen, training_candidates, rng)
        example = make_example(d.hmap, d.state, d.candidates, d.chosen, families, config, rows,
                               robot, d.levels(kind), d.refused if veto else None,
                               d.judged if relative else None)
        examples.append(replace(example, unit=fold_unit(d, folds)))
    return examples


def _learn_group(group: str, examples: list[Example], families: tuple[FeatureFamily, ...],
                 learner: Learner, Cs, cv: int, selection: str, budget: float | None,
                 veto: bool, seed: int, scales: int, log: Callable[[str], None]
                 ) -> RankingFunction:
    """One leg group's ranking function: its hyperparameters tuned, fitted, kept to the
    template budget, with a learned veto if asked for."""
    chosen = [e for e in examples if e.front == (group == "front")]
    if len(chosen) < cv:
        raise FootfallError(f"{group} legs have {len(chosen)} demonstrations; "
                            f"{cv}-fold cross-validation needs at least {cv}")
    log(f"{group} legs: {len(chosen)} demonstrations and comparisons")
    tuned = _tune(chosen, families, learner, Cs, cv, log)
    fitted = _fit(chosen, tuned, learner, Cs, cv, selection)
    fitted, kept, mask = _within_budget(fitted, chosen, tuned, learner, Cs, cv, selection,
                                        budget, log)
    vetoed = (_fit_veto(chosen, tuned, mask, cv, selection, seed, learner.threads, log)
              if veto else None)
    if vetoed is not None:  # on the columns the ranker was fitted on
        function = learner.function(fitted, kept, len(chosen), veto=vetoed.forest,
                                    veto_margin=vetoed.margin)
        function.info.update(vetoed.info())
    else:
        function = learner.function(fitted, kept, len(chosen))
    log(_fitted_line(function.info, fitted.cv_error_, scales))
    return check_function(function)


def _fitted_line(info: dict[str, Any], cv_error: float, scales: int) -> str:
    """One log line about a fitted function: its point on the path, error, columns, templates."""
    point = (f"{info['trees']} trees" if info.get("trees") is not None
             else f"lambda {info.get('lambda', math.nan):.4g}")
    return (f"  {point}, cv error {cv_error:.4f}, {info.get('n_nonzero', '?')} columns read, "
            f"templates kept {info.get('kept_counts', [0] * scales)}")


def learn_model(demos: Sequence[TrainingDemo], feature_set: str, learner: str = "l1", *,
                trials: Sequence[TrialFoothold] = (), trial_pairs: int = DEFAULT_PAIRS,
                config: FeatureConfig | None = None, robot: RobotDescription = LITTLEDOG,
                library_size: int = DEFAULT_LIBRARY_SIZE, library_capped: bool = False,
                training_candidates: int = DEFAULT_TRAINING_CANDIDATES,
                bandwidth_rms: Sequence[float] | None = None, Cs=10, cv: int = 5, seed: int = 0,
                selection: str = "1se", family_options: dict[str, dict[str, Any]] | None = None,
                folds: str = "demonstration", template_budget: float | None = None,
                supervision: str = "choice", veto: bool = False, threads: int = 1,
                log: Callable[[str], None] = lambda s: None) -> FootholdModel:
    """Learn front- and hind-leg ranking functions from demonstrations.

    ``feature_set`` names a registered feature set (``terrain``, ``templates``,
    ``both``) or joins family names with ``+``. ``library_size``,
    ``library_capped`` (at most ``library_size`` templates however many the
    demonstrations: see :func:`footfall.features.template_library.library_from_demonstrations`) and
    ``bandwidth_rms`` (fixed RBF bandwidths, as RMS height differences [m]
    per scale, instead of choosing them by cross-validation) are the template
    family's options; ``family_options`` passes any family's own options by
    family name. ``selection`` picks lambda on the path (see
    :class:`footfall.learning.ranker.FootholdRanker`); ``folds`` what the
    cross-validation folds never split (:data:`FOLDS`). ``template_budget``: a leg
    group's function learned from n demonstrations reads at most
    floor(template_budget x n) templates (fitted again on those its learner
    relied on most if it read more); None: no budget. ``supervision`` names how a
    demonstration's teacher verdict becomes relevance levels of its candidates
    (:mod:`footfall.learning.supervision`: ``choice``, the paper's; ``refusals``; ``graded``).
    ``veto``: beside each function, learn which candidates the teacher refuses outright
    (:mod:`footfall.learning.veto`). ``threads``: each fit's threads where the learner has its
    own (LightGBM's: the same model, faster on idle cores). ``trials`` are footholds of the
    robot's own runs labelled by what followed (:mod:`footfall.learning.trials`): each that
    went wrong is ranked below ``trial_pairs`` that did not, of its board and leg group --
    alone (no ``demos``) or with the demonstrations, in one fit.
    """
    feature_set = check_feature_set(feature_set)
    if folds not in FOLDS:
        raise FootfallError(f"unknown fold grouping {folds!r}; use one of {', '.join(FOLDS)}")
    chosen_learner = get_learner(learner).with_threads(require_int(threads, "threads", 1))
    kind = get_supervision(supervision)
    if veto and not chosen_learner.vetoes:
        raise FootfallError(f"learner {learner!r} cannot carry a learned veto; the boosted "
                            f"ranker (lambdarank) can")
    seed = require_int(seed, "seed", 0)
    check_count(library_size, "library_size", 3)
    check_count(training_candidates, "training_candidates", 1)
    cv = require_int(cv, "cv", 2)
    check_budget(chosen_learner, template_budget)
    config = config or FeatureConfig()
    if not demos and not trials:
        raise FootfallError("no demonstrations or trials to learn from")
    resolutions = {d.hmap.resolution for d in demos} | {t.hmap.resolution for t in trials}
    started = time.perf_counter()
    rng = np.random.default_rng(seed)
    families = _fit_families(create_families(feature_set, config, robot), demos, trials,
                             family_options, library_size, library_capped, bandwidth_rms,
                             config, robot, rng, log)
    examples = _demo_examples(demos, families, config, robot, kind, veto, training_candidates,
                              folds, rng)
    examples += _trial_examples(trials, families, config, robot, trial_pairs, folds, rng,
                                log)
    functions = {g: _learn_group(g, examples, families, chosen_learner, Cs, cv, selection,
                                 template_budget, veto, seed, len(config.scales), log)
                 for g in LEG_GROUPS}
    trial_info = {} if not trials else {
        "trial_footholds": len(trials), "trial_comparisons": len(examples) - len(demos),
        "trial_pairs": trial_pairs}
    return FootholdModel(feature_set, learner, functions, config, robot,
                         map_resolution=max(resolutions),
                         info={"n_demonstrations": len(demos), "seed": seed,
                               "library_size": library_size,
                               "library_capped": library_capped,
                               "training_candidates": training_candidates,
                               "selection": selection, "folds": folds,
                               "template_budget": template_budget, **trial_info,
                               **({} if supervision == "choice" else
                                  {"supervision": supervision,
                                   "with_verdict": sum(d.values is not None
                                                       or d.refused is not None for d in demos)}),
                               **({"veto": True} if veto else {}),
                               "seconds": time.perf_counter() - started})


def store_demonstrations(path: str | os.PathLike, source: str | Sequence[str] | None = None
                         ) -> tuple[list[Demonstration], dict[str, HeightMap]]:
    """A store's demonstrations (those whose source starts with ``source``, or with any of
    several sources) and their terrains.

    Returns
    -------
    (list of Demonstration, dict)
        The demonstrations in id order and {terrain hash: HeightMap} of their terrains.

    Raises
    ------
    FootfallError
        If the store cannot be read or holds no such demonstration.
    """
    with DemoStore(path, read_only=True) as store:  # learning only reads
        demos = store.demonstrations(source_prefix=source)
        if not demos:
            raise FootfallError(f"{path}: the store holds no demonstrations"
                                + ("" if source is None else f" from source {_sources(source)}"))
        maps = {h: store.terrain(h) for h in {d.terrain_hash for d in demos}}
    return demos, maps


def _sources(source: str | Sequence[str]) -> str:
    return repr(source) if isinstance(source, str) else " or ".join(map(repr, source))


@dataclass(frozen=True)
class LearnedModel:
    """A model learned from a store and written to a file: what was learned, from how much."""

    model: str  # the model file written
    feature_set: str
    learner: str
    demonstrations: int  # demonstrations learned from
    seconds: float  # [s] learning time
    groups: dict[str, dict[str, Any]]  # per leg group: lambda, cv_error, bandwidths, kept, ...
    trial_footholds: int = 0  # footholds of the robot's own runs learned from

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON, in field order."""
        return dict(vars(self))


def _group_summary(f: RankingFunction, scales: int) -> dict[str, Any]:
    """Lambda (or the number of trees), CV error, RBF bandwidths [1/m^2] and [m RMS], templates
    kept of a ranking function (None where its learner does not say)."""
    return {"lambda": f.info.get("lambda"), "trees": f.info.get("trees"),
            "cv_error": f.info.get("cv_error"),
            "bandwidths_per_m2": list(getattr(f.family("templates"), "bandwidths", ())),
            "bandwidth_rms_m": f.info.get("bandwidth_rms_m"),
            "templates_kept": f.info.get("kept_counts", [0] * scales),
            "library": f.info.get("library_counts", [0] * scales),
            "non_zero_weights": f.info.get("n_nonzero")}


def learn_from_store(store: str | os.PathLike | None, path: str | os.PathLike, feature_set: str,
                     learner: str = "l1", *, source: str | Sequence[str] | None = None,
                     trials: Sequence[str | os.PathLike] = (),
                     log: Callable[[str], None] = lambda s: None, **options: Any) -> LearnedModel:
    """Learn a model (:func:`learn_model`) from a store's demonstrations and save it to ``path``.

    ``source`` keeps only demonstrations whose source starts with it (or with any of
    several: ``("human", "run:")`` learns from people's labels and the synthetic expert's);
    ``trials`` are stores whose run logs add the robot's own footholds, labelled by what
    followed (:mod:`footfall.learning.trials`); with ``store`` None they are all it learns
    from. ``options`` are :func:`learn_model`'s keyword arguments (library_size,
    training_candidates, bandwidth_rms, cv, seed, selection, trial_pairs, ...).

    Raises
    ------
    FootfallError
        For a bad output path (checked first), nothing to learn from (no store and no
        trials, a store without such demonstrations, trial stores without runs), or bad
        learning settings.
    """
    trials = distinct_inputs(trials, "--trials store")
    out = writable_path(path, inputs=(store, *trials), writes=MODEL_FORMAT)
    if store is None and not trials:
        raise FootfallError("give a store of demonstrations, trial stores, or both")
    training = []
    if store is not None:
        demos, maps = store_demonstrations(store, source=source)
        training = [TrainingDemo.of(d, maps[d.terrain_hash]) for d in demos]
    tried = trial_footholds(trials) if trials else []
    model = learn_model(training, feature_set, learner, trials=tried, log=log, **options)
    model.save(out)
    return LearnedModel(str(out), feature_set, learner, len(training), model.info["seconds"],
                        {g: _group_summary(f, len(model.config.scales))
                         for g, f in model.functions.items()}, len(tried))
