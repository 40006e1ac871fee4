"""The end of a run, drawn (``footfall walk --explain-plot``): the flight recorder's time series.

Five panels over the last seconds of the run, time measured back from its
end: the trunk's roll and pitch, how far each stance foot is from where it
was put down, the centre of mass's support margin, the vertical contact
force on each foot, and the number of joints of each leg at a limit. A
leg's swing shows as a gap in its lines.
"""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import numpy as np

from footfall.core.atomic import atomic_path
from footfall.core.robot import LEG_NAMES, RobotDescription
from footfall.sim.explain import (
    SLIP_MOVED,
    TILT_BEGUN,
    com_margin,
    explanation_lines,
    saturated_joints,
    stance_slips,
)
from footfall.sim.trace import TraceSeries

LEG_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red")


def save_explain_plot(trace: TraceSeries, explanation: dict | None, robot: RobotDescription,
                      path: str | os.PathLike, title: str = "") -> None:
    """Write the figure of a run's last seconds to ``path`` (.png)."""
    matplotlib.use("Agg")  # headless: pyplot picks its backend when it is imported
    import matplotlib.pyplot as plt

    t = trace.time - trace.time[-1]  # [s] before the end
    fig, axes = plt.subplots(5, 1, figsize=(8, 10), sharex=True)
    ax = axes[0]
    ax.plot(t, trace.body_rpy[:, 0], label="roll", color="k")
    ax.plot(t, trace.body_rpy[:, 1], label="pitch", color="tab:purple")
    for sign in (-1, 1):
        ax.axhline(sign * TILT_BEGUN, color="grey", lw=0.6, ls=":")
    ax.set_ylabel("trunk [rad]")
    ax.legend(loc="upper left", fontsize=8)
    slips = 1e3 * stance_slips(trace)
    stance_force = np.where(trace.stance, trace.forces[:, :, 2], np.nan)
    saturated = saturated_joints(trace, robot).sum(axis=2)
    for k, leg in enumerate(LEG_NAMES):
        axes[1].plot(t, slips[:, k], color=LEG_COLOURS[k], label=leg)
        axes[3].plot(t, stance_force[:, k], color=LEG_COLOURS[k], label=leg)
        axes[4].step(t, saturated[:, k] + 0.05 * k, color=LEG_COLOURS[k], where="post",
                     label=leg)
    axes[1].axhline(1e3 * SLIP_MOVED, color="grey", lw=0.6, ls=":")
    axes[1].set_ylabel("stance foot moved [mm]")
    axes[1].legend(loc="upper left", fontsize=8, ncol=4)
    axes[2].plot(t, 1e3 * com_margin(trace), color="k")
    axes[2].axhline(0.0, color="tab:red", lw=0.8)
    axes[2].set_ylabel("COM support margin [mm]")
    axes[3].set_ylabel("stance foot force z [N]")
    axes[4].set_ylabel("joints at a limit")
    axes[4].set_xlabel("time before the end of the run [s]")
    heading = title
    if explanation is not None:
        heading = (title + "\n" if title else "") + explanation_lines(explanation)[0]
    fig.suptitle(heading, fontsize=10)
    fig.tight_layout()
    with atomic_path(Path(path)) as tmp:
        fig.savefig(tmp, dpi=100, format="png")
    plt.close(fig)
