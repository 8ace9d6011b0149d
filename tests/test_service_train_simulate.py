"""POST /trains/simulate: a shaft train's steady recording over HTTP — the same waveforms as the Python door, a file
in the CLI's layout that the reader takes, the record bounded before anything is allocated, and every bad input a
4xx that says what to fix (a journal pressed on its metal names the bearing and the offset the train takes)."""
from __future__ import annotations

import io
import json

import numpy as np
import pytest
from fastapi.testclient import TestClient

from rotordiag.service.main import create_app
from rotordiag.simulator.train.recording import train_recording
from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline
from tests.service_util import make_settings, shipped_or_tiny_registry

SHORT = {"transient_revs": 40, "record_revs": 8, "samples_per_rev": 64, "snr_db": None}


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    app = create_app(make_settings(tmp_path_factory.mktemp("trainsim")))
    with TestClient(app) as c:
        yield c


@pytest.fixture(scope="module")
def preset_json(client):
    r = client.post("/trains/simulate", json={"preset": "gen200_2pole", "offset_um": 100.0, **SHORT})
    assert r.status_code == 200, r.text
    return r.json()


def test_json_recording_is_the_python_doors_with_a_vertical_offset_by_default(preset_json):
    s = preset_json
    assert s["speed_rpm"] == 3000.0 and s["sample_rate_hz"] == pytest.approx(3000.0 / 60 * 64)
    assert [(c["bearing"], c["angle_deg"]) for c in s["channels"]] == [(b, a) for b in (1, 2, 3, 4) for a in (45, 135)]
    assert s["inputs"]["direction_deg"] == -90.0 and s["inputs"]["offset_um"] == 100.0   # vertical unless told
    assert s["warnings"] == [] and s["log_decrement"] > 0
    # the same train through the Python door (deterministic: no noise) gives the same waveforms
    tr = train_from_shaftline(shaftline_of("gen200_2pole")[0])
    rec = train_recording(tr, 3000.0, offset_um=100.0, transient_revs=40, record_revs=8, samples_per_rev=64,
                          snr_db=float("inf"))
    got = np.array([c["data"] for c in s["channels"]])
    np.testing.assert_allclose(got, rec.probes.waveforms_um, rtol=0, atol=1e-9)
    # one keyphasor mark per revolution, 8 revolutions
    assert np.allclose(np.diff(s["keyphasor_times_s"]), 60.0 / 3000.0, rtol=1e-6)
    # DC included: bearing 1's journal sits below its centre (y = (p45 + p135)/√2 < 0, within the clearance)
    p45, p135 = (np.mean(s["channels"][k]["data"]) for k in (0, 1))
    assert -350.0 < (p45 + p135) / np.sqrt(2) < -20.0


def test_csv_download_is_the_cli_layout_and_reads_back(client, preset_json, tmp_path):
    from rotordiag.features.reader import ReadOptions, read_recording

    r = client.post("/trains/simulate", json={"preset": "gen200_2pole", "offset_um": 100.0, "format": "csv", **SHORT})
    assert r.status_code == 200, r.text
    assert r.headers["content-type"].startswith("text/csv") and "attachment" in r.headers["content-disposition"]
    assert json.loads(r.headers["x-rotordiag-warnings"]) == []
    assert r.text.splitlines()[0] == "time_s,b1@45,b1@135,b2@45,b2@135,b3@45,b3@135,b4@45,b4@135,kp"
    path = tmp_path / "train.csv"
    path.write_bytes(r.content)
    rec = read_recording(path, options=ReadOptions(keyphasor_channel="kp")).recording
    by = {(c.bearing, c.angle_deg): c.data_um for c in rec.channels}
    for c in preset_json["channels"]:
        np.testing.assert_allclose(by[(c["bearing"], c["angle_deg"])], c["data"], atol=6e-4)  # CSV: 3 decimals
    assert len(rec.keyphasor_times_s) >= 7


def test_probes_are_chosen_and_checked_before_simulating(client):
    r = client.post("/trains/simulate", json={"preset": "gen200_2pole", **SHORT,
                                              "probes": [{"bearing": 3, "angle_deg": 0.0}, {"bearing": 3, "angle_deg": 90.0}]})
    assert r.status_code == 200, r.text
    s = r.json()
    assert [(c["bearing"], c["angle_deg"]) for c in s["channels"]] == [(3, 0.0), (3, 90.0)]
    # a probe at 0° reads x, at 90° y: the same journal as the default 45°/135° pair, projected (x cos a + y sin a)
    d = client.post("/trains/simulate", json={"preset": "gen200_2pole", **SHORT}).json()
    p45, p135 = (np.array(c["data"]) for c in d["channels"] if c["bearing"] == 3)
    x, y = (np.array(c["data"]) for c in s["channels"])
    np.testing.assert_allclose((x + y) / np.sqrt(2), p45, atol=1e-9)
    np.testing.assert_allclose((y - x) / np.sqrt(2), p135, atol=1e-9)
    bad = client.post("/trains/simulate", json={"preset": "gen200_2pole", **SHORT,
                                                "probes": [{"bearing": 6, "angle_deg": 0.0}]})
    assert bad.status_code == 422 and "bearing 1…4" in bad.text


def _two_x_pp(channel: dict, record_revs: int) -> float:
    d = np.asarray(channel["data"])
    return float(4 * np.abs(np.fft.rfft(d - d.mean()))[2 * record_revs] / d.size)


