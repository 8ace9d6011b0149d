"""Load benchmark of POST /diagnose over loopback.

Starts ``rotordiag serve`` (one uvicorn process, a fresh data directory with the
shipped model), then drives it from a *separate* process with C persistent
connections for a bounded time at several concurrencies, for the JSON and the
binary (NPY, float32) forms of one recording of 4 bearings x 2 probes x 16,384
samples (a simulated default plant, 1800 r/min, Δ = 0.2, 4096 Hz). Prints
p50/p99 latency, requests/s, error count, the server's peak RSS, and the ratio
of the HTTP p50 to the in-process diagnosis time (features + verdict, no HTTP) —
the floor a user calling the library directly would see.

Targets (2 cores, client and server sharing them): binary p99 <= 50 ms, >= 150 req/s, 0 errors.

Usage: .venv/bin/python benchmarks/bench_service.py [--duration 10] [--concurrency 1 4 8]
"""
from __future__ import annotations

import argparse
import io
import json
import multiprocessing as mp
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

N_POINTS = 16_384
SAMPLE_RATE_HZ = 4096.0
SPEED_RPM = 1800.0


def recording():
    """(channels (8, N_POINTS) float64 µm, bearings, angles) of a simulated default plant."""
    from rotordiag.simulator import Plant, simulate

    revs = int(np.ceil(N_POINTS / SAMPLE_RATE_HZ * SPEED_RPM / 60.0)) + 1
    res = simulate(Plant.default(), SPEED_RPM, 0.2, 0.05, mechanism="rigid", transient_revs=200,
                   record_revs=revs, sample_rate_hz=SAMPLE_RATE_HZ)
    d = res.journal_displacements_m[:N_POINTS] * 1e6
    rows, bearings, angles = [], [], []
    for b in range(1, 5):
        for a in (45.0, 135.0):
            t = np.deg2rad(a)
            rows.append(d[:, b - 1, 0] * np.cos(t) + d[:, b - 1, 1] * np.sin(t))
            bearings.append(b)
            angles.append(a)
    data = np.array(rows)
    assert data.shape == (8, N_POINTS), data.shape
    return data, bearings, angles


def payloads(data, bearings, angles):
    body_json = json.dumps({
        "sample_rate_hz": SAMPLE_RATE_HZ, "speed_rpm": SPEED_RPM,
        "channels": [{"bearing": b, "angle_deg": a, "units": "um", "data": [round(float(v), 4) for v in row]}
                     for b, a, row in zip(bearings, angles, data)]}).encode()
    buf = io.BytesIO()
    np.save(buf, data.astype(np.float32))
    query = (f"/diagnose?sample_rate_hz={SAMPLE_RATE_HZ:g}&speed_rpm={SPEED_RPM:g}"
             f"&bearings={','.join(map(str, bearings))}&angles_deg={','.join(f'{a:g}' for a in angles)}")
    return {
        "json": ("/diagnose", "application/json", body_json),
        "binary": (query, "application/octet-stream", buf.getvalue()),
    }


def _worker(port, path, ctype, body, duration_s, out_q, start_evt, headers=None):
    import http.client

    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    lat, errors = [], 0
    start_evt.wait()
    t_end = time.perf_counter() + duration_s
    while time.perf_counter() < t_end:
        t0 = time.perf_counter()
        try:
            conn.request("POST", path, body=body, headers={"Content-Type": ctype, **(headers or {})})
            r = conn.getresponse()
            r.read()
            ok = r.status == 200
        except (OSError, http.client.HTTPException):
            ok = False
            conn.close()
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
        dt = time.perf_counter() - t0
        if ok:
            lat.append(dt)
        else:
            errors += 1
    conn.close()
    out_q.put((lat, errors))


def drive(port, path, ctype, body, concurrency, duration_s, headers=None):
    """Run in a separate process: ``concurrency`` threads, each with one persistent connection (``headers``:
    extra request headers, e.g. the API key that stores a diagnosis with an ``asset_id``)."""
    import queue
    import threading

    q: queue.Queue = queue.Queue()
    start = threading.Event()
    threads = [threading.Thread(target=_worker, args=(port, path, ctype, body, duration_s, q, start, headers))
               for _ in range(concurrency)]
    for t in threads:
        t.start()
    t0 = time.perf_counter()
    start.set()
    for t in threads:
        t.join()
    wall = time.perf_counter() - t0
    lat, errors = [], 0
    while not q.empty():
        l, e = q.get()
        lat += l
        errors += e
    return lat, errors, wall


def _drive_entry(args, conn):
    conn.send(drive(*args))
    conn.close()


def peak_rss_mib(pid: int) -> dict[str, float]:
    """Peak resident set (VmHWM), MiB, of the server process and of each of its child processes
    (the diagnosis workers; Dask job workers when a job ran)."""
    def hwm(p: int) -> float:
        try:
            for line in Path(f"/proc/{p}/status").read_text().splitlines():
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
        except OSError:
            pass
        return 0.0

    tree = _tree(pid)
    out = {"server": hwm(pid)}
    for c in tree[1:]:
        out[f"child {c}"] = hwm(c)
    return out


def _tree(pid: int) -> list[int]:
    """The server process and its child processes."""
    children = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            children += [int(c) for c in (task / "children").read_text().split()]
        except OSError:
            pass
    return [pid] + sorted(set(children))


def _mem_mib(pid: int) -> tuple[float, float]:
    """(RSS, PSS) of one process, MiB. PSS shares the pages several processes map (the numeric
    libraries the diagnosis workers all load) among them, so its sum over processes is the memory
    the service really takes; the sum of RSS counts shared pages once per process."""
    rss = pss = 0.0
    try:
        for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
            if line.startswith("Rss:"):
                rss = int(line.split()[1]) / 1024
            elif line.startswith("Pss:"):
                pss = int(line.split()[1]) / 1024
    except OSError:
        pass
    return rss, pss


