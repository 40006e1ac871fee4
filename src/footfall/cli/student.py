"""``footfall student-curve``: how much the student needs, and of which kind of supervision."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import click

from footfall.cli.executors import executor_options, opened_executor
from footfall.cli.output import emit, json_option, progress_log
from footfall.core.errors import FootfallError
from footfall.experiments.student_curve import (
    StudentCurveConfig,
    curve_markdown,
    run_student_curve,
)


@click.command("student-curve")
@click.argument("sources", nargs=-1, required=True)
@click.option("--out", default="out/student-curve", show_default=True,
              help="The curve's folder (run again to resume).")
@click.option("--rounds", type=click.IntRange(min=1), default=None,
              help="Rounds each loop is continued to [default: 7].")
@click.option("--points", default=None, metavar="R[,R...]",
              help="The points: the labels after this many rounds [default: 1,2,4,7].")
@click.option("--variant", "variants", multiple=True, metavar="FEATURES:SUPERVISION[+veto]",
              help="A function learned at each point (repeatable) [default: both:choice, "
                   "both:refusals+veto, both:graded+veto, terrain:graded+veto, "
                   "templates:graded+veto].")
@executor_options
@json_option
def student_curve(sources: tuple[str, ...], out: str, rounds: int | None, points: str | None,
                  variants: tuple[str, ...], processes: int | None, executor_name: str,
                  ray_address: str | None, as_json: bool) -> None:
    """The student's walking learning curve: reproductions' labelling loops continued, each
    kind of supervision learned at each point, walked with the teacher and the hand-tuned
    reward.

    SOURCES are folders of footfall reproduce whose loops label every step (e.g. the seeds of
    footfall study), each a draw; they are copied, never written. The runs and models go to
    --out (run again to resume)."""
    changes: dict = {}
    if rounds is not None:
        changes["rounds"] = rounds
    if points is not None:
        try:
            changes["points"] = tuple(int(v) for v in points.split(","))
        except ValueError:
            raise FootfallError(f"--points must be whole numbers separated by commas, got "
                                f"{points!r}") from None
    if variants:
        changes["variants"] = tuple(variants)
    config = replace(StudentCurveConfig(), **changes)  # checked: one line for a bad value
    with opened_executor(executor_name, processes, ray_address) as executor:
        summary = run_student_curve(sources, Path(out), config, log=progress_log(as_json),
                                    executor=executor)
    emit(as_json, summary, curve_markdown(summary) + f"wrote {Path(out) / 'curve.md'} and .json")
