"""Gallery of the LittleDog-like terrain modules: writes docs/modules.png.

Rows are module kinds, columns difficulties 0.2, 0.6 and 1.0; all panels
share one colour scale (0-100 mm) so heights compare across the grid.

Run: ``python examples/module_gallery.py [output.png]``
"""

from __future__ import annotations

import sys
from pathlib import Path

from matplotlib.figure import Figure

from footfall.core.atomic import atomic_path
from footfall.plots.relief import draw_relief
from footfall.terrain import KINDS, make_module

DIFFICULTIES = (0.2, 0.6, 1.0)  # [-] one column each
SEED = 7  # seed of every module in the gallery
HEIGHT_RANGE = (0.0, 0.10)  # [m] shared colour scale
PANEL_SIZE = 3.2  # [inch] side of one panel
DPI = 150  # [dots/inch]
OUTPUT = Path(__file__).resolve().parent.parent / "docs" / "modules.png"


def gallery_figure(seed: int = SEED) -> Figure:
    """Figure with one relief panel per (kind, difficulty), kinds as rows."""
    kinds = list(KINDS)
    fig = Figure(figsize=(PANEL_SIZE * len(DIFFICULTIES) + 1.2, PANEL_SIZE * len(kinds)),
                 layout="constrained")
    axes = fig.subplots(len(kinds), len(DIFFICULTIES), squeeze=False)
    for row, kind in enumerate(kinds):
        for col, difficulty in enumerate(DIFFICULTIES):
            ax = axes[row, col]
            draw_relief(ax, make_module(kind, difficulty, seed), vmin=HEIGHT_RANGE[0],
                        vmax=HEIGHT_RANGE[1], title=f"{kind}, difficulty {difficulty:.1f}",
                        colorbar=col == len(DIFFICULTIES) - 1)
            if row < len(kinds) - 1:
                ax.set_xlabel("")
            if col > 0:
                ax.set_ylabel("")
    fig.suptitle(f"footfall terrain modules (61 x 61 cm, 1 mm cells, seed {seed})")
    return fig


def main(output: Path = OUTPUT) -> None:
    """Render the gallery to ``output`` (PNG)."""
    output.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(output) as tmp:
        gallery_figure().savefig(tmp, format="png", dpi=DPI)
    print(f"wrote {output}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else OUTPUT)
