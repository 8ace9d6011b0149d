"""Lengths in the engineer's units: ``?output_units=mil`` on the API and ``--output-units mil`` in the CLI
give the same numbers (µm / 25.4) under mil-named fields, evidence texts included."""
from __future__ import annotations

import json
import re

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from rotordiag.cli import app as cli_app
from rotordiag.core.units import lengths_in
from rotordiag.features.examples import example_path
from rotordiag.models.output_units import verdict_in_units
from rotordiag.service.main import create_app
from tests.service_util import make_settings, shipped_or_tiny_registry

MIL = 25.4


def test_lengths_in_renames_and_converts_every_micrometre_field():
    v = {"offset_um": 50.8, "offset_interval_um": [25.4, None], "misalignment": 0.3, "ood": False,
         "bearings": [{"clearance_um": 254.0, "features": {"b2_1x_major_um_pp": 2.54, "b2_orbit12_area_um2": 645.16,
                                                           "b2_2x_1x_major_ratio": 0.5, "b2_1x_phase_deg": 90.0}}],
         "amplitudes_um_pp": {"b2": 25.4}}
    out = lengths_in(v, "mil")
    assert out == {"offset_mil": pytest.approx(2.0), "offset_interval_mil": [pytest.approx(1.0), None],
                   "misalignment": 0.3, "ood": False,
                   "bearings": [{"clearance_mil": pytest.approx(10.0),
                                 "features": {"b2_1x_major_mil_pp": pytest.approx(0.1),
                                              "b2_orbit12_area_mil2": pytest.approx(1.0),
                                              "b2_2x_1x_major_ratio": 0.5, "b2_1x_phase_deg": 90.0}}],
                   "amplitudes_mil_pp": {"b2": pytest.approx(1.0)}}
    assert lengths_in(v, "um") is v
    with pytest.raises(ValueError, match="output units"):
        lengths_in(v, "inch")


def test_evidence_texts_and_top_features_follow():
    from rotordiag.core.notes import Length, Measured

    v = {"top_features": [{"name": "b3_y_direct_um_pp", "value": 254.0, "reference": 127.0, "contribution": 0.4}],
         "evidence": [{"scope": "bearing 3", "name": "1X y", "value": Measured.of(Length(42.1), " pk-pk ∠ 137°"),
                       "meaning": "", "number": 42.1},
                      {"scope": "coupling 2–3", "name": "2X/1X", "value": "0.54", "meaning": "", "number": 0.54}]}
    out = verdict_in_units(v, "mil")
    assert out["top_features"][0] == {"name": "b3_y_direct_mil_pp", "value": pytest.approx(10.0),
                                      "reference": pytest.approx(5.0), "contribution": 0.4}
    assert out["evidence"][0]["value"] == "1.66 mil pk-pk ∠ 137°"
    assert out["evidence"][0]["number"] == pytest.approx(42.1 / MIL)
    assert out["evidence"][1] == v["evidence"][1]          # a ratio is not a length
    assert out["output_units"] == "mil" and v["evidence"][0]["number"] == 42.1   # the input is not changed


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    registry = shipped_or_tiny_registry(tmp_path_factory.mktemp("registry"))
    app = create_app(make_settings(tmp_path_factory.mktemp("svc"), shipped_registry_dir=registry))
    with TestClient(app) as c:
        yield c


def _post(client, units: str | None) -> dict:
    path = example_path("whirl.csv")
    q = "clearance_um=350" + (f"&output_units={units}" if units else "")
    r = client.post(f"/diagnose?{q}", files={"file": (path.name, path.read_bytes())})
    assert r.status_code == 200, r.text
    return r.json()


def test_api_answers_in_mils_and_the_cli_agrees(client, tmp_path):
    um, mil = _post(client, None), _post(client, "mil")
    assert um["output_units"] == "um" and mil["output_units"] == "mil"
    assert mil["offset_mil"] == pytest.approx(um["offset_um"] / MIL)
    assert mil["offset_interval_mil"] == pytest.approx([x / MIL for x in um["offset_interval_um"]])
    assert mil["offset_um"] is None and mil["misalignment"] == um["misalignment"]
    b_um = {b["bearing"]: b for b in um["bearings"]}
    for b in mil["bearings"]:
        feats = b["features"]
        assert not any(re.search(r"(^|_)um(2|_|$)", k) for k in feats), feats.keys()
        for k, v in b_um[b["bearing"]]["features"].items():
            if k.endswith("_um_pp") and v is not None:
                assert feats[k.replace("_um_pp", "_mil_pp")] == pytest.approx(v / MIL)
    assert not any("µm" in e["value"] for e in mil["evidence"])
    # the CLI's --output-units mil gives the same offset
    out = tmp_path / "v.json"
    res = CliRunner().invoke(cli_app, ["diagnose", str(example_path("whirl.csv")), "--clearance-um", "350",
                                       "--output-units", "mil", "--out", str(out)])
    assert res.exit_code == 0, res.output
    row = json.loads(out.read_text())[0]
    assert row["offset_mil"] == pytest.approx(mil["offset_mil"])


