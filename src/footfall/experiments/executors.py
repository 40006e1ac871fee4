"""Where a batch of runs is walked: a local process pool, or a Ray cluster.

Every batch of runs -- ``walk-many``, the reproduction's correction rounds,
evaluation and difficulty sweep, the walking ablation -- hands its
:class:`~footfall.experiments.runs.RunJob` list to one :class:`Executor`,
which walks each job once and yields ``(job, (record, demonstrations))`` in
the order the runs finish. Executors only walk: the driver that consumes
them is the only process that writes a store, so the store's guarantees
(one transaction per run, a run key stored once, resumable) hold whatever
walks the runs. The same job gives the same record on either executor: a
run depends only on its job (board, reward, seed, settings).

Two executors are registered in :data:`EXECUTORS`:

* ``local`` -- a pool of spawned worker processes on this machine (one core
  per run), or the runs one after another in this process for one process.
* ``ray`` -- tasks on a Ray cluster (``pip install 'footfall[ray]'``): an
  existing cluster at ``--ray-address``, or one started here on the loopback
  interface. Board and model files are shipped through Ray's object store,
  so the nodes need footfall installed but not the driver's files. A run
  whose worker or node dies is walked again by Ray (``max_retries``); a run
  that raises fails the batch, as it does on the local pool.

A new executor is a class with ``name``, ``map(jobs)`` and ``close()``,
registered with :func:`register_executor`.
"""

from __future__ import annotations

import hashlib
import logging
import os
import socket
import tempfile
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import as_completed
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol

from footfall.core.atomic import atomic_path
from footfall.core.compute import usable_cores, worker_pool
from footfall.core.errors import FootfallError
from footfall.core.registry import Registry
from footfall.experiments.runs import RunJob, RunOutput, execute

RAY_RETRIES = 3  # times Ray walks a run again whose worker process or node died


class Executor(Protocol):
    """Walks run jobs somewhere and yields each with its output as it finishes."""

    name: str

    def map(self, jobs: Sequence[RunJob]) -> Iterator[tuple[RunJob, RunOutput]]:
        """Walk every job once; yield ``(job, (record, demonstrations))`` in finishing order.

        Closing the iterator early (an interrupted driver) cancels the runs not yet
        finished.
        """
        ...

    def close(self) -> None:
        """Release what the executor holds (worker processes, a cluster connection)."""
        ...


EXECUTORS: Registry[Callable[..., Executor]] = Registry("executor")
"""Where batches are walked: name -> factory ``(processes=..., address=...) -> Executor``."""


def register_executor(name: str, factory: Callable[..., Executor]) -> None:
    """Make ``factory(processes=..., address=...)`` available as ``--executor NAME``."""
    EXECUTORS.register(name, factory)


def make_executor(name: str = "local", processes: int | None = None,
                  address: str | None = None) -> Executor:
    """The executor ``name`` (``local`` or ``ray``).

    ``processes``: parallel runs of the local pool, or the CPUs of a Ray cluster
    started here [default: the usable cores]; ``address``: an existing Ray
    cluster's address (``ray`` only).

    Raises
    ------
    FootfallError
        For an unknown executor, an address for the local pool or a bad count.
    """
    factory = EXECUTORS.get(name)
    if processes is not None and (isinstance(processes, bool) or not isinstance(processes, int)
                                  or processes < 1):
        raise FootfallError(f"processes must be an integer >= 1, got {processes!r}")
    return factory(processes=processes, address=address)


# -------------------------------------------------------------------- local
@dataclass
class LocalPool:
    """Runs in spawned worker processes on this machine, one core each."""

    processes: int | None = None  # parallel runs [default: the usable cores]
    name: str = "local"

    def __post_init__(self) -> None:
        self.processes = self.processes or usable_cores()

    def map(self, jobs: Sequence[RunJob]) -> Iterator[tuple[RunJob, RunOutput]]:
        jobs = list(jobs)
        if self.processes <= 1 or len(jobs) <= 1:
            for job in jobs:
                yield job, execute(job)
            return
        with worker_pool(min(self.processes, len(jobs))) as pool:
            futures = {pool.submit(execute, job): job for job in jobs}
            for f in as_completed(futures):
                yield futures[f], f.result()

    def close(self) -> None:
        pass


def _local_pool(processes: int | None = None, address: str | None = None) -> LocalPool:
    if address is not None:
        raise FootfallError("--ray-address is for --executor ray")
    return LocalPool(processes)


register_executor("local", _local_pool)


# ---------------------------------------------------------------------- ray
LOOPBACK_ENV = {
    # A cluster started here listens on the loopback interface only (Ray's switch for it).
    "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0",
    "RAY_USAGE_STATS_ENABLED": "0",
}


def _import_ray() -> Any:
    try:
        import ray  # an optional extra (footfall[ray]), and heavy
    except ImportError:
        raise FootfallError("the ray executor needs Ray: pip install 'footfall[ray]'") from None
    return ray


