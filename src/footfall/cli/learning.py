"""``footfall learn`` and ``footfall rank-eval``: a foothold model from a store, and how any
scorer agrees with the expert on a store's decisions."""

from __future__ import annotations

import math
import os
from pathlib import Path

import click

from footfall.cli.choices import (
    BUDGET,
    FEATURE_SET,
    LEARNER,
    NO_BUDGET,
    SEED,
    SELECTION,
    SUPERVISION,
    Finite,
)
from footfall.cli.output import emit, json_option, progress_log
from footfall.core.errors import FootfallError
from footfall.core.files import writable_path
from footfall.core.limits import check_count
from footfall.experiments.rank_eval import rank_eval_many
from footfall.expert.settings_file import load_expert
from footfall.features.templates import ORDER_ONLY_RMS
from footfall.learning.train import FOLDS, learn_from_store
from footfall.learning.trials import DEFAULT_PAIRS

SOURCE_HELP = ("Only demonstrations whose source starts with this: walker:train, human (people's "
               "labels), run: (the synthetic expert's corrections); repeat for several.")
DECISION_NOUN = {"demonstrations": "demonstrations", "runs": "run steps"}  # rank-eval's text
RMS_RANGE = (1e-5, 1.0)  # [m] = footfall.features.templates.RMS_RANGE (not imported: --help stays light)


def model_output(path: str) -> Path:
    """The output model path, refused before learning starts if the model could not be written.

    Raises
    ------
    FootfallError
        If ``path`` is a directory, its directory does not exist or is not writable, or it
        does not end in ``.npz``.
    """
    out = writable_path(path)
    if out.suffix.lower() != ".npz":
        raise FootfallError(f"output model {out} must end in .npz")
    directory = out.parent if str(out.parent) else Path(".")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise FootfallError(f"output directory is not writable: {directory}")
    return out


def supervision_options(f):
    """Add --supervision and --veto: what a demonstration's teacher verdict tells the learner."""
    f = click.option("--veto", is_flag=True,
                     help="Beside each function, learn which candidates the teacher refuses "
                          "outright (relative to the best of a candidate set where the "
                          "demonstrations carry the values the teacher's veto judges by, else "
                          "from the refusals alone) and take a penalty from them when scoring "
                          "(lambdarank only).")(f)
    return click.option("--supervision", type=SUPERVISION, default="choice", show_default=True,
                        help="What a demonstration tells the learner: the teacher's choice (the "
                             "paper's), its choice and the candidates it refused ('never "
                             "here'), or every candidate graded by the teacher's values (where "
                             "it gave them).")(f)


@click.command()
@click.argument("store_path", metavar="[DEMOS.sqlite]", required=False)
@click.option("--features", "feature_set", type=FEATURE_SET, required=True,
              help="Feature set (each with the pose features), or feature families joined "
                   "by '+' (e.g. terrain+pose).")
@click.option("--learner", type=LEARNER, default="l1", show_default=True,
              help="L1 / L2 logistic regression, a linear SVM, a kernel ranker (random Fourier "
                   "features) or gradient-boosted trees (lambdarank).")
@click.option("--library-size", type=click.IntRange(min=3), default=1000, show_default=True,
              help="Templates in the library, over the three scales (at most the max_count "
                   "limit).")
@click.option("--training-candidates", type=click.IntRange(min=1), default=100,
              show_default=True, help="Other candidates per demonstration used for pairs (at "
                                      "most the max_count limit).")
@click.option("--bandwidth-rms", type=Finite(*RMS_RANGE), nargs=3, default=None,
              metavar="S M L",
              help="Fix the RBF bandwidths as RMS height differences [m] per scale, each from "
                   f"{RMS_RANGE[0]:g} to {RMS_RANGE[1]:g} (default: chosen by cross-validation; "
                   f"for lambdarank, whose trees read only each column's order, "
                   f"{ORDER_ONLY_RMS * 1e3:g} mm).")
@click.option("--cv", type=click.IntRange(2, 50), default=5, show_default=True,
              help="Cross-validation folds.")
@click.option("--folds", type=click.Choice(FOLDS), default="demonstration", show_default=True,
              help="What a fold never splits: a demonstration, a run (the corrections of one "
                   "walking run; a kinematic walk's board) or a board.")
@click.option("--selection", type=SELECTION, default="1se", show_default=True,
              help="Lambda: one-standard-error rule (sparser) or the smallest CV error.")
@click.option("--template-budget", type=BUDGET, default=NO_BUDGET, show_default=True,
              help="Each leg group's function reads at most this share of its "
                   "demonstrations' number of templates (fitted again on those its learner "
                   "relied on most), or 'none'.")
