"""Change against an asset baseline (issue 17): the features' change computation and the models' rule."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rotordiag.features import (
    ProbeChannel,
    Recording,
    average_signatures,
    change_features,
    extract_features,
    signature,
)
from rotordiag.models.change import ChangeRule, assess_change, compare, fit_thresholds, load_baseline_file, shipped_rule

FS_HZ = 2048.0
SPEED_RPM = 1800.0


def _recording(vec1=(20.0, 30.0), vec2=(4.0, 60.0), dc=(0.0, -100.0), speed_rpm=SPEED_RPM, noise_um=0.05, seed=0,
               bearings=(2, 3), keyphasor=True):
    """Probe pairs (45°, 135°) whose x and y carry a 1X and a 2X of (µm pk-pk, phase lag deg), plus a DC position."""
    rng = np.random.default_rng(seed)
    n = int(40 * 60.0 / speed_rpm * FS_HZ)
    t = np.arange(n) / FS_HZ
    th = 2 * math.pi * speed_rpm / 60.0 * t
    x = dc[0] + vec1[0] / 2 * np.cos(th - math.radians(vec1[1])) + vec2[0] / 2 * np.cos(2 * th - math.radians(vec2[1]))
    y = dc[1] + vec1[0] / 2 * np.cos(th - math.radians(vec1[1] + 90)) \
        + vec2[0] / 2 * np.cos(2 * th - math.radians(vec2[1] + 45))
    chans = []
    for b in bearings:
        for a in (45.0, 135.0):
            r = math.radians(a)
            chans.append(ProbeChannel(bearing=b, angle_deg=a, units="um",
                                      data=x * math.cos(r) + y * math.sin(r) + noise_um * rng.standard_normal(n)))
    period = 60.0 / speed_rpm
    kp = np.arange(0.0, t[-1], period) if keyphasor else None
    return Recording(sample_rate_hz=FS_HZ, channels=chans, keyphasor_times_s=kp, clearance_um=200.0,
                     speed_rpm=None if keyphasor else speed_rpm)


def _sig(**kw):
    return json.loads(json.dumps(signature(extract_features(_recording(**kw)))))   # as stored (JSON round trip)


def test_signature_holds_vectors_centreline_and_orbit():
    s = _sig()
    assert s["phase_reference"] == "keyphasor" and s["speed_rpm"] == pytest.approx(SPEED_RPM, rel=1e-3)
    b2 = next(e for e in s["bearings"] if e["bearing"] == 2)
    assert b2["vectors"]["x_1x"]["amp_um_pp"] == pytest.approx(20.0, rel=0.02)
    assert b2["vectors"]["x_1x"]["phase_deg"] == pytest.approx(30.0, abs=2.0)
    assert b2["mean_y_um"] == pytest.approx(-100.0, abs=0.5)
    assert b2["clearance_um"] == 200.0 and b2["orbit"]["ratio_2x_1x"] is not None


def test_same_state_gives_small_changes_and_a_redraw_of_noise_too():
    res = change_features(_sig(seed=0), _sig(seed=1))
    assert res.comparable
    assert res.largest("1x_change_um_pp")[0] < 0.5
    assert res.largest("dc_shift_um")[0] < 0.5


def test_a_180_degree_phase_change_at_equal_amplitude_is_a_change():
    """Vectors, not magnitudes: the 1X amplitude is the same, its phase turned by 180° -> change = 2 A."""
    res = change_features(_sig(), _sig(vec1=(20.0, 210.0), seed=3))
    assert abs(res.values["b2_x_1x_damp_um_pp"]) < 0.5            # the magnitudes agree
    assert res.values["b2_x_1x_dvec_um_pp"] == pytest.approx(40.0, rel=0.03)
    assert res.largest("1x_change_um_pp")[0] == pytest.approx(40.0, rel=0.03)
    assert res.values["b2_1x_change_pp_per_c"] == pytest.approx(0.2, rel=0.03)
    rule = ChangeRule({"1x_change_um_pp": 5.0, "1x_change_pp_per_c": 0.01})
    v = assess_change(res, rule)
    assert v["changed"] and v["exceeded"] == ["1x_change"]


def test_centreline_shift_per_bearing_in_um_and_clearance():
    res = change_features(_sig(), _sig(dc=(30.0, -60.0), seed=4))
    assert res.values["b3_dc_dx_um"] == pytest.approx(30.0, abs=0.5)
    assert res.values["b3_dc_dy_um"] == pytest.approx(40.0, abs=0.5)
    assert res.values["b3_dc_shift_um"] == pytest.approx(50.0, abs=0.5)
    assert res.values["b3_dc_shift_per_c"] == pytest.approx(0.25, abs=0.005)


def test_a_recording_without_a_dc_position_has_no_centreline_shift():
    """Channels whose means were removed (``dc_removed``) give no centreline to compare: the shift against a DC
    baseline is missing, not the baseline's distance from the bearing centre; the vectors still compare."""
    ac = _recording(seed=4)
    ac = Recording(sample_rate_hz=ac.sample_rate_hz, channels=ac.channels, keyphasor_times_s=ac.keyphasor_times_s,
                   clearance_um=200.0, dc_removed=True)
    sig = json.loads(json.dumps(signature(extract_features(ac))))
    res = change_features(_sig(), sig)
    assert math.isnan(res.values["b3_dc_shift_um"]) and math.isnan(res.values["b3_dc_shift_per_c"])
    assert res.values["b3_1x_change_um_pp"] < 1.0


