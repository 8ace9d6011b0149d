"""Service infrastructure through the TestClient: settings, auth, body limits, content types, health,
metrics, job persistence across restarts. (Diagnoses: tests/test_service_diagnose.py.)"""
from __future__ import annotations

import threading
import time

import pytest
from fastapi.testclient import TestClient
from pydantic import ValidationError

from rotordiag.service.core.config import Settings
from rotordiag.service.main import create_app
from tests.service_util import API_KEY, auth, make_settings


@pytest.fixture
def client(tmp_path):
    app = create_app(make_settings(tmp_path, max_body_bytes=64 * 1024))
    with TestClient(app) as c:
        yield c


# --- settings -----------------------------------------------------------------------------------

def test_settings_defaults_are_runnable(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for k in ("ROTORDIAG_API_KEY", "ROTORDIAG_ENVIRONMENT", "ROTORDIAG_DATA_DIR", "ROTORDIAG_DATABASE_URL"):
        monkeypatch.delenv(k, raising=False)
    s = Settings(_env_file=None)
    assert s.environment == "development"
    assert s.effective_database_url == f"sqlite:///{(tmp_path / 'data' / 'rotordiag.sqlite3').resolve()}"
    assert s.registry_dir == s.data_dir / "registry"
    key = s.effective_api_key
    assert len(key) >= 24 and s.effective_api_key == key      # generated once per Settings
    assert Settings(_env_file=None).effective_api_key != key   # random, not a fixed default


def test_settings_from_env_and_dotenv(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / ".env").write_text("ROTORDIAG_MAX_BODY_BYTES=123456\nROTORDIAG_API_KEY=from-dotenv\n")
    monkeypatch.setenv("ROTORDIAG_DASK_SCHEDULER_ADDRESS", " tcp://10.0.0.5:8786 ")
    s = Settings()
    assert s.max_body_bytes == 123456
    assert s.effective_api_key == "from-dotenv"
    assert s.dask_scheduler_address == "tcp://10.0.0.5:8786"


def test_production_refuses_empty_api_key(monkeypatch):
    monkeypatch.delenv("ROTORDIAG_API_KEY", raising=False)
    with pytest.raises(ValidationError, match="ROTORDIAG_API_KEY is empty"):
        Settings(environment="production", _env_file=None)
    with pytest.raises(ValidationError, match="ROTORDIAG_API_KEY is empty"):
        Settings(environment="production", api_key="   ", _env_file=None)
    assert Settings(environment="production", api_key="s3cret", _env_file=None).effective_api_key == "s3cret"


def test_serve_cli_refuses_bad_settings_cleanly(monkeypatch):
    from typer.testing import CliRunner

    from rotordiag.cli import app

    monkeypatch.setenv("ROTORDIAG_ENVIRONMENT", "production")
    monkeypatch.delenv("ROTORDIAG_API_KEY", raising=False)
    res = CliRunner().invoke(app, ["serve", "--port", "1"])
    assert res.exit_code == 2
    assert "ROTORDIAG_API_KEY is empty" in res.output
    assert "Traceback" not in res.output


# --- auth ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("method,path", [("post", "/datasets"), ("post", "/models/retrain"),
                                         ("post", "/models/v0001/activate"), ("post", "/jobs/abc/resume")])
def test_write_endpoints_need_the_key(client, method, path):
    r = getattr(client, method)(path, json={})
    assert r.status_code == 401 and "X-API-Key" in r.json()["detail"]
    r = getattr(client, method)(path, json={}, headers={"X-API-Key": "wrong"})
    assert r.status_code == 403
    r = getattr(client, method)(path, json={}, headers=auth())
    assert r.status_code not in (401, 403)


# --- body size and content type ----------------------------------------------------------------------

def test_declared_body_over_limit_is_413(client):
    r = client.post("/diagnose", content=b"0" * (64 * 1024 + 1), headers={"content-type": "application/json"})
    assert r.status_code == 413
    assert "65536 bytes" in r.json()["detail"] and "ROTORDIAG_MAX_BODY_BYTES" in r.json()["detail"]


