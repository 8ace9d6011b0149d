"""Several replicas on one database (issue 47), on SQLite and on a real PostgreSQL server: the store's
reads and writes, jobs claimed exactly once, a lease renewed by its holder and taken over when it runs
out, a stale holder fenced off, jobs shared out between two running replicas, and the API on
PostgreSQL."""
from __future__ import annotations

import threading
import time
from collections import Counter
from types import SimpleNamespace

import pytest
from sqlalchemy import select

from rotordiag.service.core.db import Job, init_db, make_engine
from rotordiag.service.jobs import JobLost, JobManager
from tests.service_util import make_settings


def _manager(tmp_path, url: str, replica: str, **overrides) -> JobManager:
    settings = make_settings(tmp_path, database_url=url, replica_id=replica, **overrides)
    return JobManager(settings, init_db(make_engine(url)), models=None)


def _queue(manager: JobManager, n: int) -> list[str]:
    manager.register("dataset", lambda params, ctx: {})
    return [manager.submit("dataset", {"i": i}).id for i in range(n)]


# --- store ----------------------------------------------------------------------------------------

def test_store_reads_and_writes(tmp_path, database_url):
    from rotordiag.service import store
    from rotordiag.service.core.db import AssetBaseline

    state = SimpleNamespace(sessions=init_db(make_engine(database_url)), settings=make_settings(tmp_path))
    ids = []
    for i in range(4):
        verdict = {"model_version": "v0001", "severity": "low", "misalignment": 0.1 * i,
                   "misalignment_interval": [0.0, 0.2 + 0.1 * i], "speed_rpm": 1800.0, "ood": False,
                   "key_features": {"h2": float(i)},
                   "baseline": {"compared": True, "changed": i == 3, "evidence": [1, 2]} if i >= 2 else None}
        ids.append(store.store_diagnosis(state, "unit-1", "north", verdict, signature={"amp_um_pp": 10.0 + i}))
    assert ids == sorted(ids) and len(set(ids)) == 4
    store.store_diagnosis(state, "unit-2", None, {"severity": "none", "misalignment": "n/a"})
    with state.sessions() as s:
        hist = store.asset_history(s, "unit-1", limit=3, since=None)
        assert [r.id for r in hist] == ids[1:]                       # latest three, oldest first
        assert hist[-1].change == {"compared": True, "changed": True} and hist[-1].alarm is True
        assert hist[0].change is None and hist[0].alarm is None
        assert hist[-1].misalignment_high == pytest.approx(0.5)
        assert store.get_diagnosis(s, "unit-2", ids[0]) is None      # another asset's row
        assert store.get_diagnosis(s, "unit-1", ids[0]).signature == {"amp_um_pp": 10.0}
        assert [r.id for r in store.first_diagnoses(s, "unit-1", 2)] == ids[:2]
        assert dict(store.latest_changes(s)) == {"unit-1": {"compared": True, "changed": True}}
    for n in (1, 2):
        store.put_baseline(state, AssetBaseline(asset_id="unit-1", source="diagnosis", diagnosis_ids=ids[:n],
                                                model_version="v0001", signature={"n": n}))
    store.put_thresholds(state, "unit-1", {"x1_amp_rel": 0.25})
    with state.sessions() as s:
        assert store.get_baseline(s, "unit-1").diagnosis_ids == ids[:2]
        assert store.get_thresholds(s, "unit-1") == {"x1_amp_rel": 0.25}
    assert store.delete_baseline(state, "unit-1") and not store.delete_baseline(state, "unit-1")


# --- claiming -------------------------------------------------------------------------------------

def test_each_job_is_claimed_exactly_once(tmp_path, database_url):
    """Four replicas claim 40 queued jobs at once: every job goes to exactly one of them."""
    managers = [_manager(tmp_path, database_url, f"r{i}") for i in range(4)]
    ids = _queue(managers[0], 40)
    got: list[tuple[str, str]] = []
    lock = threading.Lock()

    def drain(m: JobManager) -> None:
        while (c := m.claim()) is not None:
            with lock:
                got.append((c[0], m.replica))

    threads = [threading.Thread(target=drain, args=(m,)) for m in managers]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert Counter(j for j, _ in got) == Counter(ids)                 # each once, none missed
    with managers[0].sessions() as s:
        rows = list(s.scalars(select(Job)))
    assert {r.status for r in rows} == {"running"} and {r.attempts for r in rows} == {1}
    assert {r.id: r.lease_owner for r in rows} == dict(got)