def test_a_phase_in_the_noise_leaves_the_vector_change_missing():
    """2X far below the noise in the baseline: its phase is missing, so is the vector change; the amplitude
    change (a lower bound) carries the per-bearing 2X change."""
    base = _sig(vec2=(0.0, 0.0), noise_um=0.5)
    now = _sig(vec2=(12.0, 60.0), noise_um=0.5, seed=5)
    assert next(e for e in base["bearings"] if e["bearing"] == 2)["vectors"]["x_2x"]["phase_deg"] is None
    res = change_features(base, now)
    assert math.isnan(res.values["b2_x_2x_dvec_um_pp"])
    assert res.largest("2x_change_um_pp")[0] == pytest.approx(12.0, rel=0.1)
    assert any("phase in the noise" in n for n in res.notes)


def test_no_keyphasor_means_no_vector_changes():
    res = change_features(_sig(keyphasor=False), _sig(keyphasor=False, vec1=(20.0, 210.0), seed=6))
    assert math.isnan(res.values["b2_x_1x_dvec_um_pp"])
    assert res.largest("1x_change_um_pp")[0] < 1.0               # only amplitudes: the phase turn is not seen
    assert any("keyphasor" in n for n in res.notes)


def test_a_different_speed_band_is_not_compared():
    base = _sig()
    res = change_features(base, _sig(speed_rpm=SPEED_RPM * 1.08, seed=7))
    assert not res.comparable and not res.values
    assert "+8.0 %" in res.notes[0]
    section = compare(_sig(speed_rpm=SPEED_RPM * 1.08, seed=7),
                      {"signature": base, "set_at": "2026-01-01T00:00:00Z", "speed_rpm": SPEED_RPM}, shipped_rule())
    assert not section["used"] and section["changed"] is None and "not compared" in section["message"]
    assert change_features(base, _sig(speed_rpm=SPEED_RPM * 1.04, seed=7)).comparable


def test_average_of_signatures_averages_vectors():
    a, b = _sig(vec1=(20.0, 20.0)), _sig(vec1=(20.0, 40.0), seed=8)
    avg = average_signatures([a, b])
    v = next(e for e in avg["bearings"] if e["bearing"] == 2)["vectors"]["x_1x"]
    assert v["phase_deg"] == pytest.approx(30.0, abs=1.5)
    assert v["amp_um_pp"] == pytest.approx(20.0 * math.cos(math.radians(10.0)), rel=0.02)
    with pytest.raises(ValueError):
        average_signatures([])


