"""The student's validation walks (docs/learning/student.md): DAgger rounds -- the student walks
the reproduction's six training boards (seed 0), the accepted teacher labels every step with its
verdict, the student is learned again -- each round's function walked on the validation boards
(rocky:D steps:D, board seeds 7220-7229, D 0.9 and 1.0) with the teacher and the hand-tuned
reward as references. EXTRA_MODELS="name=model.npz,..." walks other models on the same runs;
FIRST_ROUND=99 walks only those. A lab script, not part of footfall's interface.

python student_dagger.py OUT ROUNDS RUNS_PER_BOARD FEATURES SUPERVISION [VAL_RUNS]
"""
import json
import sys
import time
from pathlib import Path

from footfall.data.store import DemoStore
from footfall.experiments.executors import LocalPool
from footfall.experiments.reproduce import ReproduceConfig
from footfall.experiments.runs import RunJob, Runner
from footfall.experiments.workspace import open_workspace, seed_streams
from footfall.learning.train import TrainingDemo, learn_model
from footfall.terrain.saving import save_board


def main():
    import os
    out = Path(sys.argv[1]); rounds = int(sys.argv[2]); per = int(sys.argv[3])
    fs = sys.argv[4]; sup = sys.argv[5]; val_runs = int(sys.argv[6]) if len(sys.argv) > 6 else 4
    out.mkdir(parents=True, exist_ok=True)
    saved = out / "ws" / "config.json"  # a folder walked before keeps its settings
    config = ReproduceConfig.from_dict(json.loads(saved.read_text())) if saved.exists() \
        else ReproduceConfig()
    ws = open_workspace(out / "ws", config)
    streams = seed_streams(config)
    train = [n for n in ws.paths if n.startswith("train")]
    # validation boards: the teacher's design boards of docs/learning/teacher.md at 0.7-0.9
    val = {}
    for S in range(7220, 7230):
        D = 0.9 if S < 7225 else 1.0
        p = out / f"val{S}.npz"
        if not p.exists():
            save_board([f"rocky:{D}", f"steps:{D}"], seed=S, path=str(p))
        val[f"val{S}"] = str(p)
    from footfall.core.heightmap import HeightMap
    terrains = dict(ws.by_hash)
    for p in val.values():
        h = HeightMap.load(p); terrains[h.content_hash()] = h
    store = DemoStore(out / "dagger.sqlite", create=True)
    runner = Runner(store, terrains, LocalPool(2), None, print)
    walkc = config.walk

    def validate(tag, model=None, judge=False):
        jobs = [RunJob(f"val/{tag}/{name}/s{s}", p, model, 1000 + s, walkc, expert=config.expert,
                       judge=judge, teacher="accepted")
                for name, p in val.items() for s in range(val_runs)]
        runner.run(jobs, f"validate {tag}")
        rs = [store.runs(key_prefix=j.key)[0] for j in jobs]
        ok = [r["result"]["success"] for r in rs]
        return sum(ok), len(ok), ok

    t0 = time.time()
    ref_t = validate("teacher", judge=True)
    ref_h = validate("hand")
    print(f"teacher {ref_t[0]}/{ref_t[1]}  hand {ref_h[0]}/{ref_h[1]}", flush=True)
    for item in filter(None, os.environ.get("EXTRA_MODELS", "").split(",")):
        tag, path = item.split("=")
        v = validate(tag, path)
        print(f"EXTRA {tag}: {v[0]}/{v[1]}", flush=True)
    model = None
    log = []
    for r in range(int(os.environ.get("FIRST_ROUND", 0)), rounds):
        tag = "hand" if model is None else f"r{r}"
        jobs = [RunJob(f"label/r{r}/{name}/s{k}", str(ws.paths[name]), model,
                       streams.seed_for("correction runs", r, i, k), walkc, True, config.margin, None,
                       config.expert, inspect_seed=0, teacher="accepted", every_step=True)
                for i, name in enumerate(train) for k in range(per)]
        runner.run(jobs, f"round {r} label runs")
        demos = []
        for q in range(r + 1):
            demos += store.demonstrations(source_prefix=f"run:label/r{q}/")
        crossed = sum(store.runs(key_prefix=j.key)[0]["result"]["success"] for j in jobs)
        training = [TrainingDemo.of(d, terrains[d.terrain_hash]) for d in demos]
        t1 = time.time()
        m = learn_model(training, fs, "lambdarank", library_size=1000, training_candidates=30,
                        cv=5, seed=0, selection="min", template_budget=0.5 if fs != "terrain" else None,
                        supervision=sup, log=lambda s: print("   ", s, flush=True))
        model = str(out / f"{fs}-{sup}-r{r + 1}.npz")
        m.save(model)
        lt = time.time() - t1
        v = validate(f"{fs}-{sup}-r{r + 1}", model)
        log.append({"round": r, "label_runs_crossed": crossed, "labels": len(demos), "learn_s": lt,
                    "val": v[0], "of": v[1]})
        both = sum(a and not b for a, b in zip(v[2], ref_t[2])), sum(b and not a for a, b in zip(v[2], ref_t[2]))
        print(f"ROUND {r}: {len(demos)} labels, learn {lt:.0f}s, walked {crossed}/{len(jobs)}; "
              f"validation {v[0]}/{v[1]} (teacher {ref_t[0]}, hand {ref_h[0]}; vs teacher only-student {both[0]} only-teacher {both[1]}) "
              f"elapsed {time.time() - t0:.0f}s", flush=True)
        json.dump(log, open(out / f"log-{fs}-{sup}.json", "w"), indent=1)


if __name__ == "__main__":
    main()
