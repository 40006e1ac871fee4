"""Terrain module kinds by name: the paper's six, four more for training, six held out from all
tuning, and any you register.

A kind is a :data:`~footfall.terrain.geometry.Generator` ``(difficulty in [0, 1],
rng) -> heights (610, 610) [m]``, registered under a name in :data:`KINDS` (a
:class:`~footfall.core.registry.Registry`, which loads the plugins before it
answers). Modules, boards (:mod:`footfall.terrain.modules`) and the command
line's choices find every kind here.
"""

from __future__ import annotations

from footfall.core.registry import Registry
from footfall.terrain.added import ADDED
from footfall.terrain.file_modules import FILE_KIND
from footfall.terrain.generators import barrier, flat, logs, slope, steps
from footfall.terrain.geometry import Generator
from footfall.terrain.heldout import HELD_OUT
from footfall.terrain.rocky import rocky

KINDS: Registry[Generator] = Registry("terrain kind")
"""Terrain module kinds: name -> generator ``(difficulty, rng) -> heights (610, 610) [m]``."""
_BUILTIN = (("flat", flat), ("steps", steps), ("barrier", barrier), ("slope", slope),
            ("logs", logs), ("rocky", rocky))  # the paper's module kinds (§IV-A), in this order
for _name, _generator in _BUILTIN + ADDED + HELD_OUT:
    KINDS.register(_name, _generator)
PAPER_KINDS = tuple(name for name, _ in _BUILTIN)  # the paper's kinds, which tuning used
ADDED_KINDS = tuple(name for name, _ in ADDED)  # training kinds beyond the paper's
# (footfall.terrain.added: characters none of the paper's kinds has)
TRAINING_KINDS = tuple(k for k in PAPER_KINDS if k != "flat") + ADDED_KINDS
# the kinds parameters may be chosen on: the training suite's and the ablation's
HELD_OUT_KINDS = tuple(name for name, _ in HELD_OUT)  # kinds no tuning used
# (footfall.terrain.heldout; measured by footfall benchmark-terrain, never tuned on)
BUILTIN_KINDS = PAPER_KINDS + ADDED_KINDS + HELD_OUT_KINDS  # kinds unregister_kind keeps


def register_kind(name: str, generator: Generator) -> Generator:
    """Make a terrain module kind available by name (to modules, boards and the CLI).

    ``generator(difficulty, rng)`` returns the module's heights, shape
    (MODULE_CELLS, MODULE_CELLS) [m], for a difficulty in [0, 1], drawing
    every random number from ``rng``; the edges that meet a neighbouring
    module should be at height 0. Returns the generator (usable as a decorator
    with :func:`functools.partial`).
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"a terrain kind needs a name like 'craters', got {name!r}")
    if name == FILE_KIND:
        raise ValueError(f"{FILE_KIND!r} names the board modules read from files; "
                         f"choose another name")
    if not callable(generator):
        raise ValueError(f"the generator of terrain kind {name!r} must be callable")
    return KINDS.register(name, generator)  # another generator under a taken name: ValueError


def unregister_kind(name: str) -> None:
    """Forget a kind registered with :func:`register_kind` (the built-in ones stay)."""
    if name not in BUILTIN_KINDS:
        KINDS.unregister(name)
