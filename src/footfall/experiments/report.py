"""The reproduction's report: Markdown and one self-contained HTML page, with its figures.

Every number comes from the results of :func:`footfall.experiments.reproduce.run_reproduction`;
the page embeds its pictures, so it can be mailed or archived on its own.
"""

from __future__ import annotations

import base64
import html
import json
import re
import statistics
from pathlib import Path
from typing import Callable

import matplotlib
from matplotlib.figure import Figure

from footfall.core.atomic import atomic_path, write_text_atomic
from footfall.core.files import plain_json
from footfall.experiments.batch import reward_source, save_strip
from footfall.experiments.imitation import CAUSES, END_STEPS
from footfall.features.dense import score_grid
from footfall.plots.maps import save_kept_templates, save_score_maps
from footfall.plots.relief import save_relief
from footfall.sim.episode import Frames, walk

PAPER_TABLE2 = {"terrain": (47.6, 24.8, 5.9), "templates": (76.2, 20.2, 5.1),
                "both": (100.0, 17.3, 3.3), "flat": (100.0, 13.4, 0.4)}
TABLE2_ROWS = ("terrain", "templates", "both", "flat", "expert", "default")
METHODS = ("terrain", "templates", "both", "expert", "default")  # every test and sweep board's
# the paper's Table II: success [%], slip mean and std [mm]
PAPER_TABLE1 = {"both": (1, 19, 23), "templates": (10, 24, 28)}  # templates kept of 946
NAMES = {"terrain": "Features only", "templates": "Templates only",
         "both": "Templates + Features", "flat": "Baseline (flat terrain)",
         "expert": "Teacher choosing (reference)", "default": "Hand-tuned reward (reference)"}


def _figures(out: Path, results: dict, maps: dict, models: dict, config, log) -> list[tuple[str, str]]:
    """Draw the report's pictures; returns (file name, caption) pairs."""
    matplotlib.use("Agg")
    figs = []
    save_relief(maps["test0"], out / "test-board.png",
                title="the first test board (never trained on)")
    figs.append(("test-board.png", "The first test board: modules the robot never trained on."))
    grids = [score_grid(maps["test0"], models[fs].reward_for("LF")) for fs in models]
    save_score_maps(grids, [f"{NAMES[fs]}: learned reward, front legs (terrain part)"
                            for fs in models], ["reward"] * len(grids), out / "reward-maps.png")
    figs.append(("reward-maps.png", "Learned rewards over the test board (front legs; the "
                                    "terrain part, before pose features)."))
    for fs in ("templates", "both"):
        if fs in models and save_kept_templates(models[fs], out / f"templates-{fs}.png"):
            figs.append((f"templates-{fs}.png", f"{NAMES[fs]}: the kept templates with the "
                                                f"largest weights on the three scales (front legs)."))
    # Slip distributions of the successful runs.
    fig = Figure(figsize=(7, 3.2), layout="constrained")
    ax = fig.subplots()
    data = [(NAMES[k], v) for k, v in results["slips_mm"].items() if v]
    if data:
        ax.boxplot([v for _, v in data], showfliers=True)
        ax.set_xticks(range(1, len(data) + 1), [n for n, _ in data], fontsize=7, rotation=15,
                      ha="right")
    ax.set_ylabel("slip per foothold [mm]")
    ax.set_title("slip at every foothold of the successful runs")
    with atomic_path(out / "slip.png") as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    figs.append(("slip.png", "Slip per foothold over the successful runs (touch-down to the "
                             "next lift-off, as the paper)."))
    figs.append(_success_curves(out, results))
    strip = out / "crossing.png"
    if not strip.exists():
        log("snapshot strip of a crossing (offscreen rendering)")
        _strip(maps["test0"], out / "models" / "both.npz", config, strip, results["strip_seed"])
    figs.append(("crossing.png", "Templates + features on the test board: its first evaluation "
                                 "run that crossed, if any (as the paper's Fig. 4; the title "
                                 "says how it ended)."))
    return figs


