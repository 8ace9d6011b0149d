"""The robustness conditions applied to stored (train) recordings: what each sends to the verdict."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rotordiag.models import robustness, robustness_trains
from rotordiag.models.robustness import CONDITIONS, Outcome

FS_HZ, SPEED_RPM, CLEARANCE_UM = 2560.0, 3000.0, 250.0


def _sample(bearings=(1, 2, 3, 4)) -> dict:
    """One stored recording: a 1X and a 2X per channel plus a DC per channel (distinct, so a channel mix-up shows)."""
    t = np.arange(4096) / FS_HZ
    f = SPEED_RPM / 60.0
    w = np.array([10.0 * k + 20.0 * np.cos(2 * np.pi * f * t + k) + 3.0 * np.cos(4 * np.pi * f * t + 2 * k)
                  for k in range(2 * len(bearings))])
    return {"waveforms_um": w, "bearings": bearings, "fs_hz": FS_HZ, "speed_rpm": SPEED_RPM,
            "clearance_um": CLEARANCE_UM, "delta": 0.2, "mechanism": "rigid", "family": "gen600_2pole",
            "offset_angle_rad": 0.5}


def _sent(monkeypatch, name: str, sample: dict | None = None) -> dict:
    """What condition ``name`` sends to the verdict for one stored recording."""
    seen: dict = {}

    def sent(bundle, w, bearings, fs, speed, clearance, o, **kw):
        seen.update(w=w.copy(), bearings=bearings, fs=fs, speed=speed, clearance=clearance, told=kw, outcome=o)
        return o

    monkeypatch.setattr(robustness_trains, "diagnose_waveforms", sent)
    cond = next(c for c in CONDITIONS if c.name == name)
    outs = robustness_trains.run_condition_on_recordings(None, cond, [sample or _sample()], 815)
    assert outs == [seen["outcome"]]
    return seen


def test_the_conditions_on_recordings_are_those_that_act_on_a_recording_as_measured():
    names = [c.name for c in robustness_trains.train_conditions()]
    assert names[0] == "clean" and {"gain mismatch ±10 %", "coupling journals apart", "bearings 2 and 3 swapped",
                                    "mains pickup at 2X, 10 µm, a phase per cable", "clearance unknown"} <= set(names)
    for left_out in ("runout", "SNR 15 dB", "rated-machine presets", "far plants (÷2…×2)", "192 revolutions",
                     "keyphasor, every 5th pulse missing", "bearings 3–4 in a second take, a keyphasor per take"):
        assert left_out not in names
        cond = next(c for c in CONDITIONS if c.name == left_out)
        with pytest.raises(ValueError, match="simulated sets only"):
            robustness_trains.run_condition_on_recordings(None, cond, [_sample()], 815)


def test_clean_sends_the_recording_as_stored_with_speed_and_clearance(monkeypatch):
    s = _sample()
    seen = _sent(monkeypatch, "clean", s)
    np.testing.assert_array_equal(seen["w"], s["waveforms_um"])
    assert seen["bearings"] == (1, 2, 3, 4) and seen["fs"] == FS_HZ
    assert seen["speed"] == SPEED_RPM and seen["clearance"] == CLEARANCE_UM and seen["told"] == {}
    o: Outcome = seen["outcome"]
    assert (o.delta, o.mechanism, o.machine) == (0.2, "rigid", "gen600_2pole") and o.true_angle_rad == 0.5


def test_what_the_user_withholds_or_states_wrong(monkeypatch):
    assert _sent(monkeypatch, "clearance unknown")["clearance"] is None
    assert _sent(monkeypatch, "speed unknown")["speed"] is None
    assert _sent(monkeypatch, "speed stated 0.4 % off")["speed"] == pytest.approx(SPEED_RPM * 1.004)
    told = _sent(monkeypatch, "speed unknown, nominal range ±5 % stated")["told"]
    lo, hi = told["speed_range_rpm"]
    assert lo < SPEED_RPM < hi and hi / lo == pytest.approx(1.05 / 0.95)
    assert _sent(monkeypatch, "bearings 3–4 in a second take, stated")["told"] == {"acquisitions": "1,2;3,4"}


def test_probes_sent_numbering_and_gains(monkeypatch):
    s = _sample()
    only = _sent(monkeypatch, "coupling bearings only", s)
    assert only["bearings"] == (2, 3)
    np.testing.assert_array_equal(only["w"], s["waveforms_um"][2:6])
    assert _sent(monkeypatch, "bearings 2 and 3 swapped", s)["bearings"] == (1, 3, 2, 4)
    assert _sent(monkeypatch, "bearings numbered 4-3-2-1", s)["bearings"] == (4, 3, 2, 1)
    g = _sent(monkeypatch, "gain mismatch ±10 %", s)["w"] / s["waveforms_um"]
    per_channel = g[:, 0]
    np.testing.assert_allclose(g, per_channel[:, None] * np.ones_like(g), rtol=1e-12)
    assert np.all(np.abs(per_channel - 1.0) <= 0.1) and np.ptp(per_channel) > 0.0
    # a train with three bearings (its exciter overhung): the probes it has
    three = _sample(bearings=(1, 2, 3))
    assert _sent(monkeypatch, "clean", three)["bearings"] == (1, 2, 3)
    assert _sent(monkeypatch, "coupling bearings only", three)["bearings"] == (2, 3)


def test_faults_act_on_the_stored_waveforms_as_on_the_simulated_ones(monkeypatch):
    s = _sample()
    w0 = s["waveforms_um"]
    apart = _sent(monkeypatch, "coupling journals apart", s)["w"] - w0
    np.testing.assert_allclose(apart[[0, 1, 2, 3, 6, 7]], 0.0)
    d45, d135 = apart[4].mean(), apart[5].mean()
    np.testing.assert_allclose(apart[4:6], np.array([[d45], [d135]]) * np.ones((2, w0.shape[1])), atol=1e-9)
    assert 0.1 * CLEARANCE_UM - 1e-6 <= math.hypot(d45, d135) <= 0.3 * CLEARANCE_UM + 1e-6
    inverted = _sent(monkeypatch, "bearing 2's x probe inverted", s)["w"]
    np.testing.assert_array_equal(inverted[2], -w0[2])
    np.testing.assert_array_equal(np.delete(inverted, 2, axis=0), np.delete(w0, 2, axis=0))
    pickup = _sent(monkeypatch, "mains pickup at 2X, 10 µm, a phase per cable", s)["w"] - w0
    t = np.arange(w0.shape[1]) / FS_HZ
    basis = np.stack([np.cos(4 * np.pi * SPEED_RPM / 60.0 * t), np.sin(4 * np.pi * SPEED_RPM / 60.0 * t)], axis=1)
    coef = np.linalg.lstsq(basis, pickup.T, rcond=None)[0]
    np.testing.assert_allclose(np.hypot(*coef), 10.0, rtol=1e-3)       # 10 µm 0-pk on every channel …
    assert np.unique(np.round(np.arctan2(-coef[1], coef[0]), 3)).size == w0.shape[0]     # … each its own phase
    late = _sent(monkeypatch, "bearings 3–4 in a second take, not stated", s)["w"]
    k = w0.shape[1] - late.shape[1]
    assert 0.002 * FS_HZ - 1 <= k <= 0.020 * FS_HZ + 1
    np.testing.assert_array_equal(late[:4], w0[:4, :-k])
    np.testing.assert_array_equal(late[4:], w0[4:, k:])


def test_the_base_sets_rows_send_what_they_did_before_the_faults_moved_to_one_function(monkeypatch):
    """run_condition draws the faults through ``apply_faults`` now: the per-cable pickup's draws are those of the
    clean recording's measurement followed by one phase per channel, as before (same seed, same condition)."""
    seen: dict = {}

    def sent(bundle, w, bearings, fs, speed, clearance, o, **kw):
        seen[len(seen)] = w.copy()
        return o

    monkeypatch.setattr(robustness, "diagnose_waveforms", sent)
    case = {"speed_rpm": 1800.0, "plant": {"clearance_m": 3e-4}, "misalignment": 0.0, "label_mechanism": "aligned"}
    rev = 2 * np.pi / robustness.SAMPLES_PER_REV * np.arange(60 * robustness.SAMPLES_PER_REV)
    disp = np.zeros((rev.size, 4, 2))                     # a 10 µm forward 1X orbit at every bearing
    disp[:, :, 0] = 10e-6 * np.cos(rev)[:, None]
    disp[:, :, 1] = 10e-6 * np.sin(rev)[:, None]
    cond = next(c for c in CONDITIONS if c.name == "mains pickup at 2X, 10 µm, a phase per cable")
    robustness.run_condition(None, cond, [case], [disp], 815)
    rng = robustness.measurement_rng(cond, 815, 0)
    w = robustness.measure(disp, 1800.0, cond, rng)
    phase = rng.uniform(0.0, 2.0 * np.pi, size=(w.shape[0], 1))
    t_s = np.arange(w.shape[1]) / robustness.FS_HZ
    np.testing.assert_allclose(seen[0], w + 10.0 * np.cos(2.0 * np.pi * 2 * 1800.0 / 60.0 * t_s + phase), atol=1e-9)
