"""Service state that must tell the truth (issue 44, items 4 and 6): /health says `starting` until the model is
checked and `degraded` when the model, the database or the data disk would make requests fail; a store write that
fails is a 503 saying what happened (a truncated SQLite file, a full disk); anonymous diagnoses are answered and
not stored; the history is bounded by the retention settings and its size per asset is in the metrics."""
from __future__ import annotations

import datetime as dt
import sqlite3
import time

import numpy as np
import pytest
from fastapi.testclient import TestClient
from sqlalchemy import text

from rotordiag.service.main import create_app
from tests.service_util import (
    auth,
    diagnose_json,
    full_disk,
    make_settings,
    shipped_or_tiny_registry,
    simulated_channels,
)


@pytest.fixture(scope="module")
def registry_src(tmp_path_factory):
    return shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))


@pytest.fixture(scope="module")
def body():
    fs, chans = simulated_channels(misalignment=0.1, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=40)
    return lambda asset=None, seed=0: diagnose_json(
        fs, [(b, a, np.asarray(d) + 0.05 * np.random.default_rng(seed).standard_normal(len(d))) for b, a, d in chans],
        speed_rpm=1800.0, **({"asset_id": asset} if asset else {}))


SMALL_SPEC = {
    "design": {"method": "sobol", "n_samples": 4, "seed": 11},
    "operating": {"speed_rpm": {"min": 1500, "max": 2100}, "misalignment": {"min": 0.0, "max": 0.5},
                  "mechanism": "rigid"},
    "measurement": {"sample_rate_hz": 1024.0, "duration_revs": 12, "snr_db": 40.0},
    "simulation": {"transient_revs": 60, "samples_per_rev": 64, "record_revs_min": 12, "classify_motion": False},
}


def _app(tmp_path, registry_src, **overrides):
    overrides.setdefault("min_free_disk_mb", 1)
    return create_app(make_settings(tmp_path, shipped_registry_dir=registry_src, **overrides))


# ------------------------------------------------------------------------------------------ health
def test_health_is_ok_only_with_a_checked_model_and_a_writable_database(tmp_path, registry_src, monkeypatch):
    with TestClient(_app(tmp_path, registry_src)) as c:
        h = c.get("/health")
        assert h.status_code == 200 and h.json()["status"] == "ok", h.text
        assert h.json()["database"] is True and len(h.json()["model_sha256"]) == 64
        # the write probe is a real row, rewritten by each check
        engine = c.app.state.rd.engine
        with engine.connect() as conn:
            first = conn.execute(text("SELECT written_at FROM service_probe WHERE name = 'health'")).scalar_one()
        time.sleep(0.01)
        c.get("/health")
        with engine.connect() as conn:
            assert conn.execute(text("SELECT written_at FROM service_probe WHERE name = 'health'")).scalar_one() > first
        # a model whose checksum is not known is no model to vouch for
        from rotordiag.service.inference import ModelStore

        monkeypatch.setattr(ModelStore, "file_sha256", lambda self, version: None)
        h = c.get("/health")
        assert h.status_code == 503 and h.json()["status"] == "degraded", h.text
        assert "checksum" in h.json()["detail"]


def test_health_says_degraded_when_the_data_disk_is_nearly_full(tmp_path, registry_src):
    import shutil

    free_mb = shutil.disk_usage(tmp_path).free / 2**20
    with TestClient(_app(tmp_path, registry_src, min_free_disk_mb=int(free_mb) + 1024)) as c:
        h = c.get("/health")
        assert h.status_code == 503 and h.json()["status"] == "degraded", h.text
        assert "nearly full" in h.json()["detail"] and "ROTORDIAG_MIN_FREE_DISK_MB" in h.json()["detail"]
        assert h.json()["database"] is True


def test_health_says_starting_until_a_worker_has_checked_the_model(tmp_path, registry_src):
    """With diagnosis workers, the server process never loads the model: until a worker has loaded it and
    answered a check, /health is 503 `starting` (answered at once, not after the load); then `ok` with the
    checksum the worker read."""
    app = _app(tmp_path, registry_src, diagnosis_workers=1)
    with TestClient(app) as c:
        t0 = time.monotonic()
        h = c.get("/health")
        assert time.monotonic() - t0 < 5.0
        pool = app.state.rd.pool
        assert h.status_code == 503 and h.json()["status"] == "starting", h.text
        assert h.json()["model_sha256"] is None and "starting" in h.json()["detail"]
        seen = [h.json()["status"]]
        while time.monotonic() - t0 < 120:
            h = c.get("/health")
            seen.append(h.json()["status"])
            if h.json()["status"] != "starting":
                break
            time.sleep(0.2)
        assert h.status_code == 200 and h.json()["status"] == "ok", (seen, h.text)
        assert pool.any_ready() and len(h.json()["model_sha256"]) == 64
        assert set(seen) <= {"starting", "ok"}