def _success_curves(out: Path, results: dict) -> tuple[str, str]:
    """Every method's success against the sweep boards' difficulty, with Wilson intervals."""
    fig = Figure(figsize=(6.5, 3.4), layout="constrained")
    ax = fig.subplots()
    levels = sorted(results["sweep"], key=float)
    for i, k in enumerate(METHODS):
        xs = [float(d) + 0.006 * (i - 2) for d in levels]  # side by side, not on top
        rows = [results["sweep"][d][k] for d in levels]
        ys = [100 * r["success_rate"] for r in rows]
        err = [[max(0.0, 100 * (r["success_rate"] - r["success_ci"][0])) for r in rows],
               [max(0.0, 100 * (r["success_ci"][1] - r["success_rate"])) for r in rows]]
        ax.errorbar(xs, ys, yerr=err, fmt="o-" if k in PAPER_TABLE1 or k == "terrain" else "s--",
                    capsize=2, label=NAMES[k], lw=1)
    ax.axvline(results["test_difficulty"], color="grey", lw=0.8, ls=":")
    ax.set_xlabel("board difficulty (dotted: the test difficulty)")
    ax.set_ylabel("success [%]")
    ax.set_ylim(-5, 105)
    ax.legend(fontsize=7)
    with atomic_path(out / "success-difficulty.png") as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    runs = results["config"]["sweep_runs"]
    return ("success-difficulty.png", f"Success against difficulty, every method on one sweep "
            f"board per level ({runs} runs each, the same seeds), with 95 % Wilson intervals.")


def _strip(board, model_path: Path, config, path: Path, seed: int) -> None:
    """Snapshots of the evaluation run of templates + features with ``seed`` (replayed: seeded)."""
    frames = Frames(snapshot_count=6, width=360, height=270)
    record = walk(board, reward_source(model_path, board), seed, config.walk, frames=frames)
    r = record.result
    save_strip(frames.snapshots, path, title=f"templates + features, seed "
               f"{seed}: {'success' if r['success'] else r['reason']}")


def _pct(x: float) -> str:
    return f"{100 * x:.1f} %"


def _markdown(results: dict, figs: list[tuple[str, str]]) -> str:
    """The report in Markdown: one section after another, each ending with a blank line."""
    sections = (_intro(results), _demonstration_rounds(results), _table1(results),
                _calibration(results), _table2(results), _pooled(results), _per_board(results),
                _pairs(results), _sweep(results), _ranking(results), _verdict(results),
                _gap(results), _pictures(figs))
    return "\n".join(line for section in sections for line in section)


def _intro(results: dict) -> list[str]:
    c = results["config"]
    return ["# footfall: the paper's walking experiment, reproduced", "",
            "Kalakrishnan et al., *Learning Locomotion over Rough Terrain using Terrain "
            "Templates* (IROS 2009), §II-B and §V, on the simulated LittleDog. "
            f"Seed {c['seed']}; every setting in `config.json`, every number in `results.json`, "
            f"every run and demonstration in `reproduce.sqlite`.", ""] + _boards(results)


def _boards(results: dict) -> list[str]:
    """The boards and their seeds (drawn from the reproduction's named streams), to remake one."""
    boards = results.get("boards", {})
    if not boards:
        return []
    lines = ["| board | modules (kind difficulty) | seed (`footfall terrain board ... --seed`) |",
             "| --- | --- | --- |"]
    for name, b in boards.items():
        modules = ", ".join(f"{kind} {d:g}" for kind, d in b["modules"])
        lines.append(f"| {name} | {modules} | {b['seed']} |")
    return lines + [""]


