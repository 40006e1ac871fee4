"""Fuzzing footfall's edges: every loader and every command gets random and mutated input.

A hostile user's files and arguments -- a corrupt or crafted ``.npz``, a model with NaN
bandwidths, a store with a trigger, ``-n 10**15`` -- must each end in one of two ways: a
valid result (which is then checked, so that garbage cannot slip through) or one clear
line and exit status 2. Anything else is a failure: a traceback, a hang past a time
limit, a memory blow-up, garbage accepted, an error of more than one line.

* :mod:`.harness`: runs one input under a time and memory limit and classifies the result;
* :mod:`.values`: the hostile values (Hypothesis strategies);
* :mod:`.craft`: raw ``.npz`` archives built and mutated byte by byte, bypassing footfall;
* :mod:`.bases`: the valid files the mutations start from;
* :mod:`.targets`: what a target is, and their registry; :mod:`.oracles`: the checks of an
  accepted input's result;
* the targets: :mod:`.files` (map and model files, imported scans), :mod:`.stores`,
  :mod:`.commands` (every command's arguments), :mod:`.lying` (valid files of wrong meaning,
  an output that is an input), :mod:`.concurrency` (two processes on one store);
* :mod:`.campaign`: ``footfall bench fuzz``: as many inputs as fit in a time budget.

The test suite (``tests/test_fuzz.py``) runs the same targets through Hypothesis with a
small budget.
"""

from footfall.cli.fuzz import classes, commands, concurrency, files, lying, stores  # noqa: F401,E402 - the targets register
