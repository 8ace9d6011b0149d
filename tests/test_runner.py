"""Tests of simulator.runner: a real distributed LocalCluster with worker processes."""
from __future__ import annotations

import math
import os
import socket
import time

import pytest

from rotordiag.simulator.runner import TaskError, run_tasks


def pid_after_sleep(seconds: float) -> int:
    """Task for the tests: sleep, then report which process ran it."""
    time.sleep(seconds)
    return os.getpid()


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def _wait_dead(pids, timeout_s=15.0) -> set[int]:
    deadline = time.monotonic() + timeout_s
    alive = {p for p in pids if _alive(p)}
    while alive and time.monotonic() < deadline:
        time.sleep(0.1)
        alive = {p for p in alive if _alive(p)}
    return alive


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    c = Client(cluster, set_as_default=False)
    yield c
    c.close()
    cluster.close()


def test_every_task_once_with_the_right_answer(client):
    tasks = list(range(25))
    got = dict(run_tasks(math.factorial, tasks, client=client, progress=False))
    assert sorted(got) == tasks
    assert all(got[i] == math.factorial(i) for i in tasks)
    # an existing client is not closed by the runner
    assert client.status == "running"


def test_identical_tasks_are_not_deduplicated(client):
    got = list(run_tasks(math.factorial, [6] * 10, client=client, progress=False))
    assert sorted(i for i, _ in got) == list(range(10))
    assert {v for _, v in got} == {720}


def test_failure_names_the_task_and_chains_the_cause(client):
    with pytest.raises(TaskError) as info:
        list(run_tasks(math.sqrt, [4.0, 9.0, -1.0, 16.0], client=client, progress=False))
    assert info.value.index == 2
    assert isinstance(info.value.__cause__, ValueError)
    assert "task 2 failed" in str(info.value)


def test_tasks_are_pulled_lazily_with_a_bounded_window(client):
    pulled = 0

    def tasks():
        nonlocal pulled
        for i in range(40):
            pulled += 1
            yield i

    yielded = 0
    for _ in run_tasks(math.factorial, tasks(), client=client, max_in_flight=3, progress=False):
        yielded += 1
        # at most 3 submitted-but-unreported tasks, plus the one just refilled
        assert pulled - yielded <= 3
    assert yielded == pulled == 40


def test_local_cluster_uses_worker_processes_and_is_shut_down():
    got = dict(run_tasks(pid_after_sleep, [0.2] * 8, n_workers=2, progress=False))
    pids = set(got.values())
    assert len(got) == 8
    assert os.getpid() not in pids
    assert 1 <= len(pids) <= 2
    assert _wait_dead(pids) == set(), "worker processes of the runner's own cluster still alive"


def dask_setting(name: str):
    """Task for the tests: a Dask setting as the worker process sees it."""
    import dask

    return dask.config.get(name)


def test_own_cluster_runs_with_the_lean_config_and_reports_ready():
    from rotordiag.simulator.runner import LOCAL_CLUSTER_CONFIG

    events = []
    names = list(LOCAL_CLUSTER_CONFIG)
    for i, value in run_tasks(dask_setting, names, n_workers=1, progress=False,
                              on_ready=lambda: events.append("ready")):
        events.append("result")
        assert value == LOCAL_CLUSTER_CONFIG[names[i]], names[i]
    assert events == ["ready"] + ["result"] * len(names)


def test_abandoned_iteration_shuts_the_cluster_down():
    gen = run_tasks(pid_after_sleep, [0.1] * 50, n_workers=1, progress=False)
    _, pid = next(gen)
    assert _alive(pid)
    gen.close()
    assert _wait_dead({pid}) == set()


def test_progress_bar_reports_rate(client, capsys):
    list(run_tasks(math.factorial, range(5), client=client, total=5, desc="demo", unit="sample"))
    err = capsys.readouterr().err
    assert "demo" in err and "5/5" in err and "sample/s" in err


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"n_workers": 0}, "n_workers must be a positive integer"),
        ({"n_workers": 2, "scheduler_address": "tcp://127.0.0.1:8786"}, "at most one of"),
        ({"scheduler_address": "  "}, "scheduler_address must be an address"),
        ({"max_in_flight": 0}, "max_in_flight must be a positive integer"),
    ],
)
def test_bad_arguments_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        next(run_tasks(math.factorial, [1], progress=False, **kwargs))


def test_unreachable_scheduler_is_a_clear_error():
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(OSError):
        next(run_tasks(math.factorial, [1], scheduler_address=f"tcp://127.0.0.1:{port}",
                       connect_timeout_s=1.0, progress=False))


# ------------------------------------------------------------------ the shutdown race's heartbeat, quietly
def _log_a_failed_heartbeat() -> str:
    """On a worker: log a failed heartbeat exactly as ``distributed.Worker.heartbeat`` does, with warnings on,
    and return what a handler wrote."""
    import io
    import logging

    from rotordiag.simulator._dask_plugins import HEARTBEAT_RACE_MESSAGE

    log = logging.getLogger("distributed.worker")
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    handler.setFormatter(logging.Formatter("%(levelname)s %(message)s"))
    level = log.level
    log.addHandler(handler)
    log.setLevel(logging.WARNING)
    try:
        try:
            raise OSError("in <TCP (closed) ConnectionPool.heartbeat_worker>: Stream is closed")
        except OSError:
            log.exception(HEARTBEAT_RACE_MESSAGE + ".")
        log.error("another error", exc_info=(ValueError, ValueError("kept"), None))
    finally:
        log.removeHandler(handler)
        log.setLevel(level)
    return stream.getvalue()


def test_the_heartbeat_race_filter_drops_the_traceback_only():
    import logging

    from rotordiag.simulator._dask_plugins import HEARTBEAT_RACE_MESSAGE, HeartbeatRaceFilter

    def record(msg, exc=True):
        try:
            raise OSError("Stream is closed")
        except OSError as e:
            info = (type(e), e, e.__traceback__) if exc else None
        return logging.LogRecord("rotordiag.test.heartbeat", logging.ERROR, __file__, 1, msg, (), info)

    f = HeartbeatRaceFilter()
    logging.getLogger("rotordiag.test.heartbeat").setLevel(logging.WARNING)
    r = record(HEARTBEAT_RACE_MESSAGE + ".")
    assert f.filter(r) and r.levelno == logging.WARNING and r.levelname == "WARNING" and r.exc_info is None
    other = record("Unexpected exception during heartbeat. Closing worker.")
    assert f.filter(other) and other.levelno == logging.ERROR and other.exc_info is not None
    logging.getLogger("rotordiag.test.heartbeat").setLevel(logging.ERROR)   # a logger at errors only: dropped
    assert not f.filter(record(HEARTBEAT_RACE_MESSAGE + "."))


def test_a_started_local_clusters_workers_log_the_heartbeat_race_without_a_traceback(client):
    from rotordiag.simulator.runner import start_local_cluster

    plain = list(client.run(_log_a_failed_heartbeat).values())     # a cluster started without the plugin
    assert all("Traceback" in w and "OSError: in <TCP (closed)" in w for w in plain), plain
    own, cluster = start_local_cluster(1, dashboard_address=None)   # as the service's job cluster and the runner's
    try:
        (written,) = own.run(_log_a_failed_heartbeat).values()
        assert "WARNING Failed to communicate with scheduler during heartbeat." in written, written
        assert "OSError" not in written and "Traceback" not in written, written
        assert "ERROR another error\nValueError: kept" in written, written     # other records as they were
    finally:
        own.close()
        cluster.close()
    assert cluster.status.name == "closed"
