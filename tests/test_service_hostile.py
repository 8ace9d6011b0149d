"""Hostile input against the service (issue 12): every file is generated here, every answer must be a 4xx
that says what to fix (never a 5xx, a crash, a leak or a non-finite number), and the service must stay up.

Run alone with ``.venv/bin/pytest -q tests/test_service_hostile.py`` (docs/service.md, "Security").
"""
from __future__ import annotations

import asyncio
import io
import json
import os
import signal
import time

import h5py
import numpy as np
import pytest
from fastapi.testclient import TestClient

from rotordiag.service.main import create_app
from tests.service_util import (
    API_KEY,
    auth,
    diagnose_json,
    make_settings,
    shipped_or_tiny_registry,
    simulated_channels,
    two_takes,
    write_takes_csv,
)

MB = 1 << 20
SECRET = b"ROTORDIAG_API_KEY=hunter2-secret\n"


def _strict_json(text: str):
    """Parse as strict JSON: a NaN/Infinity anywhere in a response fails here."""
    def refuse(name):
        raise AssertionError(f"response contains {name}")
    return json.loads(text, parse_constant=refuse)


def _h5(build) -> bytes:
    bio = io.BytesIO()
    with h5py.File(bio, "w") as f:
        build(f)
    return bio.getvalue()


def _npy(arr) -> bytes:
    bio = io.BytesIO()
    np.save(bio, arr)
    return bio.getvalue()


def _hostile_files(secret_path) -> dict[str, tuple[str, bytes]]:
    def external(f):
        f.create_dataset("waveforms", shape=(1, len(SECRET)), dtype="u1", external=[(str(secret_path), 0, len(SECRET))])
        f.attrs["sample_rate_hz"] = 2048.0

    def virtual(f):
        layout = h5py.VirtualLayout(shape=(1, 8), dtype="f8")
        layout[:] = h5py.VirtualSource(".", "waveforms", shape=(1, 8))   # maps itself: h5py's stack overflow
        f.create_virtual_dataset("waveforms", layout)
        f.attrs["sample_rate_hz"] = 2048.0

    def bomb(f):
        ds = f.create_dataset("waveforms", shape=(1, 1), maxshape=(None, None), chunks=(1, 4 * MB),
                              dtype="f8", compression="gzip", compression_opts=9)
        ds.resize((1, 4 * MB))
        ds[0, :] = 0.0
        ds.resize((1, 1))
        f.attrs["sample_rate_hz"] = 2048.0

    huge = _npy(np.zeros((8, 10), np.float64)).replace(b"(8, 10)", b"(8, 100000000000)")
    return {"external storage": ("rec.h5", _h5(external)), "virtual dataset": ("rec.h5", _h5(virtual)),
            "gzip bomb": ("rec.h5", _h5(bomb)), "huge-shape npy": ("rec.npy", huge)}


@pytest.fixture(scope="module")
def registry(tmp_path_factory):
    return shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))


@pytest.fixture(scope="module")
def pooled(tmp_path_factory, registry):
    app = create_app(make_settings(tmp_path_factory.mktemp("pooled"), shipped_registry_dir=registry,
                                   diagnosis_workers=2))
    with TestClient(app) as c:
        yield c


@pytest.fixture(scope="module")
def plain(tmp_path_factory, registry):
    app = create_app(make_settings(tmp_path_factory.mktemp("plain"), shipped_registry_dir=registry))
    with TestClient(app) as c:
        yield c


@pytest.fixture(scope="module")
def keyed(tmp_path_factory, registry):
    app = create_app(make_settings(tmp_path_factory.mktemp("keyed"), shipped_registry_dir=registry,
                                   diagnose_requires_key=True))
    with TestClient(app) as c:
        yield c


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    secret = tmp_path_factory.mktemp("secret") / "environ"
    secret.write_bytes(SECRET)
    return _hostile_files(secret)


@pytest.fixture(scope="module")
def rec():
    return simulated_channels(misalignment=0.2, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=40)


