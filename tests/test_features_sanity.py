"""Physics sanity checks (issue 15, item 1) and the phase noise gate (item 3), on simulated recordings.

Each broken recording is a clean simulation of the default plant with one realistic mistake
made to it (units, a dead or clipped probe, probes swapped, no signal at all); the clean
recording itself must pass every check.
"""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording, check_recording, evidence, extract_features, with_sanity
from tests.service_util import simulated_channels

CLEARANCE_UM = 350.0


def _rec(channels, fs, units="um", clearance_um=CLEARANCE_UM, **kw):
    return Recording(sample_rate_hz=fs, channels=[ProbeChannel(b, a, units, np.asarray(d, float))
                                                  for b, a, d in channels],
                     speed_rpm=kw.pop("speed_rpm", 1800.0), clearance_um=clearance_um, **kw)


@pytest.fixture(scope="module")
def sim():
    return simulated_channels(misalignment=0.2)


def _codes(fr):
    return {(f.code, f.level) for f in fr.sanity}


@pytest.mark.parametrize("delta", [0.0, 0.2])
def test_clean_simulated_recordings_pass(delta):
    fs, ch = simulated_channels(misalignment=delta)
    fr = extract_features(_rec(ch, fs))
    assert fr.sanity == ()
    # without a stated clearance as well
    assert extract_features(_rec(ch, fs, clearance_um=None)).sanity == ()


def test_micrometres_declared_as_mils_exceed_the_clearance(sim):
    fs, ch = sim
    fr = extract_features(_rec(ch, fs, units="mil"))
    fails = [f for f in fr.sanity if f.code == "orbit_exceeds_clearance"]
    assert fails and all(f.level == "fail" for f in fails)
    assert fails[0].values["units"] == "mil" and fails[0].values["ratio"] > 1.0     # the declared units, named


def test_micrometres_declared_as_mm_exceed_probe_range_and_gap(sim):
    fs, ch = sim
    codes = _codes(extract_features(_rec(ch, fs, units="mm", clearance_um=None)))
    assert ("orbit_exceeds_probe_range", "fail") in codes
    assert ("dc_implausible", "fail") in codes


def test_zero_and_flat_channels(sim):
    fs, ch = sim
    zero = [(b, a, np.zeros_like(d) if (b, a) == (2, 45.0) else d) for b, a, d in ch]
    flat = [(b, a, np.full_like(d, 1234.5) if (b, a) == (3, 135.0) else d) for b, a, d in ch]
    fz = [f for f in extract_features(_rec(zero, fs)).sanity if f.level == "fail"]
    ff = [f for f in extract_features(_rec(flat, fs)).sanity if f.level == "fail"]
    assert [(f.code, f.bearing) for f in fz] == [("zero_channel", 2)]
    assert [(f.code, f.bearing) for f in ff] == [("flat_channel", 3)]


def test_clipped_channel_but_not_a_quantised_one(sim):
    fs, ch = sim
    b, a, d = ch[4]                                       # bearing 3, 45°
    top = d.min() + 0.7 * np.ptp(d)
    clipped = [(bb, aa, np.minimum(dd, top) if (bb, aa) == (b, a) else dd) for bb, aa, dd in ch]
    found = [f for f in extract_features(_rec(clipped, fs)).sanity if f.code == "clipped_channel"]
    assert [(f.bearing, f.level) for f in found] == [(b, "fail")]
    # a 16-bit-like acquisition (0.25 µm steps) repeats its extreme values but is not clipped
    quantised = [(bb, aa, np.round(dd / 0.25) * 0.25) for bb, aa, dd in ch]
    assert extract_features(_rec(quantised, fs)).sanity == ()


@pytest.mark.parametrize("level", ["max", "min"])
def test_a_dropout_is_not_called_clipping(sim, level):
    """One channel holding one value beyond its swing for 60 ms in one stretch (a loose connector): `dropout`,
    with where and how long, and not `clipped_channel`; clipping recurs every revolution and stays clipping."""
    fs, ch = sim
    b, a, d = ch[2]                                       # bearing 2, 45°
    held = d.max() + 5.0 if level == "max" else d.min() - 5.0
    start, n = len(d) // 3, int(round(0.06 * fs))
    dropped = [(bb, aa, np.concatenate([dd[:start], np.full(n, held), dd[start + n:]]) if (bb, aa) == (b, a) else dd)
               for bb, aa, dd in ch]
    found = [f for f in extract_features(_rec(dropped, fs)).sanity if f.level == "fail"]
    assert [(f.code, f.bearing) for f in found] == [("dropout", b)]
    v = found[0].values
    assert v["duration_ms"] == pytest.approx(60.0, abs=1.0) and v["start_s"] == pytest.approx(start / fs, abs=1e-3)
    assert v["bearing"] == b and v["angle_deg"] == a and v["level"].value_um == pytest.approx(held)


