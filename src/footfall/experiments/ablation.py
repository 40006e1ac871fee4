"""The walking controller's ablation: each part switched off alone, on the same boards and seeds.

``footfall ablation`` measures what each part of the walking controller
(:mod:`footfall.sim.episode`: the reflexes of :mod:`footfall.control.reflexes`,
the stance load control of :mod:`footfall.control.load`, the COG plan within
the legs' reach of :mod:`footfall.control.cog`) is worth. Every *variant* is
the default :class:`~footfall.sim.episode.WalkConfig` with one change
(:data:`footfall.experiments.variants.VARIANTS`, a registry: a new part of the
controller adds its variant with :func:`~footfall.experiments.variants.register_variant`). Each variant walks, with the walking expert
choosing every foothold and with the hand-tuned reward, over

* the controller's test board -- ``rocky:0.7 steps:0.7``, board seed 500,
  the board ``make run`` makes for seed 0 -- with run seeds 5000-5020, and
* the six calibration boards ``rocky:D steps:D``, D = 0.5, 0.6, 0.7, board
  seeds 800 and 801, with run seeds 0-7, and
* four hard boards ``rocky:0.85 steps:0.85``, board seeds 900-903, with run
  seeds 0-15: on the test and calibration boards the defaults fail about one run in
  fifteen, too few for 69 paired runs to tell a part's worth from the luck
  of the seeds; on these about two in five, so their 64 paired runs can, and
* the training suite: four boards ``KIND:0.7 KIND:0.7`` of each training kind
  (:data:`footfall.terrain.kinds.TRAINING_KINDS`: the paper's but flat -- steps,
  barrier, slope, logs, rocky -- and ridges, pitted, rockyscan and pavers), board seeds
  1100-1103, with run seeds 0-7 -- the terrain every parameter may be chosen
  on, not only the two kinds of the other boards,

with the candidate set F within 3 cm of the gait-nominal foothold, as the
reproduction walks. The same board and seed give every variant the same
start pose, registration error, friction and sensor noise, so the variants
are compared *paired*: for each variant, the runs it crossed and the
defaults did not (won), and the reverse (lost), with the two-sided exact
sign test's p-value on those discordant runs (McNemar's exact test). The
failure taxonomy counts how the failed runs ended
(:mod:`footfall.sim.explain`'s cause).

:func:`training_rule` is the rule a change is judged by (docs/terrain-suite.md):
over the hard boards and the training suite together it wins at least as many
paired runs as it loses, for the expert and the hand-tuned reward alike, and
no group of boards is significantly worse for either. A judgement of a change walks *fresh* run seeds (``footfall ablation
--seeds-round K``, :meth:`AblationConfig.seeds_round`: every board's first
run seed moved by 1 000 K), the defaults on them too: the defaults kept are
those that did well on the seeds that judged them, so paired against the
same seeds again a new change would inherit none of that luck and look
worse than it is.

Every run is stored under the key ``variant/who/board/sSEED`` in
``ablation.sqlite`` as it arrives (:class:`footfall.experiments.runs.Runner`),
so an ablation stopped at any point resumes without walking a run twice,
and another choice of variants or choosers in the same folder walks only
the runs it does not find; ``config.json`` holds the settings, and a folder
with other boards, seeds or walk is refused. The store does not know the
code: after a change to the controller, walk into a new folder. The results go to ``ablation.json`` and ``ablation.md``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError
from footfall.core.folders import holding_folders
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, at_least, param, within
from footfall.core.registry import Registry
from footfall.core.seeds import check_seed_span
from footfall.core.stats import mcnemar_exact
from footfall.data.store import DemoStore
from footfall.experiments.executors import Executor, LocalPool
from footfall.experiments.reproduce import reproduction_walk
from footfall.experiments.runs import RunJob, Runner, board_files, claim_folder
from footfall.experiments.variants import (  # noqa: F401 (re-exported: the ablation's variants)
    BUILTIN_VARIANTS,
    VARIANTS,
    Variant,
    register_variant,
)
from footfall.expert.synthetic import walking_expert
from footfall.sim.episode import WalkConfig
from footfall.terrain.kinds import KINDS, TRAINING_KINDS

STORE_NAME = "ablation.sqlite"
SEEDS_ROUND = 1000  # each round of run seeds moves every board's first run seed by this
WHO = ("expert", "hand")  # who chooses the footholds: the walking expert, the hand-tuned reward
Spec = tuple[tuple[str, float], ...]  # a board: (kind, difficulty) of each module
GROUPS = ("", "hard_", "suite_")  # run groups paired apart: test and calibration, hard, suite
WORSE = 0.05  # [-] a group is worse when it loses more than it wins at this exact McNemar p


# ------------------------------------------------------------------ settings
def _is_spec(value: object) -> bool:
    return (isinstance(value, tuple) and len(value) > 0
            and all(isinstance(m, tuple) and len(m) == 2 and isinstance(m[0], str)
                    and isinstance(m[1], (int, float)) and 0 <= m[1] <= 1 for m in value))


def _names(value: object, known: tuple[str, ...] | Registry) -> bool:
    return (isinstance(value, tuple) and len(value) > 0 and len(set(value)) == len(value)
            and all(v in known for v in value))


@dataclass(frozen=True)
class AblationConfig(Params):
    """The ablation's boards, seeds and variants; written next to its results."""

    variants: tuple[str, ...] = param(
        BUILTIN_VARIANTS, check=lambda v: _names(v, VARIANTS),
        must=f"a tuple of distinct variant names ({', '.join(BUILTIN_VARIANTS)})",
        doc="the controller variants, compared with 'defaults' (walked whether listed or not)")
    who: tuple[str, ...] = param(WHO, check=lambda v: _names(v, WHO),
                                 must="a tuple of 'expert' and / or 'hand'",
                                 doc="who chooses the footholds")
    test_board: Spec = param((("rocky", 0.7), ("steps", 0.7)), check=_is_spec,
                             must="a tuple of (kind, difficulty in [0, 1])",
                             doc="the test board's modules")
    test_board_seed: int = param(500, range=at_least(0), doc="the test board's seed")
    test_runs: int = param(21, range=at_least(0), doc="runs on the test board")
    test_seed: int = param(5000, range=at_least(0), doc="first run seed on the test board")
    calibration_difficulties: tuple[float, ...] = param(
        (0.5, 0.6, 0.7), unit="-",
        check=lambda v: isinstance(v, tuple) and all(0 <= d <= 1 for d in v),
        must="a tuple of numbers in [0, 1]",
        doc="each a calibration board rocky:D steps:D per board seed")
    calibration_board_seeds: tuple[int, ...] = param(
        (800, 801), check=lambda v: isinstance(v, tuple) and all(
            isinstance(s, int) and s >= 0 for s in v), must="a tuple of seeds >= 0",
        doc="board seeds of the calibration boards")
    calibration_runs: int = param(8, range=at_least(0), doc="runs on each calibration board")
    calibration_seed: int = param(0, range=at_least(0), doc="first run seed on each")
    hard_difficulty: float = param(0.85, unit="-", range=within(0, 1),
                                   doc="difficulty D of the hard boards rocky:D steps:D")
    hard_board_seeds: tuple[int, ...] = param(
        (900, 901, 902, 903), check=lambda v: isinstance(v, tuple) and all(
            isinstance(s, int) and s >= 0 for s in v), must="a tuple of seeds >= 0",
        doc="board seeds of the hard boards (paired runs that separate the variants)")
    hard_runs: int = param(16, range=at_least(0), doc="runs on each hard board")
    hard_seed: int = param(0, range=at_least(0), doc="first run seed on each hard board")
    suite_kinds: tuple[str, ...] = param(
        TRAINING_KINDS, check=lambda v: isinstance(v, tuple) and len(set(v)) == len(v)
        and all(k in KINDS for k in v), must="a tuple of distinct terrain kinds",
        doc="the training suite's kinds, each a set of boards KIND:D KIND:D")
    suite_difficulty: float = param(0.7, unit="-", range=within(0, 1),
                                    doc="difficulty D of the training suite's boards")
    suite_board_seeds: tuple[int, ...] = param(
        (1100, 1101, 1102, 1103), check=lambda v: isinstance(v, tuple) and all(
            isinstance(s, int) and s >= 0 for s in v), must="a tuple of seeds >= 0",
        doc="board seeds of the training suite's boards, the same for every kind")
    suite_runs: int = param(8, range=at_least(0), doc="runs on each training suite board")
    suite_seed: int = param(0, range=at_least(0),
                            doc="first run seed on each training suite board")
    walk: WalkConfig = param(factory=lambda: reproduction_walk(),
                             doc="the walk every variant changes: the defaults with F within "
                                 "the reproduction's search radius")

    def __post_init__(self) -> None:
        super().__post_init__()
        for name, (_, _, runs, first) in self.boards().items():  # every run seed within range
            check_seed_span(first, runs, f"the {name} board's first run seed")

    @classmethod
    def quick(cls) -> AblationConfig:
        """A small version (about a minute on two cores) for a smoke test."""
        return cls(variants=("defaults", "no-tilt-reflex"), who=("hand",),
                   test_board=(("rocky", 0.5),), test_runs=2, calibration_difficulties=(0.4,),
                   calibration_board_seeds=(800,), calibration_runs=1, hard_runs=0,
                   suite_runs=0)

    def seeds_round(self, k: int) -> AblationConfig:
        """This ablation on round ``k``'s run seeds: every board's first run seed moved by
        :data:`SEEDS_ROUND` ``* k`` (round 0: these settings). A judgement walks a round no
        judgement has used, so the defaults' runs it is paired with were not selected on it."""
        if k == 0:
            return self
        step = SEEDS_ROUND * k
        return replace(self, test_seed=self.test_seed + step,
                       calibration_seed=self.calibration_seed + step,
                       hard_seed=self.hard_seed + step, suite_seed=self.suite_seed + step)

    def variant_walk(self, variant: str) -> WalkConfig:
        """The walking settings of ``variant``: its change of :attr:`walk`."""
        return VARIANTS.get(variant).change(self.walk)

    def boards(self) -> dict[str, tuple[Spec, int, int, int]]:
        """Board name -> (modules, board seed, runs, first run seed)."""
        out = {"test": (self.test_board, self.test_board_seed, self.test_runs, self.test_seed)}
        for d in self.calibration_difficulties:
            for s in self.calibration_board_seeds:
                out[f"cal{d:g}-{s}"] = ((("rocky", d), ("steps", d)), s, self.calibration_runs,
                                        self.calibration_seed)
        d = self.hard_difficulty
        for s in self.hard_board_seeds:
            out[f"hard{d:g}-{s}"] = ((("rocky", d), ("steps", d)), s, self.hard_runs,
                                     self.hard_seed)
        d = self.suite_difficulty
        for kind in self.suite_kinds:
            for s in self.suite_board_seeds:
                out[f"suite-{kind}-{s}"] = (((kind, d), (kind, d)), s, self.suite_runs,
                                            self.suite_seed)
        return {k: v for k, v in out.items() if v[2] > 0}


