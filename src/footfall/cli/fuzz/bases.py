"""The valid files every mutation starts from, made once per fuzz session in a work directory.

A height map (a rocky module, and a copy at 4 mm, with the board metadata footfall writes),
a store of the synthetic expert's demonstrations on it and one run's log, a model learned
from the demonstrations, the scan formats a
user imports (``.npy``, 16-bit PNG, PLY, XYZ) and junk (an empty file, a text file).
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass
from pathlib import Path

import laspy
import numpy as np
from PIL import Image

from footfall.cli.entry import main
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.terrain.bags import write_grid_map
from footfall.terrain.geotiff import write_geotiff


@dataclass(frozen=True)
class Bases:
    """Paths of the valid files in the work directory ``root``."""

    root: Path
    map: Path  # a rocky module's height map (.npz)
    small_map: Path  # the same at 4 mm: cheap to load many times
    store: Path  # demonstrations on ``map`` and the log of one run (.sqlite)
    model: Path  # learned from ``store`` (.npz)
    flat: Path  # a short flat board (two modules, no flat ends): a quick walk
    scans: dict  # {".npy": path, ".png": ..., ".ply": ..., ".xyz": ..., ".mcap", ".db3",
    # ".las", ".laz", ".tif": the surveyed formats, each written by its own library}
    empty: Path
    text: Path

    def fill(self, template: str, suffix: str = "") -> str:
        """A path template of :mod:`.values` with this session's files put in."""
        return template.format(missing=self.root / "missing", dir=self.root, empty=self.empty,
                               text=self.text, map=self.small_map, model=self.model,
                               store=self.store, suffix=suffix)


def _cli(*argv: str) -> None:
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        if main([str(a) for a in argv]) != 0:
            raise FootfallError(f"fuzz: could not make a base file: footfall {' '.join(argv)}")


def make_bases(root: str | Path) -> Bases:
    """Make (or reuse) the base files in ``root``."""
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    paths = {name: root / name for name in ("map.npz", "small.npz", "store.sqlite", "model.npz",
                                            "flat.npz")}
    if not paths["map.npz"].exists():
        _cli("terrain", "make", "rocky", "--seed", "1", "-o", paths["map.npz"])
    full = HeightMap.load(paths["map.npz"])
    if not paths["small.npz"].exists():
        HeightMap(full.heights[::4, ::4], full.resolution * 4, full.origin, full.frame,
                  full.metadata).save(paths["small.npz"])
    if not paths["flat.npz"].exists():
        _cli("terrain", "board", "flat", "flat", "--no-flat-ends", "--seed", "0", "-o",
             paths["flat.npz"])
    if not paths["store.sqlite"].exists():
        _cli("demos", "collect", "--terrain", paths["map.npz"], "-n", "8", "--seed", "0",
             "-o", paths["store.sqlite"])  # and a short walk, so that it holds a run log too
        _cli("walk", "--terrain", paths["flat.npz"], "--seed", "0", "--log", paths["store.sqlite"])
    if not paths["model.npz"].exists():
        _cli("learn", paths["store.sqlite"], "--features", "both", "--cv", "2",
             "--library-size", "30", "-o", paths["model.npz"])
    grid = full.heights[::8, ::8]
    scans = {".npy": root / "scan.npy", ".png": root / "scan.png", ".ply": root / "scan.ply",
             ".xyz": root / "scan.xyz"}
    np.save(scans[".npy"], grid)
    Image.fromarray((grid / max(grid.max(), 1e-9) * 60000).astype(np.uint16)).save(scans[".png"])
    ii, jj = np.meshgrid(np.arange(grid.shape[0]), np.arange(grid.shape[1]), indexing="ij")
    points = np.column_stack([ii.ravel() * 0.008, jj.ravel() * 0.008, grid.ravel()])[::3]
    np.savetxt(scans[".xyz"], points, fmt="%.5f")
    header = ("ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n"
              "property float z\nend_header\n").format(len(points))
    scans[".ply"].write_text(header + "\n".join(" ".join(f"{v:.5f}" for v in p)
                                                for p in points) + "\n")
    scans.update(_survey_bases(root, grid, points))
    empty, text = root / "empty.npz", root / "notes.npz"
    empty.write_bytes(b"")
    text.write_text("these are not the heights you are looking for\n")
    return Bases(root, paths["map.npz"], paths["small.npz"], paths["store.sqlite"],
                 paths["model.npz"], paths["flat.npz"], scans, empty, text)


def _survey_bases(root: Path, grid: np.ndarray, points: np.ndarray) -> dict[str, Path]:
    """The grid as a ROS 2 bag of a GridMap (MCAP and SQLite 3, by rosbags' writer) and a
    GeoTIFF (by rasterio), and the points as LAS and LAZ (by laspy)."""
    hmap = HeightMap(grid, 0.008, (0.0, 0.0), "odom")
    out = {suffix: root / f"survey{suffix}" for suffix in (".mcap", ".db3", ".las", ".laz",
                                                           ".tif")}
    write_grid_map(out[".mcap"], {"elevation": grid, "variance": grid * 0}, hmap,
                   topic="/map", storage="mcap")
    write_grid_map(out[".db3"], {"elevation": grid}, hmap, topic="/map", storage="sqlite3")
    write_geotiff(out[".tif"], {"elevation": grid}, hmap)
    for suffix in (".las", ".laz"):
        header = laspy.LasHeader(point_format=6, version="1.4")
        header.scales = [1e-4] * 3
        las = laspy.LasData(header)
        las.x, las.y, las.z = points[:, 0], points[:, 1], points[:, 2]
        las.classification = np.where(np.arange(len(points)) % 4, 2, 5).astype(np.uint8)
        las.write(out[suffix])
    return out