def test_thresholds_are_fitted_from_unchanged_rerecordings_and_alarm_on_a_shift():
    base = _sig()
    unchanged = [change_features(base, _sig(seed=10 + i)) for i in range(8)]
    rule = fit_thresholds(unchanged)
    assert rule.thresholds["dc_shift_um"] is not None and rule.thresholds["dc_shift_um"] < 1.0
    assert not any(assess_change(r, rule)["changed"] for r in unchanged[:1])
    shifted = change_features(base, _sig(dc=(0.0, -90.0), seed=30))
    v = assess_change(shifted, rule)
    assert v["changed"] and "dc_shift" in v["exceeded"] and v["quantities"]["dc_shift"]["bearing"] in (2, 3)
    edited = rule.with_overrides({"dc_shift_um": 50.0})
    assert "dc_shift" not in assess_change(shifted, edited)["exceeded"]
    with pytest.raises(ValueError, match="unknown change quantities"):
        rule.with_overrides({"nonsense": 1.0})


def test_shipped_thresholds_are_positive_and_cover_every_quantity():
    from rotordiag.models.change import QUANTITIES

    rule = shipped_rule()
    for um_name, c_name in QUANTITIES.values():
        assert rule.thresholds[um_name] is not None and rule.thresholds[um_name] > 0
        if c_name:
            assert c_name in rule.thresholds


def test_compare_without_baseline_and_baseline_file(tmp_path):
    s = _sig()
    none = compare(s, None, shipped_rule())
    assert not none["used"] and "no baseline" in none["message"]
    path = tmp_path / "b.json"
    path.write_text(json.dumps({"asset_id": "a", "baseline": {"signature": s, "set_at": "x", "speed_rpm": 1800.0},
                                "edited_thresholds": {"dc_shift_um": 3.0}}))
    base, rule = load_baseline_file(path)
    assert base["signature"] == s and rule.thresholds["dc_shift_um"] == 3.0
    path.write_text(json.dumps({"asset_id": "a", "baseline": None}))
    with pytest.raises(ValueError, match="no baseline"):
        load_baseline_file(path)


def test_repeatability_thresholds_are_the_assets_own_and_catch_what_the_shipped_ones_miss():
    """A small machine (1X 2 µm): three re-recordings of it set its own 1X/2X/centreline thresholds far below
    the shipped ones (tuned on a family of big machines); a 1.5 µm journal shift — under the shipped 6 µm and
    0.0135 c — is then a change, while a fourth re-recording of the unchanged machine is not."""
    from rotordiag.models.change import REPEAT_FLOOR, REPEAT_MARGIN, repeatability_thresholds

    small = dict(vec1=(2.0, 30.0), vec2=(0.4, 60.0), noise_um=0.02)
    base_sigs = [_sig(**small, seed=40 + i) for i in range(3)]
    rep = repeatability_thresholds(base_sigs)
    assert rep is not None and rep["n_recordings"] == 3 and rep["margin"] == REPEAT_MARGIN
    th = rep["thresholds"]
    for name in ("1x_change_um_pp", "2x_change_um_pp", "dc_shift_um"):
        assert th[name] >= REPEAT_FLOOR[name]
        assert th[name] == pytest.approx(max(REPEAT_MARGIN * rep["spread"][name], REPEAT_FLOOR[name]))
        assert th[name] < shipped_rule().thresholds[name]
    assert th["dc_shift_per_c"] is None and th["1x_change_pp_per_c"] is None
    own = shipped_rule().with_repeatability(rep)
    assert own.thresholds["orbit_2x_1x_change"] == shipped_rule().thresholds["orbit_2x_1x_change"]
    base = average_signatures(base_sigs)
    shifted = change_features(base, _sig(**small, dc=(0.0, -101.5), seed=50))
    assert not assess_change(shifted, shipped_rule())["changed"]
    v = assess_change(shifted, own)
    assert v["changed"] and v["exceeded"] == ["dc_shift"]
    again = change_features(base, _sig(**small, seed=51))
    assert not assess_change(again, own)["changed"]
    # the leave-one-out spread is what the recordings differ by: a noisier machine gets looser thresholds
    noisy = repeatability_thresholds([_sig(**{**small, "noise_um": 0.6}, seed=60 + i) for i in range(3)])
    assert noisy is not None and noisy["spread"]["1x_change_um_pp"] > rep["spread"]["1x_change_um_pp"]


