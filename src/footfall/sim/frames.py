"""Pictures of a run: snapshots spread over it and a video, rendered from the simulator."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from footfall.sim.simulation import Simulation

SNAPSHOT_PERIOD = 0.5  # [s] of simulated time between candidate snapshot frames


@dataclass
class Frames:
    """Requests for pictures of a run: snapshot times and a video frame rate."""

    snapshot_count: int = 0  # frames evenly spaced over the run (0: none)
    video_fps: float = 0.0  # [1/s] video frame rate (0: no video)
    width: int = 480  # [px]
    height: int = 360  # [px]
    snapshots: list = field(default_factory=list)  # filled: (time [s], image (h, w, 3) uint8)
    video: list = field(default_factory=list)  # filled: images (h, w, 3) uint8


class FrameRecorder:
    """Renders the frames a :class:`Frames` asks for as a run goes (``frames`` None: none)."""

    def __init__(self, frames: Frames | None) -> None:
        self.frames = frames
        self._kept: list = []  # (time [s], image) every SNAPSHOT_PERIOD, to pick snapshots from

    def capture(self, sim: Simulation) -> None:
        """Render what is due at the simulation's time."""
        f = self.frames
        if f is None:
            return
        t = sim.time
        if f.video_fps > 0 and t + 1e-9 >= len(f.video) / f.video_fps:
            f.video.append(sim.render(width=f.width, height=f.height))
        if f.snapshot_count > 0 and t + 1e-9 >= len(self._kept) * SNAPSHOT_PERIOD:
            self._kept.append((t, sim.render(width=f.width, height=f.height)))

    def finish(self) -> None:
        """Pick the snapshots, evenly spread over the frames kept."""
        f = self.frames
        if f is None or f.snapshot_count <= 0 or not self._kept:
            return
        pick = np.unique(np.linspace(0, len(self._kept) - 1, f.snapshot_count).round().astype(int))
        f.snapshots = [self._kept[i] for i in pick]
