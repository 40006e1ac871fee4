"""The offline experiment (paper §V, Table I): learn from demonstrations, rank unseen terrain.

Terrain: boards of one module each (between flat start and end modules) of
every training kind at several difficulties; held-out boards of the same
kinds with fresh seeds ("unseen modules"); and boards of a kind never shown
in training ("unseen kind"). The synthetic expert demonstrates footholds on
all of them with the kinematic walker; the three feature sets are learned
with each learner from the training demonstrations only, and ranked against
the expert on the held-out ones. Every number in the report comes from this
run; nothing is tuned toward the paper's.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError
from footfall.core.params import Params, at_least, param
from footfall.core.seeds import SeedStreams
from footfall.core.stats import bootstrap_ci
from footfall.data.store import DemoStore
from footfall.expert.collect import collect_demonstrations
from footfall.expert.synthetic import SyntheticExpert
from footfall.features.dense import score_grid
from footfall.features.family import PAPER_FEATURE_SETS, feature_set_families
from footfall.learning.evaluation import expert_values, rank_scores
from footfall.learning.learner import LEARNERS
from footfall.learning.model import FootholdModel
from footfall.learning.ranker import BUILTIN_LEARNERS
from footfall.learning.train import TrainingDemo, learn_model
from footfall.plots.maps import save_kept_templates, save_score_maps
from footfall.plots.relief import save_relief
from footfall.terrain import KINDS, make_board


def _kinds(value: object) -> bool:
    return isinstance(value, tuple) and len(value) > 0 and all(k in KINDS for k in value)


def _difficulties(value: object) -> bool:
    return isinstance(value, tuple) and len(value) > 0 and all(
        isinstance(d, (int, float)) and not isinstance(d, bool) and 0 <= d <= 1 for d in value)


def _feature_sets(value: object) -> bool:
    try:
        return isinstance(value, tuple) and len(value) > 0 and all(
            isinstance(v, str) and feature_set_families(v) for v in value)
    except FootfallError:
        return False


@dataclass(frozen=True)
class OfflineConfig(Params):
    """What the offline experiment runs; written next to its results (docs/configuration.md)."""

    train_kinds: tuple[str, ...] = param(("steps", "barrier", "slope", "rocky"), check=_kinds,
                                         must="a non-empty tuple of terrain kinds",
                                         doc="the kinds of the training boards")
    unseen_kind: str = param("logs", check=lambda v: _kinds((v,)), must="a terrain kind",
                             doc="a kind never shown in training")
    train_difficulties: tuple[float, ...] = param(
        (0.3, 0.6, 0.9), unit="-", check=_difficulties, must="a tuple of numbers in [0, 1]",
        doc="difficulties of the training boards (and of the unseen kind's)")
    test_difficulties: tuple[float, ...] = param(
        (0.45, 0.75), unit="-", check=_difficulties, must="a tuple of numbers in [0, 1]",
        doc="difficulties of the unseen modules of the training kinds")
    n_train: int = param(100, range=at_least(1),
                         doc="demonstrations to learn from (the paper had about 100)")
    n_test_modules: int = param(40, range=at_least(1), doc="demonstrations on unseen modules "
                                                           "of the training kinds")
    n_test_kind: int = param(30, range=at_least(1), doc="demonstrations on the unseen kind")
    feature_sets: tuple[str, ...] = param(
        PAPER_FEATURE_SETS, check=_feature_sets, must="a tuple of feature sets",
        doc="the feature sets learned (registered sets, or families joined by '+')")
    learners: tuple[str, ...] = param(
        BUILTIN_LEARNERS, check=lambda v: isinstance(v, tuple) and len(v) > 0
        and all(learner in LEARNERS for learner in v), must="a tuple of registered learners",
        doc="the learners compared")
    library_size: int = param(1000, range=at_least(3),
                              doc="templates in the library before L1 selection")
    l1_min_ablation: bool = param(True, doc="also learn L1 with lambda at the smallest CV error "
                                            "(\"l1-min\")")
    seed: int = param(0, range=at_least(0), doc="the experiment's seed: every board, "
                      "demonstration and learning seed is drawn from its named streams")
    extra_rocky_train: int = param(2, range=at_least(0), doc="more rocky boards in training: "
                                                             "the kind that matters most")

    @classmethod
    def quick(cls, seed: int = 0) -> OfflineConfig:
        """A small version for a smoke test: fewer boards and demonstrations, L1 only."""
        return cls(seed=seed, n_train=30, n_test_modules=12, n_test_kind=8, learners=("l1",),
                   library_size=150, train_difficulties=(0.5,), test_difficulties=(0.6,),
                   extra_rocky_train=1)

    @property
    def streams(self) -> SeedStreams:
        """The experiment's named seed streams (boards, demonstrations, learning)."""
        return SeedStreams("offline", self.seed)

    def boards(self) -> dict[str, list[tuple[str, float, int]]]:
        """(kind, difficulty, seed) of the boards of each split; seeds from the "boards" stream."""
        seed = self.streams.seed_for
        train = [(k, d, seed("boards", 0, i, j)) for i, k in enumerate(self.train_kinds)
                 for j, d in enumerate(self.train_difficulties)]
        train += [("rocky", d, seed("boards", 1, j)) for j, d in
                  enumerate(np.linspace(0.4, 0.8, self.extra_rocky_train).round(2))]
        test = [(k, d, seed("boards", 2, i, j)) for i, k in enumerate(self.train_kinds)
                for j, d in enumerate(self.test_difficulties)]
        kind = [(self.unseen_kind, d, seed("boards", 3, j)) for j, d in
                enumerate(self.train_difficulties)]
        return {"train": train, "test-modules": test, "test-kind": kind}


