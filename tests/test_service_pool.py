"""POST /diagnose through the diagnosis worker processes (``service/pool.py``): same answers and
the same 4xx messages as the in-process path, asset history kept, a dead worker replaced."""
from __future__ import annotations

import io
import os
import signal

import numpy as np
import pytest
from fastapi.testclient import TestClient

from tests.service_util import (
    auth,
    diagnose_json,
    pooled_and_plain_apps,
    simulated_channels,
)


@pytest.fixture(scope="module")
def clients(tmp_path_factory):
    pooled, plain = pooled_and_plain_apps(tmp_path_factory)
    with TestClient(pooled) as a, TestClient(plain) as b:
        assert a.app.state.rd.pool is not None and b.app.state.rd.pool is None
        yield a, b


@pytest.fixture(scope="module")
def rec():
    return simulated_channels(misalignment=0.2, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=40)


def _npy_request(channels):
    buf = io.BytesIO()
    np.save(buf, np.array([d for _, _, d in channels]))
    query = {"sample_rate_hz": 2048.0, "speed_rpm": 1800.0,
             "bearings": ",".join(str(b) for b, _, _ in channels),
             "angles_deg": ",".join(f"{a:g}" for _, a, _ in channels)}
    return dict(content=buf.getvalue(), params=query, headers={"Content-Type": "application/octet-stream"})


def test_worker_processes_give_the_in_process_verdict(clients, rec):
    pooled, plain = clients
    fs, channels = rec
    for kwargs in (dict(json=diagnose_json(fs, channels, speed_rpm=1800.0, clearance_um=350.0)),
                   _npy_request(channels)):
        a, b = pooled.post("/diagnose", **kwargs), plain.post("/diagnose", **kwargs)
        assert a.status_code == b.status_code == 200, (a.text, b.text)
        assert a.json() == b.json()


@pytest.mark.parametrize("case", ["non-finite", "no sample rate", "unknown version", "bad json"])
def test_worker_errors_are_the_same_4xx(clients, rec, case):
    pooled, plain = clients
    fs, channels = rec
    if case == "non-finite":
        body = diagnose_json(fs, channels)
        body["channels"][0]["data"][10] = "NaN"
        kwargs = dict(json=body)
    elif case == "no sample rate":
        kwargs = _npy_request(channels)
        del kwargs["params"]["sample_rate_hz"]
    elif case == "unknown version":
        kwargs = dict(json=diagnose_json(fs, channels), params={"model_version": "v9999"})
    else:
        kwargs = dict(content=b'{"sample_rate_hz": 2048, "channels": [', headers={"Content-Type": "application/json"})
    a, b = pooled.post("/diagnose", **kwargs), plain.post("/diagnose", **kwargs)
    assert 400 <= a.status_code < 500, a.text
    assert (a.status_code, a.json()) == (b.status_code, b.json())


def test_a_plant_model_in_the_body_and_in_batch_records_is_read_by_the_workers(clients, rec):
    """`plant_model` of a JSON body and of batch records: the workers answer as the in-process path, refusals
    included."""
    pooled, plain = clients
    fs, channels = rec
    body = diagnose_json(fs, channels, speed_rpm=1800.0, clearance_um=350.0)
    for kwargs in (dict(json={**body, "plant_model": "train:gen600_2pole"}),
                   dict(json={**body, "plant_model": "default"}, params={"plant_model": "gen50_2pole"}),
                   dict(json={"records": [{**body, "plant_model": "train:gen600_2pole"},
                                          {**body, "plant_model": "gen999"}]})):
        url = "/diagnose/batch" if "records" in kwargs["json"] else "/diagnose"
        a, b = pooled.post(url, **kwargs), plain.post(url, **kwargs)
        assert a.status_code == b.status_code, (a.text, b.text)
        assert a.json() == b.json()
    assert a.json()["items"][1]["status_code"] == 422 and "gen999" in a.json()["items"][1]["error"]


def test_asset_history_is_stored_by_the_server(clients, rec):
    pooled, _ = clients
    fs, channels = rec
    r = pooled.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0, asset_id="unit-7"),
                    headers=auth())   # storing needs the key
    assert r.status_code == 200, r.text
    hist = pooled.get("/assets/unit-7/history").json()
    assert hist["count"] == 1
    assert hist["points"][0]["severity"] == r.json()["severity"]


def test_a_killed_worker_is_replaced(clients, rec):
    pooled, _ = clients
    fs, channels = rec
    pool = pooled.app.state.rd.pool
    assert pooled.post("/diagnose", **_npy_request(channels)).status_code == 200
    old = pool.pids()
    os.kill(old[0], signal.SIGKILL)
    r = pooled.post("/diagnose", **_npy_request(channels))
    assert r.status_code == 200, r.text                 # retried on a live worker
    assert pool.pids() != old and len(pool.pids()) == len(old)


def test_activation_reaches_the_workers(clients, rec):
    """The workers read the active pointer on every request: no stale model after POST /models/{v}/activate."""
    import shutil

    pooled, _ = clients
    fs, channels = rec
    first = pooled.get("/models").json()["active"]
    registry = pooled.app.state.rd.settings.registry_dir
    shutil.copytree(registry / first, registry / "v0999")
    try:
        assert pooled.post("/diagnose", **_npy_request(channels)).json()["model_version"] == first
        assert pooled.post("/models/v0999/activate", headers=auth()).status_code == 200
        assert pooled.post("/diagnose", **_npy_request(channels)).json()["model_version"] == "v0999"
    finally:
        assert pooled.post(f"/models/{first}/activate", headers=auth()).status_code == 200
        shutil.rmtree(registry / "v0999")


def test_health_asks_the_workers_whether_the_model_loads(clients):
    """In pool mode the server process never loads a model; /health reports what the workers say."""
    import shutil

    pooled, _ = clients
    first = pooled.get("/models").json()["active"]
    registry = pooled.app.state.rd.settings.registry_dir
    shutil.copytree(registry / first, registry / "v0998")
    (registry / "v0998" / "model.skops").write_bytes(b"not a model")
    try:
        assert pooled.get("/health").status_code == 200
        assert pooled.post("/models/v0998/activate", headers=auth()).status_code == 200
        r = pooled.get("/health")
        assert r.status_code == 503 and "v0998" in r.json()["detail"], r.text
    finally:
        assert pooled.post(f"/models/{first}/activate", headers=auth()).status_code == 200
        shutil.rmtree(registry / "v0998")
    assert pooled.get("/health").status_code == 200
    assert pooled.app.state.rd.models._cache == {}       # the server process loaded nothing


def test_concurrent_requests_queue_and_all_get_the_same_answer(clients, rec):
    """More requests than the worker takes at once (depth 2): they wait, none is lost or mixed up."""
    from concurrent.futures import ThreadPoolExecutor

    pooled, _ = clients
    fs, channels = rec
    body = diagnose_json(fs, channels, speed_rpm=1800.0)
    with ThreadPoolExecutor(6) as ex:
        answers = list(ex.map(lambda _: pooled.post("/diagnose", json=body), range(6)))
    assert [a.status_code for a in answers] == [200] * 6
    assert all(a.json() == answers[0].json() for a in answers)
    assert all(w.inflight == 0 for w in pooled.app.state.rd.pool._workers)
