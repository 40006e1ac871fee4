"""Terrain suites (``footfall benchmark-terrain``): does walking carry over to terrain no one tuned on?

A suite walks the walking expert choosing every foothold and the hand-tuned
reward over boards of each of its kinds and reports, per kind and pooled,
success with a 95 % Wilson interval, the slip of the crossings, the failure
taxonomy (:mod:`footfall.sim.explain`'s cause of each failed run) and the
paired comparison of the two choosers (exact McNemar: the same boards and run
seeds).

**The rule.** footfall's parameters -- controller, rewards, expert -- are
chosen on the *training* kinds only (:data:`footfall.terrain.kinds.TRAINING_KINDS`:
the paper's but flat, and :mod:`footfall.terrain.added`;
the ``training`` suite). The ``held-out`` suite
(:data:`footfall.terrain.kinds.HELD_OUT_KINDS`, :mod:`footfall.terrain.heldout`)
is measured after a change and never tuned on: no parameter is chosen by
looking at its runs, and its numbers are reported as they come.

**Boards.** Per kind ``boards`` boards ``KIND:D KIND:D`` (two modules of the
kind, flat ground before and after), D = ``difficulty`` (0.7 by default: the
test difficulty the reproduction's calibration rule chose with the adopted
defaults, fixed before any run of the suite), board seeds from the suite's
stream "boards" at (kind's place in :data:`SUITES`, board), so a kind's boards
do not depend on which other kinds are walked. Run seeds: the stream
"evaluation runs", the same on every board and for both choosers.

A suite may also walk learned functions as choosers (``models``: a name and a model file
each; runs keyed ``model:NAME/...``), each paired with the hand-tuned reward like the expert;
a folder keeps the model file each name stood for, and refuses another under the same name.

A suite walks the default controller or one of its variants
(:mod:`footfall.experiments.variants`: ``--variant with-friction-check``), so
that a change is measured on the held-out kinds after the ablation judged it.

Runs are stored under ``WHO/KIND/bB/sSEED`` in ``suite.sqlite`` as they arrive;
a rerun walks only what is missing; other kinds or choosers in the same folder
add their runs; other boards, runs, difficulty or walking settings are refused.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError
from footfall.core.files import distinct_inputs
from footfall.core.folders import holding_folders
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, at_least, param, within
from footfall.core.seeds import SeedStreams
from footfall.core.stats import mcnemar_exact
from footfall.data.store import DemoStore
from footfall.experiments.batch import summarise
from footfall.experiments.executors import Executor, LocalPool
from footfall.experiments.reproduce import reproduction_walk
from footfall.experiments.runs import RunJob, Runner, board_files, claim_folder
from footfall.experiments.variants import VARIANTS
from footfall.expert.synthetic import walking_expert
from footfall.learning.model import FootholdModel
from footfall.sim.episode import WalkConfig
from footfall.terrain.kinds import HELD_OUT_KINDS, TRAINING_KINDS

SUITES = {"held-out": HELD_OUT_KINDS, "training": TRAINING_KINDS}
"""The suites by name: their kinds, in order (a kind's place fixes its board seeds)."""
WHO = ("expert", "hand", "teacher")  # the walking expert choosing every foothold; the hand-tuned
# reward; the reproduction's teacher choosing every foothold (the `accepted` one)
SUITE_TEACHER = "accepted"  # the teacher a "teacher" chooser is
MODEL_PREFIX = "model:"  # a learned function as a chooser: "model:NAME"
STORE_NAME = "suite.sqlite"
MODELS_NAME = "models.json"  # a suite folder's model choosers: name -> the file's sha256


def _choosers_ok(who: object, models: object) -> bool:
    names = {m[0] for m in models} if isinstance(models, tuple) else set()
    return (isinstance(who, tuple) and len(who) > 0 and len(set(who)) == len(who)
            and all(w in WHO or (isinstance(w, str) and w.startswith(MODEL_PREFIX)
                                 and w[len(MODEL_PREFIX):] in names) for w in who))


def _models_ok(models: object) -> bool:
    return isinstance(models, tuple) and all(
        isinstance(m, tuple) and len(m) == 2 and all(isinstance(x, str) and x for x in m)
        and "/" not in m[0] for m in models) and len({m[0] for m in models}) == len(models)


@dataclass(frozen=True)
class SuiteConfig(Params):
    """A terrain suite's boards, runs and choosers; written next to its results."""

    suite: str = param("held-out", choices=tuple(SUITES), doc="which kinds: the held-out "
                       "ones (never tuned on) or the training ones")
    kinds: tuple[str, ...] | None = param(
        None, check=lambda v: v is None or (isinstance(v, tuple) and len(v) > 0
                                            and len(set(v)) == len(v)),
        must="a tuple of distinct kinds of the suite",
        doc="the suite's kinds walked; None: all of them")
    who: tuple[str, ...] = param(("expert", "hand"), check=lambda v: isinstance(v, tuple)
                                 and len(v) > 0 and len(set(v)) == len(v),
                                 must="a tuple of distinct choosers: 'expert', 'hand', "
                                      "'teacher' or 'model:NAME' of a model in models",
                                 doc="who chooses the footholds")
    models: tuple[tuple[str, str], ...] = param(
        (), check=_models_ok, must="a tuple of distinct (name, model file) pairs, a name "
                                   "without '/'",
        doc="learned functions walked as choosers 'model:NAME' (name, model file .npz)")
    difficulty: float = param(0.7, unit="-", range=within(0, 1),
                              doc="difficulty D of every board KIND:D KIND:D")
    boards: int = param(2, range=at_least(1), doc="boards per kind")
    first_board: int = param(0, range=at_least(0),
                             doc="the first board walked (from 0): boards first_board .. "
                                 "boards - 1, so that boards no run has touched can be walked "
                                 "without the earlier ones (each board is the same whatever "
                                 "else is walked)")
    runs: int = param(8, range=at_least(1), doc="runs on each board (the same seeds on each)")
    seed: int = param(0, range=at_least(0), doc="the suite's seed: boards and runs")
    walk: WalkConfig = param(factory=reproduction_walk,
                             doc="the walk: the reproduction's (F within its search radius)")
    variant: str = param("defaults", check=lambda v: v in VARIANTS,
                         must="a controller variant (footfall ablation --help lists them)",
                         doc="the controller variant walked: the walk with its one change "
                             "(footfall.experiments.variants)")

    def __post_init__(self) -> None:
        super().__post_init__()
        if not _choosers_ok(self.who, self.models):
            raise FootfallError(f"who must name 'expert', 'hand', 'teacher' or 'model:NAME' of a model "
                                f"given (models: {', '.join(m[0] for m in self.models) or 'none'})"
                                f", got {self.who!r}")
        unknown = sorted(set(self.kinds or ()) - set(SUITES[self.suite]))
        if unknown:
            raise FootfallError(f"the {self.suite} suite has no kind {', '.join(unknown)}; its "
                                f"kinds are {', '.join(SUITES[self.suite])}")
        if self.first_board >= self.boards:
            raise FootfallError(f"the first board ({self.first_board}, from 0) must be below "
                                f"the number of boards ({self.boards})")

    @classmethod
    def quick(cls, suite: str = "held-out") -> SuiteConfig:
        """A small version for a smoke test: one board and two runs a kind, the hand-tuned
        reward only."""
        return cls(suite=suite, who=("hand",), boards=1, runs=2)

    def walked_kinds(self) -> tuple[str, ...]:
        """The kinds walked, in the suite's order."""
        return tuple(k for k in SUITES[self.suite] if self.kinds is None or k in self.kinds)

    def board_specs(self) -> dict[str, tuple[tuple, int, bool]]:
        """Board name ``KIND-bB`` -> (modules, board seed, flat ends) of every walked board."""
        streams = SeedStreams("terrain suite", self.seed)
        d = float(self.difficulty)
        return {f"{kind}-b{b}": (((kind, d), (kind, d)),
                                 streams.seed_for("boards", SUITES[self.suite].index(kind), b),
                                 True)
                for kind in self.walked_kinds() for b in range(self.first_board, self.boards)}

    def walked(self) -> WalkConfig:
        """The walk of every run: ``walk`` with the variant's change."""
        return VARIANTS.get(self.variant).change(self.walk)

    def run_seeds(self) -> list[int]:
        """The run seeds of every board."""
        return SeedStreams("terrain suite", self.seed).seeds("evaluation runs", self.runs)


def suite_jobs(config: SuiteConfig, paths: dict[str, Path]) -> list[RunJob]:
    """Every run, keyed ``WHO/KIND/bB/sSEED``: the hand-tuned reward's first (cheaper)."""
    expert = VARIANTS.get(config.variant).expert(walking_expert(config.walk.footstep.lead))
    files = dict(config.models)
    jobs = []
    for who in sorted(config.who, key=lambda w: w == "expert"):
        model = files[who[len(MODEL_PREFIX):]] if who.startswith(MODEL_PREFIX) else None
        for name, path in paths.items():
            kind, board = name.rsplit("-", 1)
            jobs += [RunJob(f"{who}/{kind}/{board}/s{s}", str(path), model, s, config.walked(),
                            expert=expert, judge=who in ("expert", "teacher"),
                            teacher=SUITE_TEACHER if who == "teacher" else "expert")
                     for s in config.run_seeds()]
    return jobs


def claim_models(out: Path, models: tuple[tuple[str, str], ...]) -> None:
    """Keep in ``out`` the model file each chooser name stands for (its sha256), refusing a
    name that stood for another file: its stored runs are that file's."""
    path = out / MODELS_NAME
    held = json.loads(path.read_text()) if path.exists() else {}
    for name, file in models:
        digest = _file_digest(file)
        if held.get(name, digest) != digest:
            raise FootfallError(f"{out} holds runs of another model named {name!r}; use another "
                                f"name or --out")
        held[name] = digest
    if models:
        write_text_atomic(path, json.dumps(held, indent=1, sort_keys=True))


def _file_digest(file: str) -> str:
    try:
        return hashlib.sha256(Path(file).read_bytes()).hexdigest()
    except OSError as exc:
        raise FootfallError(f"{file}: cannot read the model ({exc.strerror})") from None


@holding_folders
def run_suite(out: str | Path, config: SuiteConfig | None = None,
              processes: int | None = None, log: Callable[[str], None] = print,
              executor: Executor | None = None) -> dict:
    """Walk (or resume) the suite into ``out``; return the summary (also suite.json, suite.md)."""
    config = SuiteConfig() if config is None else config
    out = Path(out)
    distinct_inputs([file for _, file in config.models], "model")  # one file, two choosers
    claim_folder(out, config.to_dict(), "a terrain suite", free=("kinds", "who", "models"))
    for _, file in config.models:  # a bad model file: one line before anything is walked
        FootholdModel.load(file)
    claim_models(out, config.models)
    paths = board_files(out, config.board_specs())
    maps = {name: HeightMap.load(p) for name, p in paths.items()}
    jobs = suite_jobs(config, paths)
    with DemoStore(out / STORE_NAME, create=True) as store:
        Runner(store, {m.content_hash(): m for m in maps.values()},
               executor or LocalPool(processes), None, log).run(jobs, f"{config.suite} suite")
        wanted = {j.key for j in jobs}
        records = {r["key"]: store.run(r["id"]) for r in store.runs() if r["key"] in wanted}
    if len(records) != len(wanted):  # cannot happen unless the store was edited by hand
        raise FootfallError(f"{len(wanted) - len(records)} suite runs are missing from the store")
    summary = summarise_suite(config, records)
    write_text_atomic(out / "suite.json", json.dumps(summary, indent=1, sort_keys=True))
    write_text_atomic(out / "suite.md", suite_markdown(summary))
    return summary


def _paired(records: dict, kinds: tuple[str, ...], who: str = "expert") -> dict:
    """A chooser (the expert) against the hand-tuned reward on the units both walked, over
    ``kinds``."""
    outcome = {tuple(k.split("/")): bool(r.result["success"]) for k, r in records.items()}
    units = {u[1:] for u in outcome if u[0] == who and u[1] in kinds} & \
        {u[1:] for u in outcome if u[0] == "hand" and u[1] in kinds}
    a = sum(outcome[(who, *u)] and not outcome[("hand", *u)] for u in units)
    b = sum(outcome[("hand", *u)] and not outcome[(who, *u)] for u in units)
    return {"pairs": len(units), f"{'expert' if who == 'expert' else 'chooser'}_only": a,
            "hand_only": b, "p_value": mcnemar_exact(a, b)}


def summarise_suite(config: SuiteConfig, records: dict) -> dict:
    """Per kind and chooser, and pooled over the kinds: Table II's measures and the causes of
    the failures (:func:`footfall.experiments.batch.summarise`); the choosers paired."""
    kinds = config.walked_kinds()

    def of(who: str, among: tuple[str, ...]) -> dict:
        return summarise([r for k, r in sorted(records.items())
                          if k.split("/")[0] == who and k.split("/")[1] in among]).as_dict()

    rows = {kind: {who: of(who, (kind,)) for who in config.who} for kind in kinds}
    pooled = {who: of(who, kinds) for who in config.who}
    paired = {}
    if {"expert", "hand"} <= set(config.who):
        paired = {kind: _paired(records, (kind,)) for kind in kinds}
        paired["all"] = _paired(records, kinds)
    models = {}
    if "hand" in config.who:  # each learned function and the teacher against the hand-tuned
        models = {w: {**{kind: _paired(records, (kind,), w) for kind in kinds},  # reward
                      "all": _paired(records, kinds, w)}
                  for w in config.who if w.startswith(MODEL_PREFIX) or w == "teacher"}
    return {"config": config.to_dict(), "kinds": rows, "pooled": pooled, "paired": paired,
            **({"paired_models": models} if models else {})}


def _cell(s: dict) -> str:
    lo, hi = s["success_ci"]
    slip = "-" if s["slip_mean_mm"] is None else f"{s['slip_mean_mm']:.1f}"
    return f"{s['successes']} / {s['runs']} ({100 * lo:.0f}-{100 * hi:.0f} %) | {slip}"


def _causes(s: dict) -> str:
    failed = s["runs"] - s["successes"]
    named = sorted(s["causes"].items(), key=lambda x: (-x[1], x[0]))
    text = ", ".join(f"{n} {c}" for c, n in named)
    other = failed - sum(s["causes"].values())
    return (text + (f", {other} unexplained" if other else "")) or "-"


def paired_runs(these: dict[str, bool], those: dict[str, bool], who: str,
                kinds: tuple[str, ...]) -> dict:
    """Two walks of the same suite runs paired (run key -> crossed, keys ``WHO/KIND/bB/sSEED``):
    on the runs of ``who`` over ``kinds`` that both walked, the crossings of each, the runs only
    these crossed and only those, and the exact McNemar p."""
    keys = sorted(k for k in these.keys() & those.keys()
                  if k.split("/")[0] == who and k.split("/")[1] in kinds)
    won = sum(these[k] and not those[k] for k in keys)
    lost = sum(those[k] and not these[k] for k in keys)
    return {"runs": len(keys), "these": sum(these[k] for k in keys),
            "those": sum(those[k] for k in keys), "won": won, "lost": lost,
            "p_value": mcnemar_exact(won, lost)}


def compare_suites(these: dict[str, bool], those: dict[str, bool], kinds: tuple[str, ...],
                   who: tuple[str, ...]) -> dict:
    """:func:`paired_runs` per kind and pooled, for every chooser."""
    return {w: {**{k: paired_runs(these, those, w, (k,)) for k in kinds},
                "all": paired_runs(these, those, w, kinds)} for w in who}


def suite_outcomes(folder: str | Path) -> dict[str, bool]:
    """Run key -> crossed, of every run in a suite folder's store.

    Raises
    ------
    FootfallError
        If the folder holds no suite store.
    """
    path = Path(folder) / STORE_NAME
    if not path.is_file():
        raise FootfallError(f"{folder}: not a terrain suite's folder (no {STORE_NAME})")
    with DemoStore(path) as store:
        return {r["key"]: bool(r["result"]["success"]) for r in store.runs()}


def comparison_markdown(comparison: dict, label: str) -> str:
    """The paired comparison as a table: per kind and chooser, crossings of each walk, won / lost
    and p."""
    names = {"expert": "expert", "hand": "hand-tuned"}
    who = list(comparison)
    head = ["kind"] + [f"{names.get(w, w.removeprefix(MODEL_PREFIX))}: this / {label}, won / "
                       f"lost (p)" for w in who]
    lines = [f"Paired with {label} (the same boards and run seeds; exact McNemar):", "",
             "| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for kind in comparison[who[0]]:
        cells = [f"**{kind}**" if kind == "all" else kind]
        for w in who:
            c = comparison[w][kind]
            cells.append(f"{c['these']} / {c['those']} of {c['runs']}, +{c['won']} / -{c['lost']}"
                         f" ({c['p_value']:.2g})")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def suite_markdown(summary: dict) -> str:
    """The suite's table (crossings with Wilson intervals, slip, causes) and the paired test."""
    c = summary["config"]
    names = {"expert": "expert", "hand": "hand-tuned", "teacher": "the teacher",
             **{f"{MODEL_PREFIX}{m[0]}": m[0] for m in c.get("models", [])}}
    head = ["kind"] + [f"{names[w]}: {what}" for w in c["who"]
                       for what in ("crossed (95 %)", "slip of crossings [mm]", "failures")]
    variant = c.get("variant", "defaults")
    title = f"# The {c['suite']} terrain suite" + (
        "" if variant == "defaults" else f", {variant}: {VARIANTS.get(variant).description}")
    lines = [title, "",
             f"Boards KIND:{c['difficulty']:g} KIND:{c['difficulty']:g}, {c['boards']} per kind, "
             f"{c['runs']} runs each (the same seeds for every board and chooser); F within "
             f"{c['walk']['footstep']['search_radius'] * 100:g} cm.", "",
             "| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for kind, row in [*summary["kinds"].items(), ("all", summary["pooled"])]:
        cells = [f"**{kind}**" if kind == "all" else kind]
        cells += [f"{_cell(row[w])} | {_causes(row[w])}" for w in c["who"]]
        lines.append("| " + " | ".join(cells) + " |")
    if summary["paired"]:
        lines += ["", "Paired, the expert against the hand-tuned reward (exact McNemar):", ""]
        lines += [f"- {kind}: only the expert crossed {p['expert_only']}, only the hand-tuned "
                  f"reward {p['hand_only']} of {p['pairs']}, p = {p['p_value']:.3g}"
                  for kind, p in summary["paired"].items()]
    for who, by_kind in summary.get("paired_models", {}).items():
        lines += ["", f"Paired, {names[who]} against the hand-tuned reward (exact McNemar):", ""]
        lines += [f"- {kind}: only {names[who]} crossed {p['chooser_only']}, only the "
                  f"hand-tuned reward {p['hand_only']} of {p['pairs']}, p = {p['p_value']:.3g}"
                  for kind, p in by_kind.items()]
    return "\n".join(lines) + "\n"
