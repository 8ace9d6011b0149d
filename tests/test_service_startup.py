"""An asset's start-ups as evidence in the service (issue 46 item 4): POST /assets/{id}/startup stores a run's
evidence, one run is the asset's baseline start-up, a later run is compared with it, and the comparison is evidence
in the asset's verdicts (/diagnose with the asset, the report) — never a more confident verdict, never another band.
Bad start-ups (a speed that reverses, a keyphasor that drops out, a 10⁸-sample file) are refused with a 4xx saying
what to do, and nothing is stored."""
from __future__ import annotations

import html
import io
import math
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from tests.service_util import auth, pooled_and_plain_apps


def _csv_body(path: Path) -> dict:
    return {"file": (path.name, path.read_bytes())}


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    """The paper model's run-ups 300 → 2000 r/min in 17 s (settled 100 revolutions, 2560 Hz, 40 dB noise): Δ 0 (the
    baseline and a healthy re-run with another noise seed) and Δ 0.15; and a steady Δ 0 recording at 1950 r/min.
    Between Δ 0 and Δ 0.15 the coupling-end journals' centreline rise moves (docs/transient.md: 20/20 plants)."""
    from typer.testing import CliRunner

    from rotordiag.cli import app

    d = tmp_path_factory.mktemp("startups")
    run = CliRunner()
    out = {"base": d / "base.csv", "same": d / "same.csv", "changed": d / "changed.csv", "steady": d / "steady.csv"}
    for name, delta, seed in (("base", "0", "1"), ("same", "0", "2"), ("changed", "0.15", "3")):
        r = run.invoke(app, ["runup", "--profile", "300:2000:17", "--misalignment", delta, "--settle-revs", "100",
                             "--seed", seed, "--out", str(out[name])])
        assert r.exit_code == 0, r.output
    r = run.invoke(app, ["simulate", "--speed-rpm", "1950", "--misalignment", "0", "--record-revs", "80",
                         "--probes-out", str(out["steady"]), "--probe-sample-rate-hz", "2560"])
    assert r.exit_code == 0, r.output
    return out


@pytest.fixture(scope="module")
def clients(tmp_path_factory):
    pooled, plain = pooled_and_plain_apps(tmp_path_factory)
    with TestClient(pooled) as a, TestClient(plain) as b:
        yield {"pooled": a, "plain": b}


def _diagnose(c: TestClient, runs, asset: str, store: bool = True) -> dict:
    r = c.post("/diagnose", params={"asset_id": asset, "clearance_um": 350}, files=_csv_body(runs["steady"]),
               headers=auth() if store else {})
    assert r.status_code == 200, r.text
    return r.json()