def _demonstration_rounds(results: dict) -> list[str]:
    lines = ["## Demonstrations (the teacher's corrections of run logs)", "",
             "| round | robot's reward | crossings | corrections so far |",
             "| --- | --- | --- | --- |"]
    for r in results["rounds"]:
        lines.append(f"| {r['round']} | {r['reward']} | {r['successes']} / {r['runs']} | "
                     f"{r['demonstrations_total']} |")
    d = results["demonstrations"]
    return lines + ["", f"{d['n']} demonstrations, by module: " + ", ".join(
        f"{k} {v}" for k, v in d["by_module"].items()) + "; by leg: " + ", ".join(
        f"{k} {v}" for k, v in sorted(d["by_leg"].items())) + ".", ""]


def _table1(results: dict) -> list[str]:
    c = results["config"]
    how = ("L1, lambda at the smallest CV error" if c.get("learner", "l1") == "l1"
           and c["selection"] == "min" else f"learner {c.get('learner', 'l1')}, "
           f"{c['selection']} on its path, folds by {c.get('folds', 'demonstration')}")
    lines = [f"## Table I: templates kept per scale ({how})", "",
             "| features | legs | small | medium | large | paper (of 946) |",
             "| --- | --- | --- | --- | --- | --- |"]
    for fs, groups in results["table1"].items():
        for g, v in groups.items():
            paper = " / ".join(str(x) for x in PAPER_TABLE1[fs])
            lines.append(f"| {NAMES[fs]} | {g} | " + " | ".join(
                f"{k} / {n}" for k, n in zip(v["kept"], v["library"])) + f" | {paper} |")
    return lines + [""]


def _teacher(config: dict) -> str:
    """Which teacher a reproduction's config names (before there was a choice: the expert)."""
    return {"expert": "the synthetic expert", "guarded": "the hand-tuned reward, the expert "
            "vetoing severe footholds", "accepted": "the hand-tuned reward among the footholds "
            "the expert accepts"}.get(config.get("teacher", "expert"), config.get("teacher"))


def _calibration(results: dict) -> list[str]:
    c = results["calibration"]
    lines = ["## The test difficulty, by a rule", "",
             f"Rule: {c['rule']}. Test difficulty: **{c['difficulty']:g}**"
             + ("" if c["met"] else " (not met: the teacher missed the threshold even at the "
                                    "easiest level, which is used)") + ".", ""]
    if not c["levels"]:
        return lines
    cfg = results["config"]
    lines += [f"The teacher ({_teacher(cfg)}) on {cfg['calibration_boards']} calibration "
              f"board(s) per level "
              f"(boards of the test kinds with their own seeds, never trained or tested on), "
              f"{cfg['calibration_runs']} runs each (run seeds of each board's own):", "",
              "| difficulty | teacher crossed | 95 % CI (Wilson) | fitted (non-increasing) | "
              f"fit at least {c['threshold']:.0%} |", "| --- | --- | --- | --- | --- |"]
    for d, v in c["levels"].items():
        lines.append(f"| {d} | {v['successes']} / {v['runs']} | {_pct(v['success_ci'][0])} - "
                     f"{_pct(v['success_ci'][1])} | {_pct(v['fitted'])} | "
                     f"{'yes' if v['passes'] else 'no'} |")
    confirmations = c.get("confirmations") or {}
    if confirmations:
        per_board = cfg["calibration_runs"]
        lines += ["", f"The rule chose {c['selected']:g}. Its choice confirmed on fresh boards "
                      f"({-(-cfg['confirmation_runs'] // per_board)} boards a level, "
                      f"{per_board} runs each, never used to choose), hardest first:", "",
                  "| difficulty | teacher crossed | 95 % CI (Wilson) | "
                  f"interval reaches {c['threshold']:.0%} |", "| --- | --- | --- | --- |"]
        for d, v in confirmations.items():
            lines.append(f"| {d} | {v['successes']} / {v['runs']} | "
                         f"{_pct(v['success_ci'][0])} - {_pct(v['success_ci'][1])} | "
                         f"{'yes: the test difficulty' if v['confirmed'] else 'no'} |")
    held = c.get("held_on_test")
    if held:
        (k, n), (t, m), (lo, hi) = held["calibration"], held["test"], held["calibration_ci"]
        where = held.get("against", "calibration")  # results before the confirmation: none
        lines += ["", f"Did the calibration hold? The teacher crossed {t} / {m} "
                      f"({_pct(held['test_rate'])}) of its test-board runs against {k} / {n} on "
                      f"the {where} boards of that difficulty: "
                      + ("inside" if held["inside"] else "**outside**")
                      + f" their 95 % interval ({_pct(lo)} - {_pct(hi)}); Fisher's exact test "
                      f"p = {held['fisher_p']:.3g}."]
    return lines + [""]


