"""Asset baselines and trend alarms through the HTTP API (issue 17): set/show/replace/delete, the
/diagnose answer's baseline section, a speed too far from the baseline's, the alarm firing and
clearing in the history and the Prometheus gauges, the automatic proposal, the schema migration."""
from __future__ import annotations

import numpy as np
import pytest
from fastapi.testclient import TestClient

from rotordiag.service.main import create_app
from tests.service_util import auth, diagnose_json, make_settings, shipped_or_tiny_registry, simulated_channels

SPEED_RPM = 1800.0
FS_HZ = 2048.0


@pytest.fixture(scope="module")
def registry_src(tmp_path_factory):
    return shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))


@pytest.fixture(scope="module")
def client(tmp_path_factory, registry_src):
    tmp = tmp_path_factory.mktemp("svc")
    app = create_app(make_settings(tmp, shipped_registry_dir=registry_src))
    with TestClient(app) as c:
        yield c


def _body(asset=None, *, dc_shift_um=0.0, speed_rpm=SPEED_RPM, seed=0):
    """An aligned-machine recording with a keyphasor; ``dc_shift_um`` moves bearing 3's journal (both probes
    see their projection of a vertical shift), new noise per ``seed``."""
    fs, chans = simulated_channels(misalignment=0.0, speed_rpm=speed_rpm, sample_rate_hz=FS_HZ, record_revs=40,
                                   mechanism="rigid")
    rng = np.random.default_rng(seed)
    out = []
    for b, a, d in chans:
        d = np.asarray(d, float) + 0.05 * rng.standard_normal(len(d))
        if b == 3:
            d = d + dc_shift_um * np.sin(np.radians(a))
        out.append((b, a, d))
    n = len(out[0][2])
    period = 60.0 / speed_rpm
    kp = [float(v) for v in np.arange(0.0, (n - 1) / fs, period)]
    extra = {"keyphasor_times_s": kp, "clearance_um": 350.0}
    if asset:
        extra["asset_id"] = asset
    return diagnose_json(fs, out, **extra)


def test_baseline_needs_the_key(client):
    assert client.post("/assets/k1/baseline?auto=true").status_code == 401
    assert client.post("/assets/k1/baseline?auto=true", headers={"X-API-Key": "wrong"}).status_code == 403
    assert client.delete("/assets/k1/baseline").status_code == 401
    assert client.put("/assets/k1/thresholds", json={"thresholds": {}}).status_code == 401