def _variants(config: AblationConfig) -> list[str]:
    """The variants walked: 'defaults' first (every other is compared with it)."""
    return ["defaults"] + [v for v in config.variants if v != "defaults"]


def ablation_jobs(config: AblationConfig, paths: dict[str, Path]) -> list[RunJob]:
    """Every run of the ablation, keyed ``variant/who/board/sSEED``.

    The hand-tuned reward's runs come first (each takes about a sixth of an expert's run,
    whose judge weighs every candidate's terrain), then the expert's, a variant at a time. A
    variant that changes only the walking expert walks no hand-tuned runs: they would be the
    defaults' (:func:`walked_as`).
    """
    jobs = []
    for who in sorted(config.who, key=lambda w: w == "expert"):
        for v in _variants(config):
            if walked_as(config, v, who) != v:
                continue
            walk = config.variant_walk(v)
            expert = VARIANTS.get(v).expert(walking_expert(walk.footstep.lead))
            for name, (_, _, runs, seed) in config.boards().items():
                jobs += [RunJob(f"{v}/{who}/{name}/s{s}", str(paths[name]), None, s, walk,
                                expert=expert, judge=who == "expert")
                         for s in range(seed, seed + runs)]
    return jobs


def walked_as(config: AblationConfig, variant: str, who: str) -> str:
    """The variant whose runs stand for ``variant``'s by ``who``: the defaults' for the
    hand-tuned reward where the variant changes only the walking expert (the hand-tuned
    reward's runs never consult it, so they are the same runs), else the variant itself."""
    changed = VARIANTS.get(variant)
    if (who == "hand" and changed.changes_expert
            and config.variant_walk(variant) == config.variant_walk("defaults")):
        return "defaults"
    return variant


