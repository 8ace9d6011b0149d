"""GET /assets/{id}/report (service/report.py): an asset's report from the store, as PDF and HTML, in a diagnosis
worker and in a thread; what it holds is checked against the /diagnose answers it was made from. And the web page's
start-up plots (POST /ui/transient-plots): a simulated run-up's PNGs and 1X peaks, and bad input's messages."""
from __future__ import annotations

import base64
import html
import io
import shutil
import subprocess
from pathlib import Path

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
    fs, channels = simulated_channels(misalignment=0.2, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=40)
    verdicts = []
    with TestClient(pooled) as a, TestClient(plain) as b:
        for c in (a, b):
            for speed in (1800.0, 1790.0):
                r = c.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=speed, asset_id="G3",
                                                           plant="Riverside"), headers=auth())
                assert r.status_code == 200, r.text
            verdicts.append(r.json())
        yield a, b, verdicts


@pytest.mark.parametrize("which", ["pooled", "plain"])
def test_html_report_holds_the_latest_verdict_its_reasons_evidence_and_the_trend(clients, which):
    pooled, plain, verdicts = clients
    c, v = (pooled, verdicts[0]) if which == "pooled" else (plain, verdicts[1])
    r = c.get("/assets/G3/report", params={"format": "html"})      # a read: no API key, as /history
    assert r.status_code == 200, r.text
    assert r.headers["content-type"].startswith("text/html")
    assert "script-src" not in r.headers["content-security-policy"] and "default-src 'none'" in \
        r.headers["content-security-policy"]
    page = html.unescape(r.text)
    assert "rotordiag report — G3" in page
    assert f"status: {v['status']}    severity: {v['severity']}" in page
    assert f"{v['misalignment']:.3f}" in page
    assert "Reasons" in page and all(x["message"] in page for x in v["reasons"] + [{"message": w} for w in v["warnings"]])
    assert v["evidence"] and all(f"{e['name']}: {e['value']}" in page for e in v["evidence"])
    assert "Trend (2 stored diagnoses)" in page and "2 stored diagnoses" in page
    assert "plant Riverside" in page and f"model {v['model_version']}" in page
    assert "the service stores verdicts, not waveforms" in page
    assert page.count("data:image/png;base64,") == 1          # the trend plot


def test_pdf_report_is_a_pdf_with_the_same_text(clients):
    pooled, plain, verdicts = clients
    r = pooled.get("/assets/G3/report")
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "application/pdf" and r.content.startswith(b"%PDF-")
    assert 'filename="rotordiag-report-G3.pdf"' in r.headers["content-disposition"]
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext (poppler-utils) not installed: the PDF's text is not checked")
    text = subprocess.run(["pdftotext", "-", "-"], input=r.content, capture_output=True, check=True).stdout.decode()
    v = verdicts[0]
    assert f"severity: {v['severity']}" in text and "Reasons" in text and "Evidence (model-independent)" in text
    assert "Trend of G3" in text                               # the trend plot's page


def test_report_of_an_unknown_asset_is_404_and_a_bad_format_422(clients):
    pooled, plain, _ = clients
    for c in (pooled, plain):
        r = c.get("/assets/nobody/report")
        assert r.status_code == 404 and "no diagnosis stored for asset 'nobody'" in r.json()["detail"]
        assert c.get("/assets/G3/report", params={"format": "docx"}).status_code == 422
        assert c.get("/assets/bad%20id/report").status_code == 422


def test_report_past_the_time_limit_is_refused_not_left_hanging(clients, monkeypatch):
    _, plain, _ = clients
    import time

    import rotordiag.service.report as report

    monkeypatch.setattr(plain.app.state.rd.settings, "diagnosis_timeout_s", 0.2)
    monkeypatch.setattr(report, "render_asset_report", lambda inputs, fmt: time.sleep(1.0) or b"late")
    t0 = time.monotonic()
    r = plain.get("/assets/G3/report")
    assert r.status_code == 422 and "longer than the limit of 0.2 s" in r.json()["detail"]
    assert time.monotonic() - t0 < 0.9