# ------------------------------------------------------------------------------------------ hostile files
@pytest.mark.parametrize("mode", ["workers", "in-process"])
@pytest.mark.parametrize("endpoint", ["/diagnose", "/ui/plot-data"])
@pytest.mark.parametrize("name", ["external storage", "virtual dataset", "gzip bomb", "huge-shape npy"])
def test_hostile_files_are_refused_and_the_service_stays_up(request, files, mode, endpoint, name):
    client = request.getfixturevalue("pooled" if mode == "workers" else "plain")
    pool = client.app.state.rd.pool
    pids = pool.pids() if pool is not None else None
    filename, data = files[name]
    r = client.post(endpoint, files={"file": (filename, data)}, params={"sample_rate_hz": 2048.0})
    assert 400 <= r.status_code < 500, (r.status_code, r.text)
    detail = _strict_json(r.text)["detail"]
    assert "hunter2" not in r.text and "ROTORDIAG_API_KEY" not in r.text
    assert isinstance(detail, str) and len(detail) > 20
    expected = {"external storage": "external storage", "virtual dataset": "virtual dataset",
                "gzip bomb": "", "huge-shape npy": ""}[name]
    assert expected in detail, detail
    assert client.get("/health").status_code == 200
    if pool is not None:
        assert pool.pids() == pids              # no worker died on it


@pytest.mark.parametrize("mode", ["workers", "in-process"])
@pytest.mark.parametrize("endpoint", ["/diagnose", "/ui/plot-data"])
@pytest.mark.parametrize("name", ["external storage", "virtual dataset", "gzip bomb", "huge-shape npy"])
def test_a_hostile_file_as_a_second_take_is_refused_naming_it(request, files, rec, mode, endpoint, name):
    """Takes uploaded as separate files (several parts `file`): every one goes through the same reader, limits and
    worker as a single upload — a hostile second take behind a good first is a 4xx that names it, no worker dies."""
    client = request.getfixturevalue("pooled" if mode == "workers" else "plain")
    pool = client.app.state.rd.pool
    pids = pool.pids() if pool is not None else None
    fs, channels = rec
    good = _npy(np.array([d for b, _, d in channels if b in (1, 2)]))
    filename, data = files[name]
    r = client.post(endpoint, files=[("file", ("take_a.npy", good)), ("file", (filename, data))],
                    params={"sample_rate_hz": fs, "bearings": "1,1,2,2;"})
    assert 400 <= r.status_code < 500, (r.status_code, r.text)
    detail = _strict_json(r.text)["detail"]
    assert "hunter2" not in r.text and "ROTORDIAG_API_KEY" not in r.text
    assert f"take file {filename!r}" in detail, detail
    assert client.get("/health").status_code == 200
    if pool is not None:
        assert pool.pids() == pids


def test_takes_through_the_workers_give_the_in_process_verdict(pooled, plain, rec, tmp_path):
    """Two take files (bearings 1-2, 3-4, a `kp` column each) travel to a worker as their bytes and names and are
    merged there: the same verdict as parsed in-process."""
    t, first, second, kp_a, kp_b, _, names = two_takes(rec)
    files = [("file", (name, write_takes_csv(tmp_path / name, t, [*rows, kp], [*cols, "kp"]).read_bytes()))
             for name, rows, kp, cols in (("take_a.csv", first, kp_a, names[:4]), ("take_b.csv", second, kp_b, names[4:]))]
    answers = [c.post("/diagnose", params={"clearance_um": 350.0}, files=files) for c in (pooled, plain)]
    assert [a.status_code for a in answers] == [200, 200], answers[0].text
    assert answers[0].json()["probabilities"] == pytest.approx(answers[1].json()["probabilities"], rel=1e-12)
    assert answers[0].json()["speed_source"] == "keyphasor"


@pytest.mark.parametrize("parts", [5, 40])
def test_more_take_files_than_bearings_are_refused(pooled, rec, parts):
    """At most four takes (bearings 1-4; a fifth part only as /diagnose's slow_roll_file): five parts `file` are a 422
    that says so, forty are refused by the form parser before any file is read (400)."""
    fs, channels = rec
    one = _npy(np.array([d for _, _, d in channels[:2]]))
    r = pooled.post("/diagnose", files=[("file", (f"t{i}.npy", one)) for i in range(parts)],
                    params={"sample_rate_hz": fs})
    assert r.status_code == (422 if parts == 5 else 400), r.text
    assert ("at most 4 takes" if parts == 5 else "takes as separate files (at most 4") in r.json()["detail"], r.text
    assert pooled.get("/health").status_code == 200


