"""Learning curves: the share of held-out decisions above the correction margin, and the mean
shortfall of the picks, against the number of demonstrations."""

from __future__ import annotations

import os

from matplotlib.figure import Figure

from footfall.core.atomic import atomic_path

DPI = 110


def save_curve_figure(rows: list[dict], lines: dict, path: str | os.PathLike) -> None:
    """A column per feature set, a line per learner (mean over draws): above, the share above
    the margin (its range over the draws shaded); below, the mean expert shortfall of the
    picks [value units]; against demonstrations (log scale), with the hand-tuned reward and
    the expert (``lines``) as horizontal lines. ``rows``: :func:`~footfall.experiments.
    curve_report.curve_table`'s."""
    sets = list(dict.fromkeys(r["feature_set"] for r in rows)) or ["-"]
    sizes = sorted({r["n"] for r in rows})
    fig = Figure(figsize=(4.2 * len(sets), 6.4), layout="constrained")
    grid = fig.subplots(2, len(sets), sharey="row", sharex=True, squeeze=False)
    measures = (("above_margin", "share of held-out decisions\nabove the margin"),
                ("reward_loss", "mean shortfall of the pick\n[value units]"))
    for (key, label), axes in zip(measures, grid):
        for ax, fs in zip(axes, sets):
            for ln in dict.fromkeys(r["learner"] for r in rows if r["feature_set"] == fs):
                rs = [r for r in rows if (r["feature_set"], r["learner"]) == (fs, ln)]
                n = [r["n"] for r in rs]
                ax.plot(n, [r[key] for r in rs], marker="o", label=ln)
                if key == "above_margin":  # the range over the draws
                    ax.fill_between(n, [r["above_margin_min"] for r in rs],
                                    [r["above_margin_max"] for r in rs], alpha=0.15)
            ax.axhline(lines["hand-tuned"][key], color="k", ls="--", label="hand-tuned")
            ax.axhline(lines["expert"][key], color="0.5", ls=":", label="expert")
            ax.set_xscale("log")
            ax.set_xticks(sizes, [str(n) for n in sizes])
            ax.minorticks_off()
            ax.set_title(fs if key == "above_margin" else "")
        axes[0].set_ylabel(label)
    for ax in grid[-1]:
        ax.set_xlabel("demonstrations")
    grid[0][0].legend(fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI)


def save_student_curve_figure(summary: dict, path: str | os.PathLike) -> None:
    """The student's walking curve: each variant's share of runs crossed (pooled over the
    draws) against its labelled steps (mean over the draws), with the teacher choosing every
    foothold and the hand-tuned reward as horizontal lines. ``summary``: :func:`~footfall.
    experiments.student_curve.summarise`'s."""
    fig = Figure(figsize=(6.4, 4.2), layout="constrained")
    ax = fig.subplots()
    for variant, f in summary["variants"].items():
        rows = list(f["points"].values())
        labels = [sum(r["labels"]) / len(r["labels"]) for r in rows]
        ax.plot(labels, [r["successes"] / max(r["runs"], 1) for r in rows], marker="o",
                label=variant)
    for name, style in (("teacher", ("0.5", ":")), ("hand-tuned", ("k", "--"))):
        ref = summary["references"][name]
        ax.axhline(ref["successes"] / max(ref["runs"], 1), color=style[0], ls=style[1],
                   label=name)
    ax.set_xlabel("labelled steps (mean over the draws)")
    ax.set_ylabel("share of runs crossed")
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=7)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI)
