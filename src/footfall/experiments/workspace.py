"""What the stages of the reproduction share: its boards, its seed streams and its folder.

The reproduction (:mod:`footfall.experiments.reproduce`) and its stage on
unseen terrain (:mod:`footfall.experiments.unseen`) both work in a
:class:`Workspace`: the report folder with its settings and board files, and
the named seed streams (:class:`footfall.core.seeds.SeedStreams`) every board,
run, inspection, demonstration and learner seed is drawn from. Every stage's
seeds are listed here, so that :func:`planned_seeds` names them all up front.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from footfall.core.heightmap import HeightMap
from footfall.core.seeds import SeedStreams
from footfall.experiments.runs import board_files, claim_folder

if TYPE_CHECKING:  # the settings' module runs the stages, which work in a Workspace
    from footfall.experiments.reproduce import ReproduceConfig

Spec = tuple[tuple[str, float], ...]  # a board: (kind, difficulty) of each module
ROBOT_FEATURE_SET = "both"  # the function the robot walks with between correction rounds (and
# on the flat board, the slip baseline)


def seed_streams(config: ReproduceConfig) -> SeedStreams:
    """The reproduction's named seed streams (boards, runs, inspection, demonstrations, learning)."""
    return SeedStreams("reproduce", config.seed)


def boards(config: ReproduceConfig) -> dict[str, tuple[Spec, int]]:
    """The boards known before any run: name -> (spec, board seed), from the "boards" stream.

    Training boards, the flat board, one sweep board per grid difficulty and
    ``calibration_boards`` per grid difficulty; the test boards' difficulty is
    known only after the calibration (:func:`test_boards`).
    """
    streams = seed_streams(config)
    out = {f"train{i:02d}": (spec, streams.seed_for("boards", 0, i))
           for i, spec in enumerate(config.train_boards)}
    out["flat"] = ((("flat", 0.0),) * 3, streams.seed_for("boards", 2))
    for j, d in enumerate(config.difficulties):
        out[f"sweep{d:g}"] = (_kinds_at(config, d), streams.seed_for("boards", 3, j))
        out.update(calibration_boards(config, j, range(config.calibration_boards)))
    return out


def calibration_boards(config: ReproduceConfig, level: int, which: range
                       ) -> dict[str, tuple[Spec, int]]:
    """Calibration boards ``which`` of grid level ``level``: ``cal<d>-<i>`` -> (spec, seed)."""
    d = config.difficulties[level]
    streams = seed_streams(config)
    return {f"cal{d:g}-{i}": (_kinds_at(config, d), streams.seed_for("boards", 4, level, i))
            for i in which}