# ------------------------------------------------------------------------------------------ storage failures
def test_a_truncated_sqlite_file_answers_503_and_health_says_degraded(tmp_path, registry_src, body):
    app = _app(tmp_path, registry_src)
    with TestClient(app) as c:
        assert c.post("/diagnose", json=body("unit-1"), headers=auth()).status_code == 200
        assert c.get("/health").status_code == 200
        db = app.state.rd.settings.data_dir / "rotordiag.sqlite3"
        # checkpointed from outside the server (as the copy that damages it would be): a pooled connection that
        # did the checkpoint itself would go on trusting its cached pages of the file truncated below
        con = sqlite3.connect(db)
        con.execute("PRAGMA wal_checkpoint(TRUNCATE)")
        con.close()
        with open(db, "r+b") as f:              # what a crash during a copy, or a full disk, leaves
            f.truncate(1000)
        h = c.get("/health")
        assert h.status_code == 503 and h.json()["status"] == "degraded" and h.json()["database"] is False, h.text
        assert "database" in h.json()["detail"]
        r = c.post("/diagnose", json=body("unit-1"), headers=auth())
        assert r.status_code == 503, r.text
        assert "database" in r.json()["detail"] and "nothing was stored" in r.json()["detail"]
        assert "Traceback" not in r.text and "INSERT" not in r.text
        r = c.get("/assets/unit-1/history")
        assert r.status_code == 503 and "database" in r.json()["detail"], r.text
        r = c.post("/assets/unit-1/baseline", params={"diagnosis_id": 1}, headers=auth())
        assert r.status_code == 503, r.text
        r = c.post("/datasets", json={"spec": SMALL_SPEC}, headers=auth())
        assert r.status_code == 503, r.text
        # a diagnosis that stores nothing is still answered
        assert c.post("/diagnose", json=body()).status_code == 200


def _full_disk(engine, on: dict):
    """Every INSERT/UPDATE/DELETE fails as SQLite fails on a full disk while ``on["full"]``."""
    return full_disk(engine, on)


def test_a_full_disk_answers_503_saying_so_and_health_says_degraded(tmp_path, registry_src, body):
    app = _app(tmp_path, registry_src)
    with TestClient(app) as c:
        on = {"full": True}
        _full_disk(app.state.rd.engine, on)
        h = c.get("/health")
        assert h.status_code == 503 and h.json()["status"] == "degraded" and h.json()["database"] is False, h.text
        assert "disk is full" in h.json()["detail"]
        r = c.post("/diagnose", json=body("unit-2"), headers=auth())
        assert r.status_code == 503 and "disk is full" in r.json()["detail"], r.text
        assert r.headers["retry-after"] == "30"
        r = c.post("/diagnose/batch", json={"records": [body("unit-2")]}, headers=auth())
        assert r.status_code == 503 and "disk is full" in r.json()["detail"], r.text
        r = c.put("/assets/unit-2/thresholds", json={"thresholds": {}}, headers=auth())
        assert r.status_code == 503, r.text
        on["full"] = False                      # space freed: everything works again
        assert c.get("/health").status_code == 200
        r = c.post("/diagnose", json=body("unit-2"), headers=auth())
        assert r.status_code == 200 and r.json()["stored"] is True


# ------------------------------------------------------------------------------------------ history writes
def test_anonymous_diagnoses_are_answered_and_not_stored(tmp_path, registry_src, body):
    with TestClient(_app(tmp_path, registry_src)) as c:
        r = c.post("/diagnose", json=body("unit-3"))
        assert r.status_code == 200, r.text
        v = r.json()
        assert v["stored"] is False and v["diagnosis_id"] is None and "X-API-Key" in v["storage_note"]
        assert v["baseline"]["used"] is False          # still compared (read-only) with the asset's baseline
        r = c.post("/diagnose/batch", json={"records": [body("unit-3"), body("unit-3", seed=1)]})
        assert r.status_code == 200 and all(it["result"]["stored"] is False for it in r.json()["items"])
        assert c.get("/assets/unit-3/history").status_code == 404      # nothing was written
        r = c.post("/diagnose", json=body("unit-3"), headers={"X-API-Key": "wrong"})
        assert r.status_code == 403, r.text                            # a wrong key is refused, not ignored
        r = c.post("/diagnose", json=body("unit-3"), headers=auth())
        assert r.status_code == 200 and r.json()["stored"] is True and r.json()["diagnosis_id"] >= 1
        assert "storage_note" not in r.json() or r.json()["storage_note"] is None
        r = c.post("/diagnose/batch", json={"records": [body("unit-3")]}, headers=auth())
        assert r.json()["items"][0]["result"]["stored"] is True
        assert c.get("/assets/unit-3/history").json()["count"] == 2
        # the baseline: only with the key
        assert c.post("/assets/unit-3/baseline", params={"diagnosis_id": 1}).status_code == 401
        assert c.post("/assets/unit-3/baseline", json=body("unit-3")).status_code == 401