def test_the_same_hostile_npy_as_a_binary_body(pooled, files):
    r = pooled.post("/diagnose", content=files["huge-shape npy"][1], params={"sample_rate_hz": 2048.0},
                    headers={"Content-Type": "application/octet-stream"})
    assert r.status_code == 422 and "shape" in r.json()["detail"], r.text


# ------------------------------------------------------------------------------------------ JSON
_NON_FINITE = [b"NaN", b"Infinity", b"-Infinity", b"1e999"]


@pytest.mark.parametrize("token", _NON_FINITE)
@pytest.mark.parametrize("path,template,needs_key", [
    ("/diagnose", b'{"sample_rate_hz": %s, "channels": []}', False),
    ("/diagnose/batch", b'{"records": [{"sample_rate_hz": %s, "channels": []}]}', False),
    ("/ui/plot-data", b'{"sample_rate_hz": 2048, "channels": [{"bearing": 1, "angle_deg": 45, "units": "um", '
                      b'"data": [1.0, %s]}]}', False),
    ("/models/retrain", b'{"plant": {"asymmetry": %s}}', True),
    ("/datasets", b'{"spec": {"design": {"n_samples": %s}}}', True),
])
@pytest.mark.parametrize("mode", ["workers", "in-process"])
def test_non_finite_json_is_a_422_that_says_so(request, mode, path, template, needs_key, token):
    client = request.getfixturevalue("pooled" if mode == "workers" else "plain")
    headers = {"Content-Type": "application/json", **(auth() if needs_key else {})}
    r = client.post(path, content=template % token, headers=headers)
    assert r.status_code == 422, (r.status_code, r.text)
    detail = _strict_json(r.text)["detail"]
    assert isinstance(detail, str) and "finite" in detail, detail


def test_validation_errors_never_echo_non_finite_numbers(plain):
    from pydantic import BaseModel, Field, ValidationError

    from rotordiag.service.api.errors import validation_detail

    class M(BaseModel):
        x: float = Field(le=1.0)

    with pytest.raises(ValidationError) as info:
        M(x=float("inf"))
    detail = validation_detail(info.value)
    json.dumps(detail, allow_nan=False)          # raises on NaN/inf
    assert "input" not in detail[0]


# ------------------------------------------------------------------------------------------ auth
def test_plot_data_follows_the_diagnose_key_setting(keyed, plain, rec):
    fs, channels = rec
    body = diagnose_json(fs, channels, speed_rpm=1800.0)
    assert keyed.post("/ui/plot-data", json=body).status_code == 401
    assert keyed.post("/ui/plot-data", json=body, headers={"X-API-Key": "wrong"}).status_code == 403
    assert keyed.post("/ui/plot-data", json=body, headers=auth()).status_code == 200
    assert plain.post("/ui/plot-data", json=body).status_code == 200


@pytest.mark.parametrize("path", ["/models/retrain", "/datasets", "/diagnose", "/assets/pump-1/baseline"])
def test_keyless_write_bodies_are_refused_before_a_byte_is_read(keyed, path):
    """Drive the ASGI app directly and count what it pulls from ``receive``: nothing without a key."""
    app = keyed.app
    pulled = []

    async def receive():
        pulled.append(1)
        return {"type": "http.request", "body": b"{" + b" " * (8 * MB), "more_body": False}

    async def run(headers):
        sent = []

        async def send(message):
            sent.append(message)

        scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1", "method": "POST",
                 "scheme": "http", "path": path, "raw_path": path.encode(), "root_path": "", "query_string": b"",
                 "headers": headers, "client": ("127.0.0.1", 1), "server": ("127.0.0.1", 80)}
        await app(scope, receive, send)
        return next(m["status"] for m in sent if m["type"] == "http.response.start")

    base = [(b"content-type", b"application/json"), (b"content-length", str(8 * MB + 1).encode())]
    assert asyncio.run(run(base)) == 401
    assert asyncio.run(run(base + [(b"x-api-key", b"wrong")])) == 403
    assert pulled == []                                     # the body was never read
    status = asyncio.run(run(base + [(b"x-api-key", API_KEY.encode())]))
    assert pulled and 400 <= status < 500                   # with the key the body is read (and is not JSON)