def test_no_baseline_then_a_baseline_then_change_alarm_fires_and_clears(client):
    asset = "unit-7"
    v0 = client.post("/diagnose", json=_body(asset), headers=auth()).json()
    assert v0["baseline"]["used"] is False and "no baseline" in v0["baseline"]["message"]
    assert isinstance(v0["diagnosis_id"], int) and "signature" not in v0
    g = client.get(f"/assets/{asset}/baseline").json()
    assert g["baseline"] is None and "reason" in g["proposal"]

    r = client.post(f"/assets/{asset}/baseline", json=_body(asset, seed=1), headers=auth())
    assert r.status_code == 200, r.text
    b = r.json()
    assert b["source"] == "recording" and b["speed_rpm"] == pytest.approx(SPEED_RPM, rel=1e-3)
    assert b["model_version"] and b["set_at"]
    g = client.get(f"/assets/{asset}/baseline").json()
    assert g["baseline"]["diagnosis_ids"] == b["diagnosis_ids"] and g["baseline"]["signature"]["bearings"]

    same = client.post("/diagnose", json=_body(asset, seed=2), headers=auth()).json()
    assert same["baseline"]["used"] and same["baseline"]["changed"] is False, same["baseline"]
    assert same["baseline"]["set_at"] == b["set_at"]
    shifted = client.post("/diagnose", json=_body(asset, dc_shift_um=60.0, seed=3), headers=auth()).json()
    sec = shifted["baseline"]
    assert sec["changed"] is True and "dc_shift" in sec["exceeded"], sec
    assert sec["quantities"]["dc_shift"]["bearing"] == 3
    assert sec["quantities"]["dc_shift"]["value"] == pytest.approx(60.0, abs=2.0)
    assert any(e["scope"] == "change since baseline" and e["name"] == "centreline shift" for e in shifted["evidence"])
    metrics = client.get("/metrics").text
    assert f'rotordiag_asset_change{{asset="{asset}",quantity="dc_shift_um"}}' in metrics
    assert f'rotordiag_asset_alarm{{asset="{asset}"}} 1.0' in metrics

    back = client.post("/diagnose", json=_body(asset, seed=4), headers=auth()).json()
    assert back["baseline"]["changed"] is False
    assert f'rotordiag_asset_alarm{{asset="{asset}"}} 0.0' in client.get("/metrics").text
    h = client.get(f"/assets/{asset}/history").json()
    assert [e["event"] for e in h["alarms"]] == ["raised", "cleared"]
    assert h["alarms"][0]["diagnosis_id"] == shifted["diagnosis_id"] and h["alarms"][0]["quantities"]
    assert h["alarms"][1]["diagnosis_id"] == back["diagnosis_id"]
    alarm_of = {p["id"]: p["alarm"] for p in h["points"]}
    assert alarm_of[v0["diagnosis_id"]] is None and alarm_of[shifted["diagnosis_id"]] is True

    # thresholds are editable per asset: with a dc threshold above the shift, the same recording is no change
    t = client.put(f"/assets/{asset}/thresholds", json={"thresholds": {"dc_shift_um": 500.0}}, headers=auth())
    assert t.status_code == 200 and t.json()["thresholds"]["dc_shift_um"] == 500.0
    assert client.post("/diagnose", json=_body(asset, dc_shift_um=60.0, seed=5), headers=auth()).json()["baseline"]["changed"] is False
    bad = client.put(f"/assets/{asset}/thresholds", json={"thresholds": {"nonsense": 1.0}}, headers=auth())
    assert bad.status_code == 422 and "unknown change quantities" in bad.text
    assert client.put(f"/assets/{asset}/thresholds", json={"thresholds": {}}, headers=auth()).status_code == 200

    # replace from a stored diagnosis (the shifted one), then delete
    r = client.post(f"/assets/{asset}/baseline?diagnosis_id={shifted['diagnosis_id']}", headers=auth())
    assert r.status_code == 200 and r.json()["source"] == "diagnosis"
    assert client.post("/diagnose", json=_body(asset, dc_shift_um=60.0, seed=6), headers=auth()).json()["baseline"]["changed"] is False
    assert client.post(f"/assets/{asset}/baseline?diagnosis_id=999999", headers=auth()).status_code == 404
    assert client.delete(f"/assets/{asset}/baseline", headers=auth()).status_code == 204
    assert client.delete(f"/assets/{asset}/baseline", headers=auth()).status_code == 404
    assert client.post("/diagnose", json=_body(asset), headers=auth()).json()["baseline"]["used"] is False


def test_a_recording_at_another_speed_is_not_compared(client):
    asset = "unit-speed"
    assert client.post(f"/assets/{asset}/baseline", json=_body(asset), headers=auth()).status_code == 200
    far = client.post("/diagnose", json=_body(asset, speed_rpm=2100.0), headers=auth()).json()["baseline"]
    assert far["used"] is False and far["compared"] is False and far["changed"] is None
    assert "speed differs" in far["message"] and "+16.7 %" in far["message"]
    h = client.get(f"/assets/{asset}/history").json()
    assert h["points"][-1]["alarm"] is None and h["alarms"] == []