def test_cli_report_of_an_asset_has_the_service_reports_content(clients, tmp_path, monkeypatch):
    from typer.testing import CliRunner

    from rotordiag.cli import app

    _, plain, verdicts = clients
    monkeypatch.setenv("ROTORDIAG_DATA_DIR", str(plain.app.state.rd.settings.data_dir))
    monkeypatch.setenv("ROTORDIAG_ENVIRONMENT", "development")
    out = tmp_path / "g3.pdf"
    r = CliRunner().invoke(app, ["report", "--asset", "G3", "--out", str(out)])
    assert r.exit_code == 0, r.output
    cli_page = html.unescape((tmp_path / "g3.html").read_text())
    service_page = html.unescape(plain.get("/assets/G3/report", params={"format": "html"}).text)

    def body(page: str) -> list[str]:   # the text lines, without the generation time and the embedded plot
        return [ln for ln in page.splitlines() if "generated " not in ln and "base64," not in ln]

    assert body(cli_page) == body(service_page)
    assert f"severity: {verdicts[1]['severity']}" in cli_page
    r = CliRunner().invoke(app, ["report", "--asset", "nobody", "--out", str(tmp_path / "x.pdf")])
    assert r.exit_code == 2 and "has no stored diagnoses" in r.output and not (tmp_path / "x.pdf").exists()
    # the form, the asset as the argument: the same page as --asset gives
    pos = tmp_path / "g3_positional.pdf"
    r = CliRunner().invoke(app, ["report", "G3", "--out", str(pos)])
    assert r.exit_code == 0, r.output
    assert body(html.unescape(pos.with_suffix(".html").read_text())) == body(cli_page)
    r = CliRunner().invoke(app, ["report", "nobody", "--out", str(tmp_path / "y.pdf")])
    assert r.exit_code == 2 and "'nobody' has no stored diagnoses" in r.output and not (tmp_path / "y.pdf").exists()


@pytest.mark.parametrize("args, message", [
    (["G3", "--asset", "G3"], "the asset is given twice ('G3' and --asset 'G3')"),
    (["G3", "--asset", "G4"], "name it once, as the argument"),
    (["missing_run.csv"], "missing_run.csv: no such recording file"),
    (["runs/G3"], "runs/G3: no such recording file"),
    (["unit 3"], "'unit 3' is neither a recording file nor an asset's id"),
    ([], "give an ASSET or a RECORDING"),
])
def test_cli_report_refuses_an_ambiguous_or_bad_target(tmp_path, args, message, monkeypatch):
    from typer.testing import CliRunner

    from rotordiag.cli import app

    monkeypatch.chdir(tmp_path)
    out = tmp_path / "r.pdf"
    r = CliRunner().invoke(app, ["report", *args, "--out", str(out)])
    assert r.exit_code == 2 and message in r.output, r.output
    assert not out.exists() and not out.with_suffix(".html").exists()


def test_cli_report_reads_an_existing_file_argument_as_a_recording(tmp_path):
    from rotordiag.service.cli import report_target

    f = tmp_path / "G3"          # a file named like an asset: the file wins, --asset may name the asset beside it
    f.write_text("t,x\n")
    assert report_target(str(f), "G3") == (f, "G3")
    assert report_target("G3", None) == (None, "G3")
    assert report_target(None, "G3") == (None, "G3")


@pytest.fixture(scope="module")
def runup_csv(tmp_path_factory) -> Path:
    """The paper model's run-up 900 → 1500 r/min in 6 s (Δ 0.3), 8 probes + keyphasor at 2560 Hz."""
    from typer.testing import CliRunner

    from rotordiag.cli import app

    out = tmp_path_factory.mktemp("runup") / "runup.csv"
    r = CliRunner().invoke(app, ["runup", "--profile", "900:1500:6", "--misalignment", "0.3", "--out", str(out)])
    assert r.exit_code == 0, r.output
    return out


