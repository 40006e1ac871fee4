"""The imitation gap (footfall.experiments.imitation) of a model's validation walks against the
teacher's, from student_dagger.py's store. A lab script.

python student_gap.py STORE TAG
"""
import sys

from footfall.data.store import DemoStore
from footfall.experiments.imitation import imitation_gap
from footfall.experiments.reproduce import ReproduceConfig
from footfall.expert.teachers import TEACHERS

st = DemoStore(sys.argv[1], read_only=True)
tag = sys.argv[2]
c = ReproduceConfig(); fs = c.walk.footstep
teacher = TEACHERS.get("accepted").expert(c.expert, fs.bias_weight, fs.lead)
pairs = []
maps = {}
for r in st.runs(key_prefix=f"val/{tag}/"):
    k = r["key"].split("/", 2)[2]
    t = st.runs(key_prefix=f"val/teacher/{k}")
    if t:
        a, b = st.run(r["id"]), st.run(t[0]["id"])
        maps.setdefault(a.terrain_hash, st.terrain(a.terrain_hash))
        pairs.append((a, b))
g = imitation_gap(pairs, maps, teacher, 2.0)
print({k: v for k, v in g.items() if k != "runs"})
for r in g["runs"]:
    print(r)