def test_automatic_baseline_from_the_first_recordings_at_one_speed(client):
    asset = "unit-auto"
    for seed in range(2):
        v = client.post("/diagnose", json=_body(asset, seed=seed), headers=auth()).json()
        assert f"{seed + 1} with this one" in v["baseline"]["message"]       # the count includes this recording
    r = client.post(f"/assets/{asset}/baseline?auto=true", headers=auth())
    assert r.status_code == 409 and "needs 3" in r.json()["detail"]
    anon = client.post("/diagnose", json=_body(asset, seed=9)).json()         # not stored: not counted
    assert "2 stored" in anon["baseline"]["message"]
    v = client.post("/diagnose", json=_body(asset, seed=2), headers=auth()).json()
    assert "3 with this one" in v["baseline"]["message"]                      # was "2 so far" after the third
    prop = client.get(f"/assets/{asset}/baseline").json()["proposal"]
    assert len(prop["diagnosis_ids"]) == 3 and prop["speed_rpm"] == pytest.approx(SPEED_RPM, rel=1e-3)
    r = client.post(f"/assets/{asset}/baseline?auto=true", headers=auth())
    assert r.status_code == 200 and r.json()["source"] == "auto" and r.json()["diagnosis_ids"] == prop["diagnosis_ids"]


def test_an_automatic_baseline_sets_the_assets_own_thresholds_from_its_repeatability(client):
    """Three re-recordings of one machine (only the noise redrawn) make its own 1X/2X/centreline thresholds;
    a 2 µm journal shift at bearing 3 — below the shipped 6 µm — then raises the alarm, and the answer and
    GET say where each threshold comes from; an edit still wins."""
    from rotordiag.models.change import REPEAT_FLOOR, shipped_rule

    asset = "unit-own"
    for seed in range(3):
        client.post("/diagnose", json=_body(asset, seed=20 + seed), headers=auth())
    b = client.post(f"/assets/{asset}/baseline?auto=true", headers=auth()).json()
    rep = b["repeatability"]
    assert rep["n_recordings"] == 3 and set(rep["thresholds"]) >= {"1x_change_um_pp", "2x_change_um_pp", "dc_shift_um"}
    got = client.get(f"/assets/{asset}/baseline").json()
    assert got["thresholds_origin"]["dc_shift_um"] == "repeatability"
    assert got["thresholds_origin"]["orbit_2x_1x_change"] == "shipped"
    assert REPEAT_FLOOR["dc_shift_um"] <= got["thresholds"]["dc_shift_um"] < 2.0 < shipped_rule().thresholds["dc_shift_um"]
    assert got["thresholds"]["dc_shift_per_c"] is None
    same = client.post("/diagnose", json=_body(asset, seed=30), headers=auth()).json()["baseline"]
    assert same["compared"] and not same["changed"]
    assert any("own repeatability" in n for n in same["notes"])
    moved = client.post("/diagnose", json=_body(asset, dc_shift_um=2.0, seed=31), headers=auth()).json()["baseline"]
    assert moved["changed"] and "dc_shift" in moved["exceeded"]
    r = client.put(f"/assets/{asset}/thresholds", json={"thresholds": {"dc_shift_um": 5.0}}, headers=auth()).json()
    assert r["thresholds"]["dc_shift_um"] == 5.0 and r["thresholds_origin"]["dc_shift_um"] == "edited"
    again = client.post("/diagnose", json=_body(asset, dc_shift_um=2.0, seed=32), headers=auth()).json()["baseline"]
    assert not again["changed"]


def test_automatic_baseline_refuses_recordings_of_different_speed_bands(client):
    asset = "unit-mixed"
    for speed in (SPEED_RPM, SPEED_RPM, 2100.0):
        client.post("/diagnose", json=_body(asset, speed_rpm=speed), headers=auth())
    r = client.post(f"/assets/{asset}/baseline?auto=true", headers=auth())
    assert r.status_code == 409 and "not at one operating condition" in r.json()["detail"]


def test_baseline_request_mistakes_are_4xx(client):
    asset = "unit-bad"
    r = client.post(f"/assets/{asset}/baseline", headers=auth())
    assert r.status_code == 422 and "send a recording" in r.json()["detail"]
    r = client.post(f"/assets/{asset}/baseline?auto=true&diagnosis_id=1", headers=auth())
    assert r.status_code == 422
    r = client.post(f"/assets/{asset}/baseline", json=_body("someone-else"), headers=auth())
    assert r.status_code == 422 and "not the asset of the path" in r.json()["detail"]