def run_offline(out: Path, config: OfflineConfig | None = None,
                log: Callable[[str], None] = print) -> dict:
    """Run the experiment into ``out`` (a store, models, a report); return the results."""
    # Built here, not at import: a config's checks ask the registries, which load the
    # plugins (a broken plugin must fail as one line when the command runs, not on import).
    config = OfflineConfig() if config is None else config
    if out.exists() and not out.is_dir():
        raise FootfallError(f"output path is not a directory: {out}")
    out.mkdir(parents=True, exist_ok=True)
    (out / "models").mkdir(exist_ok=True)
    started = time.perf_counter()
    expert = SyntheticExpert()
    splits: dict[str, list] = {}
    maps = {}
    wanted = {"train": config.n_train, "test-modules": config.n_test_modules,
              "test-kind": config.n_test_kind}
    store_path = out / "demos.sqlite"
    if store_path.exists():
        store_path.unlink()  # the experiment's store is its own, rebuilt from the seed
    with DemoStore(store_path, create=True) as store:
        for k, (split, specs) in enumerate(config.boards().items()):
            boards = [make_board([(kind, d)], seed) for kind, d, seed in specs]
            for b in boards:
                maps[b.content_hash()] = b
            demos = collect_demonstrations(boards, expert, wanted[split],
                                           seed=config.streams.seed_for("demonstrations", k),
                                           source=f"walker:{split}")
            store.add_demonstrations(demos, terrains=boards)
            splits[split] = store.demonstrations(source_prefix=f"walker:{split}")
            log(f"{split}: {len(splits[split])} demonstrations on {len(boards)} boards")
    terrain = maps.__getitem__
    values = {s: expert_values(d, terrain, expert) for s, d in splits.items() if s != "train"}
    training = [TrainingDemo.of(d, maps[d.terrain_hash])
                for d in splits["train"]]

    results, table1 = [], {}
    models: dict[tuple[str, str], FootholdModel] = {}
    runs = [(learner, "1se") for learner in config.learners]
    if config.l1_min_ablation and "l1" in config.learners:
        runs.append(("l1", "min"))
    for feature_set in config.feature_sets:
        rms = None
        for learner, selection in runs:
            label = learner if selection == "1se" else f"{learner}-{selection}"
            t0 = time.perf_counter()
            log(f"learning {feature_set}/{label}")
            model = learn_model(training, feature_set, learner, library_size=config.library_size,
                                seed=config.streams.seed_for("learning"), bandwidth_rms=rms,
                                selection=selection,
                                log=lambda s: log("  " + s))
            # The bandwidths are chosen once per feature set, by the L1 learner's
            # cross-validation, and reused by the comparison learners.
            if rms is None and feature_set != "terrain":
                rms = tuple(np.mean([f.info.get("bandwidth_rms_m") for f in model.functions.values()],
                                    axis=0))
            models[(feature_set, label)] = model
            model.save(out / "models" / f"{feature_set}-{label}.npz")
            row = {"feature_set": feature_set, "learner": label,
                   "learn_seconds": time.perf_counter() - t0,
                   "lambda": {g: f.info["lambda"] for g, f in model.functions.items()},
                   "cv_error": {g: f.info["cv_error"] for g, f in model.functions.items()}}
            for split in ("test-modules", "test-kind"):
                row[split] = rank_scores(model, splits[split], terrain,
                                         values=values[split]).as_dict()
            results.append(row)
            if label == "l1" and feature_set != "terrain":
                table1[feature_set] = model.templates_kept()
            log(f"  unseen modules top-1 {row['test-modules']['top1']:.3f}, "
                f"unseen kind top-1 {row['test-kind']['top1']:.3f}")

    summary = {"config": config.to_dict(), "results": results, "table1": table1,
               "comparisons": compare_feature_sets(results)
               + (compare_feature_sets(results, "l1-min") if config.l1_min_ablation else []),
               "demonstrations": {s: len(d) for s, d in splits.items()},
               "seconds": time.perf_counter() - started}
    _figures(out, models, maps, splits, config)
    write_text_atomic(out / "results.json", json.dumps(summary, indent=2))
    write_text_atomic(out / "report.md", _report(summary))
    return summary


