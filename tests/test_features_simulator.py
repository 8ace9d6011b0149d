"""Features of the simulator's own output, checked against a plain FFT of the same record.

The simulator records an integer number of samples per revolution starting at τ = Ωt ≡ 0,
so the kX line of each journal displacement is exactly FFT bin k·n_revs — an answer that
does not use the features code.
"""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag import simulator
from rotordiag.features import ProbeChannel, Recording, extract_features

SPEED_RPM = 1950.0
REVS, SPR = 64, 128


@pytest.fixture(scope="module")
def sim():
    res = simulator.simulate(simulator.Plant.default(), SPEED_RPM, 0.1, 0.05, mechanism="rigid",
                             transient_revs=400, record_revs=REVS, samples_per_rev=SPR)
    assert res.status == "ok"
    return res


def _recording(res, **kw):
    d_um = res.journal_displacements_m * 1e6            # (n, 4, 2)
    chans = []
    for b in range(4):
        for a in (45.0, 135.0):
            r = np.deg2rad(a)
            chans.append(ProbeChannel(b + 1, a, "um", d_um[:, b, 0] * np.cos(r) + d_um[:, b, 1] * np.sin(r)))
    fs = SPR * SPEED_RPM / 60
    return Recording(sample_rate_hz=fs, channels=chans, clearance_um=350.0, **kw)


def test_orders_match_fft_of_simulated_journals(sim):
    fr = extract_features(_recording(sim, speed_rpm=SPEED_RPM))
    d_um = sim.journal_displacements_m * 1e6
    n = d_um.shape[0]
    spec = np.fft.rfft(d_um, axis=0) * 2 / n           # zero-to-peak complex lines
    for b in range(4):
        for j, d in enumerate("xy"):
            for k in (1, 2, 3):
                line = spec[k * REVS, b, j]
                got = fr[f"b{b + 1}_{d}_{k}x_amp_um_pp"]
                assert got == pytest.approx(2 * abs(line), rel=1e-6, abs=1e-6), (b, d, k)
                if abs(line) > 0.1:
                    ph = np.degrees(-np.angle(line)) % 360
                    assert abs((fr[f"b{b + 1}_{d}_{k}x_phase_deg"] - ph + 180) % 360 - 180) < 1e-4
        # forward / reverse 1X from the full spectrum of x + jy
        z = np.fft.fft(d_um[:, b, 0] + 1j * d_um[:, b, 1]) / n
        assert fr[f"b{b + 1}_1x_fwd_um_pp"] == pytest.approx(2 * abs(z[REVS]), rel=1e-6, abs=1e-6)
        assert fr[f"b{b + 1}_1x_rev_um_pp"] == pytest.approx(2 * abs(z[-REVS]), rel=1e-6, abs=1e-6)
    assert fr["motion_period"] == 1.0
    assert fr["b2_x_1x_amp_pp_per_c"] == pytest.approx(fr["b2_x_1x_amp_um_pp"] / 350.0)


def test_speed_estimated_from_simulated_signal(sim):
    fr = extract_features(_recording(sim))
    assert fr.speed_source == "estimated"
    assert fr.speed_rpm == pytest.approx(SPEED_RPM, rel=1e-6)
    ref = extract_features(_recording(sim, speed_rpm=SPEED_RPM))
    assert fr["b3_x_2x_1x_ratio"] == pytest.approx(ref["b3_x_2x_1x_ratio"], rel=1e-4)


@pytest.mark.slow
def test_poincare_points_and_motion_match_simulator_oil_whip():
    """Oil whip at 2500 r/min (MODEL.md §6): non-periodic. The features' once-per-revolution
    points, rebuilt from the sampled waveforms, equal the simulator's own Poincaré section, and
    the motion type equals the classifier's verdict on that section."""
    from rotordiag.simulator.analysis import classify_motion

    rpm, spr, revs = 2500.0, 64, 64
    res = simulator.simulate(simulator.Plant.default(), rpm, 0.02, 0.05, mechanism="pin",
                             transient_revs=400, record_revs=revs, samples_per_rev=spr)
    assert res.status == "ok"
    d_um = res.journal_displacements_m * 1e6
    chans = [ProbeChannel(b + 1, a, "um", d_um[:, b, 0] * np.cos(np.deg2rad(a)) + d_um[:, b, 1] * np.sin(np.deg2rad(a)))
             for b in range(4) for a in (45.0, 135.0)]
    fr = extract_features(Recording(sample_rate_hz=spr * rpm / 60, channels=chans, speed_rpm=rpm))
    section_um = res.poincare_m[:, [0, 2, 3, 5], :] * 1e6            # journals = bearings 1-4
    for b in range(4):
        np.testing.assert_allclose(fr.bearings[b + 1].poincare_um, section_um[:, b, :], atol=1e-7)
    expected = classify_motion(res.poincare_m)
    assert expected.kind != "period-n"
    assert fr.motion_type.kind == expected.kind
    assert fr["motion_period"] == 0.0
    assert max(fr[f"b{b}_subsync_frac"] for b in (1, 2, 3, 4)) > 0.1   # whip shows up sub-synchronously
    assert 0.3 < fr["b2_subsync_peak_order"] < 0.6
