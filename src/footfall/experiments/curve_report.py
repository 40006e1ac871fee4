"""A learning curve's results read, compared and reported: ``footfall curve-compare`` and the
curve's ``report.md`` (the curve itself is measured by :mod:`footfall.experiments.learning_curve`).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.stats import bootstrap_ci, mcnemar_exact
from footfall.expert.corrections import DEFAULT_MARGIN, SEVERE_SHORTFALL

FORMAT = "footfall.learning-curve"
LINES = ("hand-tuned", "expert")  # the scorers measured once, as horizontal lines


PAIRED_KEYS = ("train_kinds", "train_difficulties", "test_difficulties", "test_decisions",
               "search_radius", "path_bias", "seed")  # settings two curves share when their points are
# paired (a setting a results file predates is its default, None)


def read_curve(out: Path) -> dict:
    """The results of the curve in folder ``out`` (its ``results.json``)."""
    path = out / "results.json"
    try:
        summary = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise FootfallError(f"{path}: not a learning curve's results ({exc})") from None
    if not isinstance(summary, dict) or summary.get("format") != FORMAT:
        raise FootfallError(f"{path}: not a learning curve's results")
    return summary


def compare_points(a: dict, b: dict, n: int, a_point: tuple[str, str],
                   b_point: tuple[str, str] | str, b_n: int | None = None) -> dict:
    """Paired comparison of two curve points: ``a_point`` (feature set, learner) of curve
    ``a`` at ``n`` demonstrations against ``b_point`` of curve ``b`` at ``b_n`` (default
    ``n``; ``b`` the same curve or another with the same boards, decisions and seed, whose
    draws learned from the same demonstrations). Every size is measured on the same held-out
    decisions, so two sizes pair too. ``b_point`` may name one of curve ``b``'s
    :data:`LINES` instead: each draw of ``a`` is paired with it decision by decision.

    Per draw both hold and pooled over them: the share of decisions above the margin, the
    decisions only one of the two got above it, and the exact McNemar p-value of the pooled
    draw-decision pairs; the mean shortfall [expert value units] of each and the mean of their
    paired differences (a less b) with its 95 % bootstrap interval over the draw-decisions.
    """
    for key in PAIRED_KEYS:
        if a["config"].get(key) != b["config"].get(key):
            raise FootfallError(f"the curves differ in {key}: their points are not paired")

    b_n = n if b_n is None else b_n
    if b_point == a_point and b_n == n and (a is b or a == b):
        raise FootfallError(f"the two points are one ({a_point[0]}/{a_point[1]} at {n} "
                            f"demonstrations of the same curve): compare another size, "
                            f"feature set, learner or line")

    def find(summary: dict, point: tuple[str, str], size: int) -> dict[int, np.ndarray]:
        found = {p["draw"]: np.asarray(p["losses"], dtype=float) for p in summary["points"]
                 if p["n"] == size and (p["feature_set"], p["learner"]) == point}
        if not found:
            raise FootfallError(f"no point {point[0]}/{point[1]} at {size} demonstrations")
        return found

    la = find(a, a_point, n)
    if isinstance(b_point, str):
        if b_point not in LINES or b_point not in b.get("lines", {}):
            raise FootfallError(f"no line {b_point!r}; the lines are {', '.join(LINES)}")
        lb = {d: np.asarray(b["lines"][b_point]["losses"], dtype=float) for d in la}
    else:
        lb = find(b, b_point, b_n)
    draws = sorted(set(la) & set(lb))
    if not draws:
        raise FootfallError("the two points share no draw")
    margin = float(a["points"][0]["margin"])
    loss_a = np.concatenate([la[d] for d in draws])
    loss_b = np.concatenate([lb[d] for d in draws])
    if loss_a.shape != loss_b.shape:
        raise FootfallError("the two points were measured on different held-out decisions")
    above_a, above_b = loss_a > margin, loss_b > margin
    a_only, b_only = int(np.sum(above_a & ~above_b)), int(np.sum(above_b & ~above_a))
    return {"n": n, "b_n": b_n, "draws": draws, "margin": margin,
            "a": {"point": list(a_point), "n": n, "above_margin": float(above_a.mean()),
                  "per_draw": [float(np.mean(la[d] > margin)) for d in draws],
                  "mean_shortfall": float(loss_a.mean())},
            "b": {"point": [b_point] if isinstance(b_point, str) else list(b_point),
                  "n": None if isinstance(b_point, str) else b_n, "above_margin": float(above_b.mean()),
                  "per_draw": [float(np.mean(lb[d] > margin)) for d in draws],
                  "mean_shortfall": float(loss_b.mean())},
            "a_only_above": a_only, "b_only_above": b_only,
            "p": mcnemar_exact(a_only, b_only),
            "shortfall_difference": float((loss_a - loss_b).mean()),
            "shortfall_difference_ci": list(bootstrap_ci(loss_a - loss_b))}


def curve_table(summary: dict) -> list[dict]:
    """One row per (feature set, learner, size): the mean and range over draws of the share
    above the margin, the severe share, the mean shortfall and top-1; templates kept per
    scale (front + hind, mean over draws)."""
    rows = []
    keys = sorted({(p["feature_set"], p["learner"], p["n"]) for p in summary["points"]},
                  key=lambda k: (k[0], k[1], k[2]))
    for fs, ln, n in keys:
        ps = [p for p in summary["points"]
              if (p["feature_set"], p["learner"], p["n"]) == (fs, ln, n)]
        share = np.array([p["above_margin"] for p in ps])
        kept = np.mean([np.add(p["templates_kept"]["front"], p["templates_kept"]["hind"])
                        for p in ps], axis=0)
        rows.append({"feature_set": fs, "learner": ln, "n": n, "draws": len(ps),
                     "above_margin": float(share.mean()), "above_margin_min": float(share.min()),
                     "above_margin_max": float(share.max()),
                     "severe": float(np.mean([p["severe"] for p in ps])),
                     "reward_loss": float(np.mean([p["reward_loss"] for p in ps])),
                     "top1": float(np.mean([p["top1"] for p in ps])),
                     "templates_kept": [round(float(k), 1) for k in kept]})
    return rows


def curve_report(summary: dict) -> str:
    """The curve as a markdown table, with the lines and the settings."""
    cfg = summary["config"]
    lines = summary["lines"]
    out = ["# footfall learning curve", "",
           f"{summary['test_decisions']} held-out decisions on test boards never trained on "
           f"(kinds {', '.join(cfg['train_kinds'])}, difficulties "
           f"{', '.join(map(str, cfg['test_difficulties']))}); {cfg['draws']} draws of training "
           f"boards and demonstrations per point; folds by {cfg['folds']}; template library "
           f"{cfg['library_size']} (" + (
               "at most: from {} demonstrations a random sample of their footholds"
               if cfg.get("library_capped") else "every demonstrated foothold a template: more "
               "from {} demonstrations").format(cfg["library_size"] // 3 + 1) + "); F: " + (
               "every reachable foothold" if cfg.get("search_radius") is None else
               f"the reachable footholds within {cfg['search_radius'] * 100:g} cm of the "
               f"gait-nominal foothold") + (
               "" if cfg.get("path_bias") is None else
               f"; every scorer ranked as the footstep planner picks: its values less a path "
               f"bias of {cfg['path_bias']:g} hand-tuned reward units per metre from the "
               f"gait-nominal foothold, scaled to its spread (the expert carries its own)")
           + ". Settings in `results.json`.", "",
           f"Above margin: the share of decisions whose expert shortfall is above "
           f"{DEFAULT_MARGIN:g} value unit (1 cm of progress); severe: above "
           f"{SEVERE_SHORTFALL:g}.", "",
           "| scorer | above margin | severe | mean shortfall | top-1 |",
           "| --- | --- | --- | --- | --- |"]
    for name in LINES:
        p = lines[name]
        out.append(f"| {name} | {p['above_margin']:.3f} | {p['severe']:.3f} | "
                   f"{p['reward_loss']:.2f} | {p['top1']:.3f} |")
    out += ["", "| feature set | learner | demonstrations | draws | above margin (min - max) | "
            "severe | mean shortfall | top-1 | templates kept (S, M, L; front + hind) |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in curve_table(summary):
        out.append(f"| {r['feature_set']} | {r['learner']} | {r['n']} | {r['draws']} | "
                   f"{r['above_margin']:.3f} ({r['above_margin_min']:.3f} - "
                   f"{r['above_margin_max']:.3f}) | {r['severe']:.3f} | "
                   f"{r['reward_loss']:.2f} | {r['top1']:.3f} | "
                   f"{', '.join(f'{k:g}' for k in r['templates_kept'])} |")
    if "seconds" in summary:
        out += ["", f"This invocation took {summary['seconds'] / 60:.0f} min (measured points "
                    f"are not measured again)."]
    return "\n".join(out) + "\n"