@pytest.mark.parametrize("fs_factor, speed_rpm, reads, rate", [(1.25, 1800.0, 2250.0, 2048.0),
                                                              (0.8, 1800.0, 1440.0, 2048.0),
                                                              (1.0, 3000.0, 1800.0, 3413.33)])
def test_no_1x_at_the_given_speed_names_the_signals_speed_and_the_rate_that_fits(fs_factor, speed_rpm, reads, rate):
    """A sample rate stated 1.25× or 0.8× the true one (2048 Hz), or a 1800 r/min machine stated at 3000 r/min: no 1X at
    the given speed; the message names the running speed the signal shows and the sample rate that would put it at the
    given speed — and, where a line below 1X dominates, still names oil whirl as the other explanation."""
    fs, ch = simulated_channels(misalignment=0.2, record_revs=48)
    assert fs == 2048.0
    fr = extract_features(_rec(ch, fs * fs_factor, speed_rpm=speed_rpm))
    f = next(f for f in fr.sanity if f.code == "no_sync_signal" and f.level == "fail")
    assert f.values["signal_rpm"] == pytest.approx(reads, abs=0.5)
    assert f.values["fitting_rate_hz"] == pytest.approx(rate, abs=0.01)
    assert f.values["sample_rate_hz"] == fs * fs_factor and f.values["given_rpm"] == speed_rpm
    assert f.variant == ("whirl_speed" if fs_factor * 1800.0 / speed_rpm < 0.95 else "every_bearing_speed")
    # at the right rate and speed: no such finding
    assert "no_sync_signal" not in {f.code for f in extract_features(_rec(ch, fs, speed_rpm=1800.0)).sanity}


def test_swapped_probe_order_gives_reverse_whirl_everywhere(sim):
    fs, ch = sim
    # the probe at 135° recorded as the one at 45° and vice versa: the orbit is mirrored
    swapped = [(b, 180.0 - a, d) for b, a, d in ch]
    fr = extract_features(_rec(swapped, fs))
    assert ("reverse_whirl_all", "fail") in _codes(fr)
    f = next(f for f in fr.sanity if f.code == "reverse_whirl_all")
    assert f.values == {"bearings": "1, 2, 3, 4"}


def test_noise_only_recording_has_no_sync_signal(sim):
    fs, ch = sim
    rng = np.random.default_rng(3)
    noise = [(b, a, rng.normal(0.0, 2.0, d.size)) for b, a, d in ch]
    fr = extract_features(_rec(noise, fs))
    assert ("no_sync_signal", "fail") in _codes(fr)


def test_phase_is_missing_below_the_noise_floor():
    """A pure 1X orbit plus white noise: 1X phase measured (to its LS error), 2X/3X phase NaN."""
    fs, rpm, n = 2048.0, 1800.0, 2048 * 8
    t = np.arange(n) / fs
    th = 2 * np.pi * rpm / 60 * t
    rng = np.random.default_rng(0)
    chans = []
    for b in (2, 3):
        x = 40 * np.cos(th - 0.3) + rng.normal(0, 1.0, n)
        y = 30 * np.sin(th - 0.3) + rng.normal(0, 1.0, n)
        for a in (45.0, 135.0):
            r = np.deg2rad(a)
            chans.append((b, a, x * np.cos(r) + y * np.sin(r)))
    fr = extract_features(_rec(chans, fs))
    for b in (2, 3):
        assert np.isfinite(fr[f"b{b}_x_1x_phase_deg"])
        assert fr[f"b{b}_x_1x_phase_deg"] == pytest.approx(np.degrees(0.3), abs=1.0)
        assert np.isnan(fr[f"b{b}_x_2x_phase_deg"]) and np.isnan(fr[f"b{b}_y_3x_phase_deg"])
        assert np.isfinite(fr[f"b{b}_x_2x_amp_um_pp"])             # the amplitude stays (near 0)
        noise = fr.bearings[b].line_noise_um
        # noise-equivalent amplitude of the LS fit: 2σ/√n per quadrature → |ΔC| rms = 2σ/√n
        assert noise[0, 1] == pytest.approx(2 * 1.0 / np.sqrt(n), rel=0.3)
    assert np.isfinite(fr["dphase_1x_b2_b3_x_deg"]) and np.isnan(fr["dphase_2x_b2_b3_x_deg"])
    items = {(e.scope, e.name): e for e in evidence(fr)}
    assert "not measurable" in items[("coupling 2–3", "2X phase difference x")].value
    assert "phase not measurable" in items[("bearing 2", "2X x")].value


