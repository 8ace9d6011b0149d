"""The headline (models.headline): one sentence of what to do, from typed data, at every door — asserted on the
action and urgency codes; a few full sentences where the words are the point (units, lengths)."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from rotordiag.core.reasons import CATALOGUE
from rotordiag.models.headline import ACTIONS, UNITS_CODES, URGENCIES, headline
from rotordiag.models.output_units import verdict_in_units


def _v(status="confident", severity="aligned", codes=(), motion="period-1", offset_um=None, baseline=None):
    reasons = [{"code": c, "status": "inconclusive" if status == "inconclusive" else "uncertain", "message": c}
               for c in codes]
    v = {"status": status, "severity": severity, "reasons": reasons, "motion_type": motion, "offset_um": offset_um}
    if baseline is not None:
        v["baseline"] = baseline
    return v


@pytest.mark.parametrize(("verdict", "action", "urgency", "show"), [
    (_v(), "none", "none", True),
    (_v(status="uncertain", codes=("offset_not_assessed",)), "watch", "routine", True),
    (_v(severity="slight", offset_um=40.0), "watch", "routine", True),
    (_v(severity="moderate", offset_um=120.0), "plan_alignment", "next_outage", True),
    (_v(severity="severe", offset_um=250.0), "align_soon", "soon", True),
    (_v(status="uncertain", severity="moderate", codes=("far_band_interval",)), "confirm", "before_acting", True),
    # called aligned against its own coupling 2X: never "no action", whatever reason comes first
    (_v(status="uncertain", codes=("far_band_interval", "signature_contradicts_call")), "confirm", "before_acting",
     True),
    (_v(status="uncertain", severity="severe", codes=("ood",)), "confirm", "before_acting", True),
    # units or physics in doubt: the measurement first, whatever the band and however confident
    (_v(status="uncertain", severity="aligned", codes=("scale", "low_probability")), "check_measurement",
     "before_acting", False),
    (_v(status="inconclusive", severity="inconclusive", codes=("orbit_exceeds_clearance",)), "check_measurement",
     "before_acting", False),
    (_v(status="inconclusive", severity="inconclusive", codes=("dropout",)), "check_measurement", "before_acting",
     False),
    (_v(status="inconclusive", severity="inconclusive", codes=("signature_above_call",)), "record_again",
     "before_acting", False),
    # a whirl is a stability problem: named before any misalignment figure
    (_v(status="uncertain", severity="severe", motion="quasi-periodic", codes=("speed_ambiguous",)),
     "investigate_whirl", "soon", True),
    (_v(severity="aligned", motion="period-2"), "investigate_whirl", "soon", True),
    (_v(severity="aligned", motion="unresolved"), "none", "none", True),
    # a change since the baseline reaches the headline, even when the model reads aligned
    (_v(baseline={"compared": True, "changed": True, "exceeded": ["2x_change"], "set_at": "2026-03-02T10:00:00"}),
     "investigate_change", "next_outage", True),
    (_v(severity="moderate", baseline={"compared": True, "changed": True, "exceeded": ["dc_shift"]}),
     "investigate_change", "soon", True),
    (_v(baseline={"compared": True, "changed": False, "exceeded": []}), "none", "none", True),
])
def test_the_rules(verdict, action, urgency, show):
    h = headline(verdict)
    assert (h.action, h.urgency, h.show_severity) == (action, urgency, show), h
    assert h.action in ACTIONS and h.urgency in URGENCIES and h.text
    if "signature_contradicts_call" in [r["code"] for r in verdict["reasons"]]:
        assert "2X/1X reads misalignment" in h.text and "no action" not in h.text


def test_every_units_code_is_in_the_catalogue():
    assert UNITS_CODES <= set(CATALOGUE)


def test_the_offset_is_said_in_the_users_units_and_the_change_by_its_readable_name():
    v = _v(severity="moderate", offset_um=120.0)
    assert headline(v).text == "plan an alignment check at the next outage: the coupling offset is about 0.12 mm"
    assert "4.7 mil" in headline(v, units="mil").text and "mm" not in headline(v, units="mil").text
    assert "about 40 µm" in headline(_v(severity="slight", offset_um=40.0)).text
    changed = headline(_v(baseline={"compared": True, "changed": True, "exceeded": ["2x_change", "dc_shift"],
                                    "set_at": "2026-03-02T10:00:00"}))
    assert "the 2X vector change and centreline shift changed since the baseline of 2026-03-02 10:00 UTC" in changed.text
    assert "_" not in changed.text


def test_the_measurement_headline_carries_what_to_check():
    h = headline(_v(status="uncertain", codes=("scale",)))
    assert h.text.startswith("check the measurement first: the units look wrong")
    assert CATALOGUE["scale"].action in h.text


@pytest.fixture(scope="module")
def simulated():
    """One simulated recording of the default plant (Δ = 0.2, rigid), in µm, with its shipped-model bundle."""
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import shipped_registry_dir
    from rotordiag.simulator import Plant, simulate

    res = simulate(Plant.default(), 1800.0, 0.2, 0.05, mechanism="rigid", transient_revs=100, record_revs=34,
                   sample_rate_hz=4096.0)
    return res.journal_displacements_m * 1e6, load_bundle(shipped_registry_dir())


def _diagnose(simulated, scale=1.0, offset=0.0, clearance_um=None):
    from rotordiag.features import ProbeChannel, Recording, extract_features
    from rotordiag.models.pipeline import diagnose

    d, bundle = simulated
    rec = Recording(sample_rate_hz=4096.0, speed_rpm=1800.0, clearance_um=clearance_um, channels=[
        ProbeChannel(bearing=k, angle_deg=a, units="um",
                     data=(d[:, k - 1, 0] * np.cos(np.deg2rad(a)) + d[:, k - 1, 1] * np.sin(np.deg2rad(a))) * scale
                     + offset)
        for k in range(1, 5) for a in (45.0, 135.0)])
    return diagnose(bundle, extract_features(rec), clearance_um=clearance_um)


def test_volts_read_as_micrometres_give_no_severity(simulated):
    """The issue's case: a probe's volts (7.87 V/mm, −10 V gap) sent as µm. The model still calls a class, but the
    answer opens with "check the measurement first" and says no severity may be shown."""
    v = _diagnose(simulated, scale=7.87e-3, offset=-10.0).to_dict()
    out = verdict_in_units(v, "um")
    assert out["headline"]["action"] == "check_measurement" and out["headline"]["show_severity"] is False
    assert "scale" in [r["code"] for r in v["reasons"]]


def test_mil_answer_has_no_micrometre_amount_anywhere(simulated):
    """Mils read as µm (×25.4): every length in the mil answer — reasons, evidence, warnings, headline — is in mil;
    "µm" is left only in the words that name the unit mistake ("µm vs mils")."""
    v = _diagnose(simulated, scale=25.4, clearance_um=350.0).to_dict()
    text = json.dumps(verdict_in_units(v, "mil"), ensure_ascii=False)
    assert not re.findall(r"\d µm", text), re.findall(r".{60}\d µm.{20}", text)
    assert "mil" in text and v["reasons"]


def test_the_cli_opens_with_the_headline(tmp_path):
    from typer.testing import CliRunner

    from rotordiag.cli import app
    from rotordiag.features.examples import example_path

    r = CliRunner().invoke(app, ["diagnose", str(example_path("whirl.csv")), "--output-units", "mil"])
    assert r.exit_code == 0, r.output
    first = r.output.splitlines()[0]
    assert first.startswith("WHAT TO DO: ") and "urgency:" in first
    r = CliRunner().invoke(app, ["diagnose", str(example_path("whirl.csv")), "--json"])
    assert json.loads(r.output)["headline"]["action"] in ACTIONS


@pytest.mark.parametrize(("name", "band", "status", "action"), [
    ("aligned.csv", "aligned", "confident", "none"), ("aligned.h5", "aligned", "confident", "none"),
    ("slight.csv", "slight", "confident", "watch"), ("moderate.csv", "moderate", "confident", "plan_alignment"),
    ("severe.csv", "severe", "confident", "align_soon"),
])
def test_each_steady_shipped_example_gets_its_band(name, band, status, action):
    """The shipped examples are clean, steady cases of each state: with their sidecar (the clearance) the shipped
    model gives each its band and the headline its action, each confident (v0002 and v0003 doubted the aligned one
    for its Δ interval, 0–0.199, reaching moderate: "probably aligned, not certain" — watch; v0004 reads the
    columns across bearings: Δ 0, interval to 0.026 — "no action")."""
    from rotordiag.features import extract_features
    from rotordiag.features.examples import example_options, example_path
    from rotordiag.features.reader import ReadOptions, read_recording
    from rotordiag.models.pipeline import diagnose
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.registry import shipped_registry_dir

    opts = example_options(name)
    assert opts.get("clearance_um") == 350
    rec = read_recording(example_path(name), options=ReadOptions(**opts)).recording
    v = diagnose(load_bundle(shipped_registry_dir()), extract_features(rec), clearance_um=350.0).to_dict()
    assert (v["status"], v["severity"], v["motion_type"]) == (status, band, "period-1"), v["reasons"]
    assert verdict_in_units(v, "um")["headline"]["action"] == action


def test_the_whirl_example_is_labelled_and_says_so():
    from typer.testing import CliRunner

    from rotordiag.cli import app
    from rotordiag.features.examples import describe_example, example_path

    assert "whirl" in describe_example("whirl.csv")
    r = CliRunner().invoke(app, ["diagnose", "--json", str(example_path("whirl.csv"))])
    v = json.loads(r.output)
    assert v["motion_type"] == "quasi-periodic" and v["headline"]["action"] == "investigate_whirl"


def test_timestamps_are_readable():
    from rotordiag.core.timefmt import readable_time

    assert readable_time("2026-03-02T10:00:00.123456") == "2026-03-02 10:00 UTC"
    assert readable_time("2026-03-02T11:00:00+01:00") == "2026-03-02 10:00 UTC"
    assert readable_time("2026-03-02T10:00:00Z") == "2026-03-02 10:00 UTC"
    assert readable_time("not a time") == "not a time" and readable_time(None) == "—"


def test_api_timestamps_are_iso_8601_with_utc_as_z():
    """The service stores naive UTC; the API writes it ISO 8601 with ``Z`` (RFC 3339), an aware time as given."""
    import datetime as dt

    from rotordiag.core.timefmt import iso_utc

    assert iso_utc(dt.datetime(2026, 3, 2, 10, 0, 0)) == "2026-03-02T10:00:00Z"
    assert iso_utc(dt.datetime(2026, 3, 2, 10, 0, 0, 123456, tzinfo=dt.UTC)) == "2026-03-02T10:00:00.123456Z"
    plus_one = dt.timezone(dt.timedelta(hours=1))
    assert iso_utc(dt.datetime(2026, 3, 2, 11, 0, tzinfo=plus_one)) == "2026-03-02T11:00:00+01:00"
    assert iso_utc(None) is None


def test_a_changed_start_up_asks_to_investigate_the_change():
    """``startup_changed`` (models.checks.startup, on an "aligned" call) leads to "investigate change", naming the
    start-up; an inconclusive verdict still asks to record again first; no "aligned misalignment" wording."""
    h = headline(_v(status="uncertain", codes=("startup_changed",), offset_um=7.0))
    assert (h.action, h.urgency) == ("investigate_change", "next_outage")
    assert "start-up's coupling-end centreline changed since the baseline start-up" in h.text
    assert h.text.endswith("the model reads aligned") and "aligned misalignment" not in h.text
    h = headline(_v(status="inconclusive", severity="inconclusive", codes=("signature_above_call", "startup_changed")))
    assert h.action == "record_again"
