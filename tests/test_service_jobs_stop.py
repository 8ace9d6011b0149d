"""Jobs that can be stopped and whose end is always recorded (issue 44, item 5): an outcome the database
refuses (a full disk) is retried, shown meanwhile, and taken over (run again) at the next start;
POST /jobs/{id}/cancel stops a job within seconds in a Dask task, between samples of a dataset, and in a
training step's child process; SIGTERM/SIGINT stop `rotordiag serve` within the stated time with the job
left resumable."""
from __future__ import annotations

import json
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import text

from rotordiag.service import jobs as jobs_module
from rotordiag.service.main import create_app
from tests.service_util import API_KEY, auth, full_disk, make_settings

SPEC = {
    "design": {"method": "sobol", "n_samples": 256, "seed": 11},
    "operating": {"speed_rpm": {"min": 1500, "max": 2100}, "misalignment": {"min": 0.0, "max": 0.5},
                  "mechanism": "rigid"},
    "measurement": {"sample_rate_hz": 1024.0, "duration_revs": 12, "snr_db": 40.0},
    "simulation": {"transient_revs": 60, "samples_per_rev": 64, "record_revs_min": 12, "classify_motion": False},
}


def _wait(get, job_id, statuses, timeout=60.0):
    t0 = time.monotonic()
    job = None
    while time.monotonic() - t0 < timeout:
        job = get(f"/jobs/{job_id}").json()
        if job["status"] in statuses:
            return job
        time.sleep(0.1)
    raise AssertionError(f"job {job_id} did not reach {statuses}: {job}")


def _row_status(app, job_id) -> str:
    with app.state.rd.engine.connect() as conn:
        return conn.execute(text("SELECT status FROM jobs WHERE id = :i"), {"i": job_id}).scalar_one()


def _disk(engine, on):
    full_disk(engine, on)


# ------------------------------------------------------------------------------------------ unwritable outcomes
def test_an_outcome_the_database_refuses_is_retried_and_the_job_can_be_resumed(tmp_path, monkeypatch):
    monkeypatch.setattr(jobs_module, "RECORD_RETRY_S", 0.3)
    app = create_app(make_settings(tmp_path))
    on = {"full": False}
    calls = []

    def work(params, ctx):
        calls.append(1)
        if len(calls) == 1:
            on["full"] = True                       # the disk fills while the job runs
            raise OSError("No space left on device")
        return {"ok": True}

    with TestClient(app) as c:
        _disk(app.state.rd.engine, on)
        app.state.rd.jobs.register("dataset", work)
        job = app.state.rd.jobs.submit("dataset", {})
        j = _wait(c.get, job.id, {"failed"})
        # shown as failed at once, and said not yet written; the row itself could not be changed
        assert "No space left" in j["error"] and "not yet written to the database" in j["message"], j
        assert _row_status(app, job.id) == "running"
        r = c.post(f"/jobs/{job.id}/resume", headers=auth())
        assert r.status_code == 503 and "disk is full" in r.json()["detail"], r.text
        time.sleep(1.0)
        assert _row_status(app, job.id) == "running"       # still refused while the disk is full
        on["full"] = False                                  # space freed
        t0 = time.monotonic()
        while _row_status(app, job.id) != "failed":
            assert time.monotonic() - t0 < 5, "the refused outcome was not written after space was freed"
            time.sleep(0.1)
        assert "not yet written" not in c.get(f"/jobs/{job.id}").json()["message"]
        assert c.post(f"/jobs/{job.id}/resume", headers=auth()).status_code == 200
        assert _wait(c.get, job.id, {"succeeded"})["result"] == {"ok": True}
        other = app.state.rd.jobs.submit("dataset", {})     # and the next job runs
        assert _wait(c.get, other.id, {"succeeded"})["status"] == "succeeded"


