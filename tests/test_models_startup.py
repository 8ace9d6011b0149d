"""A start-up as evidence beside the steady verdict (models.startup, models.checks.startup): entries, and a doubt
never a band."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rotordiag.features import transient as T
from rotordiag.models.checks.startup import (
    CRITICAL_MOVED_FRACTION,
    StartupContext,
    startup_check,
    startup_findings,
)
from rotordiag.models.startup import StartupEvidence, compare_startups, startup_evidence
from rotordiag.models.status import UNCERTAIN
from tests.test_features_transient import _synthetic


def _ev(crit_rpm: float = 1500.0, half_rise_rpm: float = 1200.0, top=(10.0, 60.0),
        slow=(0.0, -150.0)) -> StartupEvidence:
    return StartupEvidence({(2, 45.0): crit_rpm, (3, 45.0): crit_rpm}, {2: half_rise_rpm, 3: half_rise_rpm},
                           {2: top, 3: top}, {2: 300.0, 3: 300.0}, (300.0, 2000.0), {2: slow, 3: slow})


def test_no_baseline_gives_entries_and_no_reason():
    entries, reasons = startup_findings(StartupContext(_ev(), None, misaligned_call=False))
    assert not reasons
    assert [e["code"] for e in entries] == ["startup_criticals", "startup_no_baseline"]
    assert "b2@45 1500 r/min" in entries[0]["text"]


def test_an_unchanged_start_up_adds_no_doubt():
    small = 1500.0 * (1 + 0.5 * CRITICAL_MOVED_FRACTION)
    entries, reasons = startup_findings(StartupContext(_ev(crit_rpm=small), _ev()))
    assert not reasons and entries[-1]["code"] == "startup_unchanged"


def test_a_moved_critical_alone_is_an_entry_not_a_doubt():
    entries, reasons = startup_findings(StartupContext(_ev(crit_rpm=1400.0), _ev()))
    assert not reasons
    moved = [e for e in entries if e["code"] == "startup_criticals_moved"]
    assert moved and "moved from 1500 to 1400 r/min (-7 %)" in moved[0]["text"] and moved[0]["effect"] == "none"


@pytest.mark.parametrize("now, what", [
    (dict(half_rise_rpm=1500.0), "half its centreline rise at 1500 r/min against 1200"),
    (dict(top=(10.0, 100.0)), "13 % of its clearance away"),          # |Δ| 40 µm of a 300 µm clearance
    # a train's offset moves the journal at every speed, slow roll included: the rise from slow roll is unchanged
    (dict(slow=(0.0, -105.0)), "sits 15 % of its clearance away from where it sat at slow roll"),
])
def test_a_changed_start_up_doubts_an_aligned_call_and_supports_a_misaligned_one(now, what):
    ctx = StartupContext(_ev(**now), _ev(), misaligned_call=False)
    entries, reasons = startup_findings(ctx)
    assert len(reasons) == 1 and reasons[0].code == "startup_changed" and reasons[0].status == UNCERTAIN
    assert what in reasons[0].values["changes"]
    assert entries[-1]["effect"] == "doubts"
    assert startup_check(ctx) == reasons                 # the check: the context in, the same reasons out
    entries, reasons = startup_findings(replace(ctx, misaligned_call=True))
    assert not reasons and entries[-1]["effect"] == "supports" and what in entries[-1]["text"]
    assert startup_check(replace(ctx, misaligned_call=True)) == []


def test_the_start_up_check_reads_the_coupling_bearings_it_is_given():
    """A train's coupling is elsewhere than the paper model's bearings 2 and 3: a change at bearings 2 and 3 is no
    doubt when the context names bearings 4 and 5, and is one when it names 2 and 3."""
    ctx = StartupContext(_ev(half_rise_rpm=1500.0), _ev())
    assert [r.code for r in startup_check(ctx)] == ["startup_changed"]
    assert startup_check(replace(ctx, coupling_bearings=(4, 5))) == []


def test_evidence_of_a_tracked_run_reads_its_critical_and_its_rise():
    """The synthetic run's 1X resonance is at 1500 r/min (ζ 0.05) and its centreline rises linearly with speed: the
    critical is found there, and the half-rise speed is the middle of the run."""
    rec, _, _ = _synthetic(rpm0=900.0, rpm1=2100.0, dur_s=20.0)
    tr = T.track_orders(rec)
    ev = startup_evidence(tr, T.centreline(rec, tr))
    assert ev.criticals and all(abs(s - 1500.0) < 0.05 * 1500.0 for s in ev.criticals.values())
    for b, s in ev.half_rise_rpm.items():
        assert abs(s - 1500.0) < 60.0, (b, s)
    same = compare_startups(ev, ev)
    assert all(v[2] == 0.0 for v in same["critical_shift"].values())
    assert all(v == 0.0 for v in same["top_change_per_clearance"].values())
    assert np.isfinite(ev.speed_range_rpm).all()


def test_report_cli_adds_the_start_up_doubt_to_an_aligned_call(tmp_path):
    """`rotordiag report steady --startup now --baseline-startup base`: the run-up at Δ 0.15 against the plant's Δ 0
    baseline run-up (the coupling-end centreline rises later) puts ``startup_changed`` on the steady Δ 0 recording's
    "aligned" verdict, whose band stays "aligned"; with the baseline as the start-up, no doubt."""
    import html as _html

    from typer.testing import CliRunner

    from rotordiag.cli import app

    run = CliRunner()
    base, now, steady = tmp_path / "base.csv", tmp_path / "now.csv", tmp_path / "steady.csv"
    for path, delta in ((base, "0"), (now, "0.15")):
        r = run.invoke(app, ["runup", "--profile", "300:2000:17", "--misalignment", delta, "--settle-revs", "100",
                             "--out", str(path)])
        assert r.exit_code == 0, r.output
    r = run.invoke(app, ["simulate", "--speed-rpm", "1950", "--misalignment", "0", "--record-revs", "80",
                         "--probes-out", str(steady), "--probe-sample-rate-hz", "2560"])
    assert r.exit_code == 0, r.output
    texts = {}
    for name, startup in (("changed", now), ("same", base)):
        out = tmp_path / f"{name}.pdf"
        r = run.invoke(app, ["report", str(steady), "--startup", str(startup), "--baseline-startup", str(base),
                             "--out", str(out), "--clearance-um", "350"])
        assert r.exit_code == 0, r.output
        texts[name] = _html.unescape(out.with_suffix(".html").read_text())
    doubt = "called aligned, but the start-up changed since the asset's baseline start-up: bearing"
    assert doubt in texts["changed"] and "start-up evidence (doubts)" in texts["changed"]
    assert "status: uncertain" in texts["changed"] and "severity: aligned" in texts["changed"]
    assert doubt not in texts["same"] and "start-up evidence (doubts)" not in texts["same"]
    r = run.invoke(app, ["report", str(steady), "--baseline-startup", str(base), "--out", str(tmp_path / "x.pdf")])
    assert r.exit_code == 2 and "--baseline-startup needs --startup" in r.output
    assert not (tmp_path / "x.pdf").exists()


def test_a_slow_roll_shift_below_the_rule_or_missing_from_stored_evidence_is_no_doubt():
    """Below 10 % of the clearance the slow-roll position is unchanged; evidence stored before the slow-roll position
    was kept (no ``slow_roll_um``) is compared on what it has, and still reads back."""
    assert not startup_check(StartupContext(_ev(slow=(0.0, -125.0)), _ev()))      # 25 µm = 8 % of 300 µm
    old = _ev().to_dict()
    del old["slow_roll_um"]
    base = StartupEvidence.from_dict(old)
    assert base.slow_roll_um == {}
    assert compare_startups(_ev(slow=(0.0, 0.0)), base)["slow_roll_change_per_clearance"] == {}
    assert not startup_check(StartupContext(_ev(slow=(0.0, 0.0)), base))
    assert StartupEvidence.from_dict(_ev().to_dict()) == _ev()


def test_the_slow_roll_position_is_the_slowest_steps_mean_gap():
    """A run whose every centreline point is moved by a constant (a train's offset) keeps its rise and half-rise
    speed, and its slow-roll position moves by that constant."""
    rec, _, _ = _synthetic(rpm0=900.0, rpm1=2100.0, dur_s=20.0)
    tr = T.track_orders(rec)
    cl = T.centreline(rec, tr)
    ev = startup_evidence(tr, cl)
    moved = replace(cl, x_um=cl.x_um + 30.0, y_um=cl.y_um - 40.0)
    ev2 = startup_evidence(tr, moved)
    for b in ev.slow_roll_um:
        assert np.allclose(np.subtract(ev2.slow_roll_um[b], ev.slow_roll_um[b]), (30.0, -40.0))
        assert ev2.half_rise_rpm[b] == ev.half_rise_rpm[b]
        assert np.allclose(ev2.top_um[b], ev.top_um[b])