def test_lease_renewed_by_holder_then_taken_over_when_it_runs_out(tmp_path, database_url):
    a = _manager(tmp_path, database_url, "host-a", job_lease_s=1.0)
    b = _manager(tmp_path, database_url, "host-b", job_lease_s=1.0)
    (job_id,) = _queue(a, 1)
    claimed = a.claim()
    assert claimed is not None and claimed[0] == job_id and claimed[3] == 1
    a._held[job_id] = 1
    t0 = time.monotonic()
    while time.monotonic() - t0 < 2.5:                                # 2.5 lease lengths, renewed
        a._renew_leases()
        assert b.claim() is None
        time.sleep(0.3)
    # host-a stops renewing (it died); host-b takes the job over once the lease has run out
    time.sleep(1.2)
    taken = b.claim()
    assert taken is not None and taken[0] == job_id and taken[3] == 2
    job = b.get(job_id)
    assert job.lease_owner == "host-b" and job.stage == "taken over"
    assert job.message == "taken over by host-b after the lease of host-a ran out"
    assert b.takeovers == 1
    # host-a comes back: its writes are fenced off
    from rotordiag.service.jobs import JobContext

    with pytest.raises(JobLost):
        JobContext(a, job_id, 1).progress(0.9, "late")
    assert not a._write_held(job_id, 1, {"status": "succeeded"})
    JobContext(b, job_id, 2).progress(0.5, "simulating")
    job = b.get(job_id)
    assert job.status == "running" and job.progress == 0.5 and job.stage == "simulating"


def test_two_running_replicas_share_the_queue_and_a_dead_ones_job_is_finished(tmp_path, database_url):
    """Two replicas with claim loops run 8 jobs between them, each once; then one 'dies' (stops
    renewing, never writes again) holding a job, and the other finishes it."""
    a = _manager(tmp_path, database_url, "host-a", job_lease_s=1.0, job_poll_s=0.1)
    b = _manager(tmp_path, database_url, "host-b", job_lease_s=1.0, job_poll_s=0.1)
    runs: list[tuple[str, str, int]] = []
    hang = threading.Event()

    def work_on(m: JobManager):
        def work(params, ctx):
            runs.append((ctx.job_id, m.replica, ctx.attempt))
            if params.get("hang") and m is a:
                hang.wait(30)               # host-a 'dies' inside this job
                return {"by": m.replica}
            for k in range(3):
                ctx.progress(k / 3, "working")
                time.sleep(0.1)
            return {"by": m.replica}
        return work

    for m in (a, b):
        m.register("dataset", work_on(m))
    ids = [a.submit("dataset", {"i": i}).id for i in range(8)]
    a.start()
    b.start()
    try:
        deadline = time.monotonic() + 60
        while {j.status for j in a.list(limit=100)} != {"succeeded"}:
            assert time.monotonic() < deadline, [(j.id, j.status) for j in a.list()]
            time.sleep(0.1)
        assert Counter(j for j, _, _ in runs) == Counter(ids)
        assert {r for _, r, _ in runs} == {"host-a", "host-b"}
        # host-a takes the next job and dies with it: no renewals, no claims, no writes
        b.stopping.set()                # hold host-b back so that host-a claims it
        for t in b._threads:
            t.join(5)
        hung = a.submit("dataset", {"hang": True}).id
        deadline = time.monotonic() + 10
        while (a.get(hung).lease_owner != "host-a"):
            assert time.monotonic() < deadline
            time.sleep(0.05)
        a.stopping.set()                # no more renewals (its job thread stays stuck in the job)
        a._threads[-1].join(5)
        b2 = _manager(tmp_path, database_url, "host-b2", job_lease_s=1.0, job_poll_s=0.1)
        b2.register("dataset", work_on(b2))
        b2.start()
        deadline = time.monotonic() + 30
        while a.get(hung).status != "succeeded":
            assert time.monotonic() < deadline, a.get(hung).message
            time.sleep(0.1)
        job = a.get(hung)
        assert job.result == {"by": "host-b2"} and job.attempts == 2 and job.lease_owner == "host-b2"
        hang.set()                      # the dead holder wakes: its outcome is not written
        time.sleep(0.3)
        assert a.get(hung).result == {"by": "host-b2"}
        b2.shutdown()
    finally:
        hang.set()
        for m in (a, b):
            m.shutdown()


def test_shutdown_interrupts_only_this_replicas_jobs(tmp_path, database_url):
    a = _manager(tmp_path, database_url, "host-a")
    b = _manager(tmp_path, database_url, "host-b")
    ja, jb, queued = _queue(a, 3)
    assert a.claim()[0] == ja and b.claim()[0] == jb
    assert a.mark_interrupted() == 1
    assert [a.get(j).status for j in (ja, jb, queued)] == ["interrupted", "running", "queued"]


# --- the API on PostgreSQL ------------------------------------------------------------------------

