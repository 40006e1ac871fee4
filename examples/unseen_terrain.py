"""Two terrains of kinds footfall's generators never make, as height-map files.

* ``stones.npz``: stepping stones -- square blocks 30-50 mm tall and 50-70 mm
  wide on a 70 mm grid, with gaps of up to 20 mm down to the ground between them --
  stored at 2 mm, so a board resamples it to its 1 mm.
* ``washboard.npz``: a 14 mm (peak to peak) ripple across the direction of
  walking, 40 mm long, with 2 mm of roughness and a no-data hole 60 mm across
  (as a scan has where the sensor saw nothing), at 1 mm.

Both are 0.61 m square, like a LittleDog module. Put them on boards with
``footfall terrain board``; docs/robust-walking.md's "Terrain it has never seen" walks
these boards::

    python examples/unseen_terrain.py out/unseen
    footfall terrain board flat out/unseen/stones.npz flat --seed 1 -o out/unseen/board_stones.npz
    footfall terrain board out/unseen/washboard.npz rocky:0.5 --seed 2 -o out/unseen/board_wash.npz
    footfall terrain board barrier:0.7 logs:0.7 --seed 700 -o out/unseen/board_barlogs.npz
    footfall terrain board slope:0.7 rocky:0.6 --seed 701 -o out/unseen/board_sloperocky.npz

Run: ``python examples/unseen_terrain.py [OUTPUT_DIR]`` (default ``out/unseen``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter

from footfall.core.heightmap import HeightMap

SIDE = 0.61  # [m] module side
SEED = 3  # seed of both terrains


def stepping_stones(rng: np.random.Generator, resolution: float = 0.002) -> HeightMap:
    """Square blocks on a 70 mm grid [m]: 30-50 mm tall, 50-70 mm wide, ground at z = 0."""
    n = round(SIDE / resolution)
    centres = (np.arange(n) + 0.5) * resolution  # [m] cell centres, along x and along y alike
    pitch = 0.07  # [m]
    stone = np.floor(centres / pitch).astype(int)  # the stone's row (x) or column (y) per cell
    stones = int(np.ceil(SIDE / pitch))
    tall = rng.uniform(0.03, 0.05, (stones, stones))  # [m] each stone's height
    half = 0.5 * rng.uniform(0.05, 0.07, (stones, stones))  # [m] each stone's half width
    off = np.abs(centres - (stone + 0.5) * pitch)  # [m] from the stone's centre line
    half_here = half[np.ix_(stone, stone)]
    on = (off[:, None] <= half_here) & (off[None, :] <= half_here)
    heights = np.where(on, tall[np.ix_(stone, stone)], 0.0)
    return HeightMap(heights, resolution, (0.0, 0.0))


def washboard(rng: np.random.Generator, resolution: float = 0.001) -> HeightMap:
    """A ripple across x [m] with roughness and a no-data hole."""
    n = round(SIDE / resolution)
    x = (np.arange(n) + 0.5) * resolution  # [m]
    ripple = 0.007 * np.sin(2 * np.pi * x / 0.04)  # [m] 14 mm peak to peak, 40 mm long
    rough = gaussian_filter(rng.normal(size=(n, n)), 3)
    heights = ripple[:, None] + 0.002 * rough / rough.std()
    hole = np.hypot(x[:, None] - 0.3, x[None, :] - 0.2) < 0.03  # [m] 60 mm across, at (0.3, 0.2)
    heights[hole] = np.nan
    return HeightMap(heights, resolution, (0.0, 0.0))


def main(output: Path) -> None:
    output.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(SEED)
    stepping_stones(rng).save(output / "stones.npz")
    washboard(rng).save(output / "washboard.npz")
    print(f"wrote {output / 'stones.npz'} and {output / 'washboard.npz'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/unseen"))