def test_an_old_database_gets_the_new_columns(tmp_path, registry_src):
    """A database made before baselines existed (no signature/change/alarm columns) is migrated at startup."""
    import sqlite3

    settings = make_settings(tmp_path, shipped_registry_dir=registry_src)
    settings.data_dir.mkdir(parents=True)
    db = settings.effective_database_url.removeprefix("sqlite:///")
    con = sqlite3.connect(db)
    con.execute("CREATE TABLE asset_diagnoses (id INTEGER PRIMARY KEY, asset_id VARCHAR(128), plant VARCHAR(128), "
                "created_at DATETIME, model_version VARCHAR(128), severity VARCHAR(32), misalignment FLOAT, "
                "misalignment_low FLOAT, misalignment_high FLOAT, speed_rpm FLOAT, ood BOOLEAN, verdict JSON, "
                "key_features JSON)")
    con.execute("INSERT INTO asset_diagnoses (asset_id, created_at, model_version, severity, verdict, key_features) "
                "VALUES ('old', '2025-01-01 00:00:00', 'v0001', 'aligned', '{}', '{}')")
    con.commit()
    con.close()
    with TestClient(create_app(settings)) as c:
        h = c.get("/assets/old/history").json()
        assert h["count"] == 1 and h["points"][0]["alarm"] is None
        did = h["points"][0]["id"]
        r = c.post(f"/assets/old/baseline?diagnosis_id={did}", headers=auth())
        expected = (f"diagnosis {did} keeps no signature (it was stored before baselines existed, or only its summary "
                    "is kept past the history's retention); send its recording instead")
        assert r.status_code == 409 and r.json()["detail"] == expected
        r = c.post(f"/assets/old/baseline/recordings?diagnosis_id={did}", headers=auth())
        assert r.status_code == 409 and r.json()["detail"] == expected          # the same refusal, the same words
        for url in ("/assets/old/baseline?diagnosis_id=999999", "/assets/old/baseline/recordings?diagnosis_id=999999"):
            r = c.post(url, headers=auth())
            assert r.status_code == 404 and r.json()["detail"] == (
                "asset 'old' has no stored diagnosis 999999; GET /assets/old/history lists its diagnoses with their ids")
        assert c.post("/diagnose", json=_body("old"), headers=auth()).json()["diagnosis_id"] == 2


