"""Policy iteration with the rollout teacher (docs/learning/teacher.md, "Its student"): the
learned function walks the training boards, the rollout teacher over that function itself
labels every step, the function is learned again from every label so far; each round's function
walked on the validation boards. A lab script, not part of footfall's interface; the rule it
follows is written in the docs.

python policy_iteration.py OUT REPRODUCTION_FOLDER LABELS.sqlite F0.npz [MAX_ROUNDS]

F0.npz: the first function, learned from the adopted function's steps as LABELS holds them
(student_supervision.py ... refusals abs THREADS LABELS). Resumable: stored runs are skipped,
saved round models are not learned again.
"""
import sys
from pathlib import Path

from student_supervision import adopted_labels, learn_as_adopted

from footfall.core.heightmap import HeightMap
from footfall.data.store import DemoStore
from footfall.experiments.executors import LocalPool
from footfall.experiments.reproduce import ReproduceConfig
from footfall.experiments.runs import RunJob, Runner
from footfall.learning.train import TrainingDemo
from footfall.sim.rollout import RolloutConfig
from footfall.terrain.saving import save_board

VALIDATION = range(7220, 7230)  # student_dagger.py's validation boards, 3 runs each
VAL_RUNS = 3


def main():
    out, folder, labels, first = (Path(a) for a in sys.argv[1:5])
    max_rounds = int(sys.argv[5]) if len(sys.argv) > 5 else 3
    out.mkdir(parents=True, exist_ok=True)
    config = ReproduceConfig()
    train = {f"train0{b}": str(folder / "terrain" / f"train0{b}.npz") for b in range(6)}
    val = {}
    for seed in VALIDATION:
        path = out / f"val{seed}.npz"
        if not path.exists():
            level = 0.9 if seed < 7225 else 1.0
            save_board([f"rocky:{level}", f"steps:{level}"], seed=seed, path=str(path))
        val[f"val{seed}"] = str(path)
    terrains = {}
    for path in [*train.values(), *val.values()]:
        hmap = HeightMap.load(path)
        terrains[hmap.content_hash()] = hmap
    over_walker = RolloutConfig(base="walker")
    with DemoStore(out / "pi.sqlite", create=True) as store:
        runner = Runner(store, terrains, LocalPool(2), None, print)

        def validate(tag, model):
            jobs = [RunJob(f"val/{tag}/{name}/s{s}", p, str(model), 1000 + s, config.walk)
                    for name, p in val.items() for s in range(VAL_RUNS)]
            runner.run(jobs, f"validate {tag}")
            return sum(store.runs(key_prefix=j.key)[0]["result"]["success"] for j in jobs)

        training = adopted_labels(folder, labels)
        model, crossed = first, validate("r0", first)
        print(f"round 0: {len(training)} labels, validation {crossed} / "
              f"{len(val) * VAL_RUNS}", flush=True)
        for r in range(1, max_rounds + 1):
            jobs = [RunJob(f"pi/r{r}/{name}/s{k}", p, str(model), 3000 + 10 * r + k,
                           config.walk, correct=True, expert=config.expert, teacher="rollout",
                           every_step=True, rollout=over_walker)
                    for name, p in train.items() for k in range(2)]
            runner.run(jobs, f"round {r} runs")
            new = sorted(store.demonstrations(source_prefix=f"run:pi/r{r}/"),
                         key=lambda d: (d.source.rsplit(":step:", 1)[0],
                                        int(d.source.rsplit(":step:", 1)[1])))
            training += [TrainingDemo.of(d, terrains[d.terrain_hash]) for d in new]
            path = out / f"round{r}.npz"
            if not path.exists():
                learn_as_adopted(folder, training, path, "refusals", "abs", threads=2)
            now = validate(f"r{r}", path)
            print(f"round {r}: {len(new)} new labels ({len(training)} in all), validation "
                  f"{now} / {len(val) * VAL_RUNS} (round {r - 1}: {crossed})", flush=True)
            model, stop, crossed = path, now <= crossed, now
            if stop:
                print(f"the gain stopped at round {r}", flush=True)
                break
        print("last function:", model, flush=True)


if __name__ == "__main__":
    main()