# ------------------------------------------------------------------ results
def _outcomes(store: DemoStore) -> dict[str, dict]:
    """Run key -> result of every stored run."""
    return {r["key"]: r["result"] for r in store.runs()}


def _group(name: str) -> str:
    """The paired group of a board: '' (test and calibration), 'hard_' or 'suite_'."""
    return "hard_" if name.startswith("hard") else "suite_" if name.startswith("suite") else ""


def _row(config: AblationConfig, results: dict[str, dict], v: str, who: str) -> dict:
    """One variant's runs by one chooser, against the defaults' on the same boards and seeds:
    won / lost over the test and calibration boards, and apart over the hard ones and over
    the training suite's."""
    row: dict = {"boards": {}, "causes": {}}
    for prefix in GROUPS:
        row[prefix + "won"] = row[prefix + "lost"] = 0
    speeds = []
    for name, (_, _, runs, seed) in config.boards().items():
        ok = 0
        prefix = _group(name)
        for s in range(seed, seed + runs):
            r = results[f"{walked_as(config, v, who)}/{who}/{name}/s{s}"]
            base = results[f"defaults/{who}/{name}/s{s}"]["success"]
            ok += bool(r["success"])
            row[prefix + "won"] += bool(r["success"]) and not base
            row[prefix + "lost"] += base and not r["success"]
            if r["success"]:
                speeds.append(r["speed_cm_s"])
            else:
                cause = (r.get("explanation") or {}).get("cause") or r.get("reason", "?")
                row["causes"][cause] = row["causes"].get(cause, 0) + 1
        row["boards"][name] = {"successes": ok, "runs": runs}
    row["test"] = row["boards"].get("test")
    for group, prefix in (("calibration", "cal"), ("hard", "hard"), ("suite", "suite")):
        boards = [b for n, b in row["boards"].items() if n.startswith(prefix)]
        row[group] = ({"successes": sum(b["successes"] for b in boards),
                       "runs": sum(b["runs"] for b in boards)} if boards else None)
    row["speed_cm_s"] = sum(speeds) / len(speeds) if speeds else None
    for prefix in GROUPS:
        row[prefix + "p_value"] = mcnemar_exact(row[prefix + "won"], row[prefix + "lost"])
    return row