def test_openapi_lists_the_key_on_diagnose_only_when_required(plain, keyed):
    for client, required in ((plain, False), (keyed, True)):
        schema = client.get("/openapi.json").json()
        for path in ("/diagnose", "/diagnose/batch"):
            assert bool(schema["paths"][path]["post"].get("security")) is required, (path, required)
        assert schema["paths"]["/models/retrain"]["post"].get("security")
        assert "BatchRequest" in schema["components"]["schemas"]


# ------------------------------------------------------------------------------------------ silent wrongs
def test_all_zero_probes_are_never_a_plain_aligned(pooled, rec):
    fs, channels = rec
    zeros = [(b, a, np.zeros_like(d)) for b, a, d in channels]
    for extra in ({"speed_rpm": 1800.0}, {}):
        r = pooled.post("/diagnose", json=diagnose_json(fs, zeros, **extra))
        assert r.status_code in (200, 422), r.text
        if r.status_code == 200:
            verdict = r.json()
            assert verdict["status"] == "inconclusive", verdict["status"]
            assert any(x["code"] in ("zero_channel", "flat_channel") for x in verdict["reasons"])


def test_asset_id_with_a_slash_is_refused_in_the_users_terms(plain, rec):
    fs, channels = rec
    r = plain.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0, asset_id="site/unit-3"))
    assert r.status_code == 422 and "no '/'" in json.dumps(r.json()), r.text
    buf = io.BytesIO()
    np.save(buf, np.array([d for _, _, d in channels]))
    r = plain.post("/diagnose", content=buf.getvalue(), headers={"Content-Type": "application/octet-stream"},
                   params={"sample_rate_hz": fs, "asset_id": "a/b"})
    assert r.status_code == 422 and "no '/'" in json.dumps(r.json()), r.text
    r = plain.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0, asset_id="site:unit-3"),
                   headers=auth())   # storing needs the key
    assert r.status_code == 200
    assert plain.get("/assets/site:unit-3/history").json()["count"] == 1


@pytest.mark.parametrize("case", ["huge values", "tiny values", "empty filename", "empty filename, big part"])
def test_messages_are_in_the_users_terms(plain, case):
    n = 2048 * 8
    t = np.arange(n) / 2048.0
    sine = np.sin(2 * np.pi * 30 * t)
    pair = {"huge values": (1e300 * np.ones(n), -1e300 * np.ones(n)), "tiny values": (1e-300 * sine, 1e-300 * sine[::-1])}
    if case.startswith("empty filename"):
        content = b"1,2\n" * (10 if case == "empty filename" else 400_000)
        r = plain.post("/diagnose", files={"file": ("", content)})
    else:
        x, y = pair[case]
        r = plain.post("/diagnose", json=diagnose_json(2048.0, [(2, 45.0, x), (2, 135.0, y)], speed_rpm=1800.0))
    assert r.status_code < 500, r.text
    for internal in ("period_rtol", "Input X contains", "Part exceeded", "dtype(", "Traceback"):
        assert internal not in r.text, r.text
    if r.status_code >= 400:
        assert "file" in r.text or "units" in r.text or "record" in r.text, r.text


@pytest.mark.parametrize("case", ["9k one-pulse takes", "32 keyphasor channels", "5 trains in JSON",
                                  "nested trains, no acquisitions"])
