"""Jobs through the API on a real local Dask cluster: a dataset job, its interruption by a server
shutdown and its resumption (only the missing samples are computed), and retraining for a perturbed plant."""
from __future__ import annotations

import time

import pytest
from fastapi.testclient import TestClient

from rotordiag.service.main import create_app
from tests.service_util import auth, make_settings

SMALL_SPEC = {
    "design": {"method": "sobol", "n_samples": 16, "seed": 11},
    "operating": {"speed_rpm": {"min": 1500, "max": 2100}, "misalignment": {"min": 0.0, "max": 0.5},
                  "mechanism": "rigid"},
    "measurement": {"sample_rate_hz": 1024.0, "duration_revs": 12, "snr_db": 40.0},
    "simulation": {"transient_revs": 60, "samples_per_rev": 64, "record_revs_min": 12, "classify_motion": False},
}


def _wait(c, job_id, statuses, timeout=240):
    t0 = time.monotonic()
    job = None
    while time.monotonic() - t0 < timeout:
        job = c.get(f"/jobs/{job_id}").json()
        if job["status"] in statuses:
            return job
        time.sleep(0.2)
    raise AssertionError(f"job {job_id} did not reach {statuses}: {job}")


def _done_count(path) -> int:
    from rotordiag.simulator.dataset.store import open_dataset

    try:
        with open_dataset(path) as f:
            return int(f["done"][...].sum())
    except Exception:  # noqa: BLE001 - not created yet / being written
        return 0


def test_dataset_job_interrupted_by_shutdown_then_resumed(tmp_path):
    settings = make_settings(tmp_path, dask_local_workers=1)
    out = settings.datasets_dir / "small.h5"
    app = create_app(settings)
    with TestClient(app) as c:
        r = c.post("/datasets", json={"spec": SMALL_SPEC, "name": "small"}, headers=auth())
        assert r.status_code == 202, r.text
        job_id = r.json()["id"]
        t0 = time.monotonic()
        while _done_count(out) < 3:
            assert time.monotonic() - t0 < 180, c.get(f"/jobs/{job_id}").json()
            job = c.get(f"/jobs/{job_id}").json()
            assert job["status"] in ("queued", "running"), job
            time.sleep(0.2)
        job = c.get(f"/jobs/{job_id}").json()
        assert job["stage"] == "simulating" and job["progress"] >= 2 / 16, job   # per-sample progress
        assert job["message"].startswith("simulating: ") and job["message"].endswith("/16")
    # server stopped mid-run
    done_before = _done_count(out)
    assert 3 <= done_before < 16
    app2 = create_app(settings)
    with TestClient(app2) as c:
        job = c.get(f"/jobs/{job_id}").json()
        assert job["status"] == "interrupted", job
        assert c.post(f"/jobs/{job_id}/resume", headers=auth()).status_code == 200
        job = _wait(c, job_id, {"succeeded", "failed"})
        assert job["status"] == "succeeded", job
        res = job["result"]
        assert res["n_samples"] == 16 and res["complete"]
        assert res["n_done_before"] >= done_before and res["n_computed"] == 16 - res["n_done_before"]
        assert res["summary"]["n_done"] == 16
        assert job["attempts"] == 2


