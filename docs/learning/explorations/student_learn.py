"""A student learned from stored demonstrations (the absolute veto's candidate (e) of
docs/learning/student.md). A lab script.

python student_learn.py STORE PREFIX[,PREFIX...] OUT.npz FEATURES SUPERVISION VETO(0/1) [CANDIDATES]
"""
import sys

from footfall.data.store import DemoStore
from footfall.learning.train import TrainingDemo, learn_model

store, prefixes, out, fs, sup, veto = sys.argv[1:7]
tc = int(sys.argv[7]) if len(sys.argv) > 7 else 30
st = DemoStore(store, read_only=True)
demos = []
for p in prefixes.split(","):
    demos += st.demonstrations(source_prefix=p)
terr = {h: st.terrain(h) for h in {d.terrain_hash for d in demos}}
tr = [TrainingDemo.of(d, terr[d.terrain_hash]) for d in demos]
m = learn_model(tr, fs, "lambdarank", library_size=1000, training_candidates=tc, cv=5, seed=0,
                selection="min", template_budget=0.5 if fs != "terrain" else None,
                supervision=sup, veto=veto == "1", log=lambda s: print("   ", s, flush=True))
m.save(out)
print("saved", out, len(tr), m.info.get("seconds"))