@pytest.mark.parametrize("which", ["pooled", "plain"])
def test_a_changed_startup_is_evidence_in_the_assets_verdict_never_a_surer_one(clients, runs, which):
    c = clients[which]
    asset = f"G7-{which}"
    before = _diagnose(c, runs, asset)
    assert before["severity"] == "aligned", before          # the steady Δ 0 recording
    assert not [e for e in before["evidence"] if e["scope"] == "start-up"]

    # a start-up before any baseline start-up: stored, compared with nothing, the verdict's status untouched
    r = c.post(f"/assets/{asset}/startup", files=_csv_body(runs["same"]), headers=auth())
    assert r.status_code == 200, r.text
    first = r.json()
    assert first["is_baseline"] is False and first["baseline_startup_id"] is None and not first["reasons"]
    assert "no baseline start-up" in first["comparison"]
    assert first["asset_verdict"]["status"] == before["status"]

    r = c.post(f"/assets/{asset}/startup", params={"baseline": "true", "note": "after the alignment"},
               files=_csv_body(runs["base"]), headers=auth())
    assert r.status_code == 200, r.text
    base = r.json()
    assert base["is_baseline"] and base["baseline_startup_id"] == base["startup_id"] and base["note"] == "after the alignment"
    assert base["kind"] == "run-up" and 250 < base["speed_range_rpm"][0] < 400 < 1900 < base["speed_range_rpm"][1]
    assert base["centreline"] and set(base["evidence"]["half_rise_rpm"]) >= {"2", "3"}

    # a healthy re-run: unchanged, no reason
    r = c.post(f"/assets/{asset}/startup", files=_csv_body(runs["same"]), headers=auth())
    assert r.status_code == 200, r.text
    same = r.json()
    assert not same["reasons"] and same["evidence_rows"][-1]["code"] == "startup_unchanged"
    assert same["asset_verdict"]["status"] == before["status"]

    # the Δ 0.15 run-up: the coupling-end rise moved — the "aligned" call is doubted, its band kept
    r = c.post(f"/assets/{asset}/startup", files=_csv_body(runs["changed"]), headers=auth())
    assert r.status_code == 200, r.text
    changed = r.json()
    assert [x["code"] for x in changed["reasons"]] == ["startup_changed"]
    assert changed["reasons"][0]["status"] == "uncertain" and changed["reasons"][0]["message"]
    av = changed["asset_verdict"]
    assert av["severity"] == "aligned" and av["status"] in ("uncertain", "inconclusive")
    assert av["headline"]["action"] == "investigate_change", av["headline"]
    assert "start-up" in av["headline"]["text"]

    # every later diagnosis of the asset carries it: evidence rows and the reason, band and Δ as without it
    after = _diagnose(c, runs, asset)
    rows = [e for e in after["evidence"] if e["scope"] == "start-up"]
    assert rows and any("half its centreline rise" in e["value"] for e in rows)
    assert "startup_changed" in [x["code"] for x in after["reasons"]]
    assert after["startup"] == {"startup_id": changed["startup_id"], "baseline_startup_id": base["startup_id"],
                                "changed": True, "reasons": ["startup_changed"]}
    assert after["severity"] == before["severity"] and after["misalignment"] == pytest.approx(before["misalignment"])
    assert after["probabilities"] == pytest.approx(before["probabilities"])
    assert after["status"] != "confident" and after["headline"]["action"] == "investigate_change"
    # ... without the API key too (not stored, the same evidence)
    unstored = _diagnose(c, runs, asset, store=False)
    assert "startup_changed" in [x["code"] for x in unstored["reasons"]]

    # the asset's report says it
    page = html.unescape(c.get(f"/assets/{asset}/report", params={"format": "html"}).text)
    assert "start-up · coupling-end centreline rise" in page and "startup_changed" not in page.split("Reasons")[0]
    assert "called aligned, but the start-up changed since the asset's baseline start-up" in page

    listed = c.get(f"/assets/{asset}/startups").json()
    assert listed["baseline_startup_id"] == base["startup_id"] and listed["compared_startup_id"] == changed["startup_id"]
    assert [s["startup_id"] for s in listed["startups"]] == [changed["startup_id"], same["startup_id"],
                                                             base["startup_id"], first["startup_id"]]

    # a new baseline start-up (e.g. after the machine was re-aligned) retires the comparison
    r = c.post(f"/assets/{asset}/startup", params={"baseline": "true"}, files=_csv_body(runs["changed"]),
               headers=auth())
    assert r.status_code == 200, r.text
    again = _diagnose(c, runs, asset)
    assert "startup_changed" not in [x["code"] for x in again["reasons"]]
    assert not [e for e in again["evidence"] if e["scope"] == "start-up"]


