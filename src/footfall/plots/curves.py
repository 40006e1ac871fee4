"""Learning curves: the share of held-out decisions above the correction margin against the
number of demonstrations."""

from __future__ import annotations

import os

from matplotlib.figure import Figure

from footfall.core.atomic import atomic_path

DPI = 110


def save_curve_figure(rows: list[dict], lines: dict, path: str | os.PathLike) -> None:
    """A panel per feature set, a line per learner (mean over draws, the range shaded), the
    share above the margin against demonstrations (log scale); the hand-tuned reward and the
    expert (``lines``) as horizontal lines. ``rows``: :func:`~footfall.experiments.
    curve_report.curve_table`'s."""
    sets = list(dict.fromkeys(r["feature_set"] for r in rows)) or ["-"]
    fig = Figure(figsize=(4.2 * len(sets), 3.6), layout="constrained")
    axes = fig.subplots(1, len(sets), sharey=True, squeeze=False)[0]
    for ax, fs in zip(axes, sets):
        for ln in dict.fromkeys(r["learner"] for r in rows if r["feature_set"] == fs):
            rs = [r for r in rows if (r["feature_set"], r["learner"]) == (fs, ln)]
            n = [r["n"] for r in rs]
            ax.plot(n, [r["above_margin"] for r in rs], marker="o", label=ln)
            ax.fill_between(n, [r["above_margin_min"] for r in rs],
                            [r["above_margin_max"] for r in rs], alpha=0.15)
        ax.axhline(lines["hand-tuned"]["above_margin"], color="k", ls="--", label="hand-tuned")
        ax.axhline(lines["expert"]["above_margin"], color="0.5", ls=":", label="expert")
        ax.set_xscale("log")
        ax.set_title(fs)
        ax.set_xlabel("demonstrations")
    axes[0].set_ylabel("share of held-out decisions above the margin")
    axes[0].legend(fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI)
