"""Several whole reproductions, and what they say together: ``footfall study``.

One reproduction learns from one set of demonstrations and tests on one
draw of boards; another seed draws other training boards, other
corrections, another test difficulty's boards and other run seeds (every
seed from the reproduction's named streams, :mod:`footfall.core.seeds`: two
seeds share none). A study runs the reproduction for each seed into
``OUT/seedN`` -- each a complete reproduction folder that resumes on its
own, on whichever executor the runs use -- and summarises them:

* each seed's Table II pooled over its test boards, its one-board table's
  row for templates + features, and its Table I;
* the spread of each method's success rate and slip across the seeds;
* a verdict on each of the paper's orderings (templates + features above
  templates above terrain features, in success and in slip): the paired
  runs of every seed pooled (units resampled within each seed's board),
  "held", "reversed" or "not separated" at this sample size, with the
  statistic behind it (:mod:`footfall.experiments.paired`), and each seed's
  own verdict beside it.

The summary goes to ``summary.json`` and ``summary.md`` in ``OUT``.

A finished seed also leaves ``OUT/seedN/study-seed.json`` (:data:`SEED_FILE`):
its reproduction's results and every paired test run's outcome, with the
settings and the source revision that made them. A study reads a seed from
that file instead of walking it again, so the seeds of one study may be
walked on different machines, or at different times, and gathered by
copying each ``seedN/study-seed.json`` into one folder: only the same
settings are accepted, and the summary names each seed's revision.
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from dataclasses import asdict
from pathlib import Path
from typing import Callable

import numpy as np

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError
from footfall.core.files import plain_json
from footfall.core.folders import holding_folders
from footfall.data.store import DemoStore
from footfall.experiments.executors import Executor
from footfall.experiments.paired import RunOutcome, compare
from footfall.experiments.report import PAIR_COLUMNS, pair_cells
from footfall.experiments.reproduce import STORE_NAME, ReproduceConfig, run_reproduction
from footfall.experiments.runs import claim_folder
from footfall.experiments.unseen import METHODS, load_runs, test_outcomes
from footfall.experiments.workspace import evaluation_seeds

PAPER_ORDERINGS = (("both", "templates"), ("templates", "terrain"), ("both", "terrain"))
# the paper's Table II: the first of each pair crossed more often and slipped less
AGAINST_START = (("expert", "default"), ("both", "default"), ("templates", "default"))
# the teacher and the learned functions against the hand-tuned reward learning starts from
NAMES = {"terrain": "terrain features", "templates": "templates",
         "both": "templates + features", "expert": "teacher", "default": "hand-tuned"}


SEED_FILE = "study-seed.json"  # a finished seed's results and paired outcomes
SEED_FORMAT, SEED_VERSION = "footfall.study-seed", 1


def source_revision() -> str | None:
    """The git commit footfall's source is checked out at (with ``+changes`` if its tree has
    uncommitted changes), or None outside a git checkout."""
    here = Path(__file__).resolve().parent
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True,
                              text=True, timeout=10)
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               cwd=here, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    if head.returncode != 0:
        return None
    return head.stdout.strip() + ("+changes" if dirty.stdout.strip() else "")


def save_seed(folder: Path, seed: int, settings: dict, results: dict, outcomes: dict) -> None:
    """Write a finished seed's :data:`SEED_FILE` (atomically)."""
    record = {"format": SEED_FORMAT, "version": SEED_VERSION, "seed": seed,
              "settings": settings, "revision": source_revision(), "results": results,
              "outcomes": {m: [[unit[0], unit[1], asdict(o)] for unit, o in units.items()]
                           for m, units in outcomes.items()}}
    write_text_atomic(folder / SEED_FILE,
                      json.dumps(plain_json(record, nonfinite="keep"), indent=1))