def test_a_misalignment_call_gets_support_not_a_doubt():
    """The comparison on a verdict that calls misalignment: a supporting evidence row, no reason, status kept."""
    from rotordiag.models.checks.startup import StartupContext, startup_findings
    from rotordiag.models.startup import StartupEvidence, with_startup

    def ev(rise: float) -> StartupEvidence:
        return StartupEvidence({}, {2: rise, 3: rise}, {2: (0.0, 50.0), 3: (0.0, 50.0)}, {2: 350.0, 3: 350.0},
                               (300.0, 2000.0))

    verdict = {"severity": "moderate", "status": "confident", "reasons": [], "evidence": []}
    entries, reasons = startup_findings(StartupContext(ev(1500.0), ev(1000.0), misaligned_call=True))
    out = with_startup(verdict, entries, reasons)
    assert not reasons and out["status"] == "confident" and out["severity"] == "moderate"
    assert [e["effect"] for e in out["evidence"]][-1] == "supports"
    # a stored evidence survives its JSON round trip
    assert StartupEvidence.from_dict(ev(1000.0).to_dict()) == ev(1000.0)
    with pytest.raises(ValueError, match="not a stored start-up evidence"):
        StartupEvidence.from_dict({"criticals": {"x": 1}})


def _count(c: TestClient, asset: str) -> int:
    r = c.get(f"/assets/{asset}/startups")
    return 0 if r.status_code == 404 else len(r.json()["startups"])


def test_bad_startups_are_refused_saying_what_to_do_and_nothing_is_stored(clients, runs, tmp_path):
    from tests.test_features_transient import _huge_npy

    fs = 2560.0
    t = np.arange(int(12 * fs)) / fs
    rpm = np.where(t < 6, 1000 + 100 * t, 1600 - 100 * (t - 6))          # a run-up that turns back at 6 s
    th = 2 * np.pi * np.cumsum(rpm / 60.0) / fs
    kp = np.interp(2 * np.pi * np.arange(1, int(th[-1] / (2 * np.pi))), th, t)
    reverses = {"sample_rate_hz": fs, "keyphasor_times_s": [float(v) for v in kp],
                "channels": [{"bearing": b, "angle_deg": a, "units": "um",
                              "data": [float(v) for v in 10 * np.cos(th - math.radians(a))]}
                             for b in (1, 2, 3, 4) for a in (45.0, 135.0)]}
    a = np.loadtxt(runs["base"], delimiter=",", skiprows=1)
    a[20000:22000, -1] = 0.0                                           # 0.8 s of keyphasor without pulses
    buf = io.StringIO()
    np.savetxt(buf, a, delimiter=",", header=runs["base"].read_text().splitlines()[0], comments="", fmt="%.6g")
    huge = _huge_npy(tmp_path / "huge.npy").read_bytes()
    for which, c in clients.items():
        asset = f"bad-{which}"
        r = c.post(f"/assets/{asset}/startup", json=reverses, headers=auth())
        assert r.status_code == 422 and "the speed reverses at t = " in r.json()["detail"], r.text
        r = c.post(f"/assets/{asset}/startup", files={"file": ("dropout.csv", buf.getvalue().encode())},
                   headers=auth())
        assert r.status_code == 422 and "keyphasor drops out" in r.json()["detail"], r.text
        r = c.post(f"/assets/{asset}/startup", params={"sample_rate_hz": 25600, "keyphasor_channel": 7},
                   files={"file": ("huge.npy", huge)}, headers=auth())
        assert 400 <= r.status_code < 500 and "(8, 100000000)" in r.json()["detail"], r.text
        r = c.post(f"/assets/{asset}/startup", files={"file": ("x.csv", b"time_s,a\n0,zz\n")}, headers=auth())
        assert 400 <= r.status_code < 500, r.text
        r = c.post(f"/assets/{asset}/startup", files=_csv_body(runs["base"]))        # no API key
        assert r.status_code == 401
        r = c.post(f"/assets/{asset}/startup", params={"recorded_at": "0.5"}, files=_csv_body(runs["base"]),
                   headers=auth())
        assert r.status_code == 422 and "ISO 8601" in r.text
        assert _count(c, asset) == 0
        r = c.get(f"/assets/{asset}/startups")
        assert r.status_code == 404 and "baseline=true" in r.json()["detail"]
