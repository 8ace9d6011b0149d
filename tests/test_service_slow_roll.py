"""POST /diagnose with a slow-roll recording as a second multipart file (``slow_roll_file``), in the
server process and in a diagnosis worker process: the runout is subtracted and the evidence says so;
a hostile or mismatched second file is a 4xx that says what to fix, the same through both doors."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest
from fastapi.testclient import TestClient

from rotordiag.service.main import create_app
from tests.service_util import make_settings, shipped_or_tiny_registry
from tests.test_features_slow_roll import (
    RUNNING_RPM,
    SLOW_RPM,
    TOL_UM_PP,
    VIBRATION,
    _recording,
    _runout,
    _truth_um,
)


@pytest.fixture(scope="module")
def registry(tmp_path_factory):
    return shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))


@pytest.fixture(scope="module")
def clients(tmp_path_factory, registry):
    pooled = create_app(make_settings(tmp_path_factory.mktemp("pooled"), shipped_registry_dir=registry,
                                      diagnosis_workers=1))
    plain = create_app(make_settings(tmp_path_factory.mktemp("plain"), shipped_registry_dir=registry))
    with TestClient(pooled) as a, TestClient(plain) as b:
        assert a.app.state.rd.pool is not None and b.app.state.rd.pool is None
        yield {"pooled": a, "plain": b}


@pytest.fixture(scope="module")
def recs():
    runout = _runout(seed=11)
    return (_recording(RUNNING_RPM, 64, runout, seed=1),
            _recording(SLOW_RPM, 12, runout, vib_scale=(SLOW_RPM / RUNNING_RPM) ** 2, seed=2))


def _csv(rec) -> bytes:
    head = ",".join(f"b{c.bearing}@{c.angle_deg:g}" for c in rec.channels)
    rows = np.array([c.data for c in rec.channels]).T
    return (head + "\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in rows)).encode()


def _npy(array) -> bytes:
    buf = io.BytesIO()
    np.save(buf, array)
    return buf.getvalue()


def _kp(rec) -> str:
    return ",".join(repr(float(t)) for t in rec.keyphasor_times_s)


def _post(client, running, slow_part=None, **params):
    q = {"sample_rate_hz": running.sample_rate_hz, "keyphasor_times_s": _kp(running), **params}
    files = {"file": ("running.csv", _csv(running), "text/csv")}
    if slow_part is not None:
        files["slow_roll_file"] = slow_part
    return client.post("/diagnose", params=q, files=files)


def _vector_um_pp(verdict, bearing: int, name: str) -> float:
    return next(e["number"] for e in verdict["evidence"] if e["scope"] == f"bearing {bearing}" and e["name"] == name)


@pytest.mark.parametrize("door", ["plain", "pooled"])
def test_slow_roll_file_is_subtracted_and_said(clients, recs, door):
    client = clients[door]
    running, slow = recs
    raw = _post(client, running)
    assert raw.status_code == 200, raw.text
    # the slow roll as an NPY file (layout from the query, its own keyphasor times)
    r = _post(client, running, ("slow.npy", _npy(np.array([c.data for c in slow.channels])), "application/octet-stream"),
              bearings="2,2,3,3", angles_deg="45,135,45,135", slow_roll_keyphasor_times_s=_kp(slow))
    assert r.status_code == 200, r.text
    comp = r.json()
    items = [e for e in comp["evidence"] if e["name"] == "slow-roll compensation"]
    assert [e["scope"] for e in items] == ["bearing 2", "bearing 3"] and "subtracted" in items[0]["value"]
    assert not [e for e in raw.json()["evidence"] if e["name"] == "slow-roll compensation"]
    for b in VIBRATION:
        for d in "xy":
            for k in (1, 2):
                truth = 2 * abs(_truth_um(b, d, k))
                assert abs(_vector_um_pp(comp, b, f"{k}X {d}") - truth) < TOL_UM_PP
    # the runout moved the raw amplitudes (by up to its size, 1–5 µm pk-pk)
    assert max(abs(_vector_um_pp(raw.json(), b, f"{k}X {d}") - 2 * abs(_truth_um(b, d, k)))
               for b in VIBRATION for d in "xy" for k in (1, 2)) > 1.0


def test_pooled_and_plain_agree(clients, recs):
    running, slow = recs
    part = ("slow.csv", _csv(slow), "text/csv")
    a = _post(clients["pooled"], running, part, slow_roll_keyphasor_times_s=_kp(slow))
    b = _post(clients["plain"], running, part, slow_roll_keyphasor_times_s=_kp(slow))
    assert a.status_code == b.status_code == 200, (a.text, b.text)
    assert a.json()["evidence"] == b.json()["evidence"]


def _hostile_cases(running, slow):
    good_csv = _csv(slow)
    kp = {"slow_roll_keyphasor_times_s": _kp(slow)}
    too_long = np.zeros((4, 262_145))                  # one sample over the service's MAX_POINTS
    return {
        "garbage hdf5": (("slow.h5", b"\x89HDF\r\n\x1a\n" + bytes(range(256)) * 8, "application/x-hdf5"), kp,
                         422, "slow_roll_file 'slow.h5'"),
        "garbage csv": (("slow.csv", b"b2@45,b2@135\n1,x\n\x00\xff", "text/csv"), kp, 422, "slow_roll_file"),
        "oversized npy": (("slow.npy", _npy(too_long), "application/octet-stream"),
                          {**kp, "bearings": "2,2,3,3", "angles_deg": "45,135,45,135"}, 422, "slow_roll_file"),
        "pickled npy": (("slow.npy", _npy(np.array([object()], dtype=object)), "application/octet-stream"),
                        kp, 422, "slow_roll_file"),
        "unknown type": (("slow.xlsx", b"PK\x03\x04", "application/zip"), kp, 415, "slow_roll_file"),
        "empty": (("slow.csv", b"", "text/csv"), kp, 422, "empty"),
        "no keyphasor": (("slow.csv", good_csv, "text/csv"), {}, 422, "keyphasor"),
        "other probes": (("slow.csv", good_csv.replace(b"b3@45", b"b3@0", 1), "text/csv"), kp, 422, "same probes"),
        "too fast": (("slow.csv", _csv(running), "text/csv"), {"slow_roll_keyphasor_times_s": _kp(running)},
                     422, "at most 20 %"),
    }


@pytest.mark.parametrize("case", ["garbage hdf5", "garbage csv", "oversized npy", "pickled npy", "unknown type",
                                  "empty", "no keyphasor", "other probes", "too fast"])
def test_hostile_or_wrong_slow_roll_file_is_a_4xx(clients, recs, case):
    running, slow = recs
    part, params, status, needle = _hostile_cases(running, slow)[case]
    answers = []
    for door in ("plain", "pooled"):
        r = _post(clients[door], running, part, **params)
        assert r.status_code == status, (door, r.text)
        assert needle in r.json()["detail"], (door, r.text)
        answers.append(r.json())
    assert answers[0] == answers[1]


def test_slow_roll_part_must_be_a_file(clients, recs):
    running, _ = recs
    r = clients["plain"].post("/diagnose", params={"sample_rate_hz": running.sample_rate_hz,
                                                   "keyphasor_times_s": _kp(running)},
                              files={"file": ("running.csv", _csv(running), "text/csv")},
                              data={"slow_roll_file": "not a file"})
    assert r.status_code == 400 and "slow_roll_file" in r.json()["detail"]


def _json_file(path, rec):
    path.write_text(json.dumps({"sample_rate_hz": rec.sample_rate_hz,
                                "keyphasor_times_s": rec.keyphasor_times_s.tolist(),
                                "channels": [{"bearing": c.bearing, "angle_deg": c.angle_deg, "units": "um",
                                              "data": c.data.tolist()} for c in rec.channels]}))
    return path


def test_cli_slow_roll(registry, recs, tmp_path):
    from typer.testing import CliRunner

    from rotordiag.cli import app

    running, slow = recs
    run_f, slow_f = _json_file(tmp_path / "running.json", running), _json_file(tmp_path / "slow.json", slow)
    res = CliRunner().invoke(app, ["diagnose", str(run_f), "--registry", str(registry), "--json",
                                   "--slow-roll", str(slow_f)])
    assert res.exit_code == 0, res.output
    v = json.loads(res.output)
    assert any(n.startswith("slow-roll compensation: runout vectors measured at 180 r/min") for n in v["notes"])
    assert [e["scope"] for e in v["evidence"] if e["name"] == "slow-roll compensation"] == ["bearing 2", "bearing 3"]
    assert abs(_vector_um_pp(v, 2, "1X x") - 2 * abs(_truth_um(2, "x", 1))) < TOL_UM_PP
    # the running file given as the slow roll: refused, naming the option and the fix
    res = CliRunner().invoke(app, ["diagnose", str(run_f), "--registry", str(registry), "--slow-roll", str(run_f)])
    assert res.exit_code != 0 and "at most 20 %" in res.output
    # a garbage slow-roll file
    bad = tmp_path / "bad.h5"
    bad.write_bytes(b"\x89HDF\r\n\x1a\njunk")
    res = CliRunner().invoke(app, ["diagnose", str(run_f), "--registry", str(registry), "--slow-roll", str(bad)])
    assert res.exit_code != 0 and f"--slow-roll {bad}" in res.output