def test_an_outcome_never_written_is_taken_over_at_the_next_start(tmp_path, monkeypatch):
    """The row of a job whose outcome never reached the database stays `running` with a lease nobody renews
    (issue 47): once the lease has run out, the next start (or any other replica) claims the job and runs it
    again (a retry), without a resume."""
    settings = make_settings(tmp_path, job_lease_s=1.0, job_poll_s=0.2)
    app = create_app(settings)
    on = {"full": False}

    def work(params, ctx):
        on["full"] = True
        raise OSError("No space left on device")

    with TestClient(app) as c:
        _disk(app.state.rd.engine, on)
        app.state.rd.jobs.register("dataset", work)
        job = app.state.rd.jobs.submit("dataset", {})
        _wait(c.get, job.id, {"failed"})
    # stopped with the disk still full: nothing could be written. The next start claims the job as soon as its job
    # threads run, before a test could register a kind: the built-in dataset work is replaced before the start
    from rotordiag.service import work as work_module

    monkeypatch.setattr(work_module, "run_dataset", lambda params, ctx: {"ok": True})
    app2 = create_app(settings)
    with TestClient(app2) as c:
        j = _wait(c.get, job.id, {"succeeded"})
        assert j["result"] == {"ok": True} and j["attempts"] == 2, j
        assert j["lease_owner"] == app2.state.rd.jobs.replica


# ------------------------------------------------------------------------------------------ cancel
def _sleep_on_dask(params, ctx):
    """A job whose one Dask task runs far longer than the test (as an absurd simulation would)."""
    future = ctx.client().submit(time.sleep, 600, pure=False)
    ctx.progress(0.1, "simulating", "one long task")
    future.result()
    return {"slept": True}


def test_cancel_stops_a_job_waiting_on_a_running_dask_task_and_frees_the_worker(tmp_path):
    app = create_app(make_settings(tmp_path, dask_local_workers=1))
    with TestClient(app) as c:
        jm = app.state.rd.jobs
        jm.register("dataset", _sleep_on_dask)
        job = jm.submit("dataset", {})
        _wait(c.get, job.id, {"running"})
        t0 = time.monotonic()
        while not any(jm.client().processing().values()):
            assert time.monotonic() - t0 < 120, "the Dask task never started"
            time.sleep(0.2)
        assert c.post(f"/jobs/{job.id}/cancel").status_code == 401
        t0 = time.monotonic()
        r = c.post(f"/jobs/{job.id}/cancel", headers=auth())
        elapsed = time.monotonic() - t0
        print(f"job on a running Dask task: cancelled in {elapsed:.2f} s")
        assert r.status_code == 200 and r.json()["status"] == "cancelled", r.text
        assert elapsed < 10, elapsed
        assert "resume" in r.json()["message"]
        # the worker that ran the task is restarted, not left sleeping: a new task runs at once
        t0 = time.monotonic()
        assert jm.client().submit(sum, [1, 2], pure=False).result(timeout=90) == 3
        print(f"next Dask task done {time.monotonic() - t0:.2f} s after the cancel answered")
        assert time.monotonic() - t0 < 90
        r = c.post(f"/jobs/{job.id}/cancel", headers=auth())
        assert r.status_code == 409 and "cancelled" in r.json()["detail"], r.text
        assert c.post("/jobs/no-such-job/cancel", headers=auth()).status_code == 404
        assert c.get("/metrics").text.count('rotordiag_jobs{status="cancelled"} 1.0') == 1


def test_cancel_stops_a_dataset_job_between_samples_and_resume_continues_it(tmp_path):
    from rotordiag.simulator.dataset.store import open_dataset

    settings = make_settings(tmp_path, dask_local_workers=1)
    app = create_app(settings)
    with TestClient(app) as c:
        r = c.post("/datasets", json={"spec": SPEC, "name": "big"}, headers=auth())
        job_id = r.json()["id"]
        t0 = time.monotonic()
        while c.get(f"/jobs/{job_id}").json()["progress"] < 3 / 256:
            assert time.monotonic() - t0 < 180, c.get(f"/jobs/{job_id}").json()
            time.sleep(0.2)
        t0 = time.monotonic()
        r = c.post(f"/jobs/{job_id}/cancel", headers=auth())
        print(f"dataset job between samples: cancelled in {time.monotonic() - t0:.2f} s")
        assert r.status_code == 200 and r.json()["status"] == "cancelled", r.text
        assert time.monotonic() - t0 < 10
        with open_dataset(settings.datasets_dir / "big.h5") as f:
            done = int(f["done"][...].sum())
        assert 3 <= done < 256
        time.sleep(1.0)
        with open_dataset(settings.datasets_dir / "big.h5") as f:
            assert int(f["done"][...].sum()) == done       # nothing more written after the cancel
        # resumed: it continues from the samples on file, and is cancelled again
        jm = app.state.rd.jobs
        assert c.post(f"/jobs/{job_id}/resume", headers=auth()).status_code == 200
        j = _wait(c.get, job_id, {"running"})
        t0 = time.monotonic()
        while c.get(f"/jobs/{job_id}").json()["progress"] <= (done + 1) / 256:
            assert time.monotonic() - t0 < 120
            time.sleep(0.2)
        j = c.post(f"/jobs/{job_id}/cancel", headers=auth()).json()
        assert j["status"] == "cancelled" and j["attempts"] == 2
        assert jm.counts()["running"] == 0