def test_chunked_body_over_limit_is_413(client):
    """No Content-Length: the middleware must count the streamed bytes."""
    def chunks():
        for _ in range(100):
            yield b"1" * 4096

    r = client.post("/diagnose", content=chunks(), headers={"content-type": "application/json"})
    assert "content-length" not in r.request.headers and r.request.headers["transfer-encoding"] == "chunked"
    assert r.status_code == 413
    r = client.post("/diagnose", content=chunks(), headers={"content-type": "application/octet-stream"})
    assert r.status_code == 413


def test_chunked_body_under_limit_passes_the_middleware(client):
    def chunks():
        yield b'{"sample_rate_hz": 100'
        yield b"}"

    r = client.post("/diagnose", content=chunks(), headers={"content-type": "application/json"})
    assert r.status_code == 422                                   # read in full, then schema errors
    assert any(e["loc"][-1] == "channels" for e in r.json()["detail"])


@pytest.mark.parametrize("ctype", ["text/plain", "application/xml", ""])
def test_unsupported_content_type_is_415(client, ctype):
    r = client.post("/diagnose", content=b"1,2,3", headers={"content-type": ctype})
    assert r.status_code == 415
    assert "application/json" in r.json()["detail"] and "multipart" in r.json()["detail"]


# --- health, metrics, openapi ------------------------------------------------------------------------

def test_health_reports_missing_model(tmp_path):
    app = create_app(make_settings(tmp_path, shipped_registry_dir=tmp_path / "nothing-shipped"))
    with TestClient(app) as c:
        r = c.get("/health")
    assert r.status_code == 503
    body = r.json()
    assert body["status"] == "degraded" and body["database"] is True
    assert "no active model" in body["detail"]


def test_metrics_exposes_latency_histogram_and_job_counts(client):
    client.get("/jobs")
    text = client.get("/metrics").text
    assert 'rotordiag_jobs{status="running"} 0.0' in text
    assert "http_request_duration_seconds_bucket" in text
    assert 'handler="/jobs"' in text


def test_metrics_handler_label_is_the_route_template_on_repeated_requests(client):
    """The handler label (the route's template, remembered per path by service.metrics) is the same on the first
    and later requests, for a templated route and for both methods of one path; an unknown path keeps its own."""
    from rotordiag.service.metrics import _CachedHandlerMiddleware

    assert any(m.cls is _CachedHandlerMiddleware for m in client.app.user_middleware)
    for _ in range(3):
        client.get("/jobs/no-such-job")
        client.get("/jobs/another-id")
        client.get("/jobs")
    client.get("/no/such/route")
    text = client.get("/metrics").text
    counts = [line for line in text.splitlines() if line.startswith("http_requests_total{")]
    assert any('handler="/jobs/{job_id}"' in line and 'status="404"' in line and line.endswith(" 6.0")
               for line in counts), counts
    assert any('handler="/jobs"' in line and line.endswith(" 3.0") for line in counts), counts
    assert not any("no-such-job" in line or "another-id" in line for line in counts)


def test_two_apps_in_one_process_have_separate_metrics(tmp_path):
    a = create_app(make_settings(tmp_path / "a"))
    b = create_app(make_settings(tmp_path / "b"))
    with TestClient(a) as ca, TestClient(b) as cb:
        ca.get("/jobs")
        assert 'handler="/jobs"' in ca.get("/metrics").text
        assert 'handler="/jobs"' not in cb.get("/metrics").text


def test_openapi_documents_units_and_bodies(client):
    spec = client.get("/openapi.json").json()
    body = spec["paths"]["/diagnose"]["post"]["requestBody"]["content"]
    assert set(body) == {"application/json", "application/octet-stream", "multipart/form-data"}
    req = spec["components"]["schemas"]["DiagnoseRequest"]["properties"]
    assert set(req) >= {"sample_rate_hz", "speed_rpm", "keyphasor_times_s", "clearance_um", "asset_id", "plant",
                        "channels"}
    ch = spec["components"]["schemas"]["ChannelIn"]["properties"]
    assert ch["data"]["maxItems"] == 262_144
    # every field of every schema carries a description or is a self-describing nested model
    for name, schema in spec["components"]["schemas"].items():
        if name in ("HTTPValidationError", "ValidationError") or name.startswith("Body_"):
            continue                                                   # FastAPI's own
        for field, prop in schema.get("properties", {}).items():
            assert prop.get("description"), f"{name}.{field} has no description"



