"""``footfall bench fuzz``: as many hostile inputs as fit in a time budget, over every target.

The targets take turns in slices of :data:`SLICE` seconds; Hypothesis draws each slice's
cases from the campaign's seed. The report counts inputs and outcomes per target and
lists every failure with the case that caused it.
"""

from __future__ import annotations

import tempfile
import time
from collections import Counter
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, Phase, Verbosity, given, settings
from hypothesis import seed as hypothesis_seed

from footfall.cli.fuzz.bases import make_bases
from footfall.cli.fuzz.harness import FAILURES, Outcome
from footfall.cli.fuzz.targets import TARGETS, run_case

SLICE = 20.0  # [s] one target's turn


class _SliceOver(BaseException):
    """Ends a target's turn (raised from inside Hypothesis' loop)."""


def _turn(name: str, seconds: float, seed: int, bases, scratch: Path,
          record: Callable[[Outcome], None]) -> None:
    target = TARGETS.get(name)
    end = time.monotonic() + seconds

    @hypothesis_seed(seed)
    @settings(max_examples=10 ** 9, deadline=None, database=None, phases=[Phase.generate],
              verbosity=Verbosity.quiet, suppress_health_check=list(HealthCheck))
    @given(target.cases)
    def one(case: Any) -> None:
        if time.monotonic() > end:
            raise _SliceOver()
        record(run_case(target, case, bases, scratch))

    try:
        one()
    except _SliceOver:
        pass


def run_campaign(minutes: float, seed: int = 0, targets: Sequence[str] | None = None,
                 workdir: str | None = None, log: Callable[[str], None] = lambda line: None
                 ) -> dict[str, Any]:
    """Fuzz ``targets`` (default: all) for ``minutes`` [min]; the counts and every failure."""
    names = list(targets or TARGETS)
    with tempfile.TemporaryDirectory(prefix="footfall-fuzz-", dir=workdir) as tmp:
        started = time.monotonic()
        bases = make_bases(Path(tmp) / "bases")
        setup = time.monotonic() - started
        counts: dict[str, Counter] = {n: Counter() for n in names}
        failures: list[dict[str, str]] = []

        def record(outcome: Outcome) -> None:
            counts[outcome.target][outcome.kind] += 1
            if outcome.failed:
                failures.append({"target": outcome.target, "kind": outcome.kind,
                                 "detail": outcome.detail, "case": outcome.case})

        budget = minutes * 60.0
        turn = 0
        while time.monotonic() - started < budget + setup:
            name = names[turn % len(names)]
            left = budget + setup - (time.monotonic() - started)
            _turn(name, min(SLICE, max(left, 0.0)), seed + turn, bases, Path(tmp) / "case",
                  record)
            turn += 1
            tried = sum(sum(c.values()) for c in counts.values())
            log(f"fuzz: {tried} inputs, {len(failures)} failures, "
                f"{time.monotonic() - started:.0f} s")
        elapsed = time.monotonic() - started - setup
    by_target = {n: {"inputs": sum(c.values()), **{k: c.get(k, 0) for k in
                                                   ("ok", "refused") + FAILURES}}
                 for n, c in counts.items()}
    return {"minutes": minutes, "seed": seed, "seconds": elapsed, "setup_seconds": setup,
            "inputs": sum(t["inputs"] for t in by_target.values()),
            "failures": len(failures),
            **{k: sum(t[k] for t in by_target.values()) for k in FAILURES},
            "targets": by_target, "failure_cases": failures}


def format_campaign(r: dict[str, Any]) -> str:
    """The campaign's report as text."""
    lines = [f"fuzz: {r['inputs']} inputs in {r['seconds']:.0f} s "
             f"({r['inputs'] / max(r['seconds'], 1e-9):.1f}/s, seed {r['seed']}): "
             f"{r['failures']} failures ("
             + ", ".join(f"{r[k]} {k}" for k in FAILURES) + ")"]
    for name, t in r["targets"].items():
        lines.append(f"  {name:12s} {t['inputs']:6d} inputs  {t['ok']:6d} accepted  "
                     f"{t['refused']:6d} refused  "
                     + "  ".join(f"{t[k]} {k}" for k in FAILURES))
    for f in r["failure_cases"][:50]:
        lines.append(f"  FAIL {f['target']} {f['kind']}: {f['detail']}\n       case: {f['case']}")
    if len(r["failure_cases"]) > 50:
        lines.append(f"  ... and {len(r['failure_cases']) - 50} more failures (see --json)")
    return "\n".join(lines)