def training_rule(rows: dict[str, dict]) -> bool | None:
    """The training-suite rule (docs/terrain-suite.md), on one variant's rows by chooser: adopted
    when, for the expert and the hand-tuned reward alike, it wins at least as many paired runs
    as it loses over the hard boards and the training suite together, and on no group (test
    and calibration, hard, suite) does it lose more than it wins with an exact McNemar p below
    :data:`WORSE`. None when a chooser or the hard boards or the suite were not walked."""
    if set(rows) != set(WHO) or any(rows[w]["hard"] is None or rows[w]["suite"] is None
                                    for w in WHO):
        return None
    for r in rows.values():
        if r["hard_won"] + r["suite_won"] < r["hard_lost"] + r["suite_lost"]:
            return False
        if any(r[p + "lost"] > r[p + "won"] and r[p + "p_value"] < WORSE for p in GROUPS):
            return False
    return True


def summarise_ablation(config: AblationConfig, results: dict[str, dict]) -> dict:
    """Per variant and chooser: crossings on the test and calibration boards, the failure
    taxonomy, the mean speed [cm/s] of the crossings, and the paired comparison with the
    defaults. ``results``: run key -> stored result."""
    out = {}
    for v in _variants(config):
        rows = {who: _row(config, results, v, who) for who in config.who}
        out[v] = {"description": VARIANTS.get(v).description, **rows,
                  "training_rule": None if v == "defaults" else training_rule(rows)}
    return out