class MemorySampler:
    """Samples the server tree's total RSS and PSS every ``period_s`` in a thread; keeps the peaks."""

    def __init__(self, pid: int, period_s: float = 0.5) -> None:
        import threading

        self.pid, self.period_s = pid, period_s
        self.peak_rss = self.peak_pss = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            mem = [_mem_mib(p) for p in _tree(self.pid)]
            self.peak_rss = max(self.peak_rss, sum(m[0] for m in mem))
            self.peak_pss = max(self.peak_pss, sum(m[1] for m in mem))

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()


def start_server(tmp: Path, env_extra: dict[str, str], quiet: bool = False) -> tuple[subprocess.Popen, int]:
    """``rotordiag serve`` on a free local port with its data under ``tmp``; returns once /health is 200."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = dict(os.environ, ROTORDIAG_DATA_DIR=str(tmp / "data"), ROTORDIAG_API_KEY="bench", **env_extra)
    exe = Path(sys.executable).parent / "rotordiag"
    server = subprocess.Popen([str(exe), "serve", "--host", "127.0.0.1", "--port", str(port)], cwd=tmp, env=env,
                              stderr=subprocess.DEVNULL if quiet else None)
    for _ in range(300):
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=2) as r:
                if r.status == 200:
                    return server, port
        except OSError:
            time.sleep(0.2)
    server.terminate()
    raise SystemExit("server did not become healthy")


def stop_server(server: subprocess.Popen) -> None:
    """Stop a server from :func:`start_server` (SIGINT, then kill after 30 s)."""
    server.send_signal(signal.SIGINT)
    try:
        server.wait(timeout=30)
    except subprocess.TimeoutExpired:
        server.kill()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0, help="seconds per (form, concurrency)")
    ap.add_argument("--concurrency", type=int, nargs="+", default=[1, 4, 8])
    ap.add_argument("--forms", nargs="+", default=["binary", "json"], choices=["binary", "json"])
    args = ap.parse_args()

    data, bearings, angles = recording()
    bodies = payloads(data, bearings, angles)

    # in-process floor: the same recording through features + verdict, no HTTP
    from rotordiag.features import ProbeChannel, Recording
    from rotordiag.service.core.config import Settings
    from rotordiag.service.inference import ModelStore

    tmp = Path(tempfile.mkdtemp(prefix="bench_service_"))
    store = ModelStore.open(Settings(data_dir=tmp / "inproc", _env_file=None))
    rec = Recording(sample_rate_hz=SAMPLE_RATE_HZ, speed_rpm=SPEED_RPM, channels=[
        ProbeChannel(bearing=b, angle_deg=a, units="um", data=row.astype(np.float32).astype(np.float64))
        for b, a, row in zip(bearings, angles, data)])
    store.diagnose(rec)
    ts = []
    for _ in range(30):
        t0 = time.perf_counter()
        store.diagnose(rec)
        ts.append(time.perf_counter() - t0)
    inproc_ms = 1e3 * float(np.median(ts))

    server, port = start_server(tmp, {"ROTORDIAG_LOG_LEVEL": "warning"})
    try:
        print(f"recording: 4 bearings x 2 probes x {N_POINTS} samples; body sizes: "
              f"json {len(bodies['json'][2]) / 1e6:.2f} MB, binary (NPY float32) {len(bodies['binary'][2]) / 1e6:.2f} MB")
        print(f"in-process diagnosis (features + verdict, no HTTP): median {inproc_ms:.1f} ms")
        print(f"cores available: {len(os.sched_getaffinity(0))}; duration {args.duration:g} s per row\n")
        print(f"{'form':<7} {'conc':>4} {'requests':>8} {'errors':>6} {'req/s':>8} {'p50 ms':>8} {'p99 ms':>8} "
              f"{'p50/in-proc':>11}")
        ctx = mp.get_context("spawn")
        sampler = MemorySampler(server.pid)
        for form in args.forms:
            path, ctype, body = bodies[form]
            # warm-up (numba caches, model load in every diagnosis worker)
            drive_args = (port, path, ctype, body, 4, 3.0)
            parent, child = ctx.Pipe()
            p = ctx.Process(target=_drive_entry, args=(drive_args, child))
            p.start(); parent.recv(); p.join()
            for c in args.concurrency:
                parent, child = ctx.Pipe()
                p = ctx.Process(target=_drive_entry, args=((port, path, ctype, body, c, args.duration), child))
                p.start()
                lat, errors, wall = parent.recv()
                p.join()
                lat_ms = 1e3 * np.asarray(lat)
                p50 = float(np.percentile(lat_ms, 50)) if lat else float("nan")
                p99 = float(np.percentile(lat_ms, 99)) if lat else float("nan")
                print(f"{form:<7} {c:>4} {len(lat):>8} {errors:>6} {len(lat) / wall:>8.1f} {p50:>8.1f} {p99:>8.1f} "
                      f"{p50 / inproc_ms:>11.2f}")
        sampler.stop()
        print(f"\nserver and its worker processes under load, sampled every 0.5 s: peak total PSS "
              f"{sampler.peak_pss:.0f} MiB (the memory they take), peak total RSS {sampler.peak_rss:.0f} MiB "
              f"(shared library pages counted once per process)")
        rss = peak_rss_mib(server.pid)
        print(f"peak RSS (VmHWM) per process, MiB: sum {sum(rss.values()):.0f} = "
              + ", ".join(f"{k} {v:.0f}" for k, v in rss.items()))
    finally:
        stop_server(server)


if __name__ == "__main__":
    main()
