"""``footfall outcomes``: what followed the robot's footholds, against the expert's judgement."""

from __future__ import annotations

import math

import click

from footfall.cli.output import emit, json_option
from footfall.core.files import writable_path
from footfall.data.outcomes import OUTCOME_LABELS as LABELS
from footfall.experiments.outcomes import outcome_report
from footfall.expert.settings_file import FORMAT as EXPERT_FORMAT
from footfall.expert.settings_file import load_expert, save_expert


def _auc(entry: dict) -> str:
    a, (lo, hi) = entry["auc"], entry["ci"]
    if not math.isfinite(a):
        return "n/a"
    return f"{a:.2f} [{lo:.2f}, {hi:.2f}]" if math.isfinite(lo) else f"{a:.2f}"


def _prediction_lines(prediction: dict, title: str) -> list[str]:
    methods = list(prediction)
    lines = [title, "  outcome      " + "".join(f"{m[:24]:>26}" for m in methods)]
    for lab in LABELS:
        pos = prediction[methods[-1]]["value"][lab]["positives"]
        lines.append(f"  {lab:<11}  " + "".join(f"{_auc(prediction[m]['value'][lab]):>26}"
                                              for m in methods) + f"   ({pos} footholds)")
    return lines


def _text(report: dict) -> str:
    lines = [f"judged by: {report['expert']}; a fall counts against the footholds of its last "
             f"{report['horizon'] + 1} steps", "", "who chose the footholds: runs crossed, failures "
             "by cause"]
    for method, m in report["methods"].items():
        causes = ", ".join(f"{c} {n}" for c, n in m["causes"].items()) or "none"
        lines.append(f"  {method}: {m['successes']} / {m['runs']}; {causes}")
    pooled = report["prediction"]["all"]
    lines += ["", f"{pooled['footholds']} footholds stood on, {pooled['boards']} boards"]
    lines += _prediction_lines(report["prediction"], "AUC of the expert's value for each outcome "
                                                     "(low value -> outcome; 95 % CI over boards):")
    lines += ["", "AUC of each raw term, all footholds (oriented worse-higher):"]
    terms = list(pooled["terms"][LABELS[0]])
    lines.append("  outcome      " + "".join(f"{t[:12]:>13}" for t in terms))
    for lab in LABELS:
        lines.append(f"  {lab:<11}  " + "".join(
            f"{pooled['terms'][lab][t]:>13.2f}" if math.isfinite(pooled["terms"][lab][t])
            else f"{'n/a':>13}" for t in terms))
    if "fit" in report:
        f = report["fit"]
        lines += ["", f"grounded in '{f['label']}' ({f['positives']} of {f['footholds']} "
                      f"footholds): {f['expert']}, {f['scale']:.3g} value units per log-odds",
                  "  weight: before -> after"]
        lines += [f"  {w}: {f['weights_before'][w]:g} -> {v:.4g}" for w, v in f["weights"].items()]
        lines += _prediction_lines(f["prediction_in_sample"], "AUC of the grounded value, "
                                                              "the same footholds (in sample):")
    return "\n".join(lines)


@click.command("outcomes")
@click.argument("store_paths", nargs=-1, required=True, metavar="STORE.sqlite...")
@click.option("--expert-config", default=None, metavar="EXPERT.json",
              help="Judge with these expert settings (e.g. a grounded expert); default: the "
                   "walking expert.")
@click.option("--horizon", type=click.IntRange(0, 100), default=3, show_default=True,
              help="A fall counts against the footholds of this many steps before the one it "
                   "came in, and that one.")
@click.option("--fit", type=click.Choice(LABELS), default=None,
              help="Ground the expert's risk weights in this outcome, on these runs.")
@click.option("-o", "--output", default=None, metavar="EXPERT.json",
              help="With --fit: write the grounded expert's settings here.")
@json_option
def outcomes_cmd(store_paths: tuple[str, ...], expert_config: str | None, horizon: int,
                 fit: str | None, output: str | None, as_json: bool) -> None:
    """What followed the footholds of logged runs -- slid, missed, a fall -- and how well the
    expert's value and each of its terms predict it; with --fit, an expert grounded in it."""
    if output is not None and fit is None:
        raise click.UsageError("-o/--output writes the grounded expert: give --fit too")
    out = (writable_path(output, (".json",), what="-o", kind="expert settings",
                         inputs=(*store_paths, expert_config), writes=EXPERT_FORMAT)
           if output is not None
           else None)
    report, fitted = outcome_report(store_paths, load_expert(expert_config) if expert_config
                                    else None, horizon, fit)
    if fitted is not None and out is not None:
        save_expert(out, fitted.config, {"fit": fitted.as_dict(), "stores": report["stores"],
                                         "horizon": horizon})
    emit(as_json, report, _text(report))