def test_keyphasor_per_take_inputs_are_bounded(plain, rec, case):
    """One keyphasor per take (features._takes) through the query, the channel option and JSON: whatever the count
    of takes, a 4xx that says what to give — never a 500, nothing allocated per take beyond the pulses sent."""
    fs, channels = rec
    data = np.array([d for _, _, d in channels])
    if case == "9k one-pulse takes":
        r = plain.post("/diagnose", content=_npy(data), headers={"Content-Type": "application/octet-stream"},
                       params={"sample_rate_hz": fs, "acquisitions": "1,2;3,4",
                               "keyphasor_times_s": ";".join(["0.1"] * 9_000)})
        needle = "at least 2 pulse times"
    elif case == "32 keyphasor channels":
        r = plain.post("/diagnose", content=_npy(np.vstack([data, data[:1]])),
                       headers={"Content-Type": "application/octet-stream"},
                       params={"sample_rate_hz": fs, "acquisitions": "1,2;3,4",
                               "keyphasor_channel": ";".join(["8"] * 32)})
        needle = "32 keyphasor channels"
    else:
        trains = [[0.0, 1 / 30.0, 2 / 30.0]] * (5 if case == "5 trains in JSON" else 2)
        extra = {"acquisitions": "1,2;3,4"} if case == "5 trains in JSON" else {}
        r = plain.post("/diagnose", json=diagnose_json(fs, channels, keyphasor_times_s=trains, **extra))
        needle = "keyphasor_times_s"
    assert 400 <= r.status_code < 500, r.text
    assert needle in r.text, r.text


@pytest.mark.parametrize("case", ["data false", "since 0.5", "activate 0", "bearing string"])
def test_no_loose_coercion(plain, rec, case):
    fs, channels = rec
    if case == "since 0.5":
        r = plain.get("/assets/x/history", params={"since": "0.5"})
    elif case == "activate 0":
        r = plain.post("/models/retrain", json={"activate": 0}, headers=auth())
    else:
        body = diagnose_json(fs, channels, speed_rpm=1800.0)
        if case == "data false":
            body["channels"][0]["data"][:3] = [False, False, False]
        else:
            body["channels"][0]["bearing"] = "2"
        r = plain.post("/diagnose", json=body)
    assert r.status_code == 422, r.text
    assert plain.get("/jobs").json()["count"] == 0          # no job was started by a coerced body


# ------------------------------------------------------------------------------------------ workers
def test_requests_spread_across_the_workers(pooled, rec):
    fs, channels = rec
    workers = pooled.app.state.rd.pool._workers
    before = [w.served for w in workers]
    for _ in range(6):
        assert pooled.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0)).status_code == 200
    served = [w.served - b for w, b in zip(workers, before, strict=True)]
    assert sum(served) == 6 and min(served) >= 2, served


def test_a_request_over_the_time_limit_is_stopped_not_retried(pooled, rec):
    fs, channels = rec
    pool = pooled.app.state.rd.pool
    pids = pool.pids()
    limit = pool.timeout_s
    for w in pool._workers:
        w.timeout_s = 0.001
    pool.timeout_s = 0.001
    try:
        r = pooled.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0))
    finally:
        pool.timeout_s = limit
        for w in pool._workers:
            w.timeout_s = limit
    assert r.status_code == 422 and "longer than the limit" in r.json()["detail"], r.text
    new = pool.pids()
    assert len(set(new) - set(pids)) == 1          # exactly one worker (the one that had it) was replaced
    _wait_ready(pool)
    for w in pool._workers:
        w.timeout_s = limit
    assert pooled.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0)).status_code == 200


def _wait_ready(pool, timeout_s=120.0):
    t0 = time.monotonic()
    while not all(w.ready and w.alive for w in pool._workers):
        assert time.monotonic() - t0 < timeout_s, "a replacement worker did not become ready"
        time.sleep(0.1)


def test_a_killed_workers_requests_go_to_the_warm_worker_at_once(pooled, rec):
    fs, channels = rec
    pool = pooled.app.state.rd.pool
    _wait_ready(pool)
    victim = pool._workers[0]
    os.kill(victim.process.pid, signal.SIGKILL)
    while victim.process.is_alive():
        time.sleep(0.01)
    t0 = time.monotonic()
    r = pooled.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0))
    elapsed = time.monotonic() - t0
    assert r.status_code == 200, r.text
    replacement = pool._workers[0]
    assert replacement is not victim
    # answered by the surviving warm worker while the replacement was still starting
    assert replacement.served == 0 or not replacement.ready, (replacement.served, elapsed)
    _wait_ready(pool)


