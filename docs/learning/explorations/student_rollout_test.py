"""Learned functions (and the hand-tuned reward) walked on the rollout teacher's test runs:
three unseen boards of the test kinds at difficulty 1.0, 21 runs each (docs/learning/teacher.md,
"Its student"). A lab script, not part of footfall's interface.

python student_rollout_test.py OUT NAME=MODEL.npz|NAME=hand-tuned ... [--processes N]

Each NAME's runs are stored in OUT/test.sqlite under test/NAME/...; stored runs are skipped, so a
stopped walk resumes. Prints each function's crossings and exact McNemar tests between them.
"""
import sys
from itertools import combinations
from pathlib import Path

from rollout_test import FIRST_RUN, RUNS, unseen_boards  # the same runs

from footfall.core.stats import mcnemar_exact
from footfall.data.store import DemoStore
from footfall.experiments.executors import LocalPool
from footfall.experiments.reproduce import ReproduceConfig
from footfall.experiments.runs import RunJob, Runner


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--processes")]
    processes = next((int(a.split("=")[1]) for a in sys.argv[1:]
                      if a.startswith("--processes=")), 2)
    out, named = Path(args[0]), dict(a.split("=", 1) for a in args[1:])
    config = ReproduceConfig()
    boards, terrains = unseen_boards(out)
    with DemoStore(out / "test.sqlite", create=True) as store:
        runner = Runner(store, terrains, LocalPool(processes), None, print)
        crossed = {}
        for name, model in named.items():
            jobs = [RunJob(f"test/{name}/{b}/s{s}", p, None if model == "hand-tuned" else model,
                           s, config.walk, expert=config.expert)
                    for b, p in boards.items() for s in range(FIRST_RUN, FIRST_RUN + RUNS)]
            runner.run(jobs, name)
            crossed[name] = {j.key.split("/", 2)[2]: store.runs(key_prefix=j.key)[0]["result"]
                             ["success"] for j in jobs}
    for name, c in crossed.items():
        print(f"{name}: {sum(c.values())} / {len(c)}", flush=True)
    for a, b in combinations(crossed, 2):
        x, y = crossed[a], crossed[b]
        only_a, only_b = sum(x[k] and not y[k] for k in x), sum(y[k] and not x[k] for k in x)
        print(f"{a} vs {b}: {only_a} / {only_b}, exact McNemar p = "
              f"{mcnemar_exact(only_a, only_b):.4f}", flush=True)


if __name__ == "__main__":
    main()
