"""API replicas as real ``rotordiag serve`` processes on loopback, sharing one database and one data
directory, and a bounded request load against them (tests/test_service_failover.py,
benchmarks/bench_fleet.py).

Each replica runs in its own session (process group), so that killing the group with SIGKILL takes
the replica and every process it started (its local Dask cluster, diagnosis workers) down at once,
as a host failure would.
"""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Replica:
    name: str
    port: int
    proc: subprocess.Popen
    log_path: Path

    @property
    def base(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def alive(self) -> bool:
        return self.proc.poll() is None

    def kill_host(self) -> None:
        """SIGKILL the replica and every process it started (its process group)."""
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.proc.wait(30)

    def stop(self) -> None:
        """SIGINT (a graceful stop), then SIGKILL of the group after 30 s."""
        if self.alive():
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                pass
        self.kill_host()

    def log(self) -> str:
        return self.log_path.read_text(errors="replace") if self.log_path.exists() else ""


def start_replica(name: str, workdir: Path, env_extra: dict[str, str], timeout_s: float = 120.0) -> Replica:
    """``rotordiag serve`` on a free loopback port; returns once /health answers 200."""
    port = free_port()
    env = dict(os.environ, ROTORDIAG_REPLICA_ID=name, **env_extra)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env.setdefault(var, "1")
    exe = Path(sys.executable).parent / "rotordiag"
    workdir.mkdir(parents=True, exist_ok=True)
    log_path = workdir / f"{name}.log"
    with open(log_path, "wb") as log:
        proc = subprocess.Popen([str(exe), "serve", "--host", "127.0.0.1", "--port", str(port)], cwd=workdir,
                                env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    rep = Replica(name, port, proc, log_path)
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        if not rep.alive():
            raise RuntimeError(f"replica {name} exited with {proc.returncode}:\n{rep.log()[-4000:]}")
        try:
            status, _ = request(rep.base + "/health", timeout=5)
            if status == 200:
                return rep
        except OSError:
            pass
        time.sleep(0.2)
    rep.kill_host()
    raise RuntimeError(f"replica {name} did not become healthy in {timeout_s} s:\n{rep.log()[-4000:]}")


def request(url: str, body: bytes | dict | None = None, headers: dict[str, str] | None = None,
            timeout: float = 60.0, method: str | None = None) -> tuple[int, dict]:
    """One HTTP request; returns (status, JSON body). Connection failures raise OSError."""
    data = json.dumps(body).encode() if isinstance(body, dict) else body
    hdrs = dict(headers or {})
    if isinstance(body, dict):
        hdrs["Content-Type"] = "application/json"
    req = urllib.request.Request(url, data=data, headers=hdrs, method=method)
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, json.loads(r.read() or b"{}")
    except urllib.error.HTTPError as exc:
        try:
            payload = json.loads(exc.read() or b"{}")
        except ValueError:
            payload = {}
        return exc.code, payload


@dataclass
class LoadResult:
    """What a bounded load saw: per request (index, replica, outcome, latency)."""

    sent: int = 0
    ok: list[tuple[int, str, int]] = field(default_factory=list)        # (index, replica, diagnosis_id)
    failed: list[tuple[int, str, str]] = field(default_factory=list)    # (index, replica, error)
    latencies_s: list[float] = field(default_factory=list)              # of every request, failed ones too
    wall_s: float = 0.0

    @property
    def worst_s(self) -> float:
        return max(self.latencies_s, default=0.0)

    def quantile_s(self, q: float) -> float:
        xs = sorted(self.latencies_s)
        return xs[min(len(xs) - 1, int(q * len(xs)))] if xs else 0.0


def bounded_load(replicas: list[Replica], make_body, n_requests: int, concurrency: int,
                 on_progress=None, mark_down: bool = True, headers: dict[str, str] | None = None) -> LoadResult:
    """Send ``n_requests`` POST /diagnose (body ``make_body(i)``) from ``concurrency`` threads, round robin
    over ``replicas``, as a load balancer would: a replica that refused a connection or dropped one is
    marked down and the requests after it go to the others (the failed request is counted, not retried).
    ``on_progress(done)`` is called after each answer; ``headers`` go with every request (the API key, so
    that the diagnoses are stored)."""
    res = LoadResult()
    lock = threading.Lock()
    down: set[str] = set()
    counter = iter(range(n_requests))

    def worker() -> None:
        while True:
            with lock:
                i = next(counter, None)
                if i is None:
                    return
                live = [r for r in replicas if r.name not in down] or replicas
                rep = live[i % len(live)]
            t0 = time.monotonic()
            try:
                status, out = request(rep.base + "/diagnose", make_body(i), headers=headers, timeout=120)
                err = None if status == 200 else f"HTTP {status}: {str(out)[:200]}"
            except OSError as exc:
                status, out, err = 0, {}, f"{type(exc).__name__}: {exc}"
            dt_s = time.monotonic() - t0
            with lock:
                res.latencies_s.append(dt_s)
                if err is None:
                    res.ok.append((i, rep.name, int(out["diagnosis_id"]) if "diagnosis_id" in out else -1))
                else:
                    res.failed.append((i, rep.name, err))
                    if status == 0 and mark_down:
                        down.add(rep.name)
                done = len(res.latencies_s)
            if on_progress is not None:
                on_progress(done)

    t0 = time.monotonic()
    threads = [threading.Thread(target=worker) for _ in range(concurrency)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    res.sent = n_requests
    res.wall_s = time.monotonic() - t0
    return res
