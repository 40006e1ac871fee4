"""What the rollout teacher saw before its own failures (docs/learning/teacher.md): each run
of rollout_test.py's store that the rollout teacher failed, walked again (the same run, checked
against the stored one), and at its last decisions whether any candidate it tried walked on in
every one of its branches -- where none did, the failure is not one a foothold choice among
those tried could fix. A lab script, not part of footfall's interface.

python rollout_failures.py FOLDER STORE KEY_PREFIX [LAST_DECISIONS]

e.g. rollout_failures.py OUT test.sqlite test/rollout/ (the boards are FOLDER/<board>.npz, the
board the key's third part; the rollout teacher with RolloutConfig's defaults)
"""
import sys
from pathlib import Path

from footfall.core.heightmap import HeightMap
from footfall.data.store import DemoStore
from footfall.experiments.reproduce import ReproduceConfig
from footfall.experiments.runs import reward_source, teacher_walk


def main():
    folder, store_name, prefix = Path(sys.argv[1]), sys.argv[2], sys.argv[3]
    last = int(sys.argv[4]) if len(sys.argv) > 4 else 4
    config = ReproduceConfig()
    with DemoStore(folder / store_name, read_only=True) as store:
        failed = [r for r in store.runs(key_prefix=prefix) if not r["result"]["success"]]
    for run in failed:
        board = run["key"].split("/")[2]
        hmap = HeightMap.load(folder / f"{board}.npz")
        walk = teacher_walk(hmap, reward_source(None, hmap), run["seed"], config.walk, "rollout",
                            config.expert)
        record = walk.run()
        same = (record.result["reason"], len(record.steps)) == (run["result"]["reason"],
                                                                run["result"]["steps"])
        print(f"{run['key']}: {record.result['reason']} after {len(record.steps)} steps "
              f"(the stored run again: {same})")
        for v in walk.verdicts[-last:]:
            safe = sorted({o.candidate for o in v.outcomes}
                          - {o.candidate for o in v.outcomes if o.fell or o.failed})
            print(f"  decision {v.decision}: taught {v.best} (base {v.base}); tried "
                  f"{len(v.tried)}, walked on in every branch: {safe or 'none'}")


if __name__ == "__main__":
    main()
