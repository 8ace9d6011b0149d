"""The report in the user's units (issue 46 item 5): a stored verdict keeps its texts' typed values, so
`GET /assets/{id}/report?output_units=mil` and `rotordiag report --output-units mil` give every length in mils —
the same texts as the /diagnose answer in mils —, never µm read out of a stored sentence."""
from __future__ import annotations

import html
import json

import pytest
from fastapi.testclient import TestClient

from rotordiag.core.notes import Length, Measured, Note, typed_from_json, typed_to_json
from rotordiag.core.units import UM_PER_MIL
from rotordiag.models.output_units import TYPED_TEXTS_KEY, revive_typed_texts, verdict_in_units, with_typed_texts
from rotordiag.service.main import create_app
from tests.service_util import auth, diagnose_json, make_settings, shipped_or_tiny_registry, simulated_channels


def test_typed_values_survive_json_and_render_in_mils():
    m = Measured("{a} pk-pk at bearing {b}", a=Length(25.4), b=3)
    back = typed_from_json(json.loads(json.dumps(typed_to_json(m))))
    assert isinstance(back, Measured) and back == m and back.render("mil") == "1 mil pk-pk at bearing 3"
    n = Note("speed_not_converged", speed_rpm=1800.123)
    nb = typed_from_json(json.loads(json.dumps(typed_to_json(n))))
    assert isinstance(nb, Note) and nb.code == n.code and nb == n
    with pytest.raises(ValueError):
        typed_from_json({"__note__": "no_such_code", "values": {}})


@pytest.fixture(scope="module")
def verdict():
    """A real verdict of the shipped (or tiny) model on a simulated Δ 0.3 recording with its clearance: an offset
    and evidence texts with lengths."""
    from rotordiag.features import ProbeChannel, Recording
    from rotordiag.models.pipeline import diagnose_recording
    from rotordiag.models.predict import load_bundle

    fs, channels = simulated_channels(misalignment=0.3, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=40)
    rec = Recording(sample_rate_hz=fs, channels=[ProbeChannel(b, a, "um", d) for b, a, d in channels],
                    clearance_um=350.0, speed_rpm=1800.0)
    bundle = load_bundle(shipped_or_tiny_registry())
    v, _ = diagnose_recording(bundle, rec, clearance_um=350.0)
    return v.to_dict()


def test_a_stored_verdict_gives_the_same_mil_answer_as_the_fresh_one(verdict):
    assert any(isinstance(e.get("value"), Measured) for e in verdict["evidence"])
    stored = json.loads(json.dumps(with_typed_texts(verdict)))        # what the database gives back
    assert TYPED_TEXTS_KEY in stored and TYPED_TEXTS_KEY not in verdict
    plain = {k: v for k, v in stored.items() if k != TYPED_TEXTS_KEY}
    fresh = verdict_in_units(verdict, "mil")
    revived = verdict_in_units(revive_typed_texts(stored), "mil")
    assert [e["value"] for e in revived["evidence"]] == [e["value"] for e in fresh["evidence"]]
    assert [str(r["message"]) for r in revived["reasons"]] == [str(r["message"]) for r in fresh["reasons"]]
    assert [str(w) for w in revived["warnings"]] == [str(w) for w in fresh["warnings"]]
    # without the typed values (a verdict stored before them) the texts stay in µm: that was the defect
    lost = verdict_in_units(plain, "mil")
    with_um = [e["value"] for e in fresh["evidence"] if e["value"] != str(
        next(x["value"] for x in verdict["evidence"] if x["name"] == e["name"] and x["scope"] == e["scope"]))]
    assert with_um, "some evidence text has a length"
    assert not set(with_um) <= {e["value"] for e in lost["evidence"]}
    assert revived["offset_mil"] == pytest.approx(verdict["offset_um"] / UM_PER_MIL)


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    registry = shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))
    app = create_app(make_settings(tmp_path_factory.mktemp("units"), shipped_registry_dir=registry,
                                   diagnosis_workers=1))
    fs, channels = simulated_channels(misalignment=0.3, speed_rpm=1800.0, sample_rate_hz=2048.0, record_revs=40)
    with TestClient(app) as c:
        answers = {}
        for units in ("mil", "um"):
            r = c.post("/diagnose", params={"output_units": units},
                       json=diagnose_json(fs, channels, speed_rpm=1800.0, asset_id="M1", clearance_um=350.0),
                       headers=auth())
            assert r.status_code == 200, r.text
            answers[units] = r.json()
        yield c, answers


def test_service_report_follows_the_requested_units(client):
    c, answers = client
    mil, um = answers["mil"], answers["um"]
    r = c.get("/assets/M1/report", params={"format": "html", "output_units": "mil"})
    assert r.status_code == 200, r.text
    page = html.unescape(r.text)
    assert "lengths in mil" in page
    assert all(f"{e['name']}: {e['value']}" in page for e in mil["evidence"])
    assert all(x["message"] in page for x in mil["reasons"]) and all(w in page for w in mil["warnings"])
    assert mil["headline"]["text"] in page
    assert f"offset δ: {mil['offset_mil']:.2f} mil" in page
    um_only = [e["value"] for e in um["evidence"] if "µm" in e["value"]]
    assert um_only and not any(v in page for v in um_only)
    page_um = html.unescape(c.get("/assets/M1/report", params={"format": "html"}).text)
    assert "lengths in µm" in page_um and f"offset δ: {um['offset_um']:.1f} µm" in page_um
    assert all(f"{e['name']}: {e['value']}" in page_um for e in um["evidence"])
    assert c.get("/assets/M1/report", params={"output_units": "furlong"}).status_code == 422
    pdf = c.get("/assets/M1/report", params={"output_units": "mil"})
    assert pdf.status_code == 200 and pdf.content.startswith(b"%PDF-")


def test_cli_report_in_mils(tmp_path):
    """`rotordiag report --output-units mil`: the verdict's offset and the start-up's peaks in mils."""
    from typer.testing import CliRunner

    from rotordiag.cli import app

    run = CliRunner()
    steady, startup = tmp_path / "steady.csv", tmp_path / "runup.csv"
    r = run.invoke(app, ["simulate", "--speed-rpm", "1800", "--misalignment", "0.3", "--record-revs", "60",
                         "--probes-out", str(steady), "--probe-sample-rate-hz", "2560"])
    assert r.exit_code == 0, r.output
    r = run.invoke(app, ["runup", "--profile", "900:1500:6", "--misalignment", "0.3", "--out", str(startup)])
    assert r.exit_code == 0, r.output
    pages = {}
    for units in ("um", "mil"):
        out = tmp_path / f"r-{units}.pdf"
        r = run.invoke(app, ["report", str(steady), "--startup", str(startup), "--clearance-um", "350",
                             "--output-units", units, "--out", str(out)])
        assert r.exit_code == 0, r.output
        pages[units] = html.unescape(out.with_suffix(".html").read_text())
    assert "lengths in mil" in pages["mil"] and "µm pk-pk at" not in pages["mil"]
    assert " mil pk-pk at " in pages["mil"] and " µm pk-pk at " in pages["um"]
    assert "offset δ: " in pages["mil"] and " mil (" in pages["mil"].split("offset δ: ")[1].splitlines()[0]
    r = run.invoke(app, ["report", str(steady), "--output-units", "furlong", "--out", str(tmp_path / "x.pdf")])
    assert r.exit_code == 2 and "--output-units" in r.output and not (tmp_path / "x.pdf").exists()
