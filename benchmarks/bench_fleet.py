"""Fleet load figures (issue 47, item 5): diagnosis throughput with one and with two API replicas on
loopback (the ratio, in one run), and the asset-history write rate the PostgreSQL store sustains.

1. Throughput. A throw-away PostgreSQL cluster (Debian's server binaries, fsync on), replicas started
   as ``rotordiag serve`` processes sharing it and one data directory, each with
   ``--workers-per-replica`` diagnosis worker processes. For 1 and then 2 replicas, ``--concurrency``
   clients per replica (a separate client process per replica, persistent connections, the binary NPY
   body of bench_service.py with an ``asset_id``, so every diagnosis also writes a history row) send
   POST /diagnose for ``--duration`` seconds. Prints requests/s, p50/p99 latency, errors, and the
   ratio 2 replicas / 1 replica, with the CPUs this machine has (the replicas share them: on a
   machine with fewer free cores than diagnosis workers the ratio measures the cores, not the
   service).
2. History writes. ``service.store.store_diagnosis`` (one transaction per row, with the shipped
   history retention applied in it, as the API writes them; 50 assets) from 1 and from 8 threads for
   ``--duration`` seconds, on PostgreSQL with ``synchronous_commit`` on (the default: each commit
   waits for its WAL flush) and off, on PostgreSQL without retention, and on the SQLite file for
   comparison. The on/off pair shows the share of the commit's flush to disk, the retention row the
   share of the per-write retention queries.

Usage: .venv/bin/python benchmarks/bench_fleet.py [--duration 10] [--concurrency 2] [--workers-per-replica 1]
"""
from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import sys
import tempfile
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

API_KEY = "bench"

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT))

from bench_service import _drive_entry, payloads, recording  # noqa: E402

from tests.fleet_util import request, start_replica  # noqa: E402
from tests.pg_util import postgres_cluster  # noqa: E402


def _throughput(replicas, body_args, concurrency: int, duration_s: float) -> dict:
    """Drive every replica at once (one client process each); returns the combined figures."""
    ctx = mp.get_context("spawn")
    procs = []
    path, ctype, body = body_args
    for i, rep in enumerate(replicas):
        parent, child = ctx.Pipe()
        p = ctx.Process(target=_drive_entry, args=((rep.port, f"{path}&asset_id=bench-{rep.name}", ctype, body,
                                                    concurrency, duration_s, {"X-API-Key": API_KEY}), child))
        p.start()
        procs.append((p, parent))
    lat: list[float] = []
    errors = 0
    wall = 0.0
    for p, parent in procs:
        l, e, w = parent.recv()
        p.join()
        lat += l
        errors += e
        wall = max(wall, w)
    lat_ms = np.array(lat) * 1e3
    return {"n": len(lat), "errors": errors, "rps": len(lat) / wall if wall else 0.0,
            "p50_ms": float(np.percentile(lat_ms, 50)) if len(lat) else float("nan"),
            "p99_ms": float(np.percentile(lat_ms, 99)) if len(lat) else float("nan")}


