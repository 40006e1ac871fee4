"""The kinds of supervision on the same labels (docs/learning/student.md): a reproduction's
templates + features function learned again from exactly its labels, in its order, with its
seed and settings, but another supervision and veto. A lab script, not part of footfall's
interface; walk the models with student_dagger.py's EXTRA_MODELS.

python student_supervision.py REPRODUCTION_FOLDER OUT.npz SUPERVISION VETO [THREADS] [LABELS]

VETO: 0 none, 1 the learned veto as the labels give it (relative where they keep the judged
values), abs an absolute veto (the judged values dropped: a classifier of the refusals).
LABELS: another teacher's labels of the same steps (a store, e.g. demos correct --teacher
rollout of the reproduction's runs): the labels of the same sources, in the same order; those it
lacks are reported and left out.
"""
import json
import sys
from dataclasses import replace
from pathlib import Path

from footfall.data.store import DemoStore
from footfall.learning.model import FootholdModel
from footfall.learning.train import TrainingDemo, learn_model


def adopted_labels(folder: Path, labels: Path) -> list:
    """The adopted function's labelled steps (models/both.npz info.sources), in its order, as
    the store ``labels`` holds them (the reproduction's own, or another teacher's of the same
    steps: those it lacks are left out), each with its board."""
    sources = FootholdModel.load(folder / "models" / "both.npz").info["sources"]
    with DemoStore(labels, read_only=True) as store:
        by_source = {d.source: d for d in store.demonstrations()}
        demos = [by_source[s] for s in sources if s in by_source]
        maps = {h: store.terrain(h) for h in {d.terrain_hash for d in demos}}
    print(f"{len(demos)} of the adopted function's {len(sources)} labelled steps", flush=True)
    return [TrainingDemo.of(d, maps[d.terrain_hash]) for d in demos]


def learn_as_adopted(folder: Path, training: list, out, supervision: str, veto: str,
                     threads: int = 1) -> FootholdModel:
    """Templates + features learned from ``training`` with the reproduction's settings and the
    adopted function's seed, but ``supervision`` and ``veto`` (see the module); saved to ``out``."""
    config = json.loads((folder / "config.json").read_text())
    seed = FootholdModel.load(folder / "models" / "both.npz").info["seed"]
    if veto == "abs":
        training = [replace(t, judged=None) for t in training]
    rms = config.get("final_bandwidth_rms")
    model = learn_model(training, "both", config["learner"], library_size=config["library_size"],
                        training_candidates=config["training_candidates"],
                        bandwidth_rms=None if rms is None else (rms,) * 3, cv=config["cv"],
                        seed=seed, selection=config["selection"],
                        folds=config["folds"], template_budget=config["template_budget"],
                        supervision=supervision, veto=veto in ("1", "abs"),
                        library_capped=config["library_capped"], threads=threads,
                        log=lambda s: print("   ", s, flush=True))
    model.save(out)
    print("saved", out, len(training), f"{model.info['seconds']:.0f} s", flush=True)
    return model


def main():
    folder, out, supervision, veto = Path(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4]
    threads = int(sys.argv[5]) if len(sys.argv) > 5 else 1
    labels = Path(sys.argv[6]) if len(sys.argv) > 6 else folder / "reproduce.sqlite"
    learn_as_adopted(folder, adopted_labels(folder, labels), out, supervision, veto, threads)


if __name__ == "__main__":
    main()