def test_routes_document_their_key_and_body_errors_one_way(client):
    """``api.errors.error_responses``: a JSON route's 400/415, a keyed route's 401/403 (saying when the key is
    needed), and what the route itself adds; no body, no 400/415."""
    from rotordiag.service.api.errors import error_responses

    doc = error_responses({422: "bad"}, key="diagnose", body="json")
    assert sorted(doc) == [400, 401, 403, 415, 422] and doc[422]["description"] == "bad"
    assert "ROTORDIAG_DIAGNOSE_REQUIRES_KEY" in doc[401]["description"]
    assert sorted(error_responses({404: "none"}, key="always")) == [401, 403, 404]
    paths = client.get("/openapi.json").json()["paths"]
    cancel = paths["/jobs/{job_id}/cancel"]["post"]["responses"]
    assert {"401", "403", "404", "409"} <= cancel.keys() and not {"400", "415"} & cancel.keys()
    assert paths["/jobs/{job_id}"]["get"]["responses"]["404"]["description"] == "No job with this id."
    for path, method in (("/diagnose", "post"), ("/assets/{asset_id}/baseline", "post")):
        assert "NPY" in paths[path][method]["responses"]["415"]["description"]

# --- jobs: persistence, interruption, resume --------------------------------------------------------------

class _Gate:
    """A job body that runs until released, reporting progress (stands in for the simulations)."""

    def __init__(self):
        self.release = threading.Event()
        self.started = threading.Event()

    def __call__(self, params, ctx):
        self.started.set()
        for i in range(1000):
            ctx.progress(i / 1000, "simulating", f"{i}/1000")   # raises JobInterrupted at shutdown
            if self.release.wait(0.01):
                return {"n": params["n"], "resumed_attempt": True}
        raise RuntimeError("gate never released")


def _wait(c, job_id, statuses, timeout=20):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        job = c.get(f"/jobs/{job_id}").json()
        if job["status"] in statuses:
            return job
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} still {job['status']}")


def test_job_survives_restart_as_interrupted_and_resumes(tmp_path):
    settings = make_settings(tmp_path)
    gate = _Gate()
    app = create_app(settings)
    with TestClient(app) as c:
        app.state.rd.jobs.register("dataset", gate)
        job = app.state.rd.jobs.submit("dataset", {"n": 7})
        assert gate.started.wait(10)
        running = _wait(c, job.id, {"running"})
        assert running["attempts"] == 1
    # the app stopped while the job ran
    app2 = create_app(settings)
    gate2 = _Gate()
    with TestClient(app2) as c:
        app2.state.rd.jobs.register("dataset", gate2)
        j = c.get(f"/jobs/{job.id}").json()
        assert j["status"] == "interrupted" and "resume" in j["message"]
        assert c.get("/metrics").text.count('rotordiag_jobs{status="interrupted"} 1.0') == 1
        assert c.post(f"/jobs/{job.id}/resume", headers=auth()).status_code == 200
        assert gate2.started.wait(10)
        gate2.release.set()
        done = _wait(c, job.id, {"succeeded", "failed"})
        assert done["status"] == "succeeded", done
        assert done["result"] == {"n": 7, "resumed_attempt": True}
        assert done["attempts"] == 2 and done["progress"] == 1.0
        r = c.post(f"/jobs/{job.id}/resume", headers=auth())
        assert r.status_code == 409 and "succeeded" in r.json()["detail"]


def test_failed_job_reports_error(tmp_path):
    app = create_app(make_settings(tmp_path))

    def boom(params, ctx):
        raise ValueError("simulation blew up at sample 3")

    with TestClient(app) as c:
        app.state.rd.jobs.register("dataset", boom)
        job = app.state.rd.jobs.submit("dataset", {})
        j = _wait(c, job.id, {"failed", "succeeded"})
        assert j["status"] == "failed" and "sample 3" in j["error"]
        assert c.get("/jobs", params={"status": "failed"}).json()["count"] == 1
        assert c.get("/jobs/nope").status_code == 404