def test_cancel_kills_a_training_step_in_its_child_process(tmp_path):
    """A step without progress reports (a model fit) runs in a child process (service.work.run_in_child),
    killed on cancel."""
    from rotordiag.service.work import run_in_child

    app = create_app(make_settings(tmp_path))
    started = threading.Event()

    def fit(params, ctx):
        ctx.progress(0.8, "training", "training")
        started.set()
        run_in_child(ctx, time.sleep, 600)
        return {}

    with TestClient(app) as c:
        app.state.rd.jobs.register("retrain", fit)
        job = app.state.rd.jobs.submit("retrain", {})
        assert started.wait(30)
        t0 = time.monotonic()
        def job_children():      # the training child, not the app's Dask workers (also children of this process)
            return [p for p in multiprocessing.active_children() if p.name.startswith("rotordiag-job-")]

        while not job_children():
            assert time.monotonic() - t0 < 30
            time.sleep(0.05)
        children = job_children()
        t1 = time.monotonic()
        r = c.post(f"/jobs/{job.id}/cancel", headers=auth())
        print(f"training child process: cancelled in {time.monotonic() - t1:.2f} s")
        assert r.status_code == 200 and r.json()["status"] == "cancelled", r.text
        assert r.json()["stage"] == "cancelled"
        assert time.monotonic() - t0 < 15
        for child in children:
            child.join(5)
            assert not child.is_alive()


def test_a_child_process_error_reaches_the_job(tmp_path):
    from rotordiag.service.work import run_in_child

    app = create_app(make_settings(tmp_path))

    def fit(params, ctx):
        return {"x": run_in_child(ctx, int, "not a number")}

    with TestClient(app) as c:
        app.state.rd.jobs.register("retrain", fit)
        job = app.state.rd.jobs.submit("retrain", {})
        j = _wait(c.get, job.id, {"failed", "succeeded"}, timeout=60)
        assert j["status"] == "failed" and "ValueError" in j["error"] and "not a number" in j["error"], j


# ------------------------------------------------------------------------------------------ signals
def _request(url, body=None, method=None):
    headers = {"X-API-Key": API_KEY}
    if body is not None:
        headers["Content-Type"] = "application/json"
    req = urllib.request.Request(url, data=body, headers=headers, method=method)
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def _serve(tmp: Path, port: int) -> subprocess.Popen:
    env = dict(os.environ, ROTORDIAG_DATA_DIR=str(tmp / "data"), ROTORDIAG_API_KEY=API_KEY,
               ROTORDIAG_DIAGNOSIS_WORKERS="0", ROTORDIAG_DASK_LOCAL_WORKERS="1", ROTORDIAG_SHUTDOWN_TIMEOUT_S="5")
    exe = Path(sys.executable).parent / "rotordiag"
    proc = subprocess.Popen([str(exe), "serve", "--host", "127.0.0.1", "--port", str(port)], cwd=tmp, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    t0 = time.monotonic()
    while True:
        assert proc.poll() is None, proc.stdout.read()
        try:
            _request(f"http://127.0.0.1:{port}/jobs")
            return proc
        except OSError:
            time.sleep(0.2)
        assert time.monotonic() - t0 < 60, "server did not start"


#: docs/service.md: a server stops within 2 × ROTORDIAG_SHUTDOWN_TIMEOUT_S + 20 s of SIGINT/SIGTERM
STOP_BOUND_S = 2 * 5 + 20


@pytest.mark.parametrize("sig", [signal.SIGTERM, pytest.param(signal.SIGINT, marks=pytest.mark.slow)])
def test_a_signal_stops_the_server_in_the_stated_time_and_the_job_resumes(tmp_path, sig):
    from tests.test_service_e2e import _free_port

    port = _free_port()
    base = f"http://127.0.0.1:{port}"
    proc = _serve(tmp_path, port)
    try:
        status, job = _request(base + "/datasets", json.dumps({"spec": SPEC, "name": "sig"}).encode())
        assert status == 202, job
        t0 = time.monotonic()
        while _request(f"{base}/jobs/{job['id']}")[1]["progress"] < 2 / 256:
            assert time.monotonic() - t0 < 180
            time.sleep(0.2)
        t0 = time.monotonic()
        proc.send_signal(sig)
        out, _ = proc.communicate(timeout=STOP_BOUND_S + 30)
        elapsed = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    print(f"{signal.Signals(sig).name}: server stopped {elapsed:.1f} s after the signal")
    assert elapsed < STOP_BOUND_S, (elapsed, out[-3000:])
    assert "Traceback" not in out, out[-3000:]
    port = _free_port()           # a fresh port: another test process may have taken the old one meanwhile
    base = f"http://127.0.0.1:{port}"
    proc = _serve(tmp_path, port)
    try:
        status, j = _request(f"{base}/jobs/{job['id']}")
        assert j["status"] == "interrupted", j
        status, j = _request(f"{base}/jobs/{job['id']}/resume", b"", "POST")
        assert status == 200 and j["status"] in ("queued", "running"), j
        status, j = _request(f"{base}/jobs/{job['id']}/cancel", b"", "POST")
        assert status == 200 and j["status"] == "cancelled", j
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=STOP_BOUND_S + 30)