@supervision_options
@click.option("--source", multiple=True, help=SOURCE_HELP)
@click.option("--trials", multiple=True, metavar="RUNS.sqlite",
              help="Also learn from the robot's own runs in this store (repeatable): every "
                   "foothold followed by a slide, a miss or a fall is ranked below footholds of "
                   "its board that were not. Without DEMOS.sqlite, learn from them alone.")
@click.option("--trial-pairs", type=click.IntRange(1, 100), default=DEFAULT_PAIRS,
              show_default=True,
              help="Footholds that went well each one that went wrong is ranked below.")
@click.option("--seed", type=SEED, default=0, show_default=True,
              help="Seed of the template library's sample and the training candidates.")
@click.option("-o", "--output", required=True, help="Output model (.npz).")
@json_option
def learn(store_path: str, feature_set: str, learner: str, library_size: int,
          training_candidates: int, bandwidth_rms: tuple[float, float, float] | None, cv: int,
          folds: str, selection: str, template_budget: float | str, supervision: str,
          veto: bool, source: tuple[str, ...], trials: tuple[str, ...],
          trial_pairs: int, seed: int, output: str, as_json: bool) -> None:
    """Learn front- and hind-leg foothold ranking functions from demonstrations, from the
    robot's own trials, or from both."""
    if store_path is None and not trials:
        raise FootfallError("give DEMOS.sqlite, --trials RUNS.sqlite, or both")
    check_count(library_size, "--library-size", 3)
    check_count(training_candidates, "--training-candidates", 1)
    out = model_output(output)
    learned = learn_from_store(store_path, out, feature_set, learner, source=source or None,
                               trials=trials, trial_pairs=trial_pairs,
                               log=progress_log(as_json), library_size=library_size,
                               training_candidates=training_candidates,
                               bandwidth_rms=bandwidth_rms, cv=cv, seed=seed,
                               selection=selection, folds=folds,
                               template_budget=(None if template_budget == NO_BUDGET
                                                else template_budget),
                               supervision=supervision, veto=veto)
    tried = (f" and {learned.trial_footholds} footholds of its own runs"
             if learned.trial_footholds else "")
    lines = [f"wrote {learned.model}: {feature_set}/{learner} from {learned.demonstrations} "
             f"demonstrations{tried} in {learned.seconds:.1f} s"]
    for g, v in learned.groups.items():
        chosen = (f"{v['trees']} trees" if v.get("trees") is not None
                  else f"lambda {v['lambda']:.4g}")
        lines.append(f"  {g}: {chosen}, cv error {v['cv_error']:.4f}, "
                     f"templates kept {v['templates_kept']} of {v['library']}")
    emit(as_json, learned.as_dict(), "\n".join(lines))


@click.command("rank-eval")
@click.argument("paths", nargs=-1, required=True, metavar="[MODEL.npz]... STORE.sqlite")
@click.option("--reward", default=None, metavar="NAME",
              help="Rank with a named scorer instead of a model file: hand-tuned (the reward "
                   "learning starts from) or expert (the expert's own value, the ceiling).")
@click.option("--decisions", type=click.Choice(["demonstrations", "runs"]),
              default="demonstrations", show_default=True,
              help="What to rank: the store's demonstrations (the expert's choices), or the "
                   "steps of its run logs -- the states the robot visited -- against the "
                   "expert's best of each step.")
@click.option("--run-key", default=None, metavar="PREFIX",
              help="With --decisions runs: only the runs whose key starts with this.")
@click.option("--margin", type=Finite(min=0.0), default=1.0, show_default=True,
              help="The correction margin [value units] whose share of decisions above it is "
                   "reported (the reproduction's own is 2).")
@click.option("--no-expert", is_flag=True,
              help="Skip the reward loss and its shares (they need the expert).")
@click.option("--expert-config", default=None, metavar="EXPERT.json",
              help="Judge with these expert settings; default: the synthetic expert that made "
                   "the demonstrations, or the walking expert (run steps, mixed sources).")
@click.option("--source", multiple=True, help=SOURCE_HELP)
@click.option("--path-bias", type=Finite(min=0.0), default=None, metavar="REWARD/M",
              help="Rank as the footstep planner picks: each scorer's values less this path "
                   "bias per metre from the gait-nominal foothold, scaled to its spread (the "
                   "reproduction walks 60; the expert carries its own) [default: the scorer "
                   "alone].")
@click.option("--by-term", is_flag=True,
              help="Split each scorer's severe shortfalls by the expert's terms (slip margin, "
                   "drop-off, leg clearance ...): what its worst picks lose.")