@pytest.mark.parametrize("path", ["/diagnose/batch", "/datasets", "/models/retrain"])
def test_json_endpoints_refuse_other_content_types(client, path):
    r = client.post(path, content=b'{"records": []}', headers={"content-type": "text/plain", **auth()})
    assert r.status_code == 415 and "application/json" in r.json()["detail"]


def test_development_key_is_generated_and_logged_once(tmp_path, caplog):
    settings = make_settings(tmp_path, api_key="")
    with caplog.at_level("WARNING", logger="rotordiag.service"):
        with TestClient(create_app(settings)) as c:
            key = settings.effective_api_key
            assert c.post("/jobs/x/resume", headers={"X-API-Key": key}).status_code == 404   # key accepted
            assert c.post("/jobs/x/resume", headers={"X-API-Key": API_KEY}).status_code == 403
    logged = [r.getMessage() for r in caplog.records if key in r.getMessage()]
    assert len(logged) == 1 and "X-API-Key" in logged[0]


def test_job_times_are_utc_and_non_finite_results_are_null(tmp_path):
    app = create_app(make_settings(tmp_path))
    with TestClient(app) as c:
        app.state.rd.jobs.register("dataset", lambda params, ctx: {"spearman": float("nan"), "q": float("inf")})
        job = app.state.rd.jobs.submit("dataset", {})
        j = _wait(c, job.id, {"succeeded", "failed"})
        assert j["result"] == {"spearman": None, "q": None}
        for key in ("created_at", "started_at", "finished_at", "updated_at"):
            assert j[key].endswith("+00:00") or j[key].endswith("Z"), j[key]


def test_diagnose_key_is_optional_and_enforced_when_configured(tmp_path):
    body = {"sample_rate_hz": 100.0, "channels": []}        # schema-invalid: 422 once past the key check
    with TestClient(create_app(make_settings(tmp_path / "open"))) as c:
        assert c.post("/diagnose", json=body).status_code == 422
    with TestClient(create_app(make_settings(tmp_path / "closed", diagnose_requires_key=True))) as c:
        assert c.post("/diagnose", json=body).status_code == 401
        assert c.post("/diagnose/batch", json={"records": []}, headers={"X-API-Key": "no"}).status_code == 403
        assert c.post("/diagnose", json=body, headers=auth()).status_code == 422


def test_shipped_default_model_is_usable():
    """`make run` on a fresh clone diagnoses with the shipped model: it must exist and run with this code."""
    from rotordiag.service.core.config import SHIPPED_REGISTRY_DIR
    from rotordiag.service.inference import ModelStore

    assert (SHIPPED_REGISTRY_DIR / "active").is_file(), f"no shipped registry at {SHIPPED_REGISTRY_DIR}"
    bundle = ModelStore(SHIPPED_REGISTRY_DIR).load()      # raises ModelUnavailable with the reason
    assert bundle.version == (SHIPPED_REGISTRY_DIR / "active").read_text().strip()


def test_model_that_fails_when_used_gives_503_not_500(tmp_path, monkeypatch):
    from rotordiag.models.estimators import MisalignmentModel
    from tests.service_util import shipped_or_tiny_registry

    src = shipped_or_tiny_registry()

    def broken(self, X):
        raise AttributeError("'ConformalIntervalRegressor' object has no attribute 'center_model_'")

    monkeypatch.setattr(MisalignmentModel, "predict_misalignment", broken)
    with TestClient(create_app(make_settings(tmp_path, shipped_registry_dir=src))) as c:
        h = c.get("/health")
        assert h.status_code == 503 and "cannot be used with this code version" in h.json()["detail"]
        r = c.post("/diagnose", json={"sample_rate_hz": 1000.0, "channels": [
            {"bearing": 1, "angle_deg": 45.0, "units": "um", "data": [0.0] * 100},
            {"bearing": 1, "angle_deg": 135.0, "units": "um", "data": [0.0] * 100}]})
        assert r.status_code == 503 and "retrain" in r.json()["detail"]
