"""Every command of the ``footfall`` command line, added to its group (:mod:`footfall.cli.entry`).

Every command lives in the module of its group (terrain, features, demos, store, learning,
walking, experiments, bench, teach) and is added here.
"""

from __future__ import annotations

from footfall.cli.bench import bench
from footfall.cli.demos import demos
from footfall.cli.entry import cli
from footfall.cli.experiments import ablation, demo, offline, reproduce, study
from footfall.cli.features import features
from footfall.cli.learning import learn, rank_eval_cmd
from footfall.cli.store import store
from footfall.cli.teach import teach
from footfall.cli.terrain import terrain
from footfall.cli.walking import walk_cmd, walk_many_cmd

for _command in (terrain, features, demos, store, learn, rank_eval_cmd, walk_cmd,
                 walk_many_cmd, offline, reproduce, study, ablation, demo, bench, teach):
    cli.add_command(_command)
