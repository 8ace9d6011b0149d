"""Property-based fuzz of numbers at the float edges on every door of the service (issue 44): 5e-324, 1e308,
-0.0, subnormals, NaN/Infinity in their spellings, in the JSON body, the query, CSV, NPY, HDF5 and UFF uploads,
the batch and the job bodies. No answer may be a 5xx, and no answer may carry a non-finite number.

Hypothesis runs derandomized (a fixed seed: the same examples every run).
"""
from __future__ import annotations

import io
import json
import math

import h5py
import numpy as np
import pytest
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rotordiag.service.main import create_app
from tests.service_util import auth, diagnose_json, make_settings, shipped_or_tiny_registry, simulated_channels

#: spellings of numbers at the edges: JSON can carry all but the non-standard ones, which must be refused cleanly
EDGE_TEXT = ["5e-324", "-5e-324", "1e308", "-1e308", "1.7976931348623157e308", "1e309", "1e999", "-0.0", "0",
             "2.2250738585072014e-308", "1e-310", "NaN", "nan", "Infinity", "-Infinity", "inf", "-inf", "1e-320",
             "4.9e-324", "1E+308", "0e0", "123456789" * 40]
EDGE_FLOATS = [5e-324, -5e-324, 1e308, -1e308, 1.7976931348623157e308, -0.0, 0.0, 2.2250738585072014e-308, 1e-310,
               math.nan, math.inf, -math.inf, 1e-320]

edge_text = st.sampled_from(EDGE_TEXT) | st.floats(allow_subnormal=True, width=64).map(repr)
edge_float = st.sampled_from(EDGE_FLOATS) | st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)

FUZZ = settings(max_examples=20, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _strict(text: str) -> None:
    """The answer is strict JSON: a NaN/Infinity anywhere fails here."""
    def refuse(name):
        raise AssertionError(f"response contains {name}")
    json.loads(text, parse_constant=refuse)


def _ok(r) -> None:
    assert r.status_code < 500, (r.status_code, r.text[:500])
    _strict(r.text)


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    registry = shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))
    app = create_app(make_settings(tmp_path_factory.mktemp("edges"), shipped_registry_dir=registry))
    with TestClient(app) as c:
        queued: list = []

        class _Job:                       # job bodies are validated, never run here
            id, status = "fuzz", "queued"

        def submit(kind, params):
            json.dumps(params, allow_nan=False)   # what is stored must be finite JSON
            queued.append(kind)
            return _Job()

        app.state.rd.jobs.submit = submit
        yield c


@pytest.fixture(scope="module")
def rec():
    fs, channels = simulated_channels(misalignment=0.2, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=24)
    return fs, [(b, a, d[:1024]) for b, a, d in channels[:4]]


PLACEHOLDER = "987654.321"


def _with_text(body: dict, path: tuple, text: str) -> bytes:
    """``body`` as JSON text with the value at ``path`` spelled exactly as ``text``."""
    target = body
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = float(PLACEHOLDER)
    return json.dumps(body).replace(PLACEHOLDER, text, 1).encode()


JSON_PATHS = [("sample_rate_hz",), ("speed_rpm",), ("clearance_um",), ("speed_range_rpm", 0), ("speed_range_rpm", 1),
              ("channels", 0, "data", 5), ("channels", 1, "angle_deg"), ("keyphasor_times_s", 1)]


@FUZZ
@given(path=st.sampled_from(JSON_PATHS), text=edge_text)
def test_json_body(client, rec, path, text):
    fs, channels = rec
    body = diagnose_json(fs, channels, speed_rpm=1800.0)
    body["speed_range_rpm"] = [1700.0, 1900.0]
    body["keyphasor_times_s"] = [i / 30.0 for i in range(10)]
    _ok(client.post("/diagnose", content=_with_text(body, path, text), headers={"Content-Type": "application/json"}))


def _npy(arr) -> bytes:
    bio = io.BytesIO()
    np.save(bio, np.asarray(arr))
    return bio.getvalue()


