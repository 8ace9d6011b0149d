"""GET /trains/presets and POST /trains/summary: a shaft train's bearings at their static state and its
stability margin, for a preset or an uploaded shaft line; every bad input a 4xx that says what to fix."""
from __future__ import annotations

from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from rotordiag.service.main import create_app
from rotordiag.simulator.shaftline import PRESETS
from tests.service_util import make_settings

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "shaftline_200mw.toml"
G = 9.81


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    app = create_app(make_settings(tmp_path_factory.mktemp("trains")))
    with TestClient(app) as c:
        yield c


def test_presets_are_listed_with_their_rated_speeds(client):
    r = client.get("/trains/presets")
    assert r.status_code == 200
    names = {p["name"]: p["rated_speed_rpm"] for p in r.json()}
    assert names.keys() == PRESETS.keys() and names["gen600_4pole"][0] == 1500.0


def test_preset_summary_carries_the_weight_and_is_stable_at_rated_speed(client):
    r = client.post("/trains/summary", json={"preset": "gen200_2pole"})
    assert r.status_code == 200, r.text
    s = r.json()
    assert s["source"] == "gen200_2pole" and s["speed_rpm"] == s["rated_speed_rpm"] == 3000.0
    assert [b["name"] for b in s["bearings"]] == ["B1", "B2", "B3", "B4"]
    # the bearings carry the train's weight: Σ vertical load = −(Σ rotor masses)·g (an independent sum over
    # the elements' and body masses' mass), no horizontal resultant
    weight_kn = sum(r["mass_kg"] for r in s["rotors"]) * G / 1e3
    assert sum(b["load_vertical_kn"] for b in s["bearings"]) == pytest.approx(-weight_kn, rel=1e-6)
    assert abs(sum(b["load_horizontal_kn"] for b in s["bearings"])) < 1e-6 * weight_kn
    assert all(0 <= b["eccentricity"] < 1 for b in s["bearings"])
    assert s["n_stations"] == sum(r["n_stations"] for r in s["rotors"])
    assert s["stable"] and s["log_decrement"] > 0 and s["warning"] is None


def test_uploaded_shaftline_text_and_tables_give_the_same_summary(client):
    import tomllib

    text = EXAMPLE.read_text()
    a = client.post("/trains/summary", json={"shaftline_toml": text, "speed_rpm": 3000.0})
    b = client.post("/trains/summary", json={"shaftline": tomllib.loads(text), "speed_rpm": 3000.0})
    assert a.status_code == b.status_code == 200, (a.text, b.text)
    assert a.json() == b.json() and a.json()["source"] == "shaftline" and a.json()["rated_speed_rpm"] is None


@pytest.mark.parametrize("body, status, says", [
    ({}, 422, "exactly one"),
    ({"preset": "gen200_2pole", "shaftline_toml": "x = 1"}, 422, "exactly one"),
    ({"preset": "gen999"}, 422, "unknown shaft-line preset"),
    ({"shaftline_toml": "[generator\nsegments = 1", "speed_rpm": 3000.0}, 422, "not valid TOML"),
    ({"shaftline_toml": "[generator]\nsegments = [[1.0, 0.5]]\n"}, 422, "speed_rpm"),
    ({"shaftline_toml": "[generator]\nsegments = [[-1.0, 0.5]]\n", "speed_rpm": 3000.0}, 422, "shaft line: "),
    ({"shaftline_toml": "x" * 100_001, "speed_rpm": 3000.0}, 422, "100000"),
    ({"preset": "gen200_2pole", "speed_rpm": 1e9}, 422, "speed_rpm"),
    ({"preset": "gen200_2pole", "extra": 1}, 422, "extra"),
])
def test_bad_trains_are_422s_that_say_what_to_fix(client, body, status, says):
    r = client.post("/trains/summary", json=body)
    assert r.status_code == status, r.text
    assert says in r.text


def test_body_that_is_not_json_is_415(client):
    r = client.post("/trains/summary", content=b"[generator]", headers={"content-type": "application/toml"})
    assert r.status_code == 415 and "application/json" in r.text


def test_openapi_describes_every_field_and_the_errors(client):
    spec = client.get("/openapi.json").json()
    for name in ("TrainSummaryRequest", "TrainSummaryOut", "TrainBearingOut", "TrainRotorOut", "TrainPreset"):
        props = spec["components"]["schemas"][name]["properties"]
        assert all(p.get("description") for p in props.values()), name
    responses = spec["paths"]["/trains/summary"]["post"]["responses"]
    assert {"200", "400", "415", "422"} <= responses.keys()