def _metric(text_: str, name: str, **labels) -> float | None:
    for line in text_.splitlines():
        if line.startswith(name + "{") and all(f'{k}="{v}"' in line for k, v in labels.items()):
            return float(line.rsplit(" ", 1)[1])
    return None


def test_history_retention_keeps_full_records_then_summaries_and_the_size_is_in_the_metrics(
        tmp_path, registry_src, body, monkeypatch):
    from rotordiag.service import metrics

    monkeypatch.setattr(metrics, "HISTORY_SIZES_TTL_S", 0.0)
    app = _app(tmp_path, registry_src, history_keep_recordings=2, history_keep_days=30, history_summary_days=365)
    with TestClient(app) as c:
        ids = [c.post("/diagnose", json=body("unit-4", seed=i), headers=auth()).json()["diagnosis_id"]
               for i in range(4)]
        m = c.get("/metrics").text
        # no baseline yet: the first 3 (what an automatic baseline is made of) keep their signature, so all 4 do
        assert _metric(m, "rotordiag_asset_history_rows", asset="unit-4", kind="full") == 4
        assert _metric(m, "rotordiag_asset_history_rows", asset="unit-4", kind="summary") == 0
        size_before = _metric(m, "rotordiag_asset_history_bytes", asset="unit-4")
        assert size_before > 4 * 10_000                 # four verdicts of tens of kB
        assert c.post("/assets/unit-4/baseline", params={"auto": "true"}, headers=auth()).status_code == 200
        ids.append(c.post("/diagnose", json=body("unit-4", seed=9), headers=auth()).json()["diagnosis_id"])
        m = c.get("/metrics").text
        assert _metric(m, "rotordiag_asset_history_rows", asset="unit-4", kind="full") == 2   # the latest 2
        assert _metric(m, "rotordiag_asset_history_rows", asset="unit-4", kind="summary") == 3
        assert _metric(m, "rotordiag_asset_history_bytes", asset="unit-4") < 0.7 * size_before
        h = c.get("/assets/unit-4/history").json()
        assert [p["id"] for p in h["points"]] == ids         # every summary is still in the trend
        assert h["points"][0]["severity"] and h["points"][0]["misalignment"] is not None
        assert h["points"][0]["key_features"] == {} and h["points"][-1]["key_features"]
        # a trimmed diagnosis cannot become the baseline (its signature is gone); the message says why
        r = c.post("/assets/unit-4/baseline", params={"diagnosis_id": ids[0]}, headers=auth())
        assert r.status_code == 409 and "retention" in r.json()["detail"], r.text
        # by age: a full record older than keep_days keeps its summary, a summary older than summary_days goes
        from rotordiag.service.core.db import AssetDiagnosis

        now = dt.datetime.now(dt.UTC)
        with app.state.rd.sessions.begin() as s:
            s.get(AssetDiagnosis, ids[-1]).created_at = now - dt.timedelta(days=31)
            s.get(AssetDiagnosis, ids[0]).created_at = now - dt.timedelta(days=400)
        ids.append(c.post("/diagnose", json=body("unit-4", seed=10), headers=auth()).json()["diagnosis_id"])
        with app.state.rd.sessions() as s:
            assert s.get(AssetDiagnosis, ids[0]) is None
            assert s.get(AssetDiagnosis, ids[-2]).signature is None and s.get(AssetDiagnosis, ids[-2]).severity
            assert s.get(AssetDiagnosis, ids[-1]).signature is not None
        # what a summary holds (docs/service.md: about 5 kB with a change against a baseline, 20 kB in full)
        with app.state.rd.engine.connect() as conn:
            sizes = conn.execute(text(
                "SELECT LENGTH(verdict) + LENGTH(key_features) + COALESCE(LENGTH(signature), 0) "
                "+ COALESCE(LENGTH(change), 0), signature IS NULL FROM asset_diagnoses")).all()
        summary = max(n for n, trimmed in sizes if trimmed)
        full = min(n for n, trimmed in sizes if not trimmed)
        print(f"stored JSON per diagnosis: full {full} B, summary {summary} B")
        assert 3 * summary < full
        # and at most history_max_rows rows per asset, the oldest deleted first
        app.state.rd.settings.history_max_rows = 3
        ids.append(c.post("/diagnose", json=body("unit-4", seed=11), headers=auth()).json()["diagnosis_id"])
        kept = [p["id"] for p in c.get("/assets/unit-4/history").json()["points"]]
        assert kept == [ids[3], ids[5], ids[6]]          # the 3 latest by time (ids[4] was back-dated 31 days)