COMPARISONS = (("both", "templates"), ("templates", "terrain"), ("both", "terrain"))


def compare_feature_sets(results: list[dict], learner: str = "l1") -> list[dict]:
    """Paired differences of reward loss between feature sets, on the same demonstrations.

    For each pair (a, b) of :data:`COMPARISONS` and each split: the mean of
    loss(a) - loss(b) over the held-out demonstrations (negative: a ranks
    better), its 95 % paired bootstrap interval, and how many
    demonstrations each one wins. A difference whose interval contains zero
    is not resolved by this many demonstrations.
    """
    by = {(r["feature_set"], r["learner"]): r for r in results}
    out = []
    for a, b in COMPARISONS:
        if (a, learner) not in by or (b, learner) not in by:
            continue
        for split in ("test-modules", "test-kind"):
            la = np.array(by[(a, learner)][split]["losses"])
            lb = np.array(by[(b, learner)][split]["losses"])
            if la.size == 0 or la.size != lb.size:
                continue
            d = la - lb
            lo, hi = bootstrap_ci(d)
            out.append({"a": a, "b": b, "learner": learner, "split": split, "n": int(d.size),
                        "mean_difference": float(d.mean()), "ci95": [lo, hi],
                        "a_better": int(np.sum(d < -1e-9)), "b_better": int(np.sum(d > 1e-9))})
    return out