def test_a_flexible_coupling_under_offset_gets_its_kinematic_2x(client):
    """coupling: flexible replaces the preset's rigid one; the offset then drives the double-engagement coupling's 2X
    (docs/train.md), which a rigid coupling does not have: 2X at the exciter's coupling-end bearing grows with δ."""
    body = {"preset": "gen200_2pole", "coupling": "flexible", "unbalance_kg_m": 0.0, **SHORT}
    aligned = client.post("/trains/simulate", json=body)
    off = client.post("/trains/simulate", json={**body, "offset_um": 100.0})
    assert aligned.status_code == off.status_code == 200, (aligned.text, off.text)
    assert off.json()["inputs"]["coupling"] == "flexible"
    b3 = [k for k, c in enumerate(off.json()["channels"]) if c["bearing"] == 3][0]
    a2, o2 = (_two_x_pp(r.json()["channels"][b3], 8) for r in (aligned, off))
    assert o2 > 3 * a2 and o2 > 5.0, (a2, o2)


def test_h5_download_carries_the_speed(client):
    import h5py

    r = client.post("/trains/simulate", json={"preset": "gen50_2pole", "format": "h5", **SHORT})
    assert r.status_code == 200, r.text
    with h5py.File(io.BytesIO(r.content), "r") as f:
        assert f["waveforms"].shape == (9, 8 * 64) and f.attrs["speed_rpm"] == 3000.0


@pytest.mark.parametrize("body, says", [
    ({}, "exactly one"),
    ({"preset": "gen999"}, "unknown shaft-line preset"),
    ({"shaftline_toml": "[generator]\nsegments = [[1.0, 0.5]]\n"}, "speed_rpm"),
    ({"shaftline": {"generator": {"segments": [[-1.0, 0.5]]}, "exciter": {"segments": [[1.0, 0.3]]}},
      "speed_rpm": 3000.0}, "length"),
    ({"shaftline": {"generator": {"segments": [[1, 0.3]]}, "exciter": {"segments": [[1, 0.3]]},
                    "bearings": {"type": ["plain", "plain", "none", "plain"]}}, "speed_rpm": 3000.0}, "only bearing 4"),
    ({"shaftline": {"generator": {"segments": [[1, 0.3]], "disks": [[3.0, 10, 1, 1]]},
                    "exciter": {"segments": [[1, 0.3]]}}, "speed_rpm": 3000.0}, "outside the span"),
    ({"shaftline": {"generator": {"segments": [[20.0, 0.6]], "body_masses": [[0.1 * k + 0.05, 10.0] for k in range(190)]},
                    "exciter": {"segments": [[2.0, 0.3]]}}, "speed_rpm": 3000.0}, "max_element_m"),
    ({"preset": "gen200_2pole", "record_revs": 256, "samples_per_rev": 512}, "32768"),
    ({"preset": "gen200_2pole", "speed_rpm": 1e9}, "speed_rpm"),
    ({"preset": "gen200_2pole", "offset_um": float("nan")}, "NaN"),
    ({"preset": "gen200_2pole", "offset_um": 1e6}, "offset_um"),
    ({"preset": "gen200_2pole", "format": "xlsx"}, "format"),
    ({"preset": "gen200_2pole", "extra": 1}, "extra"),
])
def test_bad_input_is_a_422_that_says_what_to_fix(client, body, says):
    r = client.post("/trains/simulate", content=json.dumps(body, allow_nan=True),
                    headers={"content-type": "application/json"})
    assert r.status_code == 422, r.text
    assert says in r.text


def test_an_offset_that_presses_a_journal_on_its_metal_names_the_bearing_and_the_offset_it_takes(client):
    r = client.post("/trains/simulate", json={"preset": "gen200_2pole", "offset_um": 5000.0,
                                              "offset_angle_deg": 0.0, **SHORT})
    assert r.status_code == 422, r.text
    d = r.json()["detail"]
    assert "bearing B3" in d and "film eccentricity" in d and "at most about" in d and "Along 0°" in d


def test_a_simulation_over_the_time_limit_is_a_422(tmp_path):
    app = create_app(make_settings(tmp_path, diagnosis_timeout_s=0.05))
    with TestClient(app) as c:
        r = c.post("/trains/simulate", json={"preset": "gen200_2pole", "transient_revs": 320, "record_revs": 64})
    assert r.status_code == 422 and "limit of 0.05 s" in r.text, r.text


def test_runs_in_a_diagnosis_worker_with_the_same_answer(tmp_path_factory, preset_json):
    registry = shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))
    app = create_app(make_settings(tmp_path_factory.mktemp("pooled"), shipped_registry_dir=registry,
                                   diagnosis_workers=1))
    with TestClient(app) as c:
        assert c.app.state.rd.pool is not None
        r = c.post("/trains/simulate", json={"preset": "gen200_2pole", "offset_um": 100.0, **SHORT})
        assert r.status_code == 200, r.text
        assert r.json()["channels"] == preset_json["channels"]
        bad = c.post("/trains/simulate", json={"preset": "gen200_2pole", "offset_um": 5000.0, **SHORT})
        assert bad.status_code == 422 and "bearing B3" in bad.text


def test_openapi_describes_the_route(client):
    spec = client.get("/openapi.json").json()
    for name in ("TrainSimulateRequest", "TrainSimulateOut", "TrainChannelOut"):
        props = spec["components"]["schemas"][name]["properties"]
        assert all(p.get("description") for p in props.values()), name
    assert {"200", "415", "422"} <= spec["paths"]["/trains/simulate"]["post"]["responses"].keys()