def _count(c: dict | None) -> str:
    return "-" if c is None else f"{c['successes']} / {c['runs']}"


def _paired(row: dict, prefix: str, any_runs: bool) -> str:
    won, lost, p = row[prefix + "won"], row[prefix + "lost"], row[prefix + "p_value"]
    return f"+{won} / -{lost} ({p:.2g})" if any_runs else "-"


def ablation_markdown(config: AblationConfig, summary: dict) -> str:
    """The ablation table and the failure taxonomy, as Markdown."""
    suite = config.suite_runs > 0 and bool(config.suite_kinds)
    head = ["variant"]
    for who in config.who:
        label = "expert" if who == "expert" else "hand-tuned"
        head += [f"{label}, test board", f"{label}, calibration boards",
                 f"{label}: won / lost vs defaults (p)", f"{label}, hard boards",
                 f"{label}, hard boards: won / lost (p)"]
        if suite:
            head += [f"{label}, training suite", f"{label}, training suite: won / lost (p)"]
    ruled = any(row["training_rule"] is not None for row in summary.values())
    if ruled:
        head.append("by the training-suite rule")
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for v, row in summary.items():
        cells = [row["description"] if v == "defaults" else f"{v}: {row['description']}"]
        for who in config.who:
            r = row[who]
            other = v != "defaults"
            cells += [_count(r["test"]), _count(r["calibration"]), _paired(r, "", other),
                      _count(r["hard"]), _paired(r, "hard_", other and r["hard"] is not None)]
            if suite:
                cells += [_count(r["suite"]),
                          _paired(r, "suite_", other and r["suite"] is not None)]
        if ruled:
            verdict = row["training_rule"]
            cells.append("-" if verdict is None else "adopted" if verdict else "not adopted")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Failure taxonomy (all boards; footfall.sim.explain's cause of each failed "
              "run):", ""]
    for v, row in summary.items():
        for who in config.who:
            causes = ", ".join(f"{n} x {c}" for c, n in sorted(row[who]["causes"].items(),
                                                                 key=lambda x: (-x[1], x[0])))
            speed = row[who]["speed_cm_s"]
            lines.append(f"- {v}, {who}: {causes or 'no failures'}"
                         + ("" if speed is None else f"; crossings at {speed:.2f} cm/s"))
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ the job
@holding_folders
def run_ablation(out: str | os.PathLike, config: AblationConfig | None = None,
                 processes: int | None = None, log: Callable[[str], None] = print,
                 executor: Executor | None = None) -> dict:
    """Walk (or resume) the ablation into ``out``; return the summary (also ablation.json/.md).

    The runs are walked on ``executor`` [default: a local pool of ``processes`` workers].
    """
    # Built here, not at import: a config's checks ask the registries, which load the
    # plugins (a broken plugin must fail as one line when the command runs, not on import).
    config = AblationConfig() if config is None else config
    out = Path(out)
    claim_folder(out, config.to_dict(), "an ablation", free=("variants", "who"))
    paths = board_files(out, {name: (spec, seed, True)
                              for name, (spec, seed, _, _) in config.boards().items()})
    maps = {n: HeightMap.load(p) for n, p in paths.items()}
    by_hash = {m.content_hash(): m for m in maps.values()}
    jobs = ablation_jobs(config, paths)
    with DemoStore(out / STORE_NAME, create=True) as store:
        Runner(store, by_hash, executor or LocalPool(processes), None, log).run(
            jobs, "ablation runs")
        results = _outcomes(store)
    missing = [j.key for j in jobs if j.key not in results]
    if missing:  # cannot happen unless the store was edited by hand
        raise FootfallError(f"{len(missing)} ablation runs are missing from the store")
    summary = summarise_ablation(config, results)
    write_text_atomic(out / "ablation.json", json.dumps(
        {"config": config.to_dict(), "variants": summary}, indent=1, sort_keys=True))
    write_text_atomic(out / "ablation.md", "# Walking controller ablation\n\n"
                      + ablation_markdown(config, summary))
    return summary