@pytest.mark.parametrize("which", ["pooled", "plain"])
def test_transient_plots_of_a_runup_show_the_plots_and_the_critical_speed(clients, runup_csv, which):
    pooled, plain, _ = clients
    c = pooled if which == "pooled" else plain
    r = c.post("/ui/transient-plots", files={"file": ("runup.csv", runup_csv.read_bytes())})
    assert r.status_code == 200, r.text
    t = r.json()
    assert t["kind"] == "run-up" and t["speed_source"] == "keyphasor" and t["units"] == "um"
    lo, hi = t["speed_range_rpm"]
    assert 880 < lo < 950 and 1450 < hi <= 1501
    names = [f["name"] for f in t["figures"]]
    assert {"bode", "polar", "centreline", "orbits"} <= set(names)
    assert {f"{k}_b{b}" for k in ("waterfall", "full_spectrum") for b in (1, 2, 3, 4)} <= set(names)
    from PIL import Image

    for f in t["figures"]:
        img = Image.open(io.BytesIO(base64.b64decode(f["png_base64"])))
        assert img.format == "PNG" and img.width >= 400
    # bearing 1 horizontal-ish probe: the linearised model's damped critical at 1106 r/min, half-power half-width
    # ±105 r/min (docs/transient.md, simulator.campbell): the 1X peak lies within it
    b1 = [p for p in t["peaks"] if p["order"] == 1 and p["bearing"] == 1 and p["angle_deg"] == 45.0]
    assert b1 and abs(b1[0]["speed_rpm"] - 1106) < 105, t["peaks"]
    assert "pk-pk" in t["conventions"] and "phase lag" in t["conventions"]


@pytest.mark.parametrize("which", ["pooled", "plain"])
def test_an_assets_plant_model_draws_its_campbell_under_the_startup_plots(clients, runup_csv, which):
    """The asset's configuration names its plant model: its start-up plots then carry the Campbell diagram of that
    model; an unknown plant model is refused when it is stored, naming the choices."""
    from tests.service_util import auth

    pooled, plain, _ = clients
    c = pooled if which == "pooled" else plain
    asset = f"unit-campbell-{which}"
    r = c.put(f"/assets/{asset}/probes", json={"plant_model": "gen200_2pole"}, headers=auth())
    assert r.status_code == 200, r.text
    bad = c.put(f"/assets/{asset}/probes", json={"plant_model": "gen999"}, headers=auth())
    assert bad.status_code == 422 and "gen200_2pole" in bad.json()["detail"]
    body = {"file": ("runup.csv", runup_csv.read_bytes())}
    with_model = c.post("/ui/transient-plots", params={"asset_id": asset}, files=body)
    assert with_model.status_code == 200, with_model.text
    assert "campbell" in [f["name"] for f in with_model.json()["figures"]]
    without = c.post("/ui/transient-plots", files=body).json()
    assert "campbell" not in [f["name"] for f in without["figures"]]
    # the asset's own shaft line instead of a preset (the tables of examples/shaftline_200mw.toml)
    import tomllib

    tables = tomllib.loads((Path(__file__).resolve().parents[1] / "examples" / "shaftline_200mw.toml").read_text())
    r = c.put(f"/assets/{asset}/probes", json={"plant_shaftline": tables}, headers=auth())
    assert r.status_code == 200, r.text
    own = c.post("/ui/transient-plots", params={"asset_id": asset}, files=body)
    assert own.status_code == 200 and "campbell" in [f["name"] for f in own.json()["figures"]]
    both = c.put(f"/assets/{asset}/probes", json={"plant_model": "default", "plant_shaftline": tables},
                 headers=auth())
    assert both.status_code == 422 and "one way" in both.json()["detail"]


def test_transient_plots_refuse_a_keyphasor_that_drops_out_and_a_broken_file(clients, runup_csv):
    pooled, plain, _ = clients
    a = np.loadtxt(runup_csv, delimiter=",", skiprows=1)
    a[6000:7500, -1] = 0.0                                    # 0.6 s of keyphasor without pulses, mid-run
    buf = io.StringIO()
    np.savetxt(buf, a, delimiter=",", header=runup_csv.read_text().splitlines()[0], comments="", fmt="%.6g")
    for c in (pooled, plain):
        r = c.post("/ui/transient-plots", files={"file": ("dropout.csv", buf.getvalue().encode())})
        assert r.status_code == 422 and "keyphasor drops out" in r.json()["detail"], r.text
        r = c.post("/ui/transient-plots", files={"file": ("x.csv", b"time_s,a\n0,zz\n")})
        assert 400 <= r.status_code < 500, r.text
        r = c.post("/ui/transient-plots", params={"output_units": "furlong"},
                   files={"file": ("runup.csv", runup_csv.read_bytes())})
        assert r.status_code == 422