def test_a_start_on_a_full_disk_still_starts_and_the_previous_jobs_are_taken_over_once_it_can(tmp_path,
                                                                                              monkeypatch):
    """A job a killed process left `running` (no lease: written before leases, or its holder is gone) is
    claimed by the next start once the database takes writes again (issue 47: leases), and finishes."""
    from rotordiag.service import state as state_module
    from rotordiag.service.core.db import make_engine as plain_engine

    settings = make_settings(tmp_path, job_poll_s=0.2)
    with TestClient(create_app(settings)):
        pass                                        # the database exists
    engine = plain_engine(settings.effective_database_url)
    with engine.begin() as conn:                    # a job the previous process left running
        conn.execute(text("INSERT INTO jobs (id, kind, status, params, progress, stage, message, attempts, "
                          "created_at, updated_at) VALUES ('old-job', 'dataset', 'running', '{}', 0.5, "
                          "'simulating', 'simulating: 8/16', 1, '2026-01-01 00:00:00', '2026-01-01 00:00:00')"))
    engine.dispose()
    on = {"full": True}
    make_engine = state_module.make_engine

    def full_engine(url):
        engine = make_engine(url)
        _disk(engine, on)
        return engine

    monkeypatch.setattr(state_module, "make_engine", full_engine)
    app = create_app(settings)
    with TestClient(app) as c:
        h = c.get("/health")
        assert h.status_code == 503 and "disk is full" in h.json()["detail"], h.text
        app.state.rd.jobs.register("dataset", lambda params, ctx: {"ok": True})
        time.sleep(0.5)
        assert c.get("/jobs/old-job").json()["status"] == "running"      # cannot be claimed yet
        on["full"] = False
        j = _wait(c.get, "old-job", {"succeeded"}, timeout=20)
        assert j["result"] == {"ok": True} and j["attempts"] == 2 and j["lease_owner"] == app.state.rd.jobs.replica


def test_a_job_busy_in_its_own_thread_says_cancel_requested_then_ends_cancelled(tmp_path):
    """A step in the job's thread that does not check (feature extraction of one recording) cannot be cut
    short: the cancel answer says it was requested, and the job ends `cancelled` at its next check."""
    app = create_app(make_settings(tmp_path))
    busy = threading.Event()

    def work(params, ctx):
        busy.set()
        time.sleep(2.0)                       # no check in here
        ctx.progress(0.5, "features")         # the next check
        return {"never": True}

    with TestClient(app) as c:
        jm = app.state.rd.jobs
        jm.register("dataset", work)
        job = jm.submit("dataset", {})
        assert busy.wait(10)
        j = jm.cancel(job.id, wait_s=0.3)
        assert j.status == "running" and j.message.startswith("cancel requested"), (j.status, j.message)
        j = _wait(c.get, job.id, {"cancelled", "succeeded"}, timeout=10)
        assert j["status"] == "cancelled" and j["result"] is None, j