def test_api_on_postgresql_history_and_jobs(tmp_path, postgres):
    from fastapi.testclient import TestClient

    from rotordiag.service.main import create_app
    from tests.service_util import auth, diagnose_json, shipped_or_tiny_registry, simulated_channels

    url = postgres.new_database()
    settings = make_settings(tmp_path, database_url=url, shipped_registry_dir=shipped_or_tiny_registry(),
                             replica_id="pg-replica")
    fs, channels = simulated_channels(misalignment=0.2, record_revs=40)
    app = create_app(settings)
    with TestClient(app) as c:
        ids = []
        for _ in range(2):
            r = c.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0, asset_id="unit-9"),
                       headers=auth())   # storing history needs the key
            assert r.status_code == 200, r.text
            ids.append(r.json()["diagnosis_id"])
        h = c.get("/assets/unit-9/history").json()
        assert h["count"] == 2 and [p["id"] for p in h["points"]] == ids
        app.state.rd.jobs.register("dataset", lambda params, ctx: {"n": params["n"]})
        job = app.state.rd.jobs.submit("dataset", {"n": 5})
        deadline = time.monotonic() + 20
        while (j := c.get(f"/jobs/{job.id}").json())["status"] != "succeeded":
            assert time.monotonic() < deadline, j
            time.sleep(0.05)
        assert j["result"] == {"n": 5} and j["attempts"] == 1
        assert c.get("/health").json()["replica"] == "pg-replica"
        assert 'rotordiag_replica_info{replica="pg-replica"} 1.0' in c.get("/metrics").text


def test_activation_on_one_replica_is_seen_by_the_other_at_its_next_request(tmp_path, postgres):
    """Two replicas sharing the database and the registry folder: a version activated through one is what
    the other diagnoses with at its very next request (the active pointer is read per request)."""
    import shutil

    from fastapi.testclient import TestClient

    from rotordiag.service.main import create_app
    from tests.service_util import auth, diagnose_json, shipped_or_tiny_registry, simulated_channels

    src = tmp_path / "shipped"
    shutil.copytree(shipped_or_tiny_registry(), src)
    first = src.joinpath("active").read_text().strip()
    second = f"v{int(first[1:]) + 1:04d}"
    shutil.copytree(src / first, src / second)        # the same model under a second version name
    url = postgres.new_database()
    fs, channels = simulated_channels(misalignment=0.2, record_revs=40)
    body = diagnose_json(fs, channels, speed_rpm=1800.0)
    apps = [create_app(make_settings(tmp_path, database_url=url, shipped_registry_dir=src, replica_id=f"r{i}"))
            for i in range(2)]
    with TestClient(apps[0]) as a, TestClient(apps[1]) as b:
        assert b.post("/diagnose", json=body).json()["model_version"] == first
        r = a.post(f"/models/{second}/activate", headers=auth())
        assert r.status_code == 200, r.text
        assert b.post("/diagnose", json=body).json()["model_version"] == second
        assert b.get("/health").json()["model_version"] == second


def test_retrain_taken_over_after_registering_reuses_the_version(tmp_path):
    """A retraining job whose holder died between registering the model and recording success is not
    trained (and registered) a second time by the replica that takes it over."""
    import json

    from rotordiag.models.registry import Registry
    from rotordiag.service.work import _registered_by

    for version, job in (("v0001", None), ("v0002", "job-a"), ("v0003", "job-b")):
        (tmp_path / version).mkdir()
        (tmp_path / version / "card.json").write_text(json.dumps({"retrain_job": job} if job else {}))
    (tmp_path / "v0004").mkdir()                      # a version whose card is unreadable is passed over
    reg = Registry(tmp_path)
    assert _registered_by(reg, "job-a") == "v0002" and _registered_by(reg, "job-b") == "v0003"
    assert _registered_by(reg, "job-c") is None


def test_cancel_through_another_replica_stops_the_holder(tmp_path, database_url):
    """POST /jobs/{id}/cancel may reach a replica that does not run the job: the row is cancelled there, and
    the holder stops at its next progress report without writing over it."""
    a = _manager(tmp_path, database_url, "host-a", job_poll_s=0.1)
    b = _manager(tmp_path, database_url, "host-b")
    stopped = threading.Event()

    def work(params, ctx):
        try:
            while True:
                ctx.progress(0.5, "working")
                time.sleep(0.05)
        except JobLost:
            stopped.set()
            raise

    a.register("dataset", work)
    b.register("dataset", work)
    job_id = a.submit("dataset", {}).id
    a.start()
    try:
        deadline = time.monotonic() + 20
        while a.get(job_id).status != "running":
            assert time.monotonic() < deadline
            time.sleep(0.05)
        job = b.cancel(job_id)
        assert job.status == "cancelled"
        assert stopped.wait(10)
        deadline = time.monotonic() + 5
        while a.held():
            assert time.monotonic() < deadline
            time.sleep(0.05)
        job = a.get(job_id)
        assert job.status == "cancelled" and job.attempts == 1 and "cancel" in job.message
    finally:
        a.shutdown()
