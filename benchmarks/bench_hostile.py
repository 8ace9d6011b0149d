"""Legitimate latency beside the worst hostile bodies of issue 44, against a quiet phase of the same run.

Starts ``rotordiag serve`` on 127.0.0.1 (loopback only) with two diagnosis workers and drives POST /diagnose with
the binary NPY form of bench_service.py's recording at concurrency 2 (the legitimate load), in two phases:

1. quiet: ``--duration`` seconds of the legitimate load alone;
2. hostile: right after it, the same load while one more client sends, one after the other, the bodies that killed or held the
   workers before issue 44: a 28.6 MB JSON channel of 1.5e7 numbers, a 20 MB one of 1e7 (both also as a batch),
   one of 2.2 M numbers (just under the value count, so it is decoded and refused by the schema), an HDF5 file
   of 190,000 one-element chunks, a CSV of 10^7 rows, and JSON/batch records with 5e-324 Hz.

Prints p50/p99/max of the legitimate requests in both phases and their ratio (target: hostile p99 <= 2 x quiet
p99), the hostile answers by status, the number of 5xx answers (target 0) and of diagnosis-worker deaths (the
workers' process ids before and after; target 0). Every phase is bounded by ``--duration``.

The hostile client sends one body after the other, ``--hostile-interval`` seconds apart (one hostile phase per
value; default 1 s, then back to back).

Usage: .venv/bin/python benchmarks/bench_hostile.py [--duration 15] [--hostile-interval 1 0]
"""
from __future__ import annotations

import argparse
import collections
import http.client
import io
import json
import multiprocessing as mp
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_failover import _diagnosis_workers  # noqa: E402
from bench_service import _drive_entry, payloads, recording, start_server, stop_server  # noqa: E402

CONCURRENCY = 2


def _multipart(name: str, data: bytes) -> tuple[str, bytes]:
    boundary = "benchhostileboundary"
    body = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"{name}\"\r\n"
            "Content-Type: application/octet-stream\r\n\r\n").encode() + data + f"\r\n--{boundary}--\r\n".encode()
    return f"multipart/form-data; boundary={boundary}", body


def hostile_bodies() -> list[tuple[str, str, str, bytes]]:
    """``(label, path, content type, body)`` of the issue's worst bodies."""
    import h5py

    def channel(n: int) -> bytes:
        head = b'{"sample_rate_hz": 4096.0, "channels": [{"bearing": 2, "angle_deg": 45.0, "units": "um", "data": ['
        return head + b",".join([b"1.5"] * n) + b"]}]}"

    j15, j10, j22 = channel(15_000_000), channel(10_000_000), channel(2_200_000)
    bio = io.BytesIO()
    with h5py.File(bio, "w") as f:
        f.create_dataset("waveforms", data=np.zeros((1, 190_000)), chunks=(1, 1))
        f.attrs["sample_rate_hz"] = 2048.0
    h5_type, h5 = _multipart("chunks.h5", bio.getvalue())
    csv_type, csv = _multipart("rows.csv", b"b2@45,b2@135\n" + b"1,2\n" * 10_000_000)
    tiny = json.dumps({"sample_rate_hz": 5e-324, "speed_rpm": 1800.0, "channels": [
        {"bearing": 2, "angle_deg": a, "units": "um", "data": [float(np.sin(i / 7.0 + a)) for i in range(4096)]}
        for a in (45.0, 135.0)]}).encode()
    js = "application/json"
    return [("json 1.5e7 values (28.6 MB)", "/diagnose", js, j15),
            ("json 1e7 values (20 MB)", "/diagnose", js, j10),
            ("batch of the 1e7 body", "/diagnose/batch", js, b'{"records": [' + j10 + b"]}"),
            ("json 2.2e6 values", "/diagnose", js, j22),
            ("hdf5 190,000 chunks", "/diagnose?bearings=2&angles_deg=45", h5_type, h5),
            ("csv 1e7 rows", "/diagnose?sample_rate_hz=2048", csv_type, csv),
            ("json 5e-324 Hz", "/diagnose", js, tiny),
            ("batch with a 5e-324 Hz record", "/diagnose/batch", js, b'{"records": [' + tiny + b"]}")]