def test_cli_text_in_mils_converts_every_length_not_only_the_offset(tmp_path):
    """``rotordiag diagnose --output-units mil`` (the text, not --json): the offset, the evidence amplitudes and
    any µm-named feature are in mils, each the µm text's number / 25.4 (issue 45: only the offset was)."""
    from rotordiag.models.predict import FeatureContribution, Verdict, format_verdict

    args = ["diagnose", str(example_path("whirl.csv")), "--clearance-um", "350"]
    um = CliRunner().invoke(cli_app, args)
    mil = CliRunner().invoke(cli_app, [*args, "--output-units", "mil"])
    assert um.exit_code == 0 and mil.exit_code == 0, um.output + mil.output

    def section(text):
        return text.split("evidence (measured, independent of the model):")[1]

    um_amounts = [float(x) for x in re.findall(r"(-?\d+(?:\.\d+)?) µm", section(um.stdout))]
    mil_amounts = [float(x) for x in re.findall(r"(-?\d+(?:\.\d+)?) mil", section(mil.stdout))]
    assert um_amounts and "µm" not in section(mil.stdout)
    assert mil_amounts == pytest.approx([x / MIL for x in um_amounts], rel=5e-3)   # 3 significant digits
    # every length of the whole text, the reasons and warnings included: no µm amount left in the mil text
    assert not re.findall(r"\d µm", mil.stdout), re.findall(r".{50}\d µm.{10}", mil.stdout)
    # a µm-named feature among the top features and a training range: renamed and converted
    verdict = json.loads(CliRunner().invoke(cli_app, [*args, "--json"]).stdout)

    fields = {k: verdict.get(k) for k in Verdict.__dataclass_fields__ if k in verdict}
    fields["top_features"] = [FeatureContribution(name="b2_1x_major_um_pp", value=50.8, reference=25.4,
                                                  contribution=0.1)]
    fields["ood_findings"] = [{"feature": "b3_x_direct_um_pp", "value": 254.0, "train_min": 2.54, "train_max": 127.0}]
    for k in ("misalignment_interval", "offset_interval_um"):
        if isinstance(fields.get(k), list):
            fields[k] = tuple(fields[k])
    text = format_verdict(Verdict(**fields), "mil")
    assert re.search(r"b2_1x_major_mil_pp\s+2 +\(typical 1\)", text), text
    assert "b3_x_direct_mil_pp = 10 (training 0.1 … 5)" in text
    assert "_um_pp" not in text
    # typed reason and warning texts are rendered in mil too (a sentence is never parsed)
    from rotordiag.core.notes import Length, Note
    from rotordiag.models.status import Reason

    fields.update(reasons=[Reason("scale", "uncertain", {"bearing": 3, "amp": Length(254.0), "factor": 25.0,
                                                         "typical": Length(10.16)}, "above").to_dict()],
                  warnings=[Note("motion_not_classified", orbit=Length(25.4))])
    text = format_verdict(Verdict(**fields), "mil")
    typed = [ln for ln in text.splitlines() if ln.startswith(("  uncertain:", "warning:"))]
    assert any(ln.startswith("  uncertain: 1X vibration at bearing 3 is 10 mil pk-pk, 25× above the training data's "
                             "typical 0.4 mil") for ln in typed), text
    assert any("(1 mil)" in ln for ln in typed), text
    assert not any(re.search(r"\d µm", ln) for ln in typed)   # (the evidence here came back from JSON: untyped)
    # an inconclusive verdict with the clearance given does not ask for the clearance (issue 45)
    fields.update(misalignment=None, offset_um=None, offset_interval_um=None, status="inconclusive")
    text = format_verdict(Verdict(**fields), "um")
    assert "offset δ: not given (inconclusive)" in text and "give the bearing clearance" not in text


def test_unknown_output_units_is_a_422_that_names_the_choices(client):
    path = example_path("whirl.csv")
    r = client.post("/diagnose?output_units=inch", files={"file": (path.name, path.read_bytes())})
    assert r.status_code == 422 and "um" in r.text and "mil" in r.text