def test_noise_free_simulation_keeps_its_phases(sim):
    fs, ch = sim
    fr = extract_features(_rec(ch, fs))
    for b in (1, 2, 3, 4):
        for k in (1, 2, 3):
            assert np.isfinite(fr[f"b{b}_x_{k}x_phase_deg"])


def test_check_recording_is_what_extract_features_reports(sim):
    fs, ch = sim
    rec = _rec(ch, fs, units="mil")
    fr = extract_features(rec)
    assert check_recording(rec, fr) == fr.sanity
    assert fr.sanity[0].level == "fail"                   # failures first


def test_the_sanity_stage_apart_gives_what_extract_features_reports(sim):
    """``extract_features(..., sanity=False)`` then ``with_sanity`` (the verdict pipeline's two stages) is
    ``extract_features``: the same features, the same findings (a failing recording: orbit in mil read as µm)."""
    fs, ch = sim
    rec = _rec(ch, fs, units="mil")
    whole = extract_features(rec)
    bare = extract_features(rec, sanity=False)
    assert bare.sanity == () and whole.sanity
    staged = with_sanity(rec, bare)
    assert staged.sanity == whole.sanity
    assert np.array_equal(staged.values, whole.values, equal_nan=True) and staged.names == whole.names


def test_slow_roll_vectors_are_subtracted():
    """Runout added to each probe as a known 1X/2X vector, then given as slow-roll: the orders equal
    those of the recording without runout (exact: the subtraction is linear in the fitted orders)."""
    from rotordiag import simulator

    rpm, spr, revs = 1950.0, 128, 32
    res = simulator.simulate(simulator.Plant.default(), rpm, 0.1, 0.05, mechanism="rigid",
                             transient_revs=300, record_revs=revs, samples_per_rev=spr)
    d = res.journal_displacements_m * 1e6
    f = rpm / 60.0
    fs = spr * f
    theta = 2 * np.pi * f * np.arange(d.shape[0]) / fs
    kp = np.arange(revs + 1) / f
    rng = np.random.default_rng(7)
    clean, runout, vectors = [], [], []
    for b in range(4):
        for a in (45.0, 135.0):
            r = np.deg2rad(a)
            p = d[:, b, 0] * np.cos(r) + d[:, b, 1] * np.sin(r)
            sr = {1: (rng.uniform(0, 6), rng.uniform(0, 360)), 2: (rng.uniform(0, 2), rng.uniform(0, 360))}
            ro = sum(amp / 2 * np.cos(k * theta - np.deg2rad(ph)) for k, (amp, ph) in sr.items())
            clean.append(ProbeChannel(b + 1, a, "um", p))
            runout.append(ProbeChannel(b + 1, a, "um", p + ro, slow_roll_um_pp=sr))
            vectors.append(ProbeChannel(b + 1, a, "um", p + ro))
    ref = extract_features(Recording(fs, clean, keyphasor_times_s=kp))
    comp = extract_features(Recording(fs, runout, keyphasor_times_s=kp))
    raw = extract_features(Recording(fs, vectors, keyphasor_times_s=kp))
    for b in (1, 2, 3, 4):
        np.testing.assert_allclose(comp.bearings[b].x_coeffs_um[:2], ref.bearings[b].x_coeffs_um[:2], atol=1e-6)
        np.testing.assert_allclose(comp.bearings[b].y_coeffs_um[:2], ref.bearings[b].y_coeffs_um[:2], atol=1e-6)
        assert comp[f"b{b}_2x_1x_major_ratio"] == pytest.approx(ref[f"b{b}_2x_1x_major_ratio"], rel=1e-6)
    # and the runout did change the uncompensated orders
    assert max(abs(raw.bearings[b].x_coeffs_um[1] - ref.bearings[b].x_coeffs_um[1]) for b in (1, 2, 3, 4)) > 0.05
    with pytest.raises(ValueError, match="keyphasor"):
        Recording(fs, runout)
    with pytest.raises(ValueError, match="order 3"):
        ProbeChannel(1, 45.0, "um", clean[0].data, slow_roll_um_pp={3: (1.0, 0.0)})


def _whip_recording(scale=1.0, seed=5):
    """An oil-whip orbit (0.47X, forward circle of 0.9 × 2c pk-pk) at 15 dB SNR, a 1X of 0.5 µm buried in the
    noise, at every bearing; ``scale`` multiplies the numbers (25.4: µm read as mils)."""
    fs, rpm, n = 2048.0, 1800.0, 2048 * 4
    t = np.arange(n) / fs
    rng = np.random.default_rng(seed)
    amp = 0.9 * CLEARANCE_UM
    sigma = amp / np.sqrt(2) / 10 ** (15 / 20)
    w_whip, w1 = 2 * np.pi * 0.47 * rpm / 60, 2 * np.pi * rpm / 60
    x = amp * np.cos(w_whip * t) + 0.5 * np.cos(w1 * t)
    y = amp * np.sin(w_whip * t) + 0.5 * np.sin(w1 * t)
    chans = [(b, a, scale * (x * np.cos(np.radians(a)) + y * np.sin(np.radians(a)) + rng.normal(0, sigma, n)))
             for b in (1, 2, 3, 4) for a in (45.0, 135.0)]
    return fs, chans


