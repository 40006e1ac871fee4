"""A student learned with a relative veto from demonstrations stored before they kept the judged
values: those recomputed (the walking expert behind the accepted teacher's veto). A lab script.

python student_learn_judged.py STORE PREFIX[,PREFIX...] OUT.npz FEATURES SUPERVISION [CANDIDATES]
"""
import sys
from dataclasses import replace

from footfall.data.store import DemoStore
from footfall.experiments.reproduce import ReproduceConfig
from footfall.expert.synthetic import SyntheticExpert
from footfall.learning.train import TrainingDemo, learn_model

store, prefixes, out, fs, sup = sys.argv[1:6]
tc = int(sys.argv[6]) if len(sys.argv) > 6 else 30
st = DemoStore(store, read_only=True)
demos = []
for p in prefixes.split(","):
    demos += st.demonstrations(source_prefix=p)
terr = {h: st.terrain(h) for h in {d.terrain_hash for d in demos}}
expert = SyntheticExpert(ReproduceConfig().expert)
tr = []
for d in demos:
    h = terr[d.terrain_hash]
    tr.append(replace(TrainingDemo.of(d, h), judged=expert.values(h, d.state, d.candidates)))
m = learn_model(tr, fs, "lambdarank", library_size=1000, training_candidates=tc, cv=5, seed=0,
                selection="min", template_budget=0.5 if fs != "terrain" else None,
                supervision=sup, veto=True, log=lambda s: print("   ", s, flush=True))
m.save(out)
print("saved", out, len(tr), m.info.get("seconds"))
