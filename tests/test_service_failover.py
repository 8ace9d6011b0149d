"""The fault test of issue 47: two API replicas (real `rotordiag serve` processes on loopback) share a
PostgreSQL server and a data directory; the one running a retraining job is killed with SIGKILL (with its
local Dask cluster: the whole process group, as a lost host) while both serve a bounded /diagnose load.

Checked: the other replica takes the job over once its lease has run out and finishes it (one new model
version, attempt 2); every diagnosis answered 200 is stored exactly once under its own asset, a request
cut off by the kill is stored at most once, and no row is written twice; the failed requests are counted
and the worst latency reported."""
from __future__ import annotations

import threading
import time
from collections import Counter

from sqlalchemy import create_engine, func, select

from rotordiag.service.core.db import AssetDiagnosis, Job, normalize_url
from tests.fleet_util import bounded_load, request, start_replica
from tests.service_util import API_KEY, diagnose_json, shipped_or_tiny_registry, simulated_channels

LEASE_S = 4.0
POLL_S = 0.5
N_REQUESTS = 48
CONCURRENCY = 3

RETRAIN = {
    "sweep": {"design": {"n_samples": 24, "seed": 3},
              "operating": {"speed_rpm": {"min": 1600, "max": 2000}, "misalignment": {"min": 0.0, "max": 0.6}},
              "measurement": {"sample_rate_hz": 1024.0, "duration_revs": 12, "snr_db": 35.0},
              "simulation": {"transient_revs": 60, "samples_per_rev": 64, "record_revs_min": 12,
                             "classify_motion": False}},
    "training": {"seed": 1, "classifier": {"max_iter": 20, "min_samples_leaf": 2},
                 "regressor": {"max_iter": 20, "min_samples_leaf": 2}, "evaluation": {"n_splits": 3}},
    "activate": False, "report_cases": 1,
}


def _job(base: str, job_id: str) -> dict:
    status, job = request(f"{base}/jobs/{job_id}", timeout=10)
    assert status == 200, job
    return job


def test_replica_killed_during_retrain_under_load(tmp_path, postgres):
    url = postgres.new_database()
    env = {"ROTORDIAG_DATABASE_URL": url, "ROTORDIAG_DATA_DIR": str(tmp_path / "data"),
           "ROTORDIAG_API_KEY": API_KEY, "ROTORDIAG_SHIPPED_REGISTRY_DIR": str(shipped_or_tiny_registry()),
           "ROTORDIAG_JOB_LEASE_S": str(LEASE_S), "ROTORDIAG_JOB_POLL_S": str(POLL_S),
           "ROTORDIAG_DIAGNOSIS_WORKERS": "0", "ROTORDIAG_DASK_LOCAL_WORKERS": "1"}
    fs, channels = simulated_channels(misalignment=0.2, record_revs=40)
    template = diagnose_json(fs, channels, speed_rpm=1800.0)
    replicas = [start_replica("replica-a", tmp_path / "a", env)]   # seeds the shared registry first
    replicas.append(start_replica("replica-b", tmp_path / "b", env))
    try:
        a, b = replicas
        _, before = request(a.base + "/models")
        status, job = request(a.base + "/models/retrain", RETRAIN, headers={"X-API-Key": API_KEY})
        assert status == 202, job
        job_id = job["id"]
        # wait until the job runs and has simulated a few samples
        deadline = time.monotonic() + 300
        while not ((j := _job(a.base, job_id))["status"] == "running" and j["progress"] >= 0.1):
            assert j["status"] in ("queued", "running") and time.monotonic() < deadline, j
            time.sleep(0.2)
        holder = next(r for r in replicas if r.name == j["lease_owner"])
        survivor = next(r for r in replicas if r is not holder)

        killed_at: list[float] = []

        def kill_midway(done: int) -> None:
            if done == N_REQUESTS // 3 and not killed_at:
                killed_at.append(time.monotonic())
                threading.Thread(target=holder.kill_host).start()

        load = bounded_load(replicas, lambda i: {**template, "asset_id": f"load-{i:04d}"}, N_REQUESTS,
                            CONCURRENCY, on_progress=kill_midway, headers={"X-API-Key": API_KEY})
        assert killed_at and not holder.alive()
        print(f"\n/diagnose load: {load.sent} sent, {len(load.ok)} ok, {len(load.failed)} failed "
              f"(all on {holder.name}: {Counter(r for _, r, _ in load.failed)}), worst latency "
              f"{load.worst_s:.2f} s, p50 {load.quantile_s(0.5):.2f} s")
        assert all(r == holder.name for _, r, _ in load.failed), load.failed
        assert len(load.failed) <= CONCURRENCY, load.failed     # only those in flight at the kill
        assert len(load.ok) + len(load.failed) == N_REQUESTS

        # the survivor takes the job over and finishes it
        deadline = time.monotonic() + 600
        taken_s = None
        while (j := _job(survivor.base, job_id))["status"] not in ("succeeded", "failed"):
            if taken_s is None and j["lease_owner"] == survivor.name:
                taken_s = time.monotonic() - killed_at[0]
            assert time.monotonic() < deadline, j
            time.sleep(0.3)
        print(f"job {job_id}: {j['status']} after takeover ({j['attempts']} attempts); claimed by "
              f"{survivor.name} {taken_s if taken_s is None else round(taken_s, 1)} s after the kill "
              f"(lease {LEASE_S} s, poll {POLL_S} s)")
        assert j["status"] == "succeeded", j
        assert j["attempts"] == 2 and j["lease_owner"] == survivor.name
        assert j["result"]["dataset"]["n_samples"] == 24 and j["result"]["dataset"]["complete"]
        assert j["result"]["dataset"]["n_done_before"] >= 1          # the dead holder's samples were kept
        _, after = request(survivor.base + "/models")
        new = sorted(set(v["version"] for v in after["versions"]) - set(v["version"] for v in before["versions"]))
        assert new == [j["result"]["version"]]                        # registered once
        # no diagnosis lost or written twice
        engine = create_engine(normalize_url(url))
        with engine.connect() as conn:
            rows = conn.execute(select(AssetDiagnosis.id, AssetDiagnosis.asset_id)).all()
            assert conn.execute(select(func.count()).select_from(Job)).scalar_one() == 1
        engine.dispose()
        per_asset = Counter(asset for _, asset in rows)
        assert max(per_asset.values()) == 1, [a for a, n in per_asset.items() if n > 1]
        by_id = dict(rows)
        for i, _, diag_id in load.ok:
            assert by_id.get(diag_id) == f"load-{i:04d}"                # answered => stored, under its asset
        unanswered_stored = sum(per_asset[f"load-{i:04d}"] for i, _, _ in load.failed)
        assert len(rows) == len(load.ok) + unanswered_stored
        print(f"history rows: {len(rows)} ({len(load.ok)} answered, {unanswered_stored} stored by the killed "
              "replica before it could answer), none twice")
    finally:
        for r in replicas:
            r.stop()