def _figures(out: Path, models: dict, maps: dict, splits: dict, config: OfflineConfig) -> None:
    test_board = maps[splits["test-modules"][0].terrain_hash]
    rocky = [maps[d.terrain_hash] for d in splits["test-modules"]
             if maps[d.terrain_hash].metadata["modules"][1]["kind"] == "rocky"]
    board = rocky[0] if rocky else test_board
    save_relief(board, out / "test-board.png", title="an unseen test board")
    grids, titles = [], []
    for fs in config.feature_sets:
        model = models.get((fs, "l1"))
        if model is None:
            continue
        reward = model.reward_for("LF")
        grids.append(score_grid(board, reward))
        titles.append(f"learned reward ({fs}, L1), front legs: terrain part")
    if grids:
        save_score_maps(grids, titles, ["reward"] * len(grids), out / "reward-maps.png")
    for fs in ("both", "templates"):
        model = models.get((fs, "l1"))
        if model is not None:
            save_kept_templates(model, out / f"templates-{fs}.png")


def _report(s: dict) -> str:
    lines = ["# footfall offline experiment", "",
             f"Demonstrations: {s['demonstrations']} (synthetic expert, kinematic walker). "
             f"Run time {s['seconds'] / 60:.1f} min. Configuration in `results.json`.", "",
             "## Ranking on unseen terrain", "",
             "Top-1: the model's best candidate is the expert's choice. Percentile: the share "
             "of other candidates the expert's choice outranks in the model's ranking. Loss: "
             "the expert's value of its best candidate minus its value of the model's pick "
             "(1 unit = 1 cm of progress), with its 95 % bootstrap interval over the "
             "demonstrations. Within 1 cm: the model's pick lies within 1 cm of the expert's "
             "(candidates are 5 mm apart).", ""]
    for split, title in (("test-modules", "Unseen modules of the training kinds"),
                         ("test-kind", "The unseen terrain kind")):
        n = s["results"][0][split]["n"] if s["results"] else 0
        lines += [f"### {title} ({n} demonstrations)", "",
                  "| features | learner | top-1 | within 1 cm | percentile | loss | loss 95 % CI |",
                  "| --- | --- | --- | --- | --- | --- | --- |"]
        for r in s["results"]:
            a = r[split]
            lo, hi = a["reward_loss_ci"]
            lines.append(f"| {r['feature_set']} | {r['learner']} | {a['top1']:.3f} | "
                         f"{a['top1_near']:.3f} | {a['percentile']:.4f} | "
                         f"{a['reward_loss']:.2f} | {lo:.2f} to {hi:.2f} |")
        lines.append("")
    if s.get("comparisons"):
        lines += ["## Feature sets compared on the same demonstrations", "",
                  "Mean of loss(a) - loss(b) per demonstration (negative: a is better), its "
                  "95 % paired bootstrap interval, and the demonstrations each side wins "
                  "(the rest tie). An interval that contains 0 means this many "
                  "demonstrations do not resolve the difference. `l1` picks lambda by the "
                  "one-standard-error rule (the default: sparser), `l1-min` at the smallest "
                  "cross-validation error, with the same bandwidths.", "",
                  "| learner | a | b | split | mean difference | 95 % CI | a better | b better |",
                  "| --- | --- | --- | --- | --- | --- | --- | --- |"]
        for c in s["comparisons"]:
            lo, hi = c["ci95"]
            lines.append(f"| {c['learner']} | {c['a']} | {c['b']} | {c['split']} | "
                         f"{c['mean_difference']:+.2f} | {lo:+.2f} to {hi:+.2f} | "
                         f"{c['a_better']} | {c['b_better']} |")
    lines += ["", "## Table I: templates kept (L1), per scale, of the library", "",
              "| features | legs | small | medium | large |", "| --- | --- | --- | --- | --- |"]
    for fs, groups in s["table1"].items():
        for g, v in groups.items():
            lines.append(f"| {fs} | {g} | " + " | ".join(
                f"{k} / {n}" for k, n in zip(v["kept"], v["library"])) + " |")
    lines += ["", "## Pictures", "", "![test board](test-board.png)", "",
              "![reward maps](reward-maps.png)", "",
              "![kept templates, templates + features](templates-both.png)", "",
              "![kept templates, templates only](templates-templates.png)", ""]
    return "\n".join(lines)
