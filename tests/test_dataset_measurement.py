"""Measurement model on synthetic journal motions with closed-form probe signals."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rotordiag.simulator.dataset.measurement import (
    MeasurementDraws,
    MeasurementSettings,
    draw_measurement,
    probe_waveforms_um,
    required_record_revs,
    shaft_angle_rad,
)

S = 128  # simulator samples per revolution


def settings(**kw):
    base = dict(bearings=(1, 2, 3, 4), probe_angles_deg=(45.0, 135.0), sample_rate_hz=2048.0, n_points=2048)
    base.update(kw)
    return MeasurementSettings(**base)


def draws(n_b=4, theta0=0.7, phase_m=1.1, r1=0.0, p1=0.0, r2=0.0, p2=0.0, snr=math.inf):
    f = lambda v: np.full(n_b, float(v))  # noqa: E731
    return MeasurementDraws(snr, theta0, phase_m, f(r1), f(p1), f(r2), f(p2))


def orbit(n_revs, radius_m=(20e-6, 10e-6, 30e-6, 5e-6), dc_m=(-100e-6, -50e-6, -80e-6, -120e-6)):
    """Forward circular whirl at 1X about a static position below the centre, sampled like the simulator."""
    tau = 2 * np.pi / S * np.arange(n_revs * S)
    d = np.zeros((tau.size, 4, 2))
    for b in range(4):
        d[:, b, 0] = radius_m[b] * np.cos(tau)
        d[:, b, 1] = dc_m[b] + radius_m[b] * np.sin(tau)
    return d


def expected(theta, radius_m, dc_m, alpha_deg):
    a = math.radians(alpha_deg)
    # (r cos θ) cos α + (y0 + r sin θ) sin α = r cos(θ − α) + y0 sin α, in µm
    return 1e6 * (radius_m * np.cos(theta - a) + dc_m * math.sin(a))


@pytest.mark.parametrize("fluctuation", [0.0, 0.01])
def test_circular_orbit_gives_the_closed_form_probe_signals(fluctuation):
    st = settings(speed_fluctuation=fluctuation, speed_fluctuation_hz=2.0)
    dr = draws()
    speed = 1800.0
    revs = required_record_revs(speed, st, dr)
    out = probe_waveforms_um(orbit(revs), S, speed, st, dr, np.random.default_rng(0))
    assert out.shape == (8, 2048) and out.dtype == np.float32
    t = np.arange(2048) / 2048.0
    omega = speed * np.pi / 30
    theta = 0.7 + omega * t
    if fluctuation:
        wm = 2 * np.pi * 2.0
        theta += omega * fluctuation / wm * (np.cos(1.1) - np.cos(wm * t + 1.1))
    radius, dc = (20e-6, 10e-6, 30e-6, 5e-6), (-100e-6, -50e-6, -80e-6, -120e-6)
    for c, (b, alpha) in enumerate(st.channels):
        ref = expected(theta, radius[b - 1], dc[b - 1], alpha)
        # cubic spline at 128 samples/rev on a pure 1X orbit: error ≈ r (2π/128)^4 / 384 ≈ 1e-7 r
        np.testing.assert_allclose(out[c], ref, atol=1e-3 * radius[b - 1] * 1e6 + 1e-4)


def test_speed_fluctuation_changes_the_instantaneous_speed_by_epsilon():
    st = settings(speed_fluctuation=0.02, speed_fluctuation_hz=1.0, n_points=4096)
    theta = shaft_angle_rad(st.time_s, 3000.0, st, draws(phase_m=0.0))
    speed = np.gradient(theta, st.time_s) / (np.pi / 30)
    assert speed.max() == pytest.approx(3000 * 1.02, rel=1e-4)
    assert speed.min() >= 3000 * 0.98 - 1


def test_runout_is_fixed_to_the_shaft_surface():
    st = settings(bearings=(2,), probe_angles_deg=(45.0, 135.0), sample_rate_hz=2000.0)
    dr = draws(n_b=1, theta0=0.0, r1=3.0, p1=0.4, r2=1.5, p2=2.0)
    speed = 1500.0
    zero = np.zeros((required_record_revs(speed, st, dr) * S, 4, 2))
    out = probe_waveforms_um(zero, S, speed, st, dr, np.random.default_rng(0))
    theta = shaft_angle_rad(st.time_s, speed, st, dr)
    for c, alpha in enumerate((45.0, 135.0)):
        psi = math.radians(alpha) - theta
        ref = 3.0 * np.cos(psi - 0.4) + 1.5 * np.cos(2 * psi - 2.0)
        np.testing.assert_allclose(out[c], ref, atol=1e-5)
    # the second probe sees the same profile a quarter turn later
    lag = int(round(0.25 * 60 / speed * st.sample_rate_hz))
    np.testing.assert_allclose(out[1, lag:], out[0, :-lag], atol=1e-4)


def test_noise_has_the_requested_snr():
    st = settings(n_points=2 ** 16, sample_rate_hz=8192.0)
    dr = draws(snr=20.0)
    speed = 1800.0
    disp = orbit(required_record_revs(speed, st, dr))
    clean = probe_waveforms_um(disp, S, speed, st, draws(snr=math.inf), np.random.default_rng(1)).astype(float)
    noisy = probe_waveforms_um(disp, S, speed, st, dr, np.random.default_rng(1)).astype(float)
    ratio = (noisy - clean).var(axis=1) / clean.var(axis=1)
    np.testing.assert_allclose(ratio, 10 ** (-20 / 10), rtol=0.03)  # 65536 points: σ² within ~1 %


def test_points_beyond_an_early_stop_are_nan():
    st = settings(n_points=1024)
    dr = draws(snr=30.0)
    speed = 1800.0  # 30 Hz: 1024 points at 2048 Hz = 15 revolutions
    short = orbit(5)
    out = probe_waveforms_um(short, S, speed, st, dr, np.random.default_rng(0))
    theta = shaft_angle_rad(st.time_s, speed, st, dr)
    inside = theta <= 2 * np.pi / S * (5 * S - 1)
    assert np.all(np.isfinite(out[:, inside])) and np.all(np.isnan(out[:, ~inside]))
    empty = probe_waveforms_um(np.zeros((0, 4, 2)), S, speed, st, dr, np.random.default_rng(0))
    assert np.all(np.isnan(empty))


def test_draws_come_from_the_seed_in_a_fixed_order():
    st = settings(snr_db=(20.0, 40.0), runout_1x_um=(0.0, 2.0), runout_2x_um=(1.0, 1.0))
    a = draw_measurement(st, np.random.default_rng(42))
    b = draw_measurement(st, np.random.default_rng(42))
    assert a.snr_db == b.snr_db and np.array_equal(a.runout_1x_um, b.runout_1x_um)
    assert 20 <= a.snr_db <= 40 and 0 <= a.start_angle_rad < 2 * np.pi
    assert np.all(a.runout_2x_um == 1.0) and np.all((a.runout_1x_um >= 0) & (a.runout_1x_um <= 2))
    rng = np.random.default_rng(42)  # independent replay of the documented order
    assert rng.uniform(20, 40) == a.snr_db and rng.uniform(0, 2 * np.pi) == a.start_angle_rad


def test_record_is_long_enough_for_the_shaft_angle():
    st = settings(speed_fluctuation=0.05, speed_fluctuation_hz=0.3)
    dr = draws(theta0=6.0)
    revs = required_record_revs(2400.0, st, dr)
    theta = shaft_angle_rad(st.time_s, 2400.0, st, dr)
    assert (revs - 1) * 2 * np.pi > theta.max()


def test_bad_displacement_shape():
    with pytest.raises(ValueError, match=r"shape \(n, n_bearings ≥ 4, 2\)"):
        probe_waveforms_um(np.zeros((10, 4)), S, 1800.0, settings(), draws(), np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"n_bearings ≥ 4"):   # a 3-bearing train with a probe at bearing 4
        probe_waveforms_um(np.zeros((10, 3, 2)), S, 1800.0, settings(), draws(), np.random.default_rng(0))
