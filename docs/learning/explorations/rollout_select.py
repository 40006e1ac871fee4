"""Choosing the rollout teacher's settings (docs/learning/teacher.md, "Choosing its settings"):
the rule's four candidates and the accepted teacher walked on one fresh board of each training
kind at difficulty 1.0. A lab script, not part of footfall's interface.

python rollout_select.py OUT [PROCESSES]
"""
import sys
from pathlib import Path

from footfall.core.heightmap import HeightMap
from footfall.core.stats import mcnemar_exact
from footfall.data.store import DemoStore
from footfall.experiments.executors import LocalPool
from footfall.experiments.reproduce import ReproduceConfig
from footfall.experiments.runs import RunJob, Runner
from footfall.sim.rollout import RolloutConfig
from footfall.terrain.saving import save_board

KINDS = ("rocky", "steps", "barrier", "slope", "logs")
FIRST_BOARD, RUNS, FIRST_RUN = 7400, 2, 1000
CANDIDATES = {"A": RolloutConfig(),
              "B": RolloutConfig(candidates=2, horizon=2, branches=1),
              "C": RolloutConfig(candidates=5),
              "D": RolloutConfig(horizon=8)}


def main():
    out = Path(sys.argv[1])
    processes = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    out.mkdir(parents=True, exist_ok=True)
    config = ReproduceConfig()
    boards, terrains = {}, {}
    for i, kind in enumerate(KINDS):
        path = out / f"{kind}-{FIRST_BOARD + i}.npz"
        if not path.exists():
            save_board([f"{kind}:1.0"], seed=FIRST_BOARD + i, path=str(path))
        boards[path.stem] = str(path)
        hmap = HeightMap.load(path)
        terrains[hmap.content_hash()] = hmap
    store = DemoStore(out / "select.sqlite", create=True)
    runner = Runner(store, terrains, LocalPool(processes), None, print)

    def walk(name, teacher, rollout=RolloutConfig()):
        jobs = [RunJob(f"sel/{name}/{b}/s{s}", p, None, s, config.walk, expert=config.expert,
                       judge=True, teacher=teacher, rollout=rollout)
                for b, p in boards.items() for s in range(FIRST_RUN, FIRST_RUN + RUNS)]
        runner.run(jobs, name)
        return [store.runs(key_prefix=j.key)[0]["result"]["success"] for j in jobs]

    base = walk("accepted", "accepted")
    print(f"accepted teacher: {sum(base)} / {len(base)}", flush=True)
    for name, rollout in CANDIDATES.items():
        got = walk(name, "rollout", rollout)
        only, lost = (sum(a and not b for a, b in zip(got, base)),
                      sum(b and not a for a, b in zip(got, base)))
        cost = (rollout.candidates + 1) * rollout.branches * (rollout.horizon + 1)
        print(f"{name} (K {rollout.candidates}, horizon {rollout.horizon}, S {rollout.branches}; "
              f"{cost} branch steps a decision): {sum(got)} / {len(got)}; against the accepted "
              f"teacher {only} / {lost} runs only one crossed, p = {mcnemar_exact(only, lost):.3f}",
              flush=True)


if __name__ == "__main__":
    main()