def _row_cells(t: dict) -> str:
    slip = ("-" if t["slip_mean_mm"] is None
            else f"{t['slip_mean_mm']:.1f} +- {t['slip_std_mm']:.1f}")
    speed = "-" if t["speed_cm_s"] is None else f"{t['speed_cm_s']:.1f}"
    dist = "-" if t.get("distance_mean_m") is None else f"{t['distance_mean_m']:.2f}"
    return (f"{t['successes']} / {t['runs']} ({_pct(t['success_rate'])}) | "
            f"{_pct(t['success_ci'][0])} - {_pct(t['success_ci'][1])} | {slip} | "
            f"{t['slip_count']} | {speed} | {dist}")


def _table2(results: dict) -> list[str]:
    lines = ["## Table II: walking on the unseen test board test0 "
             f"(difficulty {results['test_difficulty']:g}): the paper's one-board table", "",
             "| method | success | 95 % CI (Wilson) | slip on successful runs [mm] | footholds | "
             "speed [cm/s] | distance walked [m] | paper: success, slip |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for k in (k for k in TABLE2_ROWS if k in results["table2"]):
        p = PAPER_TABLE2.get(k)
        paper = "-" if p is None else f"{p[0]:.1f} %, {p[1]:.1f} +- {p[2]:.1f}"
        lines.append(f"| {NAMES[k]} | {_row_cells(results['table2'][k])} | {paper} |")
    return lines + [
        "", "The references walk the same test boards with the same seeds: the teacher "
        f"({_teacher(results['config'])}) choosing every foothold itself bounds what a function "
        "learned from its corrections can do; the hand-tuned reward is the robot before any "
        "learning. The "
        "baseline is the templates + features function on the flat board. Distance walked: "
        "the mean over all runs of how far the robot got (a crossing walks the whole course).",
        "", "How runs ended: " + "; ".join(
            f"{NAMES[k]}: " + ", ".join(f"{r} {n}" for r, n in
                                        sorted(results["table2"][k]["reasons"].items()))
            for k in TABLE2_ROWS if k in results["table2"]) + ".", ""]


def _pooled(results: dict) -> list[str]:
    boards = list(results["table2_boards"])
    pooled = results["table2_pooled"]
    lines = [f"## Table II pooled over the {len(boards)} test boards ({', '.join(boards)})", "",
             "| method | success | 95 % CI (Wilson) | slip on successful runs [mm] | footholds | "
             "speed [cm/s] | distance walked [m] | distance of the failed runs [m] |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for k in (k for k in TABLE2_ROWS if k in pooled):
        t = pooled[k]
        failed = "-" if t["distance_failed_mean_m"] is None else f"{t['distance_failed_mean_m']:.2f}"
        lines.append(f"| {NAMES[k]} | {_row_cells(t)} | {failed} |")
    return lines + [""]


def _per_board(results: dict) -> list[str]:
    boards = results["table2_boards"]
    lines = ["### Success per test board", "",
             "| method | " + " | ".join(boards) + " |", "| --- |" + " --- |" * len(boards)]
    for k in METHODS:
        lines.append(f"| {NAMES[k]} | " + " | ".join(
            f"{b[k]['successes']} / {b[k]['runs']}" for b in boards.values()) + " |")
    return lines + [""]


def _pairs(results: dict) -> list[str]:
    lines = ["### Paired comparisons over every test board", "",
             "Each pair walked the same boards with the same run seeds. *A only* / *B only*: "
             "runs only A (only B) crossed; p: exact McNemar test (two-sided) on those; "
             "differences A - B with 95 % paired bootstrap intervals (runs resampled as pairs "
             "within each board); verdict on \"A above B\" at p < 0.05 (success) or an "
             "interval excluding 0 (slip: A slips less).", "",
             f"| A | B | {PAIR_COLUMNS} |", "|" + " --- |" * 12]
    for c in results["pairs"]:
        lines.append(f"| {NAMES[c['a']]} | {NAMES[c['b']]} | {pair_cells(c)} |")
    return lines + [""]


PAIR_COLUMNS = ("pairs | A only | B only | p (McNemar) | success A - B | 95 % CI | "
                "slip A - B [mm] | 95 % CI | success: A above B | slip: A below B")
# the columns of pair_cells


def pair_cells(c: dict) -> str:
    """A paired comparison (:func:`footfall.experiments.paired.compare`) as table cells."""
    lo, hi = c["success_difference_ci"]
    slo, shi = c["slip_difference_ci_mm"]
    slip = "-" if c["slip_difference_mm"] is None else f"{c['slip_difference_mm']:+.1f}"
    return (f"{c['pairs']} | {c['a_only']} | {c['b_only']} | {c['p_value']:.3g} | "
            f"{100 * c['success_difference']:+.1f} % | {100 * lo:+.1f} to {100 * hi:+.1f} % | "
            f"{slip} | {slo:+.1f} to {shi:+.1f} | {c['success_verdict']} | {c['slip_verdict']}")


def _sweep(results: dict) -> list[str]:
    levels = sorted(results["sweep"], key=float)
    if not levels:
        return []
    lines = ["### Success against difficulty (one sweep board per level)", "",
             "| difficulty | " + " | ".join(NAMES[k] for k in METHODS) + " |",
             "| --- |" + " --- |" * len(METHODS)]
    for d in levels:
        v = results["sweep"][d]
        lines.append(f"| {d} | " + " | ".join(f"{v[k]['successes']} / {v[k]['runs']}"
                                              for k in METHODS) + " |")
    return lines + [""]


def _ranking(results: dict) -> list[str]:
    lines = ["## Offline ranking on the teacher's demonstrations over the first test board", "",
             "Loss: the expert's value of its best candidate minus its value of the function's "
             "pick (1 unit = 1 cm off the gait-nominal foothold for the walking expert), 95 % "
             "bootstrap interval.", "",
             "| features | top-1 | within 1 cm | percentile | loss | loss 95 % CI |",
             "| --- | --- | --- | --- | --- | --- |"]
    for fs, a in results["ranking"].items():
        lo, hi = a["reward_loss_ci"]
        lines.append(f"| {NAMES[fs]} | {a['top1']:.3f} | {a['top1_near']:.3f} | "
                     f"{a['percentile']:.3f} | {a['reward_loss']:.2f} | {lo:.2f} to {hi:.2f} |")
    return lines + [""]


def _verdict(results: dict) -> list[str]:
    judged = {k: v for k, v in results.get("choices", {}).items() if v["steps"]}
    if not judged:
        return []
    c = results["config"]
    severe = next(iter(judged.values()))["severe_above"]
    lines = ["## The expert's verdict on the robot's choices in the test-board runs", "",
             "Shortfall: the expert's value of its best foothold in a step's candidate set "
             "minus its value of the robot's choice [value units], over every step of each "
             f"method's {c['eval_runs']} runs on each test board; corrected above "
             f"{c['margin']:g} (the "
             f"reproduction's margin), severe above {severe:g}.", "",
             "| method | steps | mean | median | 90th percentile | above the margin | severe |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for k, v in judged.items():
        lines.append(f"| {NAMES[k]} | {v['steps']} | {v['mean']:.2f} | {v['median']:.2f} | "
                     f"{v['p90']:.2f} | {_pct(v['above_margin'])} | {_pct(v['severe'])} |")
    return lines + [""]


def _gap(results: dict) -> list[str]:
    gap = results.get("imitation_gap")
    if not gap:
        return []
    lines = ["## The imitation gap: test runs a learned function failed and the teacher crossed",
             "", "Same board, same run seed. The teacher judges every step of the learned "
             "function's run; a foothold is *unacceptable* where the teacher refuses it or values "
             "it short of its best by more than the margin. *At the end*: the robot stood on one "
             f"in its last {END_STEPS} steps before failing (the last gait cycle); *earlier*: only "
             "before that; *accepted throughout*: never, a failure the teacher's choices could "
             "have met on its way. *Refused*: the first unacceptable foothold was refused "
             "outright. *Parted*: the median step at which its foothold first was not the "
             "teacher's choice.", "",
             "| method | paired runs | only it crossed | only the teacher crossed | imitation "
             "error at the end | earlier | accepted throughout | refused | parted at step "
             "(median) |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for fs, g in gap.items():
        parted = [r["parted"] for r in g["runs"] if r["parted"] is not None]
        by = g["by_cause"]
        lines.append(f"| {NAMES[fs]} | {g['pairs']} | {g['student_only']} | {g['teacher_only']} "
                     + "".join(f"| {by[c]} " for c in CAUSES) + f"| {g['refused']} | "
                     f"{format(statistics.median(parted), 'g') if parted else '-'} |")
    return lines + [""]


def _pictures(figs: list[tuple[str, str]]) -> list[str]:
    lines = ["## Pictures", ""]
    for name, caption in figs:
        lines += [f"![{caption}]({name})", "", f"*{caption}*", ""]
    return lines


def _inline(md: str) -> str:
    text = html.escape(md)
    text = re.sub(r"\*\*(.+?)\*\*", r"<b>\1</b>", text)
    text = re.sub(r"`(.+?)`", r"<code>\1</code>", text)
    return re.sub(r"\*(.+?)\*", r"<i>\1</i>", text)


def _html(md: str, out: Path) -> str:
    """The Markdown report as one HTML page with its pictures embedded (no external files)."""
    body, table = [], []

    def flush() -> None:
        if table:
            head, rows = table[0], table[2:]
            body.append("<table><tr>" + "".join(f"<th>{_inline(c)}</th>" for c in head)
                        + "</tr>" + "".join("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in r)
                                            + "</tr>" for r in rows) + "</table>")
            table.clear()

    for line in md.splitlines():
        if line.startswith("|"):
            table.append([c.strip() for c in line.strip().strip("|").split("|")])
            continue
        flush()
        m = re.match(r"!\[(.*)\]\((.*)\)", line)
        if m:
            data = base64.b64encode((out / m.group(2)).read_bytes()).decode()
            body.append(f'<img alt="{html.escape(m.group(1))}" src="data:image/png;base64,{data}">')
        elif line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            body.append(f"<h{level}>{_inline(line[level:].strip())}</h{level}>")
        elif line.strip():
            body.append(f"<p>{_inline(line)}</p>")
    flush()
    style = ("body{font-family:sans-serif;max-width:1000px;margin:2em auto;line-height:1.4}"
             "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;"
             "padding:3px 8px;font-size:90%}img{max-width:100%}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>footfall reproduction"
            f"</title><style>{style}</style></head><body>{''.join(body)}</body></html>")


def write_report(out: Path, results: dict, maps: dict, models: dict, config,
                 log: Callable[[str], None] = print) -> None:
    """Write results.json, report.md and report.html (pictures embedded) into ``out``."""
    figs = _figures(out, results, maps, models, config, log)
    md = _markdown(results, figs)
    write_text_atomic(out / "results.json", json.dumps(plain_json(results, nonfinite="keep"), indent=1))
    write_text_atomic(out / "report.md", md)
    write_text_atomic(out / "report.html", _html(md, out))