def _hostile_loop(port: int, bodies, duration_s: float, interval_s: float, conn) -> None:
    """One client sending the hostile bodies in turn for ``duration_s``, ``interval_s`` apart (0: back to back):
    ``{label: Counter(status)}``."""
    seen: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    t_end = time.perf_counter() + duration_s
    i = 0
    while time.perf_counter() < t_end:
        label, path, ctype, body = bodies[i % len(bodies)]
        i += 1
        c = http.client.HTTPConnection("127.0.0.1", port, timeout=120)
        try:
            c.request("POST", path, body=body, headers={"Content-Type": ctype})
            r = c.getresponse()
            r.read()
            seen[label][r.status] += 1
        except (OSError, http.client.HTTPException) as exc:
            seen[label][f"connection error: {type(exc).__name__}"] += 1
        finally:
            c.close()
        time.sleep(interval_s)
    conn.send({k: dict(v) for k, v in seen.items()})
    conn.close()


def _phase(port: int, legit, duration_s: float, bodies=None, interval_s: float = 0.0):
    ctx = mp.get_context("spawn")
    parent, child = ctx.Pipe()
    p = ctx.Process(target=_drive_entry, args=((port, *legit, CONCURRENCY, duration_s), child))
    hp = hparent = None
    if bodies is not None:
        hparent, hchild = ctx.Pipe()
        hp = ctx.Process(target=_hostile_loop, args=(port, bodies, duration_s, interval_s, hchild))
        hp.start()
    p.start()
    lat, errors, wall = parent.recv()
    p.join()
    seen = None
    if hp is not None and hparent is not None:
        seen = hparent.recv()
        hp.join()
    return np.asarray(lat) * 1e3, errors, wall, seen


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=15.0, help="seconds per phase")
    ap.add_argument("--hostile-interval", type=float, nargs="+", default=[1.0, 0.0],
                    help="seconds between two hostile requests, one hostile phase each (0: back to back)")
    args = ap.parse_args()

    data, bearings, angles = recording()
    legit = payloads(data, bearings, angles)["binary"]
    bodies = hostile_bodies()
    tmp = Path(tempfile.mkdtemp(prefix="bench_hostile_"))
    server, port = start_server(tmp, {"ROTORDIAG_LOG_LEVEL": "critical", "ROTORDIAG_DIAGNOSIS_WORKERS": "2"},
                                quiet=True)
    try:
        _phase(port, legit, 3.0)                                            # warm-up
        workers = sorted(_diagnosis_workers(server.pid))
        print(f"2 diagnosis workers, legitimate load: concurrency {CONCURRENCY}, binary NPY body "
              f"{len(legit[2]) / 1e6:.2f} MB; {args.duration:g} s per phase; loopback 127.0.0.1; "
              f"cores available: {len(os.sched_getaffinity(0))}")
        print(f"{'phase':<12} {'requests':>8} {'errors':>6} {'req/s':>7} {'p50 ms':>7} {'p99 ms':>7} {'max ms':>7}")
        p99 = {}
        seen = None
        seen: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
        # each hostile phase right after a quiet one: the machine's own load drifts between phases
        phases = [p for i, v in enumerate(args.hostile_interval)
                  for p in ((f"quiet {i + 1}", None, 0.0), (f"hostile/{v:g}s", bodies, v))]
        for name, hostile, interval in phases:
            lat, errors, wall, got = _phase(port, legit, args.duration, hostile, interval)
            for label, counts in (got or {}).items():
                seen[label].update(counts)
            p50, p99[name] = np.percentile(lat, [50, 99])
            print(f"{name:<12} {lat.size:>8} {errors:>6} {lat.size / wall:>7.1f} {p50:>7.1f} {p99[name]:>7.1f} "
                  f"{lat.max():>7.1f}")
        after = sorted(_diagnosis_workers(server.pid))
        print("hostile answers over the hostile phases (status: count):")
        n5xx = 0
        for label, counts in seen.items():
            n5xx += sum(n for s, n in counts.items() if not isinstance(s, int) or s >= 500)
            print(f"  {label:<32} {dict(counts)}")
        deaths = len(set(workers) - set(after))
        print(f"hostile 5xx or connection errors: {n5xx}; legitimate errors: the 'errors' column; diagnosis workers "
              f"before {workers}, after {after}: {deaths} died")
        names = list(p99)
        for quiet, hostile in zip(names[::2], names[1::2]):
            print(f"{hostile} p99 / {quiet} p99: {p99[hostile] / p99[quiet]:.2f}  (target <= 2)")
    finally:
        stop_server(server)


if __name__ == "__main__":
    threading.excepthook = lambda a: None
    main()