def test_transient_plots_take_the_cascade_scale_and_say_it(clients, runup_csv):
    _, plain, _ = clients
    r = plain.post("/ui/transient-plots", params={"cascade_scale": "row"},
                   files={"file": ("runup.csv", runup_csv.read_bytes())})
    assert r.status_code == 200, r.text
    t = r.json()
    assert t["cascade_scale"] == "row"
    cascades = [f for f in t["figures"] if f["name"].startswith(("waterfall", "full_spectrum"))]
    assert cascades and all("each trace to its own largest line" in f["title"] for f in cascades)
    r = plain.post("/ui/transient-plots", params={"cascade_scale": "log"},
                   files={"file": ("runup.csv", runup_csv.read_bytes())})
    assert r.status_code == 422, r.text


def test_transient_plots_take_the_centreline_reference_and_need_the_clearance_for_a_slow_roll(clients, runup_csv):
    """``centreline_reference=slow_roll`` (the slowest step at the bottom of the clearance) needs the clearance —
    the run-up's CSV carries none: refused with what to give —, draws another centreline than the probes' own zero,
    and an unknown reference is a 422."""
    _, plain, _ = clients
    body = {"file": ("runup.csv", runup_csv.read_bytes())}
    r = plain.post("/ui/transient-plots", params={"centreline_reference": "slow_roll"}, files=body)
    assert r.status_code == 422 and "clearance_um" in r.text, r.text
    recorded = plain.post("/ui/transient-plots", params={"clearance_um": 350}, files=body).json()
    r = plain.post("/ui/transient-plots", params={"centreline_reference": "slow_roll", "clearance_um": 350},
                   files=body)
    assert r.status_code == 200, r.text
    slow = r.json()
    assert recorded["centreline_reference"] == "recorded" and slow["centreline_reference"] == "slow_roll"

    def centreline_png(t: dict) -> str:
        return next(f["png_base64"] for f in t["figures"] if f["name"] == "centreline")

    assert centreline_png(slow) != centreline_png(recorded)
    r = plain.post("/ui/transient-plots", params={"centreline_reference": "bottom"}, files=body)
    assert r.status_code == 422, r.text


def test_transient_plots_refuse_a_1e8_sample_file_with_a_4xx_saying_why(clients, tmp_path):
    """A 10⁸-sample NPY (its header says 8 × 10⁸ float32, 3.2 GB; the file is 200 bytes): refused before it is
    read, with the size, through both service paths."""
    from tests.test_features_transient import _huge_npy

    body = _huge_npy(tmp_path / "huge.npy").read_bytes()
    pooled, plain, _ = clients
    for c in (pooled, plain):
        r = c.post("/ui/transient-plots", params={"sample_rate_hz": 25600, "keyphasor_channel": 7},
                   files={"file": ("huge.npy", body)})
        assert 400 <= r.status_code < 500, r.text
        assert "(8, 100000000)" in r.json()["detail"], r.text


def test_report_shows_the_latest_full_verdict_when_retention_trimmed_the_last(clients):
    from sqlalchemy import update

    from rotordiag.service.core.db import AssetDiagnosis

    _, plain, _ = clients
    fs, channels = simulated_channels(misalignment=0.2, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=40)
    for _ in range(2):
        r = plain.post("/diagnose", json=diagnose_json(fs, channels, speed_rpm=1800.0, asset_id="G4"), headers=auth())
        assert r.status_code == 200, r.text
    ids = [p["id"] for p in plain.get("/assets/G4/history").json()["points"]]
    with plain.app.state.rd.sessions.begin() as s:          # what retention leaves of an old diagnosis
        s.execute(update(AssetDiagnosis).where(AssetDiagnosis.id == ids[-1]).values(verdict={}, key_features={}))
    page = html.unescape(plain.get("/assets/G4/report", params={"format": "html"}).text)
    assert f"latest: stored diagnosis #{ids[0]}" in page
    assert f"the latest diagnosis (#{ids[-1]}) keeps only its summary; the verdict shown is #{ids[0]}'s" in page
    assert "status: " in page and "Trend (2 stored diagnoses)" in page
    with plain.app.state.rd.sessions.begin() as s:
        s.execute(update(AssetDiagnosis).where(AssetDiagnosis.asset_id == "G4").values(verdict={}))
    page = html.unescape(plain.get("/assets/G4/report", params={"format": "html"}).text)
    assert "no stored diagnosis of this asset keeps its full verdict" in page and "status: " not in page