def test_health_sees_the_model_file_change_under_the_workers(pooled, rec, monkeypatch):
    import shutil

    from rotordiag.service import pool as pool_module

    interval_s = 0.5       # /health reuses the workers' answer this long (MODEL_CHECK_INTERVAL_S, 5 s in service)
    monkeypatch.setattr(pool_module, "MODEL_CHECK_INTERVAL_S", interval_s)
    fs, channels = rec
    pool = pooled.app.state.rd.pool
    _wait_ready(pool)
    first = pooled.get("/models").json()["active"]
    registry = pooled.app.state.rd.settings.registry_dir
    shutil.copytree(registry / first, registry / "v0997")
    try:
        assert pooled.post("/models/v0997/activate", headers=auth()).status_code == 200
        h = pooled.get("/health")
        assert h.status_code == 200 and h.json()["model_sha256"], h.text
        (registry / "v0997" / "model.skops").write_bytes(b"corrupted under the running service")
        time.sleep(interval_s + 0.2)
        h = pooled.get("/health")
        assert h.status_code == 503 and "v0997" in h.json()["detail"], h.text
        r = pooled.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0))
        assert r.status_code == 503, r.text           # what /health said: diagnoses fail
    finally:
        assert pooled.post(f"/models/{first}/activate", headers=auth()).status_code == 200
        shutil.rmtree(registry / "v0997")
    time.sleep(interval_s + 0.2)
    assert pooled.get("/health").status_code == 200


# ------------------------------------------------------------------------------------------ real sockets
@pytest.fixture(scope="module")
def server(tmp_path_factory, registry):
    """``rotordiag serve`` (uvicorn) with one diagnosis worker and a 2 s body timeout."""
    import subprocess
    import sys
    from pathlib import Path

    from tests.test_service_e2e import _free_port, _request

    tmp = tmp_path_factory.mktemp("socket")
    port = _free_port()
    env = dict(os.environ, ROTORDIAG_DATA_DIR=str(tmp / "data"), ROTORDIAG_API_KEY=API_KEY,
               ROTORDIAG_BODY_TIMEOUT_S="2", ROTORDIAG_DIAGNOSIS_WORKERS="1",
               ROTORDIAG_SHIPPED_REGISTRY_DIR=str(registry))
    exe = Path(sys.executable).parent / "rotordiag"
    proc = subprocess.Popen([str(exe), "serve", "--host", "127.0.0.1", "--port", str(port)], cwd=tmp, env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    base = f"http://127.0.0.1:{port}"
    t0 = time.monotonic()
    while True:
        assert proc.poll() is None, "server exited"
        try:
            if _request(base + "/health")[0] == 200:
                break
        except OSError:
            pass
        assert time.monotonic() - t0 < 90, "server did not answer /health"
        time.sleep(0.2)
    yield base, port
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()


def _read_answer(sock, timeout_s: float) -> bytes:
    sock.settimeout(timeout_s)
    got = b""
    try:
        while True:
            more = sock.recv(65536)
            if not more:
                break                    # the server closed the connection
            got += more
    except TimeoutError:
        pass
    return got


def test_half_sent_bodies_get_408_and_hold_no_worker(server, rec):
    import socket

    from tests.test_service_e2e import _request

    base, port = server
    fs, channels = rec
    body = json.dumps(diagnose_json(fs, channels, speed_rpm=1800.0)).encode()
    head = (b"POST /diagnose HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
            b"Content-Length: %d\r\n\r\n" % len(body))
    slow = []
    for _ in range(5):
        s = socket.create_connection(("127.0.0.1", port), timeout=10)
        s.sendall(head + body[: len(body) // 2])
        slow.append(s)
    t0 = time.monotonic()
    status, raw = _request(base + "/diagnose", body, {"Content-Type": "application/json"})
    assert status == 200, raw[:300]                    # the one worker is free: slow clients hold none
    answers = [_read_answer(s, 10.0) for s in slow]
    elapsed = time.monotonic() - t0
    for s in slow:
        s.close()
    for a in answers:
        assert a.startswith(b"HTTP/1.1 408"), a[:200]
        assert b"did not arrive within 2 s" in a
    assert elapsed < 10.0


def test_keyless_large_write_is_answered_before_the_body_is_sent(server):
    import socket

    _, port = server
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(b"POST /models/retrain HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                  b"Content-Length: 50000000\r\n\r\n{")           # 50 MB announced, 1 byte sent
        answer = _read_answer(s, 5.0)
    assert answer.startswith(b"HTTP/1.1 401"), answer[:200]