def load_seed(folder: Path, seed: int, settings: dict) -> tuple[dict, dict, str | None] | None:
    """A finished seed's results, paired outcomes and revision from its :data:`SEED_FILE`;
    None without one. A file of other settings, another seed or format is refused."""
    path = folder / SEED_FILE
    if not path.exists():
        return None
    try:
        record = json.loads(path.read_text())
        if (record.get("format"), record.get("version")) != (SEED_FORMAT, SEED_VERSION):
            raise ValueError(f"not a {SEED_FORMAT} file of version {SEED_VERSION}")
        outcomes = {m: {(str(board), int(s)): RunOutcome(**o) for board, s, o in units}
                    for m, units in record["outcomes"].items()}
        results = record["results"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise FootfallError(f"{path}: unreadable ({exc}); remove it to walk the seed "
                            f"again") from None
    if record.get("seed") != seed or record.get("settings") != json.loads(json.dumps(settings)):
        raise FootfallError(f"{path} holds seed {record.get('seed')} of other settings; "
                            f"remove it or use another --out")
    return results, outcomes, record.get("revision")


def seed_folder(out: Path, seed: int) -> Path:
    """Where the study keeps the reproduction of ``seed``."""
    return out / f"seed{seed}"


@holding_folders
def run_study(out: str | os.PathLike, seeds: list[int], quick: bool = False,
              executor: Executor | None = None, processes: int | None = None,
              log: Callable[[str], None] = print,
              config_for: Callable[[int], ReproduceConfig] | None = None,
              on_run: Callable[[str], None] | None = None) -> dict:
    """Run (or resume) a reproduction per seed into ``out/seedN``; summarise them all.

    ``quick``: each reproduction's small version (:meth:`ReproduceConfig.quick`);
    ``config_for(seed)``: other settings (the same for every seed but the seed).
    ``on_run(key)`` is called after each run is stored.
    """
    seeds = list(seeds)
    if not seeds or len(set(seeds)) != len(seeds):
        raise FootfallError(f"a study needs distinct seeds, got {seeds}")
    config_for = config_for or (ReproduceConfig.quick if quick else
                                lambda seed: ReproduceConfig(seed=seed))
    out = Path(out)
    settings = {k: v for k, v in config_for(0).to_dict().items() if k != "seed"}
    claim_folder(out, {"study of": "reproduce", "settings": settings}, "a study")
    started = time.perf_counter()
    results, outcomes = {}, {m: {} for m in METHODS}
    revisions = {}
    for n, seed in enumerate(seeds):
        folder = seed_folder(out, seed)
        finished = load_seed(folder, seed, settings)
        if finished is not None:
            results[seed], mine, revisions[seed] = finished
            log(f"=== reproduction seed {seed} ({n + 1} of {len(seeds)}): finished, read from "
                f"{folder / SEED_FILE}")
        else:
            log(f"=== reproduction seed {seed} ({n + 1} of {len(seeds)})")
            results[seed] = run_reproduction(folder, config_for(seed), processes=processes,
                                             log=log, on_run=on_run, executor=executor)
            with DemoStore(folder / STORE_NAME) as store:
                runs = load_runs(store, "eval/test")
            mine = test_outcomes(runs, list(results[seed]["table2_boards"]),
                                 evaluation_seeds(config_for(seed)), tag=f"seed{seed}/")
            save_seed(folder, seed, settings, results[seed], mine)
            revisions[seed] = source_revision()
        for m, units in mine.items():
            outcomes[m].update(units)
    summary = summarise_study(results, outcomes)
    summary["revisions"] = {str(seed): rev for seed, rev in revisions.items()}
    summary["seconds_this_session"] = time.perf_counter() - started
    write_text_atomic(out / "summary.json",
                      json.dumps(plain_json(summary, nonfinite="keep"), indent=1))
    write_text_atomic(out / "summary.md", study_markdown(summary))
    return summary


def _held(held: dict | None) -> str:
    """A seed's calibration check in words: the teacher's test runs against the runs its test
    difficulty was calibrated (or confirmed) on."""
    if not held:
        return "-"
    (t, m), (k, n) = held["test"], held["calibration"]
    return (f"{t} / {m} against {k} / {n} ({held.get('against', 'calibration')}): "
            f"{'inside' if held['inside'] else 'outside'}, p = {held['fisher_p']:.2g}")


def summarise_study(results: dict[int, dict], outcomes: dict) -> dict:
    """The study's summary from each seed's reproduction results and every seed's paired test
    runs (method -> ("seedN/board", run seed) -> RunOutcome)."""
    per_seed = {}
    for seed, r in results.items():
        pairs = {(c["a"], c["b"]): c for c in r["pairs"]}
        per_seed[seed] = {
            "test_difficulty": r["test_difficulty"],
            "calibration_met": r["calibration"]["met"],
            "calibration_held": r["calibration"].get("held_on_test"),  # the teacher's test runs
            # against its confirmation's (or calibration's) interval; None: not calibrated
            "test_boards": len(r["table2_boards"]),
            "table2_pooled": {m: _brief(t) for m, t in r["table2_pooled"].items()},
            "table2_one_board": {m: _brief(t) for m, t in r["table2"].items()},
            "table1": r["table1"],
            "demonstrations": _per_group(r["demonstrations"]["by_leg"]),
            "verdicts": {f"{a}>{b}": {"success": pairs[a, b]["success_verdict"],
                                      "slip": pairs[a, b]["slip_verdict"],
                                      "p_value": pairs[a, b]["p_value"]}
                         for a, b in PAPER_ORDERINGS},
            "seconds_last_session": r.get("seconds_this_session")}
    spread = {}
    for m in (*METHODS, "flat"):
        rates = [per_seed[s]["table2_pooled"][m]["success_rate"] for s in per_seed]
        slips = [per_seed[s]["table2_pooled"][m]["slip_mean_mm"] for s in per_seed]
        slips = [x for x in slips if x is not None]
        spread[m] = {"success_rates": rates, "success_mean": float(np.mean(rates)),
                     "success_min": float(np.min(rates)), "success_max": float(np.max(rates)),
                     "slip_means_mm": slips,
                     "slip_mean_mm": float(np.mean(slips)) if slips else None}
    verdicts = [{"ordering": f"{NAMES[a]} above {NAMES[b]}",
                 **compare(outcomes, a, b, seed=0),
                 "per_seed": {s: per_seed[s]["verdicts"][f"{a}>{b}"] for s in per_seed}}
                for a, b in PAPER_ORDERINGS]
    against = [{"ordering": f"{NAMES[a]} above {NAMES[b]}", **compare(outcomes, a, b, seed=0)}
               for a, b in AGAINST_START]
    return {"seeds": list(results), "per_seed": per_seed, "spread": spread,
            "verdicts": verdicts, "against_start": against,
            "fewer_templates_than_demonstrations": {
                fs: all(sum(p["table1"][fs][g]["kept"]) < p["demonstrations"][g]
                        for p in per_seed.values() for g in ("front", "hind"))
                for fs in ("templates", "both")}}


def _per_group(by_leg: dict) -> dict:
    """Demonstrations per leg group from those per leg (LF, RF, LH, RH)."""
    return {"front": sum(n for leg, n in by_leg.items() if leg.endswith("F")),
            "hind": sum(n for leg, n in by_leg.items() if leg.endswith("H"))}


def _brief(t: dict) -> dict:
    return {k: t[k] for k in ("successes", "runs", "success_rate", "success_ci",
                              "slip_mean_mm", "distance_mean_m") if k in t}


def _to_separate(v: dict) -> str:
    n = v.get("pairs_to_separate")
    return ("none would (as many runs only one crossed either way)" if n is None
            else f"{n:.0f} (here {v['pairs']})")


def _pct(x: float) -> str:
    return f"{100 * x:.1f} %"


def study_markdown(summary: dict) -> str:
    """The summary as Markdown: verdicts first, then the spread, then each seed."""
    seeds = summary["seeds"]
    lines = ["# footfall study: the paper's walking experiment over several seeds", "",
             f"Reproduction seeds {', '.join(map(str, seeds))}: each with its own training "
             "boards, corrections, test difficulty and boards, and run seeds (`seedN/` holds "
             "each whole reproduction and its report).", "",
             "## Verdicts on the paper's orderings", "",
             "Every seed's paired test-board runs pooled. Success: exact McNemar test on the "
             "runs only one of the two crossed (held / reversed at p < 0.05). Slip (over the "
             "successful runs' footholds): 95 % paired bootstrap interval of the difference, "
             "resampled within each seed's board (held / reversed if it excludes 0).", "",
             f"| ordering | {PAIR_COLUMNS} | per seed (success / slip) |", "|" + " --- |" * 12]
    for v in summary["verdicts"]:
        per = "; ".join(f"{s}: {x['success']} / {x['slip']}" for s, x in v["per_seed"].items())
        lines.append(f"| {v['ordering']} | {pair_cells(v)} | {per} |")
    lines += ["", "Paired runs a success verdict would need (exact McNemar at p < 0.05 with "
              "power 0.8, were the runs only one of the two crossed as frequent as here; "
              "Connor 1987): " + "; ".join(
                  f"{v['ordering']} {_to_separate(v)}"
                  for v in summary["verdicts"] + summary.get("against_start", [])) + "."]
    lines += ["", "## Against the hand-tuned reward learning starts from", "",
              "The same pooled paired runs and tests.", "",
              f"| ordering | {PAIR_COLUMNS} |", "|" + " --- |" * 11]
    lines += [f"| {v['ordering']} | {pair_cells(v)} |" for v in summary.get("against_start", [])]
    lines += ["", "## Spread across the seeds (Table II pooled over each seed's test boards)",
              "", "| method | " + " | ".join(f"seed {s}" for s in seeds)
              + " | mean | min - max |", "| --- |" + " --- |" * (len(seeds) + 2)]
    for m, sp in summary["spread"].items():
        cells = []
        for s in seeds:
            t = summary["per_seed"][s]["table2_pooled"][m]
            slip = "-" if t["slip_mean_mm"] is None else f"{t['slip_mean_mm']:.1f} mm"
            cells.append(f"{t['successes']} / {t['runs']}, {slip}")
        lines.append(f"| {NAMES.get(m, 'flat baseline')} | " + " | ".join(cells)
                     + f" | {_pct(sp['success_mean'])} | {_pct(sp['success_min'])} - "
                     f"{_pct(sp['success_max'])} |")
    lines += ["", "## Each seed", "", "| seed | test difficulty | boards | one-board table: "
              "templates + features | demonstrations (front / hind) | Table I: templates kept "
              "(small, medium, large; front / hind), templates only | templates + features | "
              "the teacher on the test boards against its calibration |",
              "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for s in seeds:
        p = summary["per_seed"][s]
        one = p["table2_one_board"]["both"]
        t1 = {fs: " / ".join(",".join(map(str, g["kept"])) for g in p["table1"][fs].values())
              for fs in ("templates", "both")}
        met = "" if p["calibration_met"] else " (rule not met)"
        demos = p.get("demonstrations", {})
        lines.append(f"| {s} | {p['test_difficulty']:g}{met} | {p['test_boards']} | "
                     f"{one['successes']} / {one['runs']} | {demos.get('front', '?')} / "
                     f"{demos.get('hind', '?')} | {t1['templates']} | {t1['both']} | "
                     f"{_held(p.get('calibration_held'))} |")
    fewer = summary.get("fewer_templates_than_demonstrations")
    if fewer:
        lines += ["", "Fewer templates kept than demonstrations, every seed and leg group: "
                  + "; ".join(f"{NAMES[fs]} {'yes' if ok else 'no'}" for fs, ok in fewer.items())
                  + "."]
    revisions = summary.get("revisions")
    if revisions:
        lines += ["", "Source revision of each seed: " + "; ".join(
            f"seed {s}: {rev or 'unknown'}" for s, rev in revisions.items()) + "."]
    seconds = summary.get("seconds_this_session")
    if seconds is not None:
        lines += ["", f"This invocation took {seconds / 60:.0f} min (stored runs are not "
                      "walked again)."]
    return "\n".join(lines) + "\n"