def _history_rate(url: str, threads: int, duration_s: float, sync_commit: bool = True,
                  retention: bool = True) -> float:
    """Rows per second ``store_diagnosis`` sustains from ``threads`` threads (one transaction per row), with
    the shipped history retention applied by each write, or (``retention=False``) none."""
    from sqlalchemy import event

    from rotordiag.service import store
    from rotordiag.service.core.db import init_db, make_engine

    engine = make_engine(url)
    if not sync_commit:
        @event.listens_for(engine, "connect")
        def _async_commit(dbapi_connection, _record):
            cur = dbapi_connection.cursor()
            cur.execute("SET synchronous_commit TO off")
            cur.close()
            dbapi_connection.commit()
    from rotordiag.service.core.config import Settings

    # the shipped retention settings: each write also applies the asset's retention, as the API's do
    off = dict(history_keep_recordings=0, history_keep_days=0, history_summary_days=0, history_max_rows=0)
    state = SimpleNamespace(sessions=init_db(engine), settings=Settings(_env_file=None, **({} if retention else off)))
    verdict = {"model_version": "v0001", "severity": "moderate", "misalignment": 0.21,
               "misalignment_interval": [0.15, 0.27], "speed_rpm": 1800.0, "ood": False,
               "key_features": {f"f{i}": float(i) for i in range(24)}, "warnings": [], "bearings": []}
    signature = {f"b{b}_x1_amp_um_pp": 40.0 + b for b in range(1, 5)}
    counts = [0] * threads
    stop = threading.Event()

    def writer(k: int) -> None:
        while not stop.is_set():
            store.store_diagnosis(state, f"hist-{k % 50}", "plant", verdict, signature)
            counts[k] += 1

    ts = [threading.Thread(target=writer, args=(k,)) for k in range(threads)]
    t0 = time.perf_counter()
    for t in ts:
        t.start()
    time.sleep(duration_s)
    stop.set()
    for t in ts:
        t.join()
    rate = sum(counts) / (time.perf_counter() - t0)
    engine.dispose()
    return rate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0, help="seconds per measurement")
    ap.add_argument("--concurrency", type=int, default=2, help="client connections per replica")
    ap.add_argument("--workers-per-replica", type=int, default=1, help="diagnosis worker processes per replica")
    args = ap.parse_args()

    from tests.service_util import shipped_or_tiny_registry

    print(f"machine: {os.cpu_count()} CPUs, usable {len(os.sched_getaffinity(0))}, "
          f"load average {os.getloadavg()[0]:.1f} at start")
    data, bearings, angles = recording()
    body_args = payloads(data, bearings, angles)["binary"]
    with postgres_cluster(durable=True) as pg, tempfile.TemporaryDirectory(prefix="bench-fleet-") as tmp:
        url = pg.new_database()
        env = {"ROTORDIAG_DATABASE_URL": url, "ROTORDIAG_DATA_DIR": str(Path(tmp) / "data"),
               "ROTORDIAG_API_KEY": API_KEY, "ROTORDIAG_SHIPPED_REGISTRY_DIR": str(shipped_or_tiny_registry()),
               "ROTORDIAG_DIAGNOSIS_WORKERS": str(args.workers_per_replica), "ROTORDIAG_LOG_LEVEL": "warning"}
        replicas = [start_replica("r1", Path(tmp) / "r1", env)]
        replicas.append(start_replica("r2", Path(tmp) / "r2", env))
        try:
            _throughput(replicas, body_args, args.concurrency, 2.0)          # warm both (model, numba)
            print(f"\n/diagnose (binary NPY, 8 channels x 16384 points, with asset_id: one history row each), "
                  f"{args.concurrency} client(s) per replica, {args.workers_per_replica} diagnosis worker(s) per "
                  f"replica, {args.duration:g} s each, PostgreSQL fsync on")
            print(f"{'replicas':>8} {'req/s':>8} {'p50 ms':>8} {'p99 ms':>8} {'errors':>7} {'requests':>9}")
            res = {}
            for n in (1, 2):
                r = res[n] = _throughput(replicas[:n], body_args, args.concurrency, args.duration)
                print(f"{n:>8} {r['rps']:8.1f} {r['p50_ms']:8.0f} {r['p99_ms']:8.0f} {r['errors']:7d} {r['n']:9d}")
            print(f"ratio 2 replicas / 1 replica: {res[2]['rps'] / res[1]['rps']:.2f} "
                  f"(load average {os.getloadavg()[0]:.1f} now)")
            stored = sum(request(f"{replicas[0].base}/assets/bench-{r.name}/history?limit=10000")[1].get("count", 0)
                         for r in replicas)
            print(f"history rows stored by the runs (warm-up included): {stored}")
        finally:
            for rep in replicas:
                rep.stop()

        print(f"\nhistory writes (service.store.store_diagnosis, one transaction per row), {args.duration:g} s each")
        print(f"{'store':<50} {'threads':>7} {'rows/s':>9}")
        for label, u, sync, keep in (
                ("PostgreSQL, synchronous_commit on", None, True, True),
                ("PostgreSQL, synchronous_commit off", None, False, True),
                ("PostgreSQL, synchronous_commit on, no retention", None, True, False),
                ("SQLite (WAL, synchronous=NORMAL)", f"sqlite:///{Path(tmp) / 'h.sqlite3'}", True, True)):
            for threads in (1, 8):
                rate = _history_rate(u or pg.new_database(), threads, args.duration, sync, keep)
                print(f"{label:<50} {threads:>7} {rate:9.0f}")


if __name__ == "__main__":
    main()
