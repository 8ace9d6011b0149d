"""Latency while a diagnosis worker is killed, against steady state (issue 12, item 4).

Starts ``rotordiag serve`` with two diagnosis workers, drives POST /diagnose (the binary NPY
form of bench_service.py's recording) at concurrency 4 from a separate process, and measures:

1. steady: ``--duration`` seconds, no kill;
2. kill: ``--duration`` seconds during which one diagnosis worker is SIGKILLed ``--kill-after``
   seconds in (its in-flight requests are retried on the warm worker; a replacement starts).

Prints p50/p99/max latency and errors of both phases, the ratio of the p99s (target <= 2), and
how long the replacement took to become ready. Every request must succeed (0 errors).

Usage: .venv/bin/python benchmarks/bench_failover.py [--duration 8] [--kill-after 2] [--repeat 1]
"""
from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_service import _drive_entry, _tree, payloads, recording, start_server, stop_server  # noqa: E402

CONCURRENCY = 4


def _diagnosis_workers(server_pid: int) -> list[int]:
    """Child processes of the server started by multiprocessing's spawn (the diagnosis workers)."""
    out = []
    for pid in _tree(server_pid)[1:]:
        try:
            cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ")
        except OSError:
            continue
        if b"spawn_main" in cmd and b"resource_tracker" not in cmd and b"forkserver" not in cmd:
            out.append(pid)
    return out


def _phase(port, body_args, duration_s, kill_after_s, server_pid):
    ctx = mp.get_context("spawn")
    parent, child = ctx.Pipe()
    p = ctx.Process(target=_drive_entry, args=((port, *body_args, CONCURRENCY, duration_s), child))
    p.start()
    ready_s = None
    killed = None
    if kill_after_s is not None:
        time.sleep(kill_after_s)
        before = _diagnosis_workers(server_pid)
        killed = before[0]
        os.kill(killed, signal.SIGKILL)
        t_kill = time.perf_counter()
        # the replacement is ready when the server lists a new worker and /health (which asks every
        # ready worker) has been answered by it; approximate with: new pid present and 1 s of CPU time used
        while time.perf_counter() - t_kill < 120:
            now = _diagnosis_workers(server_pid)
            new = [q for q in now if q not in before]
            if new and _cpu_s(new[0]) > 1.0 and _settled(new[0]):
                ready_s = time.perf_counter() - t_kill
                break
            time.sleep(0.05)
    lat, errors, wall = parent.recv()
    p.join()
    return np.asarray(lat) * 1e3, errors, wall, killed, ready_s


def _cpu_s(pid: int) -> float:
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


def _settled(pid: int) -> bool:
    """The process is waiting (state S), not computing: a started worker waiting for requests."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "S"
    except OSError:
        return False


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=8.0, help="seconds per phase")
    ap.add_argument("--kill-after", type=float, default=2.0, help="seconds into the kill phase")
    ap.add_argument("--repeat", type=int, default=1, help="steady/kill pairs")
    args = ap.parse_args()

    data, bearings, angles = recording()
    path, ctype, body = payloads(data, bearings, angles)["binary"]
    tmp = Path(tempfile.mkdtemp(prefix="bench_failover_"))
    server, port = start_server(tmp, {"ROTORDIAG_LOG_LEVEL": "critical", "ROTORDIAG_DIAGNOSIS_WORKERS": "2"},
                                quiet=True)
    try:
        _phase(port, (path, ctype, body), 3.0, None, server.pid)            # warm-up
        print(f"2 diagnosis workers, concurrency {CONCURRENCY}, binary NPY body {len(body) / 1e6:.2f} MB, "
              f"{args.duration:g} s per phase; cores available: {len(os.sched_getaffinity(0))}")
        print(f"{'phase':<8} {'requests':>8} {'errors':>6} {'req/s':>7} {'p50 ms':>7} {'p99 ms':>7} {'max ms':>7}")
        ratios = []
        for _ in range(args.repeat):
            rows = {}
            for name, kill in (("steady", None), ("kill", args.kill_after)):
                lat, errors, wall, killed, ready_s = _phase(port, (path, ctype, body), args.duration, kill, server.pid)
                p50, p99 = np.percentile(lat, [50, 99])
                rows[name] = p99
                print(f"{name:<8} {lat.size:>8} {errors:>6} {lat.size / wall:>7.1f} {p50:>7.1f} {p99:>7.1f} "
                      f"{lat.max():>7.1f}" + (f"   (killed worker {killed} at {kill:g} s; replacement ready after "
                                              f"~{ready_s:.1f} s)" if killed and ready_s else
                                              (f"   (killed worker {killed})" if killed else "")))
            ratios.append(rows["kill"] / rows["steady"])
            time.sleep(3.0)   # let the replacement finish warming before the next pair
        print("p99 during a kill / steady p99: " + ", ".join(f"{r:.2f}" for r in ratios) + "  (target <= 2)")
    finally:
        stop_server(server)


if __name__ == "__main__":
    threading.excepthook = lambda a: None
    main()