def test_noise_on_a_whip_orbit_near_the_clearance_is_not_an_impossible_orbit():
    """White noise at 15 dB SNR adds ≈ 2 × 4.5σ to the pk-pk of an oil-whip orbit at 0.9 × 2c, reading 1.2–1.3 × 2c:
    that is noise, not a units error (docs/robustness.md had 35 % of its SNR 15 dB recordings inconclusive for
    it). The units mistake on the same recording still fails, and the missing 1X is reported as whip."""
    from rotordiag.features._sanity import ORBIT_CLEARANCE_MARGIN

    fs, ch = _whip_recording()
    rec = _rec(ch, fs)
    x, _ = rec.xy_um(2)
    assert np.ptp(x) > ORBIT_CLEARANCE_MARGIN * 2 * CLEARANCE_UM          # the raw pk-pk is beyond the old limit
    fr = extract_features(rec)
    assert not [f for f in fr.sanity if f.code == "orbit_exceeds_clearance"]
    (f,) = [f for f in fr.sanity if f.code == "no_sync_signal"]
    assert f.level == "fail" and f.variant in ("whirl", "whirl_speed") and f.values["near"] == " near 0.47X"
    fs, ch = _whip_recording(scale=25.4)
    fails = [f for f in extract_features(_rec(ch, fs)).sanity if f.code == "orbit_exceeds_clearance"]
    assert len(fails) == 4 and fails[0].variant == "noise_allowance" and fails[0].values["noise"].value_um > 0


def test_noise_allowance_grows_with_the_record_and_the_noise():
    from rotordiag.features._sanity import noise_peak_to_peak_um

    assert noise_peak_to_peak_um((np.nan, np.nan), 1000) == 0.0
    a = noise_peak_to_peak_um((1.0, 2.0), 1000)
    assert 2 * 2 * 4.0 < a < 2 * 2 * 5.0                                   # k ≈ 4.4 for 1e-3 over 1000 samples
    assert noise_peak_to_peak_um((1.0, 2.0), 100_000) > a
    assert noise_peak_to_peak_um((2.0, 4.0), 1000) == pytest.approx(2 * a)


def test_evidence_angles_never_print_as_360_degrees():
    """A journal straight below the centre sits on the load line: attitude angle 0°, also when rounding puts it at
    −0.0009° (the ROSS machines' linear bearings printed "attitude angle 360°")."""
    from rotordiag.features._evidence import _whole_degrees

    assert [f"{_whole_degrees(a):.0f}" for a in (-0.0009, 359.6, 359.4, 0.0, 360.0, 720.2, -90.0)] == \
        ["0", "0", "359", "0", "0", "0", "270"]


def test_a_single_spike_is_a_glitch_not_a_units_mistake(sim):
    """One 5000 µm sample on one probe (a connector glitch) makes the orbit larger than the clearance: the check says spike (what to check:
    the cable, the connector) and warns; the same numbers ×25.4 everywhere remain a units mistake that fails."""
    fs, ch = sim
    spiked = [(b, a, d.copy()) for b, a, d in ch]
    spiked[2][2][777] += 5000.0
    codes = _codes(extract_features(_rec(spiked, fs)))
    assert ("spike", "warn") in codes and not any(c == "orbit_exceeds_clearance" for c, _ in codes)
    f = next(f for f in extract_features(_rec(spiked, fs)).sanity if f.code == "spike")
    assert f.bearing == 2 and f.values["bearing"] == 2 and f.values["n_samples"] == 1
    assert f.values["orbit_without"].value_um < 100.0 < 1000.0 < f.values["orbit"].value_um   # a 5000 µm glitch
    assert ("orbit_exceeds_clearance", "fail") in _codes(extract_features(_rec(ch, fs, units="mil")))


def test_a_sampled_sine_has_no_spikes():
    from rotordiag.features._sanity import spike_samples

    for samples_per_rev in (8, 13, 64):
        assert spike_samples(np.cos(2 * np.pi * np.arange(2000) / samples_per_rev)).size == 0
    x = np.cos(2 * np.pi * np.arange(2000) / 13)
    x[[100, 1500]] += 3.0
    assert spike_samples(x).tolist() == [100, 1500]