QUERY_KEYS = ["sample_rate_hz", "speed_rpm", "clearance_um", "speed_range_rpm", "angles_deg", "keyphasor_times_s",
              "sensitivity_v_per_mm", "gap_voltage_v", "keyphasor_threshold_v", "slow_roll_sample_rate_hz"]


@FUZZ
@given(key=st.sampled_from(QUERY_KEYS), text=edge_text)
def test_query_parameters(client, rec, key, text):
    fs, channels = rec
    query = {"sample_rate_hz": str(fs), "speed_rpm": "1800", "bearings": ",".join(str(b) for b, _, _ in channels),
             "angles_deg": ",".join(str(a) for _, a, _ in channels)}
    if key in ("sensitivity_v_per_mm", "gap_voltage_v"):
        query["units"] = "V"
        query.setdefault("sensitivity_v_per_mm", "7.87")
    if key == "speed_range_rpm":
        text = f"{text},1900"
    elif key == "angles_deg":
        text = ",".join([text] + [str(a) for _, a, _ in channels[1:]])
    elif key == "keyphasor_times_s":
        text = f"0,{text},0.1"
    query[key] = text
    _ok(client.post("/diagnose", params=query, content=_npy(np.stack([d for _, _, d in channels])),
                    headers={"Content-Type": "application/octet-stream"}))


@FUZZ
@given(text=edge_text, row=st.integers(0, 1023), col=st.integers(0, 3), rate=edge_text)
def test_csv_upload(client, rec, text, row, col, rate):
    fs, channels = rec
    data = np.stack([d for _, _, d in channels]).T.astype(str)
    data[row, col] = text
    head = ",".join(f"b{b}@{a:g}" for b, a, _ in channels)
    csv = head + "\n" + "\n".join(",".join(r) for r in data) + "\n"
    _ok(client.post("/diagnose", params={"sample_rate_hz": str(fs), "speed_rpm": "1800"},
                    files={"file": ("edge.csv", csv.encode(), "text/csv")}))
    _ok(client.post("/diagnose", params={"sample_rate_hz": rate, "speed_rpm": "1800"},
                    files={"file": ("edge.csv", csv.encode(), "text/csv")}))


@FUZZ
@given(value=edge_float, scale_all=st.booleans(), dtype=st.sampled_from(["<f8", "<f4"]))
def test_npy_upload(client, rec, value, scale_all, dtype):
    fs, channels = rec
    arr = np.stack([d for _, _, d in channels])
    with np.errstate(all="ignore"):
        if scale_all:
            arr = arr * value if math.isfinite(value) else np.full_like(arr, value)
        else:
            arr = arr.copy()
            arr[1, 7] = value
        arr = arr.astype(dtype)
    query = {"sample_rate_hz": str(fs), "speed_rpm": "1800", "bearings": ",".join(str(b) for b, _, _ in channels),
             "angles_deg": ",".join(str(a) for _, a, _ in channels)}
    _ok(client.post("/diagnose", params=query, content=_npy(arr), headers={"Content-Type": "application/octet-stream"}))
    _ok(client.post("/diagnose", params=query, files={"file": ("edge.npy", _npy(arr), "application/octet-stream")}))


@FUZZ
@given(key=st.sampled_from(["sample_rate_hz", "speed_rpm", "clearance_um", "data"]), value=edge_float)
def test_hdf5_upload(client, rec, key, value):
    fs, channels = rec
    arr = np.stack([d for _, _, d in channels])
    bio = io.BytesIO()
    with h5py.File(bio, "w") as f:
        if key == "data":
            arr = arr.copy()
            arr[0, 3] = value
        ds = f.create_dataset("waveforms", data=arr)
        f.attrs["sample_rate_hz"] = fs
        f.attrs["speed_rpm"] = 1800.0
        if key != "data":
            ds.attrs[key] = value
    query = {"bearings": ",".join(str(b) for b, _, _ in channels), "angles_deg": ",".join(str(a) for _, a, _ in channels)}
    _ok(client.post("/diagnose", params=query, files={"file": ("edge.h5", bio.getvalue(), "application/x-hdf5")}))