def shipped_file(data: bytes, suffix: str, folder: str | os.PathLike | None = None) -> Path:
    """A file with the bytes ``data`` on this node, named by their hash (written once, atomically).

    ``folder``: where such files are kept [default: footfall-ray in the temporary folder].
    """
    base = Path(folder) if folder is not None else Path(tempfile.gettempdir()) / "footfall-ray"
    base.mkdir(parents=True, exist_ok=True)
    path = base / f"{hashlib.sha256(data).hexdigest()}{suffix}"
    if not path.exists():
        with atomic_path(path) as tmp:
            tmp.write_bytes(data)
    return path


def walk_shipped(job: RunJob, terrain: bytes, model: bytes | None) -> RunOutput:
    """One run on a Ray worker: the job's board and model from the bytes Ray shipped."""
    local = replace(job, terrain=str(shipped_file(terrain, Path(job.terrain).suffix)),
                    model=None if model is None
                    else str(shipped_file(model, Path(job.model).suffix)))
    return execute(local)


@dataclass
class RayCluster:
    """Runs as Ray tasks (one CPU each) on the cluster at ``address``, or on one started here."""

    processes: int | None = None  # CPUs of a cluster started here [default: the usable cores]
    address: str | None = None  # an existing cluster (HOST:PORT, ray://HOST:PORT, auto); None: start one
    name: str = "ray"
    _ray: Any = field(default=None, repr=False)

    def _connect(self) -> Any:
        if self._ray is not None:
            return self._ray
        ray = _import_ray()
        if not ray.is_initialized():
            options = dict(log_to_driver=False, logging_level=logging.ERROR,
                           configure_logging=True)
            if self.address is None:
                for key, value in LOOPBACK_ENV.items():
                    os.environ.setdefault(key, value)
                options.update(num_cpus=self.processes or usable_cores(),
                               include_dashboard=False)
            else:
                _check_answers(self.address)
                options["address"] = self.address
            try:
                ray.init(**options)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                where = self.address or "a local cluster"
                first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
                raise FootfallError(f"could not connect to Ray at {where}: {first}") from None
        self._ray = ray
        return ray

    def map(self, jobs: Sequence[RunJob]) -> Iterator[tuple[RunJob, RunOutput]]:
        jobs = list(jobs)
        if not jobs:
            return
        ray = self._connect()
        task = ray.remote(walk_shipped).options(num_cpus=1, max_retries=RAY_RETRIES,
                                                retry_exceptions=False)
        shipped: dict[str, Any] = {}  # file path -> object ref of its bytes, each put once

        def put(path: str | None) -> Any:
            if path is None:
                return None
            if path not in shipped:
                try:
                    shipped[path] = ray.put(Path(path).read_bytes())
                except OSError as exc:
                    raise FootfallError(f"{path}: cannot read ({exc.strerror})") from None
            return shipped[path]

        refs = {task.remote(job, put(job.terrain), put(job.model)): job for job in jobs}
        pending = list(refs)
        try:
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                for ref in ready:
                    yield refs[ref], _ray_result(ray, ref)
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)

    def close(self) -> None:
        if self._ray is not None:
            self._ray.shutdown()
            self._ray = None


CONNECT_TIMEOUT = 5.0  # [s] longest wait for a cluster's address to answer


def _check_answers(address: str) -> None:
    """Refuse an address where nothing answers, at once (Ray itself would retry for minutes).

    A loopback address also keeps this driver on loopback (Ray would otherwise speak to
    the cluster through this machine's network address).
    """
    if address == "auto":
        return  # Ray finds the cluster this machine runs
    host, sep, port = address.removeprefix("ray://").rpartition(":")  # ray:// - Ray Client
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise FootfallError(f"--ray-address must be HOST:PORT, ray://HOST:PORT or auto, "
                            f"got {address!r}")
    try:
        with socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT):
            pass
    except OSError as exc:
        raise FootfallError(f"no Ray cluster answers at {address} "
                            f"({exc.strerror or type(exc).__name__})") from None
    if host in ("127.0.0.1", "localhost", "::1"):
        for key, value in LOOPBACK_ENV.items():
            os.environ.setdefault(key, value)


def _ray_result(ray: Any, ref: Any) -> RunOutput:
    """A finished task's output; a run that raised raises its own error here, as on the pool."""
    try:
        return ray.get(ref)
    except ray.exceptions.RayTaskError as exc:
        cause = getattr(exc, "cause", None)
        if isinstance(cause, FootfallError):
            raise FootfallError(str(cause)) from None
        raise
    except ray.exceptions.WorkerCrashedError:
        raise FootfallError(f"a Ray worker died {RAY_RETRIES + 1} times walking one run; "
                            "the runs stored so far are kept") from None


def _ray_cluster(processes: int | None = None, address: str | None = None) -> RayCluster:
    if address is not None and not address.strip():
        raise FootfallError("--ray-address is empty")
    return RayCluster(processes, address)


register_executor("ray", _ray_cluster)
