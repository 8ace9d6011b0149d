"""Run many independent tasks on Dask and get the results back as they finish.

Shared by the dataset generator (``simulator.dataset``) and the analysis sweeps
(``simulator.analysis``). One job: take a function and a list of independent,
picklable tasks, run ``func(task)`` for each on a ``distributed.Client``, and
yield ``(index, result)`` pairs in completion order with a progress bar
(samples/s and ETA).

Where the work runs
-------------------
* default: a ``distributed.LocalCluster`` with ``n_workers`` worker *processes*,
  one thread each (the simulator is single-threaded numba code, so processes are
  what scale). The runner starts it and shuts it down when the iteration ends,
  is abandoned, or fails. It is started with :data:`LOCAL_CLUSTER_CONFIG`, which
  turns off Dask's diagnostics that nobody looks at in a batch run (the worker's
  statistical profiler, which samples the compute thread every 10 ms; the 20 ms
  event-loop watchdog, in every process; the 0.5 s system monitor). With two
  workers they burnt about 0.12 CPU-s per second in all (parent 0.045, workers
  0.036 each; 0.027 without them), CPU time that the workers' simulations lack
  when every core runs a worker. Its workers log the heartbeat that meets a scheduler
  already closing (``Failed to communicate with scheduler during heartbeat``, a
  race inside ``distributed``'s shutdown when a worker is busy in a task) as a
  warning without traceback (``simulator._dask_plugins``); the service's job
  cluster is started the same way (:func:`start_local_cluster`).
* ``scheduler_address="tcp://host:8786"``: an existing scheduler (for example
  the ``docker-compose.yml`` cluster). The runner connects a client, and closes
  only that client; the cluster is left running.
* ``client=``: a client the caller already holds; the runner closes nothing.

At most ``max_in_flight`` tasks are submitted at a time (default: four per
worker thread, at least 32), so a sweep of a million samples neither floods the scheduler
nor keeps finished results in memory: each result is yielded and then released.

Tasks are submitted, and (with scheduler-side queuing) started, in the order of
the iterable: a caller that knows which tasks are slow should put them first,
so that the end of the run is not one worker finishing a long task while the
others idle.

Example
-------
>>> from simulator.runner import run_tasks
>>> for i, value in run_tasks(math.factorial, [5, 3, 4], n_workers=2):  # doctest: +SKIP
...     print(i, value)                                                 # any order
0 120
2 24
1 6

``func`` must be importable by the workers (a module-level function of an
installed package, not a lambda or a function defined in ``__main__``) when the
workers are separate processes; tasks and results must be picklable.
"""
from __future__ import annotations

import logging
import os
import time
import uuid
from collections.abc import Callable, Iterable, Iterator
from typing import Any

__all__ = ["TaskError", "default_n_workers", "run_tasks", "start_local_cluster", "LOCAL_CLUSTER_CONFIG"]

#: Dask settings of the local cluster the runner starts (not applied to an existing
#: scheduler or client: those keep their own configuration). Memory limits, heartbeats
#: and work stealing keep their defaults.
LOCAL_CLUSTER_CONFIG: dict[str, Any] = {
    "distributed.worker.profile.enabled": False,        # dashboard profiler: samples every thread every 10 ms
    "distributed.admin.tick.interval": "1s",            # event-loop watchdog (default 20 ms, in every process)
    "distributed.admin.system-monitor.interval": "5s",  # dashboard CPU/memory/network graphs (default 0.5 s)
}


def start_local_cluster(n_workers: int, *, dashboard_address: str | None = ":0") -> tuple[Any, Any]:
    """A ``distributed.LocalCluster`` of ``n_workers`` one-thread worker processes and a client of it.

    Started with :data:`LOCAL_CLUSTER_CONFIG`, logs at ERROR, and ``simulator._dask_plugins.QuietHeartbeatRace``
    in every worker. The caller closes both (the client first). ``dashboard_address=None``: no dashboard.

    Returns
    -------
    (distributed.Client, distributed.LocalCluster)
    """
    import dask
    from distributed import Client, LocalCluster

    from ._dask_plugins import QuietHeartbeatRace

    # the nannies hand this configuration on to the worker processes they start
    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                               dashboard_address=dashboard_address, silence_logs=logging.ERROR)
    client = Client(cluster, set_as_default=False)
    try:
        client.register_plugin(QuietHeartbeatRace(), name=QuietHeartbeatRace.name)
    except BaseException:
        client.close()
        cluster.close()
        raise
    return client, cluster


class TaskError(RuntimeError):
    """A task raised: carries the task's ``index`` and chains the original exception."""

    def __init__(self, index: int, exc: BaseException):
        super().__init__(f"task {index} failed: {type(exc).__name__}: {exc}")
        self.index = index


