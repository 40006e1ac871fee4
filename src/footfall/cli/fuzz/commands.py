"""The command-line target: every command with valid arguments, one or two of them made hostile.

Each command is a list of argument slots, each slot a kind (a count, a seed, a number in a
range, an input file, an output file) with a valid value. A case replaces some slots with
values of :mod:`.values`; a value from a "bad" list must be refused (exit 2, one line) --
accepting it is garbage, working on before refusing it is a hang. Commands that would walk,
learn or collect for long always get at least one bad value, so that a case stays cheap.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from hypothesis import strategies as st

from footfall.cli.fuzz import values
from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import cli_work
from footfall.cli.fuzz.targets import Target, register_target


@dataclass(frozen=True)
class Slot:
    """One argument of a command: ``option`` (None for a positional), its kind and valid value."""

    option: str | None
    kind: str  # "count", "seed", "unit" (in [0, 1]), "positive", "nonnegative", "input",
    # "output", "folder"
    valid: str  # a template of :meth:`Bases.fill`
    suffix: str = ""  # the output's expected suffix


BAD = {"count": values.BAD_COUNTS, "seed": values.BAD_SEEDS,
       "unit": values.BAD_NUMBERS + ("-0.5", "1.5"),
       "positive": values.BAD_NUMBERS + ("0", "-1", "1e-400", "1e-300", "1e300"),
       "nonnegative": values.BAD_NUMBERS + ("-1", "-1e-300"),
       "input": values.BAD_INPUT, "output": values.BAD_OUTPUT,
       "folder": ("{text}", "{empty}", "/proc/footfall", "/dev/null/out", "/proc/version")}


@dataclass(frozen=True)
class Command:
    """A command, its fixed words and its slots; ``heavy`` commands always get a bad value."""

    words: tuple[str, ...]
    slots: tuple[Slot, ...]
    heavy: bool = False


def _out(option: str, suffix: str) -> Slot:
    return Slot(option, "output", "{dir}/out" + suffix, suffix)


COMMANDS = (
    Command(("terrain", "make", "rocky"), (Slot("--difficulty", "unit", "0.5"),
                                           Slot("--seed", "seed", "1"), _out("-o", ".npz"))),
    Command(("terrain", "board", "flat", "steps:0.5"), (Slot("--seed", "seed", "1"),
                                                       _out("-o", ".npz"))),
    Command(("terrain", "show"), (Slot(None, "input", "{map}"), _out("-o", ".png"))),
    Command(("terrain", "import"), (Slot(None, "input", "{dir}/scan.npy"),
                                    Slot("--resolution", "positive", "0.008"),
                                    _out("-o", ".npz"))),
    Command(("features",), (Slot(None, "input", "{map}"),
                            Slot("--template-resolution", "positive", "0.004"))),
    Command(("demos", "info"), (Slot(None, "input", "{store}"),)),
    Command(("store", "check"), (Slot(None, "input", "{store}"),)),
    Command(("rank-eval", "--no-expert"), (Slot(None, "input", "{model}"),
                                           Slot(None, "input", "{store}"))),
    Command(("demos", "collect"), (Slot("--terrain", "input", "{map}"),
                                   Slot("-n", "count", "2"), Slot("--seed", "seed", "0"),
                                   Slot("--noise", "nonnegative", "0.1"),
                                   _out("-o", ".sqlite")), heavy=True),
    Command(("learn", "--cv", "2", "--library-size", "30"),
            (Slot(None, "input", "{store}"), Slot("--seed", "seed", "0"),
             Slot("--training-candidates", "count", "20"), _out("-o", ".npz")), heavy=True),
    Command(("walk",), (Slot("--terrain", "input", "{map}"), Slot("--model", "input", "{model}"),
                        Slot("--seed", "seed", "0"), Slot("--search-radius", "positive", "0.03"),
                        Slot("--frames", "count", "4"), _out("--video", ".mp4"),
                        _out("--snapshots", ".png")), heavy=True),
    Command(("reproduce", "--quick"), (Slot("--out", "folder", "{dir}/out"),
                                       Slot("--seed", "seed", "0"),
                                       Slot("--processes", "count", "1")), heavy=True),
    Command(("offline", "--quick"), (Slot("--out", "folder", "{dir}/out"),
                                     Slot("--seed", "seed", "0")), heavy=True),
    Command(("demo",), (Slot("--out", "folder", "{dir}/out"), Slot("--seed", "seed", "0")),
            heavy=True),
    Command(("walk-many",), (Slot("--terrain", "input", "{map}"), Slot("--runs", "count", "2"),
                             Slot("--seed", "seed", "0"),
                             Slot("--search-radius", "positive", "0.03"),
                             Slot("--processes", "count", "1")), heavy=True),
)

cli_cases = st.tuples(st.integers(0, len(COMMANDS) - 1),
                      st.lists(st.tuples(st.integers(0, 100), st.booleans(), st.integers(0, 100),
                                         values.argument_text), min_size=1, max_size=2))


def build_argv(case: tuple, bases: Bases) -> tuple[list[str], bool]:
    """The argument list of a case and whether it holds a value that must be refused."""
    index, edits = case
    command = COMMANDS[index]
    chosen = {i: (bases.fill(slot.valid), False) for i, slot in enumerate(command.slots)}
    for n, (which, bad, pick, text) in enumerate(edits):
        i = which % len(command.slots)
        slot = command.slots[i]
        pool = BAD[slot.kind]
        if bad or (command.heavy and n == len(edits) - 1):
            template = pool[pick % len(pool)]
            chosen[i] = (bases.fill(template, slot.suffix), not _maybe_valid(slot, template))
        else:
            chosen[i] = (text, False)
    must_refuse = any(bad for _, bad in chosen.values())
    argv = list(command.words)
    for i, slot in enumerate(command.slots):
        value = chosen[i][0]
        argv += [value] if slot.option is None else [slot.option, value]
    return argv, must_refuse


def _maybe_valid(slot: Slot, template: str) -> bool:
    """Bad-list values that a command may rightly take in some position."""
    if slot.kind == "input" and template in ("{map}", "{model}", "{store}"):
        return True  # the right file for another slot may be right for this one
    return False


def _cli_work(case: tuple, bases: Bases, scratch: Path) -> Callable[[], None]:
    argv, must_refuse = build_argv(case, bases)
    argv = [a.replace(str(bases.root) + "/out", str(scratch) + "/out") for a in argv]
    return cli_work(argv, must_refuse, cwd=scratch)


register_target(Target("cli", cli_cases, _cli_work, seconds=20.0))