def test_dataset_spec_errors_are_422_before_any_job(tmp_path):
    with TestClient(create_app(make_settings(tmp_path))) as c:
        bad = {**SMALL_SPEC, "operating": {**SMALL_SPEC["operating"], "misalignment": {"min": 0.5, "max": 0.1}}}
        r = c.post("/datasets", json={"spec": bad}, headers=auth())
        assert r.status_code == 422 and "misalignment" in r.json()["detail"] and "empty range" in r.json()["detail"]
        r = c.post("/datasets", json={"spec_toml": "[design]\nmethod = 'sobol'\nn_samples = 4\nseed = 1\n"
                                      "[plant]\nfile = '/etc/passwd'\n"}, headers=auth())
        assert r.status_code == 422 and "plant.file" in r.json()["detail"] and "root" not in r.json()["detail"]
        r = c.post("/datasets", json={"spec_toml": "not toml ["}, headers=auth())
        assert r.status_code == 422 and "TOML" in r.json()["detail"]
        from tests.test_dataset_transient import BASE as RUNUP  # a run-up spec whose profile turns back

        reverses = RUNUP.replace("start_rpm = 800\nend_rpm = 1600\nduration_s = 16",
                                 "times_s = [0, 8, 16]\nspeeds_rpm = [800, 1600, 1200]")
        r = c.post("/datasets", json={"spec_toml": reverses}, headers=auth())
        assert r.status_code == 422 and "speed profile reverses at t = 8 s" in r.json()["detail"]
        r = c.post("/models/retrain", json={"plant": {"asymmetry": 0.7}}, headers=auth())
        assert r.status_code == 422 and "asymmetry" in r.json()["detail"]
        r = c.post("/models/retrain", json={"training": {"bogus": 1}}, headers=auth())
        assert r.status_code == 422 and "bogus" in r.json()["detail"]
        assert c.get("/jobs").json()["count"] == 0


@pytest.mark.slow
def test_retrain_tiny_model_for_a_perturbed_plant(tmp_path):
    """POST /models/retrain for a plant unlike the default, on a real local Dask cluster; the new
    version is registered with its held-out evaluation and its plant's quality report, activated (forced, or
    by its report), and then diagnoses."""
    from tests.service_util import diagnose_json, shipped_or_tiny_registry, simulated_channels

    settings = make_settings(tmp_path, dask_local_workers=2, shipped_registry_dir=shipped_or_tiny_registry())
    fs, channels = simulated_channels(misalignment=0.3, record_revs=40)
    body = {
        "plant": {"generator_mass_kg": 28000.0, "asymmetry": 0.035},
        "sweep": {"design": {"n_samples": 40, "seed": 5},
                  "operating": {"speed_rpm": {"min": 1600, "max": 2000}, "misalignment": {"min": 0.0, "max": 0.6}},
                  "measurement": {"sample_rate_hz": 1024.0, "duration_revs": 16, "snr_db": 35.0},
                  "simulation": {"transient_revs": 80, "samples_per_rev": 64, "record_revs_min": 16,
                                 "classify_motion": False}},
        "training": {"seed": 1, "classifier": {"max_iter": 30, "min_samples_leaf": 2},
                     "regressor": {"max_iter": 30, "min_samples_leaf": 2}, "evaluation": {"n_splits": 3}},
        "field_data": [{"misalignment": 0.3, "recording": diagnose_json(fs, channels, speed_rpm=1800.0)}],
        "activate": True, "force": True, "report_cases": 1,
    }
    app = create_app(settings)
    with TestClient(app) as c:
        before = c.get("/models").json()
        r = c.post("/models/retrain", json=body, headers=auth())
        assert r.status_code == 202, r.text
        job = _wait(c, r.json()["id"], {"succeeded", "failed"}, timeout=900)
        assert job["status"] == "succeeded", job
        res = job["result"]
        assert res["field_records"] == 1 and res["n_rows"] >= 30
        # classify_motion = false: the motion features are never computed, so never trained on
        assert {"motion_period", "motion_quasi_periodic", "motion_chaotic"} <= set(res["features_never_measured"])
        assert res["dataset"]["n_samples"] == 40
        assert "per_mechanism" in res["metrics"]
        after = c.get("/models").json()
        assert after["active"] == res["version"] and len(after["versions"]) == len(before["versions"]) + 1
        # its quality report on the plant, beside the model that was active, and how it was activated
        assert res["activated_by"] == ("report" if res["better"] else "forced")
        shown = c.get(f"/models/{res['version']}").json()
        assert shown["activated_by"] == res["activated_by"] and shown["plant_report"]["held_out"]["n_cases"] == 5
        assert shown["plant_report"]["models"]["active"] == f"{before['active']} (active)"
        card = next(v for v in after["versions"] if v["version"] == res["version"])
        assert card["plant_overrides"] == body["plant"] and card["retrain_job"] == job["id"]
        assert card["plant_family"]["base_plant"]["generator_mass_kg"] == 28000.0
        v = c.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0)).json()
        assert v["model_version"] == res["version"]
