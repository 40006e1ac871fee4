"""A teaching server on a real socket for tests: a store of logged runs, the server in a thread."""

from __future__ import annotations

from footfall.data.store import DemoStore
from footfall.teach.server import serving_in_thread
from footfall.teach.service import TeachService
from test_runlog import _run
from test_store import terrain


def store_of_runs(path, runs=3, steps=8):
    """A store holding ``runs`` logged runs of ``steps`` steps each on one test board."""
    hm = terrain()
    with DemoStore(path, create=True) as store:
        store.add_terrain(hm)
        for r in range(runs):
            store.add_run(_run(hm, n_steps=steps, key=f"test/{r}", seed=r))
    return path


def serving(service: TeachService):
    """Serve ``service`` on a free loopback port; yield (base URL, token, page address)."""
    return serving_in_thread(service)
