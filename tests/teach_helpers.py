"""A teaching server on a real socket for tests: a store of logged runs, the server in a thread."""

from __future__ import annotations

import contextlib
import threading
import time

import uvicorn

from footfall.data.store import DemoStore
from footfall.teach.server import address, bind, create_app, new_token
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


@contextlib.contextmanager
def serving(service: TeachService):
    """Serve ``service`` on a free loopback port; yield (base URL, token, page address)."""
    token, sock = new_token(), bind()
    server = uvicorn.Server(uvicorn.Config(create_app(service, token), log_level="error",
                                           access_log=False, lifespan="off", ws="none"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the teaching server did not start")
        time.sleep(0.01)
    host, port = sock.getsockname()[:2]
    try:
        yield f"http://{host}:{port}", token, address(sock, token)
    finally:
        server.should_exit = True
        thread.join(20)
        service.close()