def test_repeatability_needs_three_comparable_recordings():
    from rotordiag.models.change import repeatability_thresholds

    assert repeatability_thresholds([_sig(seed=1), _sig(seed=2)]) is None
    assert repeatability_thresholds([_sig(seed=1), _sig(seed=2), _sig(seed=3, speed_rpm=2100.0)]) is None
    # an automatic baseline's recordings lie within ±5 % of their median: 9 % apart from each other is fine
    spread = [_sig(seed=4, speed_rpm=SPEED_RPM * 0.955), _sig(seed=5), _sig(seed=6, speed_rpm=SPEED_RPM * 1.045)]
    assert repeatability_thresholds(spread) is not None
    rule = shipped_rule()
    assert rule.with_repeatability(None) is rule
    with pytest.raises(ValueError, match="unknown change quantity"):
        rule.with_repeatability({"thresholds": {"nonsense": 1.0}})


def test_a_baseline_file_carries_its_repeatability_thresholds(tmp_path):
    from rotordiag.models.change import repeatability_thresholds

    sigs = [_sig(seed=70 + i) for i in range(3)]
    rep = repeatability_thresholds(sigs)
    path = tmp_path / "b.json"
    path.write_text(json.dumps({"asset_id": "a", "baseline": {"signature": average_signatures(sigs),
                                                               "repeatability": rep}, "edited_thresholds": {}}))
    _, rule = load_baseline_file(path)
    assert rule.thresholds["dc_shift_um"] == pytest.approx(rep["thresholds"]["dc_shift_um"])
    section = compare(sigs[0], {"signature": average_signatures(sigs), "set_at": "x", "repeatability": rep}, rule)
    assert section["thresholds_basis"]["basis"] == "own"
    assert [n.code for n in section["notes"] if getattr(n, "code", "").startswith("change_thresholds")] == \
        ["change_thresholds_own"]


def test_three_identical_recordings_give_the_floors_not_zero_thresholds():
    """No spread at all (the same recording three times) leaves each threshold at its floor, a probe system's
    resolution: a zero threshold would alarm on any re-recording."""
    from rotordiag.models.change import REPEAT_FLOOR, repeatability_thresholds

    s = _sig(seed=90)
    rep = repeatability_thresholds([s, s, s])
    assert rep is not None and all(v < 1e-9 for v in rep["spread"].values())
    assert {k: v for k, v in rep["thresholds"].items() if v is not None} == REPEAT_FLOOR


def test_thresholds_basis_says_own_or_fleet_and_why():
    """Own thresholds need 3 recordings at one operating condition with something measured; otherwise the fleet-wide
    ones, with the reason as a code and a typed warning — and the comparison then uses the shipped thresholds."""
    from rotordiag.models.change import REPEAT_MIN, basis_note, repeatability_thresholds, thresholds_basis

    sigs = [_sig(seed=80 + i) for i in range(3)]
    rep = repeatability_thresholds(sigs)
    assert thresholds_basis({"diagnosis_ids": [1, 2, 3], "repeatability": rep}) == {
        "basis": "own", "reason": "own_repeatability", "n_recordings": 3, "needed": REPEAT_MIN, "margin": 4.0}
    one = thresholds_basis({"diagnosis_ids": [7], "repeatability": None})
    assert (one["basis"], one["reason"], one["n_recordings"]) == ("fleet", "too_few_recordings", 1)
    note = basis_note(one)
    assert note.code == "change_thresholds_fleet" and note.severity == "caution"
    assert "baseline has 1 recording, its own repeatability needs 3" in note
    far = thresholds_basis({"diagnosis_ids": [1, 2, 3], "repeatability": None})
    assert far["reason"] == "recordings_not_comparable" and "not at one operating condition" in basis_note(far)
    blind = thresholds_basis({"n_recordings": 4, "repeatability": {"thresholds": {}, "n_recordings": 4}})
    assert blind["reason"] == "nothing_measured" and blind["n_recordings"] == 4
    # a one-recording baseline's comparison: the shipped thresholds, and the answer's last note says so
    section = compare(sigs[0], {"signature": sigs[1], "set_at": "x", "diagnosis_ids": [5]}, shipped_rule())
    assert section["thresholds_basis"]["reason"] == "too_few_recordings"
    assert section["notes"][-1].code == "change_thresholds_fleet"
    assert section["quantities"]["dc_shift"]["threshold"] == shipped_rule().thresholds["dc_shift_um"]
    assert compare(sigs[0], None, shipped_rule())["thresholds_basis"] is None