def default_n_workers() -> int:
    """Number of worker processes used when none is given: the CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


def _validate(n_workers: int | None, scheduler_address: str | None, client: Any,
              max_in_flight: int | None) -> None:
    given = [name for name, v in (("n_workers", n_workers), ("scheduler_address", scheduler_address),
                                  ("client", client)) if v is not None]
    if len(given) > 1:
        raise ValueError(f"give at most one of n_workers, scheduler_address, client (got {', '.join(given)})")
    if n_workers is not None and (not isinstance(n_workers, int) or n_workers < 1):
        raise ValueError(f"n_workers must be a positive integer, got {n_workers!r}")
    if scheduler_address is not None and (not isinstance(scheduler_address, str) or not scheduler_address.strip()):
        raise ValueError(f"scheduler_address must be an address such as 'tcp://host:8786', got {scheduler_address!r}")
    if max_in_flight is not None and (not isinstance(max_in_flight, int) or max_in_flight < 1):
        raise ValueError(f"max_in_flight must be a positive integer, got {max_in_flight!r}")


def run_tasks(
    func: Callable[[Any], Any],
    tasks: Iterable[Any],
    *,
    n_workers: int | None = None,
    scheduler_address: str | None = None,
    client: Any = None,
    max_in_flight: int | None = None,
    progress: bool = True,
    desc: str = "samples",
    unit: str = "sample",
    total: int | None = None,
    connect_timeout_s: float = 30.0,
    on_ready: Callable[[], None] | None = None,
) -> Iterator[tuple[int, Any]]:
    """Run ``func(task)`` for every task on Dask; yield ``(index, result)`` as each completes.

    Parameters
    ----------
    func : callable
        Module-level function of one argument (importable on the workers).
    tasks : iterable
        Independent picklable task objects. ``index`` in the output is the
        task's position in this iterable (0-based). Consumed lazily.
    n_workers : int, optional
        Worker processes of the local cluster started by default (one thread
        each). Default: :func:`default_n_workers`.
    scheduler_address : str, optional
        Address of an existing scheduler, e.g. ``"tcp://127.0.0.1:8786"``,
        instead of a local cluster.
    client : distributed.Client, optional
        An existing client to use; it is not closed.
    max_in_flight : int, optional
        Maximum number of submitted, unfinished tasks. Default: four per worker
        thread, at least 32 (re-evaluated as workers join or leave).
    progress : bool
        Show a tqdm progress bar on stderr (rate in ``unit``/s and ETA).
    desc, unit : str
        Progress-bar label and unit.
    total : int, optional
        Number of tasks, for the progress bar's ETA when ``tasks`` has no
        ``len()``.
    connect_timeout_s : float
        How long to wait for ``scheduler_address`` to answer.
    on_ready : callable, optional
        Called once, without arguments, when the client is connected (a local
        cluster's worker processes started), just before the first task is
        submitted: lets the caller time start-up apart from the work.

    Yields
    ------
    (int, object)
        Task index and ``func``'s return value, in completion order.

    Raises
    ------
    TaskError
        When a task raises; its ``index`` names the task and the original
        exception is chained (``__cause__``). Unfinished tasks are cancelled.
    OSError
        When ``scheduler_address`` cannot be reached within ``connect_timeout_s``.
    """
    _validate(n_workers, scheduler_address, client, max_in_flight)
    from distributed import Client, as_completed
    from tqdm.auto import tqdm

    if total is None and hasattr(tasks, "__len__"):
        total = len(tasks)  # type: ignore[arg-type]

    cluster = None
    own_client = None
    if client is None:
        if scheduler_address is not None:
            own_client = Client(scheduler_address, timeout=connect_timeout_s, set_as_default=False)
        else:
            own_client, cluster = start_local_cluster(n_workers or default_n_workers())
        client = own_client

    bar = tqdm(total=total, desc=desc, unit=unit, disable=not progress, dynamic_ncols=True, smoothing=0.1)
    prefix = f"{getattr(func, '__name__', 'task')}-{uuid.uuid4().hex[:12]}"
    in_flight: dict[Any, int] = {}
    try:
        cached = {"at": -1e9, "value": 32}

        def limit() -> int:
            if max_in_flight is not None:
                return max_in_flight
            # re-read at most once a second: workers may join or leave an external cluster mid-run
            now = time.monotonic()
            if now - cached["at"] > 1.0:
                cached["value"] = max(32, 4 * sum(client.nthreads().values()))
                cached["at"] = now
            return int(cached["value"])

        task_iter = enumerate(tasks)
        pending = as_completed(loop=client.loop)

        def submit_next() -> bool:
            try:
                index, task = next(task_iter)
            except StopIteration:
                return False
            future = client.submit(func, task, key=f"{prefix}-{index}", pure=False)
            in_flight[future] = index
            pending.add(future)
            return True

        if on_ready is not None:
            on_ready()
        cap = limit()
        while len(in_flight) < cap and submit_next():
            pass
        for future in pending:
            index = in_flight.pop(future)
            if future.status == "error":
                exc = future.exception()
                raise TaskError(index, exc) from exc
            result = future.result()
            del future
            cap = limit()
            while len(in_flight) < cap and submit_next():
                pass
            bar.update(1)
            yield index, result
    finally:
        bar.close()
        for future in in_flight:
            future.cancel()
        in_flight.clear()
        if own_client is not None:
            own_client.close()
        if cluster is not None:
            cluster.close()