def test_cli_sets_shows_and_uses_a_baseline(tmp_path, monkeypatch, registry_src):
    """`rotordiag baseline set|show|clear` on the service database, and `rotordiag diagnose --baseline`."""
    import json

    from typer.testing import CliRunner

    from rotordiag.cli import app

    monkeypatch.setenv("ROTORDIAG_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("ROTORDIAG_SHIPPED_REGISTRY_DIR", str(registry_src))
    body = _body()
    rec = tmp_path / "after-alignment.json"
    rec.write_text(json.dumps(body))
    shifted = tmp_path / "later.json"
    shifted.write_text(json.dumps(_body(dc_shift_um=60.0, seed=9)))
    run = CliRunner().invoke
    res = run(app, ["baseline", "show", "unit-cli"])
    assert res.exit_code == 0 and "no baseline" in res.output
    res = run(app, ["baseline", "set", "unit-cli"])
    assert res.exit_code == 2 and "exactly one" in res.output
    res = run(app, ["baseline", "set", "unit-cli", str(rec)])
    assert res.exit_code == 0, res.output
    assert "baseline set from recording" in res.output and "1800 r/min" in res.output
    res = run(app, ["baseline", "show", "unit-cli", "--json"])
    assert res.exit_code == 0
    saved = tmp_path / "unit-cli.json"
    saved.write_text(res.output)
    assert json.loads(res.output)["baseline"]["source"] == "recording"
    res = run(app, ["diagnose", str(shifted), "--baseline", str(saved), "--registry", str(registry_src)])
    assert res.exit_code == 0, res.output
    assert "baseline: changed since the baseline" in res.output and "centreline shift" in res.output
    res = run(app, ["diagnose", str(rec), "--baseline", str(saved), "--registry", str(registry_src), "--json"])
    assert json.loads(res.output)["baseline"]["changed"] is False
    assert run(app, ["baseline", "clear", "unit-cli"]).exit_code == 0
    res = run(app, ["baseline", "clear", "unit-cli"])
    assert res.exit_code == 2 and "has no baseline" in res.output


def test_a_baseline_grows_recording_by_recording_and_its_own_thresholds_follow(client):
    """One recording: fleet-wide thresholds, and the answer says so (typed note, reason code); a 2 µm journal
    shift at bearing 3 — under the shipped 6 µm — passes unseen. Three recordings (added one by one, from a body and
    from a stored diagnosis): the asset's own thresholds, and the same shift is detected. Removing one goes back."""
    from rotordiag.models.change import shipped_rule

    asset = "unit-grow"
    assert client.post(f"/assets/{asset}/baseline/recordings?diagnosis_id=1").status_code == 401
    b = client.post(f"/assets/{asset}/baseline", json=_body(asset, seed=40), headers=auth()).json()
    assert b["n_recordings"] == 1 and len(b["recordings"]) == 1
    assert b["thresholds_basis"] == {"basis": "fleet", "reason": "too_few_recordings", "n_recordings": 1,
                                     "needed": 3, "margin": None}
    sec = client.post("/diagnose", json=_body(asset, dc_shift_um=2.0, seed=41), headers=auth()).json()
    base = sec["baseline"]
    assert base["compared"] and not base["changed"], base
    assert base["thresholds_basis"]["basis"] == "fleet"
    assert any(n.startswith("fleet-wide change thresholds: this asset's baseline has 1 recording") for n in base["notes"])
    assert base["quantities"]["dc_shift"]["threshold"] == shipped_rule().thresholds["dc_shift_um"]

    r = client.post(f"/assets/{asset}/baseline/recordings", json=_body(asset, seed=42), headers=auth())
    assert r.status_code == 200, r.text
    assert r.json()["n_recordings"] == 2 and r.json()["thresholds_basis"]["basis"] == "fleet"
    later = client.post("/diagnose", json=_body(asset, seed=43), headers=auth()).json()["diagnosis_id"]
    r = client.post(f"/assets/{asset}/baseline/recordings?diagnosis_id={later}", headers=auth())
    assert r.status_code == 200, r.text
    b3 = r.json()
    assert b3["n_recordings"] == 3 and [x["diagnosis_id"] for x in b3["recordings"]] == b3["diagnosis_ids"]
    assert b3["diagnosis_ids"][-1] == later and b3["repeatability"]["n_recordings"] == 3
    assert b3["thresholds_basis"]["basis"] == "own" and b3["thresholds_basis"]["margin"] == 4.0
    got = client.get(f"/assets/{asset}/baseline").json()
    assert got["thresholds_origin"]["dc_shift_um"] == "repeatability" and got["baseline"]["n_recordings"] == 3
    assert got["thresholds"]["dc_shift_um"] < 2.0
    moved = client.post("/diagnose", json=_body(asset, dc_shift_um=2.0, seed=44), headers=auth()).json()["baseline"]
    assert moved["changed"] and "dc_shift" in moved["exceeded"], moved
    assert moved["thresholds_basis"]["reason"] == "own_repeatability"
    assert any("own repeatability (3 baseline recordings" in n for n in moved["notes"])

    r = client.post(f"/assets/{asset}/baseline/recordings?diagnosis_id={later}", headers=auth())
    assert r.status_code == 409 and "already in the baseline" in r.json()["detail"]
    fast = client.post("/diagnose", json=_body(asset, speed_rpm=2100.0, seed=45), headers=auth()).json()["diagnosis_id"]
    r = client.post(f"/assets/{asset}/baseline/recordings?diagnosis_id={fast}", headers=auth())
    assert r.status_code == 409 and "not at one operating condition" in r.json()["detail"]
    assert client.post(f"/assets/{asset}/baseline/recordings?diagnosis_id=999999", headers=auth()).status_code == 404
    r = client.post(f"/assets/{asset}/baseline/recordings", headers=auth())
    assert r.status_code == 422 and "send a recording" in r.json()["detail"]

    r = client.delete(f"/assets/{asset}/baseline/recordings/{later}", headers=auth())
    assert r.status_code == 200, r.text
    b2 = r.json()
    assert later not in b2["diagnosis_ids"] and b2["n_recordings"] == 2 and b2["repeatability"] is None
    assert b2["thresholds_basis"]["basis"] == "fleet"
    got = client.get(f"/assets/{asset}/baseline").json()
    assert got["thresholds_origin"]["dc_shift_um"] == "shipped"
    again = client.post("/diagnose", json=_body(asset, dc_shift_um=2.0, seed=46), headers=auth()).json()["baseline"]
    assert not again["changed"]
    assert client.delete(f"/assets/{asset}/baseline/recordings/{later}", headers=auth()).status_code == 404
    first, second = b2["diagnosis_ids"]
    assert client.delete(f"/assets/{asset}/baseline/recordings/{second}", headers=auth()).status_code == 200
    r = client.delete(f"/assets/{asset}/baseline/recordings/{first}", headers=auth())
    assert r.status_code == 409 and "only recording" in r.json()["detail"]
    assert client.delete(f"/assets/{asset}/baseline/recordings/{first}").status_code == 401


def test_an_automatic_baseline_keeps_its_recordings_and_drops_to_fleet_thresholds_when_one_goes(client):
    asset = "unit-auto-rm"
    for seed in range(3):
        client.post("/diagnose", json=_body(asset, seed=60 + seed), headers=auth())
    b = client.post(f"/assets/{asset}/baseline?auto=true", headers=auth()).json()
    assert b["source"] == "auto" and len(b["recordings"]) == 3 and b["thresholds_basis"]["basis"] == "own"
    r = client.delete(f"/assets/{asset}/baseline/recordings/{b['diagnosis_ids'][0]}", headers=auth()).json()
    assert r["diagnosis_ids"] == b["diagnosis_ids"][1:] and r["thresholds_basis"]["reason"] == "too_few_recordings"
    assert r["speed_rpm"] == pytest.approx(SPEED_RPM, rel=1e-3)


def test_cli_adds_and_removes_baseline_recordings(tmp_path, monkeypatch, registry_src):
    """`rotordiag baseline add|remove` on the service database: three recordings give the asset's own thresholds
    (said in words), removing one goes back to the fleet-wide ones; mistakes exit 2 with what to fix."""
    import json

    from typer.testing import CliRunner

    from rotordiag.cli import app

    monkeypatch.setenv("ROTORDIAG_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("ROTORDIAG_SHIPPED_REGISTRY_DIR", str(registry_src))
    files = []
    for seed in range(3):
        f = tmp_path / f"take{seed}.json"
        f.write_text(json.dumps(_body(seed=70 + seed)))
        files.append(f)
    run = CliRunner().invoke
    res = run(app, ["baseline", "add", "unit-cli2"])
    assert res.exit_code == 2 and "exactly one" in res.output
    res = run(app, ["baseline", "add", "unit-cli2", str(files[0])])
    assert res.exit_code == 0, res.output
    assert "made of 1 recording(s)" in res.output and "fleet-wide change thresholds" in res.output
    for f in files[1:]:
        res = run(app, ["baseline", "add", "unit-cli2", str(f)])
        assert res.exit_code == 0, res.output
    assert "made of 3 recording(s)" in res.output and "own repeatability (3 baseline recordings" in res.output
    shown = json.loads(run(app, ["baseline", "show", "unit-cli2", "--json"]).output)
    ids = shown["baseline"]["diagnosis_ids"]
    assert len(ids) == 3 and shown["thresholds_origin"]["dc_shift_um"] == "repeatability"
    assert [r["diagnosis_id"] for r in shown["baseline"]["recordings"]] == ids
    res = run(app, ["baseline", "add", "unit-cli2", "--diagnosis-id", str(ids[0])])
    assert res.exit_code == 2 and "already in the baseline" in res.output
    res = run(app, ["baseline", "remove", "unit-cli2", "--diagnosis-id", str(ids[1])])
    assert res.exit_code == 0 and "made of 2 recording(s)" in res.output and "fleet-wide" in res.output
    res = run(app, ["baseline", "remove", "unit-cli2", "--diagnosis-id", str(ids[1])])
    assert res.exit_code == 2 and "is not a recording of the baseline" in res.output


def test_cli_set_and_add_read_a_recording_with_the_same_options(tmp_path, monkeypatch, registry_src):
    """`rotordiag baseline set` and `add` take one shared set of reading options: an NPY file without a sidecar is
    read only with --sample-rate-hz, --channels, --speed-rpm and --clearance-um, by both commands alike, and both
    list the same options."""
    import json

    from typer.testing import CliRunner

    from rotordiag.cli import app

    monkeypatch.setenv("ROTORDIAG_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.setenv("ROTORDIAG_SHIPPED_REGISTRY_DIR", str(registry_src))
    files = []
    for seed in (80, 81):
        body = _body(seed=seed)
        f = tmp_path / f"take{seed}.npy"
        np.save(f, np.array([c["data"] for c in body["channels"]]))
        files.append(f)
    layout = ",".join(f"{c['bearing']}@{c['angle_deg']:g}" for c in body["channels"])
    opts = ["--sample-rate-hz", str(FS_HZ), "--channels", layout, "--speed-rpm", str(SPEED_RPM),
            "--clearance-um", "350", "--units", "um"]
    run = CliRunner().invoke
    res = run(app, ["baseline", "set", "unit-cli3", str(files[0])])
    assert res.exit_code == 2 and "sample rate" in res.output          # an NPY file says nothing of how to read it
    res = run(app, ["baseline", "set", "unit-cli3", str(files[0]), *opts])
    assert res.exit_code == 0, res.output
    assert f"{SPEED_RPM:.0f} r/min" in res.output
    res = run(app, ["baseline", "add", "unit-cli3", str(files[1]), *opts])
    assert res.exit_code == 0, res.output
    assert "made of 2 recording(s)" in res.output
    shown = json.loads(run(app, ["baseline", "show", "unit-cli3", "--json"]).output)
    assert len(shown["baseline"]["diagnosis_ids"]) == 2

    import typer

    baseline = typer.main.get_command(app).commands["baseline"]

    def options(command: str) -> dict[str, tuple]:
        return {p.opts[0]: (p.name, p.help, p.default) for p in baseline.commands[command].params
                if p.opts[0] in ("--diagnosis-id", "--sample-rate-hz", "--units", "--speed-rpm", "--clearance-um",
                                 "--channels")}

    assert options("set") == options("add") and len(options("set")) == 6


def test_openapi_documents_the_baseline_recording_routes(client):
    spec = client.get("/openapi.json").json()
    add = spec["paths"]["/assets/{asset_id}/baseline/recordings"]["post"]
    rm = spec["paths"]["/assets/{asset_id}/baseline/recordings/{diagnosis_id}"]["delete"]
    for op in (add, rm):
        assert {"200", "400", "401", "403", "404", "409", "415", "422"} <= op["responses"].keys()
    assert set(add["requestBody"]["content"]) == {"application/json", "application/octet-stream", "multipart/form-data"}
    schemas = spec["components"]["schemas"]
    basis = schemas["ThresholdsBasisOut"]["properties"]
    assert basis["basis"]["enum"] == ["own", "fleet"] and "too_few_recordings" in basis["reason"]["enum"]
    assert {"n_recordings", "recordings", "thresholds_basis"} <= schemas["BaselineOut"]["properties"].keys()
    assert "thresholds_basis" in schemas["BaselineSectionOut"]["properties"]
