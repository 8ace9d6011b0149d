"""Run-ups and coast-downs of the paper's model (simulator.transient) and its critical speeds (simulator.campbell)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rotordiag.simulator import Plant, simulate
from rotordiag.simulator.campbell import campbell, critical_speeds
from rotordiag.simulator.transient import SpeedProfile, simulate_transient


def _rev_1x(d: np.ndarray, t0: float, t1: float, fs: float) -> np.ndarray:
    """Complex 1X (0-pk, e^{-j·lag}) of every column of ``d`` over one revolution t0 → t1, by a least-squares fit
    of [1, cos θ, sin θ, cos 2θ, sin 2θ] at θ = 2π(t − t0)/(t1 − t0): an independent reference (no FFT, no tracking)."""
    j0, j1 = int(np.ceil(t0 * fs)), int(np.ceil(t1 * fs))
    th = 2 * np.pi * (np.arange(j0, j1) / fs - t0) / (t1 - t0)
    basis = np.column_stack([np.ones_like(th), np.cos(th), np.sin(th), np.cos(2 * th), np.sin(2 * th)])
    c, *_ = np.linalg.lstsq(basis, d[j0:j1].reshape(j1 - j0, -1), rcond=None)
    return c[1] - 1j * c[2]


def test_profile_angle_and_revolutions_exact():
    p = SpeedProfile.table([0, 10, 30], [600, 1200, 1200])
    # ∫Ω dt: 10 s averaging 900 r/min, then 20 s at 1200 r/min = 150 + 400 revolutions
    assert p.angle_rad(np.array([30.0]))[0] / (2 * math.pi) == pytest.approx(550.0, rel=1e-12)
    rt = p.revolution_times_s()
    assert rt.size == 551
    assert np.allclose(p.angle_rad(rt) / (2 * math.pi), np.arange(551), atol=1e-9)
    assert rt[-1] == pytest.approx(30.0)


@pytest.mark.parametrize("text, message", [
    ("0:3000:60", "outside the model's range"),
    ("0@1000,10@2000,20@1500", "reverses at t = 10 s"),
    ("0@1000,10@1000", "never changes"),
    ("1000:3000", "START:END:DURATION"),
    ("0@1000,0@2000", "times must increase"),
    ("100:7000:10", "outside the model's range"),
])
def test_bad_profiles_are_refused_with_what_to_fix(text, message):
    with pytest.raises(ValueError, match=message):
        SpeedProfile.parse(text)


def test_slow_ramp_agrees_with_the_steady_solution():
    """A 5 r/min/s ramp through 1500 r/min: each journal's 1X over the revolution at 1500 r/min within 2 % (and 2°)
    of the steady simulation's at 1500 r/min (same keyphasor reference τ ≡ 0)."""
    plant = Plant.default()
    res = simulate_transient(plant, SpeedProfile.linear(1450, 1550, 20), 0.0, 0.05, sample_rate_hz=5120,
                             settle_revs=300)
    assert res.ok
    kp = res.keyphasor_times_s
    rpm = 60.0 / np.diff(kp)
    k = int(np.argmin(np.abs(rpm - 1500.0)))
    got = _rev_1x(res.journal_displacements_m * 1e6, kp[k], kp[k + 1], res.sample_rate_hz)
    st = simulate(plant, float(rpm[k]), 0.0, 0.05, transient_revs=400, record_revs=4, samples_per_rev=256)
    spr = 256
    d = st.journal_displacements_m[-spr:] * 1e6
    th = 2 * np.pi * np.arange(spr) / spr
    ref = (2.0 / spr) * (d.reshape(spr, -1) * np.exp(-1j * th)[:, None]).sum(axis=0)
    assert np.abs(got) == pytest.approx(np.abs(ref), rel=0.02)
    assert np.degrees(np.abs(np.angle(got / ref))).max() < 2.0


def test_run_up_1x_peaks_at_the_damped_criticals():
    """The 1X Bode of a 50 r/min/s run-up peaks within the half-power half-width (ζ·n_c) of a damped critical speed
    of the linearised model (simulator.modal): bearing 1 vertical at the lightly damped ~1250 r/min mode,
    bearing 1 horizontal at the ~1100 r/min one."""
    plant = Plant.default()
    res = simulate_transient(plant, SpeedProfile.linear(800, 1600, 16), 0.0, 0.05, sample_rate_hz=2560,
                             settle_revs=200)
    kp = res.keyphasor_times_s
    amp = np.array([np.abs(_rev_1x(res.journal_displacements_m[:, 0] * 1e6, kp[k], kp[k + 1], 2560.0))
                    for k in range(kp.size - 1)])
    rpm = 60.0 / np.diff(kp)
    crit = critical_speeds(campbell(plant, np.arange(800, 1601, 25.0)))
    assert crit, "no lightly damped critical between 800 and 1600 r/min"
    for axis in (0, 1):
        peak = float(rpm[np.argmax(amp[:, axis])])
        nearest = min(crit, key=lambda c: abs(c.speed_rpm - peak))
        assert abs(peak - nearest.speed_rpm) <= 0.5 * nearest.half_power_width_rpm, (axis, peak, nearest)
    # and the two directions peak at different criticals (the anisotropic bearings split them)
    peaks = [min(crit, key=lambda c: abs(c.speed_rpm - float(rpm[np.argmax(amp[:, a])]))) for a in (0, 1)]
    assert peaks[0].speed_rpm < peaks[1].speed_rpm


def test_keyphasor_signal_reads_back_to_the_marks():
    from rotordiag.features.reader import keyphasor_times_from_pulses

    res = simulate_transient(Plant.default(), SpeedProfile.linear(1000, 1400, 3), 0.0, 0.05, sample_rate_hz=4096,
                             settle_revs=50)
    sig = res.keyphasor_signal()
    got = keyphasor_times_from_pulses(sig, res.sample_rate_hz)
    kp = res.keyphasor_times_s[res.keyphasor_times_s > 0.5 / res.sample_rate_hz]
    assert got.size == kp.size
    assert np.max(np.abs(got - kp)) < 1e-3 / res.sample_rate_hz


def test_a_model_behind_the_variable_speed_interface_runs_the_same():
    """The door a shaft train comes in by: a model object in place of the plant gives the same run."""
    from rotordiag.simulator.transient import PlantModel

    plant = Plant.default()
    prof = SpeedProfile.linear(1000, 1100, 1.0)
    a = simulate_transient(plant, prof, 0.2, 0.05, settle_revs=20)
    b = simulate_transient(PlantModel(plant, 0.2, 0.05), prof, settle_revs=20)
    assert np.array_equal(a.journal_displacements_m, b.journal_displacements_m)
    assert np.array_equal(a.keyphasor_times_s, b.keyphasor_times_s)


@pytest.mark.parametrize("kwargs, message", [
    ({"sample_rate_hz": 100.0}, "sample_rate_hz must be in"),
    ({"settle_revs": -1}, "settle_revs must be in"),
    ({"misalignment": 1.5}, "misalignment"),
])
def test_simulate_transient_refuses_bad_arguments(kwargs, message):
    args = {"misalignment": 0.1, "unbalance": 0.05, **kwargs}
    with pytest.raises(ValueError, match=message):
        simulate_transient(Plant.default(), SpeedProfile.linear(1000, 1500, 2), args.pop("misalignment"),
                           args.pop("unbalance"), **args)
    with pytest.raises(ValueError, match="profile must be a SpeedProfile"):
        simulate_transient(Plant.default(), "1000:1500:2")  # type: ignore[arg-type]