@FUZZ
@given(rate=edge_float, value=edge_float)
def test_uff_upload(client, rec, tmp_path_factory, rate, value):
    from rotordiag.simulator.cli import write_probes

    fs, channels = rec
    arr = np.stack([d for _, _, d in channels]).copy()
    arr[2, 11] = value
    path = tmp_path_factory.mktemp("uff") / "edge.uff"
    for fs_written in (fs, rate):
        try:
            with np.errstate(all="ignore"):
                write_probes(path, arr, [(b, a) for b, a, _ in channels], fs_written)
        except (ValueError, ZeroDivisionError, OverflowError):
            continue                       # the writer refused it: nothing to upload
        _ok(client.post("/diagnose", params={"speed_rpm": "1800"},
                        files={"file": ("edge.uff", path.read_bytes(), "application/octet-stream")}))
        path.unlink()


@FUZZ
@given(path=st.sampled_from(JSON_PATHS[:5] + [("channels", 0, "data", 5)]), text=edge_text)
def test_batch(client, rec, path, text):
    fs, channels = rec
    good = diagnose_json(fs, channels, speed_rpm=1800.0)
    bad = json.loads(json.dumps(good))
    bad["speed_range_rpm"] = [1700.0, 1900.0]
    record = _with_text(bad, path, text).decode()
    body = ('{"records": [' + json.dumps(good) + "," + record + "]}").encode()
    r = client.post("/diagnose/batch", content=body, headers={"Content-Type": "application/json"})
    _ok(r)
    if r.status_code == 200:
        items = r.json()["items"]
        assert items[0]["status_code"] == 200, items[0]
        assert all(it["status_code"] < 500 for it in items), items


SPEC = {"design": {"method": "sobol", "n_samples": 8, "seed": 1},
        "operating": {"misalignment": {"min": 0.0, "max": 0.6}, "speed_rpm": {"min": 1500.0, "max": 2100.0}},
        "measurement": {"sample_rate_hz": 2048.0, "duration_revs": 16.0, "snr_db": 30.0}}
SPEC_PATHS = [("spec", "measurement", "sample_rate_hz"), ("spec", "measurement", "duration_revs"),
              ("spec", "measurement", "snr_db"), ("spec", "operating", "misalignment", "max"),
              ("spec", "operating", "speed_rpm", "min"), ("spec", "design", "n_samples")]
RETRAIN_PATHS = [("plant", "generator_mass_kg"), ("plant", "clearance_m"), ("plant", "asymmetry"),
                 ("training", "classifier", "max_iter"), ("training", "classifier", "learning_rate"),
                 ("sweep", "measurement", "duration_revs")]


@FUZZ
@given(path=st.sampled_from(SPEC_PATHS + RETRAIN_PATHS), text=edge_text)
def test_job_bodies(client, path, text):
    if path[0] == "spec":
        body: dict = {"spec": json.loads(json.dumps(SPEC))}
        url = "/datasets"
    else:
        body = {"plant": {}, "training": {"classifier": {}}, "sweep": {"measurement": {}}}
        url = "/models/retrain"
    target = body
    for key in path[:-1]:
        target = target.setdefault(key, {})
    _ok(client.post(url, content=_with_text(body, path, text), headers={**auth(), "Content-Type": "application/json"}))
    if path[0] == "spec":                  # the same number in the TOML text
        toml = (f"[design]\nmethod = 'sobol'\nn_samples = 8\nseed = 1\n[operating]\n"
                f"misalignment = {{min = 0.0, max = 0.6}}\nspeed_rpm = {{min = 1500.0, max = 2100.0}}\n"
                f"[measurement]\nsample_rate_hz = 2048.0\nsnr_db = 30.0\nduration_revs = {text}\n")
        _ok(client.post(url, json={"spec_toml": toml}, headers=auth()))