def most_calibration_boards(config: ReproduceConfig) -> int:
    """The most calibration boards a grid level may get: enough for ``calibration_level_runs``."""
    return max(config.calibration_boards,
               -(-config.calibration_level_runs // config.calibration_runs))


def confirmation_boards(config: ReproduceConfig, level: int, which: range
                        ) -> dict[str, tuple[Spec, int]]:
    """Confirmation boards ``which`` of grid level ``level`` (fresh boards that confirm the
    rule's choice, :mod:`footfall.experiments.difficulty`): ``confirm<d>-<i>`` -> (spec, seed)."""
    d = config.difficulties[level]
    streams = seed_streams(config)
    return {f"confirm{d:g}-{i}": (_kinds_at(config, d), streams.seed_for("boards", 5, level, i))
            for i in which}


def confirmation_board_count(config: ReproduceConfig) -> int:
    """Fresh boards a confirmed level gets: ``confirmation_runs``, ``calibration_runs`` each."""
    return -(-config.confirmation_runs // config.calibration_runs)


def confirmation_seeds(config: ReproduceConfig, level: int, board: int) -> list[int]:
    """The teacher's run seeds on confirmation board ``board`` of grid level ``level``."""
    return seed_streams(config).seeds("confirmation runs", config.calibration_runs, level, board)


def test_boards(config: ReproduceConfig, difficulty: float) -> dict[str, tuple[Spec, int]]:
    """The unseen test boards at ``difficulty``: test0, test1, ... (fresh seeds)."""
    streams = seed_streams(config)
    return {f"test{b}": (_kinds_at(config, difficulty), streams.seed_for("boards", 1, b))
            for b in range(config.test_boards)}


def _kinds_at(config: ReproduceConfig, difficulty: float) -> Spec:
    return tuple((kind, float(difficulty)) for kind in config.test_kinds)


def correction_seeds(config: ReproduceConfig, r: int) -> list[list[tuple[int, int]]]:
    """Round ``r``'s (run seed, inspection seed) of each run on each training board (the first
    run of a board keeps the seeds a round of one run a board always had)."""
    streams = seed_streams(config)
    return [[(streams.seed_for("correction runs", r, i, *([k] if k else [])),
              streams.seed_for("inspection", r, i, *([k] if k else [])))
             for k in range(config.round_runs)] for i in range(len(config.train_boards))]


def calibration_seeds(config: ReproduceConfig, level: int, board: int) -> list[int]:
    """The expert's run seeds on calibration board ``board`` of grid level ``level``.

    Every calibration board has run seeds of its own: with the same few seeds
    on every board, the rule measured how those seeds fare rather than the
    expert's success at a difficulty (reusing 2 seeds on all boards once chose
    0.8, where the expert then crossed 39 of 63 test runs).
    """
    return seed_streams(config).seeds("calibration runs", config.calibration_runs, level, board)


def evaluation_seeds(config: ReproduceConfig) -> list[int]:
    """The run seeds of Table II: every method walks these on every test board (paired runs)."""
    return seed_streams(config).seeds("evaluation runs", config.eval_runs)


def sweep_seeds(config: ReproduceConfig) -> list[int]:
    """The run seeds of the sweep: the same at every difficulty."""
    return seed_streams(config).seeds("sweep runs", config.sweep_runs)


def planned_seeds(config: ReproduceConfig) -> dict[str, list[int]]:
    """Every seed the reproduction may use, by purpose (what the stages draw, listed up front)."""
    streams = seed_streams(config)
    rounds = range(config.rounds + config.extra_rounds)
    extra = range(config.calibration_boards, most_calibration_boards(config))
    confirm = range(confirmation_board_count(config))
    levels = range(len(config.difficulties))
    return {"boards": [seed for _, seed in boards(config).values()]
            + [seed for j in levels for _, seed in calibration_boards(config, j, extra).values()]
            + [seed for j in levels for _, seed in confirmation_boards(config, j, confirm).values()]
            + [seed for _, seed in test_boards(config, 0.0).values()],
            "correction runs": [a for r in rounds for board in correction_seeds(config, r)
                                for a, _ in board],
            "inspection": [b for r in rounds for board in correction_seeds(config, r)
                           for _, b in board],
            "calibration runs": [s for j in levels for i in range(most_calibration_boards(config))
                                 for s in calibration_seeds(config, j, i)],
            "confirmation runs": [s for j in levels for i in confirm
                                  for s in confirmation_seeds(config, j, i)],
            "evaluation runs": evaluation_seeds(config), "sweep runs": sweep_seeds(config),
            "demonstrations": [streams.seed_for("demonstrations", 0)],
            "learning": [streams.seed_for("learning")]}


@dataclass(frozen=True)
class Workspace:
    """A reproduction's folder: its settings, boards and seed streams (stage 1)."""

    out: Path  # the report folder
    config: ReproduceConfig
    paths: dict[str, Path]  # board name -> height map file
    maps: dict[str, HeightMap]  # board name -> height map
    by_hash: dict[str, HeightMap]  # the boards by content hash (how runs and demonstrations
    # name their terrain), hashed once
    streams: SeedStreams

    def model_path(self, name: str) -> Path:
        """Where the model ``name`` (a round's or a final function's) is kept."""
        return self.out / "models" / f"{name}.npz"

    def add_boards(self, specs: dict[str, tuple[Spec, int]]) -> None:
        """Boards made once a stage knows them (the test boards, after the calibration)."""
        paths = board_files(self.out, {name: (spec, seed, True)
                                       for name, (spec, seed) in specs.items()})
        for name, path in paths.items():
            self.paths[name] = path
            self.maps[name] = HeightMap.load(path)
            self.by_hash[self.maps[name].content_hash()] = self.maps[name]


def open_workspace(out: str | os.PathLike, config: ReproduceConfig,
                   hold: bool = True) -> Workspace:
    """The folder ``out`` made ready: refused if it holds other settings or another command
    runs in it (``hold`` False: a worker of the command that holds it); boards made once."""
    out = Path(out)
    claim_folder(out, config.to_dict(), "a reproduction", hold=hold)
    (out / "models").mkdir(exist_ok=True)
    paths = board_files(out, {name: (spec, seed, name != "flat")
                              for name, (spec, seed) in boards(config).items()})
    maps = {n: HeightMap.load(p) for n, p in paths.items()}
    return Workspace(out, config, paths, maps, {m.content_hash(): m for m in maps.values()},
                     seed_streams(config))
