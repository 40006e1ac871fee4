"""The rollout teacher against the accepted teacher on unseen boards of the test kinds at
difficulty 1.0 (docs/learning/teacher.md, "On unseen boards of the test kinds"). A lab script,
not part of footfall's interface.

python rollout_test.py OUT [PROCESSES]
"""
import sys
from pathlib import Path

from footfall.core.heightmap import HeightMap
from footfall.core.stats import mcnemar_exact
from footfall.data.store import DemoStore
from footfall.experiments.executors import LocalPool
from footfall.experiments.reproduce import ReproduceConfig
from footfall.experiments.runs import RunJob, Runner
from footfall.terrain.saving import save_board

BOARDS, RUNS, FIRST_RUN = (7500, 7501, 7502), 21, 1000


def unseen_boards(out: Path) -> tuple[dict, dict]:
    """The three test boards in ``out`` (made once): name -> file, and hash -> map."""
    out.mkdir(parents=True, exist_ok=True)
    boards, terrains = {}, {}
    for seed in BOARDS:
        path = out / f"test-{seed}.npz"
        if not path.exists():
            save_board(["rocky:1.0", "steps:1.0"], seed=seed, path=str(path))
        boards[path.stem] = str(path)
        hmap = HeightMap.load(path)
        terrains[hmap.content_hash()] = hmap
    return boards, terrains


def main():
    out = Path(sys.argv[1])
    processes = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    config = ReproduceConfig()
    boards, terrains = unseen_boards(out)
    store = DemoStore(out / "test.sqlite", create=True)
    runner = Runner(store, terrains, LocalPool(processes), None, print)
    crossed = {}
    for teacher in ("accepted", "rollout"):
        jobs = [RunJob(f"test/{teacher}/{b}/s{s}", p, None, s, config.walk, expert=config.expert,
                       judge=True, teacher=teacher)
                for b, p in boards.items() for s in range(FIRST_RUN, FIRST_RUN + RUNS)]
        runner.run(jobs, teacher)
        crossed[teacher] = {j.key.split("/", 2)[2]: store.runs(key_prefix=j.key)[0]["result"]
                            ["success"] for j in jobs}
    a, r = crossed["accepted"], crossed["rollout"]
    only_r = sum(r[k] and not a[k] for k in a)
    only_a = sum(a[k] and not r[k] for k in a)
    print(f"accepted {sum(a.values())} / {len(a)}, rollout {sum(r.values())} / {len(r)}; only the "
          f"rollout teacher {only_r}, only the accepted {only_a}, exact McNemar p = "
          f"{mcnemar_exact(only_r, only_a):.4f}; of the accepted teacher's "
          f"{len(a) - sum(a.values())} failures the rollout teacher crossed {only_r}", flush=True)
    for k in sorted(a):
        if not r[k]:
            print("rollout failed:", k, "(accepted crossed)" if a[k] else "(both failed)")


if __name__ == "__main__":
    main()
