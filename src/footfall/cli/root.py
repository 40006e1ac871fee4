"""Every command of the ``footfall`` command line: where it lives, and its line of help.

Each command lives in the module of its group (terrain, features, demos, store, learning,
walking, experiments, bench, teach). The group (:mod:`footfall.cli.entry`) imports a
command's module only when that command runs or shows its help, so that ``footfall --help``
does not import the whole library (MuJoCo, scikit-learn, SciPy: seconds) to print this table.
``tests/test_cli.py`` checks every line here against its command's own help.
"""

from __future__ import annotations

COMMANDS: dict[str, tuple[str, str, str]] = {
    # name: (module, attribute, short help)
    "terrain": ("footfall.cli.terrain", "terrain",
                "Make, import and look at terrain height maps."),
    "features": ("footfall.cli.features", "features",
                 "The 27 terrain features and three template patches of a foothold."),
    "demos": ("footfall.cli.demos", "demos",
              "Collect and inspect demonstrated footholds (a demonstration store, .sqlite)."),
    "store": ("footfall.cli.store", "store", "Inspect a demonstration store file (.sqlite)."),
    "learn": ("footfall.cli.learning", "learn",
              "Learn front- and hind-leg foothold ranking functions from demonstrations, "
              "from the robot's own trials, or from both."),
    "rank-eval": ("footfall.cli.learning", "rank_eval_cmd",
                  "How a scorer ranks a store's decisions against the expert: top-1, within 1 "
                  "cm, percentile, the expert's shortfall of its pick and the shares above "
                  "the correction margin and the severe threshold."),
    "outcomes": ("footfall.cli.outcomes", "outcomes_cmd",
                 "What followed the footholds of logged runs -- slid, missed, a fall -- and how "
                 "well the expert's value and each of its terms predict it; with --fit, an "
                 "expert grounded in it."),
    "walk": ("footfall.cli.walking", "walk_cmd",
             "One run of the simulated robot across a board (success, slip, speed)."),
    "walk-many": ("footfall.cli.walking", "walk_many_cmd",
                  "N runs in parallel: success rate (Wilson 95 % CI), slip, speed."),
    "offline": ("footfall.cli.experiments", "offline",
                "The offline experiment: learn from demonstrations, rank unseen terrain "
                "(Table I)."),
    "learning-curve": ("footfall.cli.experiments", "learning_curve",
                       "Learning curves: each feature set and learner from 25 to 1 600 "
                       "demonstrations, on held-out decisions, with the hand-tuned and expert "
                       "lines."),
    "curve-compare": ("footfall.cli.experiments", "curve_compare",
                      "Two learning-curve points on the same held-out decisions, paired: shares "
                      "above the margin and the exact McNemar test, mean shortfalls and their "
                      "paired bootstrap interval."),
    "curve-walk": ("footfall.cli.experiments", "curve_walk",
                   "Walk a learning curve's points on boards never trained on, paired with "
                   "the hand-tuned reward: crossings beside the curve's offline measure."),
    "student-curve": ("footfall.cli.student", "student_curve",
                      "The student's walking learning curve: reproductions' labelling loops "
                      "continued, each kind of supervision learned at each point, walked with "
                      "the teacher and the hand-tuned reward."),
    "reproduce": ("footfall.cli.experiments", "reproduce",
                  "The paper's walking experiment end to end: corrections, learning, Tables I "
                  "and II."),
    "study": ("footfall.cli.experiments", "study",
              "Several whole reproductions and a verdict on each of the paper's orderings."),
    "ablation": ("footfall.cli.experiments", "ablation",
                 "The walking controller's ablation: each part switched off alone, paired runs."),
    "benchmark-terrain": ("footfall.cli.experiments", "benchmark_terrain",
                          "A terrain suite: the expert and the hand-tuned reward on every kind, "
                          "success with Wilson intervals, slip and the failure taxonomy per "
                          "kind."),
    "demo": ("footfall.cli.experiments", "demo",
             "Build a board, score it densely and draw the terrain, features and templates."),
    "score": ("footfall.cli.score", "score_cmd",
              "Score every cell of MAP with a foothold scorer and write the scores as a layer."),
    "bench": ("footfall.cli.bench", "bench",
              "Benchmarks: print figures, compared with a baseline run in the same process."),
    "teach": ("footfall.cli.teach", "teach",
              "Serve a store's runs for labelling: open the printed address, pick a run, step "
              "through it, click the foothold the robot should have chosen."),
}