@json_option
def rank_eval_cmd(paths: tuple[str, ...], reward: str | None, decisions: str,
                  run_key: str | None, margin: float, no_expert: bool,
                  expert_config: str | None, source: tuple[str, ...], path_bias: float | None,
                  by_term: bool, as_json: bool) -> None:
    """How a scorer ranks a store's decisions against the expert: top-1, within 1 cm,
    percentile, the expert's shortfall of its pick and the shares above the correction margin
    and the severe threshold. Several models (and --reward) are judged on the same decisions,
    the expert's values computed once."""
    if len(paths) < 2 and reward is None:
        raise FootfallError("give MODEL.npz... STORE.sqlite, or --reward NAME STORE.sqlite")
    agreements = rank_eval_many(
        paths[:-1], paths[-1], reward=reward, with_expert=not no_expert, source=source or None,
        decisions=decisions, run_key=run_key, margin=margin,
        expert_config=load_expert(expert_config) if expert_config else None,
        path_bias=path_bias, by_term=by_term)
    data = ([a.as_dict() for a in agreements] if len(agreements) > 1
            else agreements[0].as_dict())
    emit(as_json, data, "\n".join(_agreement_text(a) for a in agreements))


def _agreement_text(agreement) -> str:
    """One scorer's measures on the decisions, in a line (and its outcome AUCs)."""
    s = agreement.scores
    who = (agreement.model if agreement.feature_set == "-"
           else f"{agreement.model}: {agreement.feature_set}/{agreement.learner}")
    return (f"{who} on {s.n} {DECISION_NOUN[agreement.decisions]}: "
            f"top-1 {s.top1:.3f}, within 1 cm {_number(s.top1_near)}, "
            f"percentile {s.percentile:.3f}, reward loss {_number(s.reward_loss)} "
            f"(95 % CI {_number(s.reward_loss_ci[0])} to {_number(s.reward_loss_ci[1])}), "
            f"above the margin {_number(s.above_margin)}, severe {_number(s.severe)}"
            + ("" if agreement.expert is None else f"; judged by {agreement.expert}")
            + ("" if agreement.path_bias is None
               else f"; as the planner picks (path bias {agreement.path_bias:g} /m)")
            + _outcome_text(agreement.outcomes) + _terms_text(agreement.severe_terms)
            + _degenerate_text(s)
            + _trained_here_text(agreement.trained_here))


def _terms_text(split: dict | None) -> str:
    """The severe shortfalls' split by the expert's terms (the terms of 1 % or more)."""
    if split is None:
        return ""
    if not split["decisions"]:
        return f"\n  no shortfall above {split['above']:g}"
    parts = ", ".join(f"{t.replace('_', ' ')} {100 * v:.0f} %"
                      for t, v in split["terms"].items() if abs(v) >= 0.01)
    return (f"\n  its {split['decisions']} shortfalls above {split['above']:g} "
            f"({split['shortfall']:.0f} value units) by the expert's term: {parts}")


def _trained_here_text(terrains: int) -> str:
    """A warning for a model whose templates were drawn from the terrains it is measured on."""
    if not terrains:
        return ""
    return (f"\n  warning: its template library was drawn from {terrains} of these decisions' "
            f"terrains: this is not a held-out measure")


DEGENERATE = 0.5  # [-] a scorer valuing every candidate alike on more decisions is flagged


def _degenerate_text(s) -> str:
    """A warning for a scorer that cannot tell candidates apart (ties counted as ties)."""
    if not s.constant > DEGENERATE:
        return ""
    return (f"\n  warning: it values every candidate alike on {100 * s.constant:.0f} % of the "
            f"decisions: it cannot tell them apart (ties are counted as ties)")


def _outcome_text(outcomes: dict | None) -> str:
    """Run decisions: the AUC of the scorer's value for a fall and a slide, with their CIs."""
    if outcomes is None:
        return ""
    parts = []
    for lab in ("fall", "slid"):
        o = outcomes[lab]
        auc = "n/a" if o["auc"] is None else f"{o['auc']:.2f}"
        ci = "" if o["ci"][0] is None else f" [{o['ci'][0]:.2f}, {o['ci'][1]:.2f}]"
        parts.append(f"{lab} {auc}{ci} ({o['positives']} footholds)")
    return "\nAUC of its value for what followed the footholds stood on: " + "; ".join(parts)


def _number(value: float) -> str:
    """A measure for the text output: three decimals, or "n/a" where it is not defined (NaN)."""
    return f"{value:.3f}" if math.isfinite(value) else "n/a"
