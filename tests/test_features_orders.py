"""Order analysis against signals whose orders are known exactly."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import FEATURE_NAMES, extract_features
from rotordiag.features._orders import _uniform_gram, fit_orders

from .test_features_synth import DEFAULT_COMPONENTS, keyphasor_times, make_recording


def _wrap(d):
    return (np.asarray(d) + 180.0) % 360.0 - 180.0


def _check_components(fr, comps, rtol=1e-6, phase_tol_deg=1e-6):
    for b, cs in comps.items():
        for k, ax, phx, ay, phy in cs:
            if k > 3:
                continue
            for d, a, ph in (("x", ax, phx), ("y", ay, phy)):
                got = fr[f"b{b}_{d}_{k}x_amp_um_pp"]
                assert got == pytest.approx(2 * a, rel=rtol), (b, d, k)
                if a > 0:
                    assert abs(_wrap(fr[f"b{b}_{d}_{k}x_phase_deg"] - ph)) < phase_tol_deg, (b, d, k)


@pytest.mark.parametrize("fs,n,rpm", [(5120.0, 16384, 1953.7), (12800.0, 8192, 3000.0), (2000.0, 4000, 1234.567)])
def test_exact_orders_given_speed(fs, n, rpm):
    """Pure 1X + 2X + 3X at a non-integer number of samples per revolution: recovered to 1e-6."""
    rec = make_recording(fs=fs, n=n, rpm=rpm, speed_rpm=rpm)
    fr = extract_features(rec)
    assert fr.speed_source == "given"
    assert fr.speed_rpm == rpm
    _check_components(fr, DEFAULT_COMPONENTS)
    for b, cs in DEFAULT_COMPONENTS.items():
        (_, ax1, _, ay1, _), (_, ax2, _, ay2, _) = cs[0], cs[1]
        assert fr[f"b{b}_x_2x_1x_ratio"] == pytest.approx(ax2 / ax1, rel=1e-9)
        assert fr[f"b{b}_y_2x_1x_ratio"] == pytest.approx(ay2 / ay1, rel=1e-9)
        assert fr[f"b{b}_nonsync_frac"] < 1e-20
    assert not {"few_revolutions_subharmonic", "few_revolutions_motion"} & {w.code for w in fr.warnings}


def test_exact_orders_keyphasor_with_offset():
    """Phase is measured from the keyphasor pulse: pulses at t0 + m/f1 shift θ = 0 to t0."""
    rpm, fs, n, t0 = 1953.7, 5120.0, 16384, 0.0123
    f1 = rpm / 60
    rec = make_recording(fs=fs, n=n, rpm=rpm, theta_fn=lambda t: 2 * np.pi * f1 * (t - t0),
                         keyphasor_times_s=keyphasor_times(rpm, n / fs, t0))
    fr = extract_features(rec)
    assert fr.speed_source == "keyphasor" and fr.phase_reference == "keyphasor"
    assert fr.speed_rpm == pytest.approx(rpm, rel=1e-9)
    _check_components(fr, DEFAULT_COMPONENTS, rtol=1e-6, phase_tol_deg=1e-5)


def test_first_sample_phase_reference_without_keyphasor():
    rec = make_recording(speed_rpm=1953.7)
    fr = extract_features(rec)
    assert fr.phase_reference == "first sample"
    assert fr.bearings[2].phase_deg("x", 1) == pytest.approx(50.0, abs=1e-6)


def test_varying_speed_tracked_by_keyphasor():
    """Speed ramps 3 % over the record: keyphasor order tracking keeps amplitudes to 1e-3."""
    fs, n, f0, ramp = 5120.0, 16384, 32.0, 0.03
    dur = n / fs
    # θ(t) = 2π (f0 t + ½ a t²): speed f0 → f0 (1 + ramp)
    acc = f0 * ramp / dur
    theta_fn = lambda t: 2 * np.pi * (f0 * t + 0.5 * acc * t ** 2)  # noqa: E731
    # pulses where θ = 2πm
    m = np.arange(0, int(f0 * dur * (1 + ramp / 2)))
    kp = (-f0 + np.sqrt(f0 ** 2 + 2 * acc * m)) / acc
    rec = make_recording(fs=fs, n=n, theta_fn=theta_fn, keyphasor_times_s=kp)
    fr = extract_features(rec)
    _check_components(fr, DEFAULT_COMPONENTS, rtol=1e-3, phase_tol_deg=0.2)
    # the same record analysed at one mean speed smears the orders badly
    rec2 = make_recording(fs=fs, n=n, theta_fn=theta_fn, speed_rpm=fr.speed_rpm)
    fr2 = extract_features(rec2)
    assert abs(fr2["b2_x_2x_amp_um_pp"] / 40.0 - 1) > 0.05


@pytest.mark.parametrize("noise", [0.5, 2.0])
def test_orders_with_noise(noise):
    """White probe noise σ: amplitude errors stay within 5 standard errors.

    Unweighted least squares gives σ·√(2/N) per cosine/sine coefficient; Hann weights
    raise that by √(N·Σw²)/Σw = √(N·3N/8)/(N/2) = √1.5 ≈ 1.22 (x, y are orthonormal probe
    combinations at ±45°, so they carry the probe noise σ unchanged).
    """
    rec = make_recording(noise_um=noise, seed=7, speed_rpm=1953.7)
    fr = extract_features(rec)
    n = 16384
    se_pp = 2 * noise * np.sqrt(2.0 / n) * np.sqrt(1.5)
    for b, cs in DEFAULT_COMPONENTS.items():
        for k, ax, phx, ay, phy in cs:
            for d, a, ph in (("x", ax, phx), ("y", ay, phy)):
                assert abs(fr[f"b{b}_{d}_{k}x_amp_um_pp"] - 2 * a) < 5 * se_pp
                assert abs(_wrap(fr[f"b{b}_{d}_{k}x_phase_deg"] - ph)) < np.degrees(5 * se_pp / (2 * a))
        nonsync = fr[f"b{b}_nonsync_frac"]
        # x and y each carry noise of variance σ² (an orthonormal combination of two probes)
        total = sum(ax ** 2 / 2 + ay ** 2 / 2 for _, ax, _, ay, _ in cs) + 2 * noise ** 2
        assert nonsync == pytest.approx(2 * noise ** 2 / total, rel=0.1)


def test_forward_reverse_known_circles():
    """x + jy = F e^{jθ} + R e^{-jθ} with known F, R (and 2X F2, R2)."""
    f1c, r1c, f2c, r2c = 30 * np.exp(0.4j), 8 * np.exp(-1.1j), 6 * np.exp(2.0j), 9 * np.exp(0.3j)
    rpm = 1953.7

    def extra(t, b):
        th = 2 * np.pi * rpm / 60 * t
        z = f1c * np.exp(1j * th) + r1c * np.exp(-1j * th) + f2c * np.exp(2j * th) + r2c * np.exp(-2j * th)
        return z.real, z.imag

    rec = make_recording(components={2: []}, extra=extra, speed_rpm=rpm)
    fr = extract_features(rec)
    assert fr["b2_1x_fwd_um_pp"] == pytest.approx(60.0, rel=1e-9)
    assert fr["b2_1x_rev_um_pp"] == pytest.approx(16.0, rel=1e-9)
    assert fr["b2_2x_fwd_um_pp"] == pytest.approx(12.0, rel=1e-9)
    assert fr["b2_2x_rev_um_pp"] == pytest.approx(18.0, rel=1e-9)
    assert fr["b2_1x_rev_fwd_ratio"] == pytest.approx(8 / 30, rel=1e-9)
    assert fr["b2_1x_major_um_pp"] == pytest.approx(2 * 38.0, rel=1e-9)
    assert fr["b2_1x_ellipticity"] == pytest.approx(22 / 38, rel=1e-9)
    assert fr["b2_2x_1x_major_ratio"] == pytest.approx(30 / 76, rel=1e-9)
    d = fr.bearings[2]
    np.testing.assert_allclose(d.forward_um[:2], [f1c, f2c], rtol=1e-9)
    np.testing.assert_allclose(d.reverse_um[:2], [r1c, r2c], rtol=1e-9)


def test_forward_reverse_equal_full_spectrum_lines():
    """With an integer number of samples per revolution the ±kX bins of FFT(x + jy) are exact."""
    rpm, spr, revs = 1800.0, 128, 64
    fs, n = spr * rpm / 60, spr * revs
    rec = make_recording(fs=fs, n=n, rpm=rpm, speed_rpm=rpm)
    fr = extract_features(rec)
    for b in (1, 2, 3, 4):
        pair = [c for c in rec.channels if c.bearing == b]
        # x, y from probes at 45°/135°: x = (p1 - p2)/√2, y = (p1 + p2)/√2
        p1, p2 = pair[0].data, pair[1].data
        z = (p1 - p2) / np.sqrt(2) + 1j * (p1 + p2) / np.sqrt(2)
        spec = np.fft.fft(z) / n
        for k in (1, 2):
            assert fr[f"b{b}_{k}x_fwd_um_pp"] == pytest.approx(2 * abs(spec[k * revs]), rel=1e-9)
            assert fr[f"b{b}_{k}x_rev_um_pp"] == pytest.approx(2 * abs(spec[-k * revs]), rel=1e-9)


def test_phase_differences_across_coupling_and_along_rotors():
    fr = extract_features(make_recording(speed_rpm=1953.7))
    c = DEFAULT_COMPONENTS
    for k_i, k in ((0, 1), (1, 2)):
        for (bi, bj) in ((2, 3), (1, 2), (3, 4)):
            for d, col in (("x", 2), ("y", 4)):
                expect = _wrap(c[bi][k_i][col] - c[bj][k_i][col])
                got = fr[f"dphase_{k}x_b{bi}_b{bj}_{d}_deg"]
                assert abs(_wrap(got - expect)) < 1e-6
                assert -180.0 < got <= 180.0
    # 2X across the coupling, x: 200° − 20° = 180° (the wrap boundary)
    # (either end of the interval within rounding)
    assert abs(fr["dphase_2x_b2_b3_x_deg"]) == pytest.approx(180.0, abs=1e-6)


def test_uniform_gram_matches_direct():
    n, step, k = 3001, 2 * np.pi / 41.7, 7
    th = step * np.arange(n)
    cols = [np.ones(n)]
    for m in range(1, k + 1):
        cols += [np.cos(m * th), np.sin(m * th)]
    d = np.column_stack(cols)
    np.testing.assert_allclose(_uniform_gram(n, step, k, hann_taper=False), d.T @ d, atol=1e-8 * n)
    w = np.hanning(n)
    np.testing.assert_allclose(_uniform_gram(n, step, k), (d * w[:, None]).T @ d, atol=1e-8 * n)


def test_fit_orders_general_and_uniform_paths_agree():
    rng = np.random.default_rng(3)
    n, step = 5000, 2 * np.pi / 57.3
    th = step * np.arange(n)
    data = rng.normal(size=(3, n)) + 5 * np.cos(th - 0.3) + 2 * np.sin(3 * th)
    a = fit_orders(th, data, 6)
    b = fit_orders(th, data, 6, uniform_step_rad=step)
    for u, v in zip(a, b):
        np.testing.assert_allclose(u, v, rtol=1e-9, atol=1e-9)


def test_feature_vector_is_fixed_and_finite_for_full_recording():
    fr = extract_features(make_recording(speed_rpm=1953.7, clearance_um=350.0))
    assert fr.names == FEATURE_NAMES
    assert fr.values.dtype == np.float64 and fr.values.shape == (len(FEATURE_NAMES),)
    d = fr.as_dict()
    assert list(d) == list(FEATURE_NAMES)
    nan_names = [k for k, v in d.items() if not np.isfinite(v)]
    # only the sub-synchronous peak order is undefined for a purely synchronous signal
    assert all(n.endswith("subsync_peak_order") for n in nan_names), nan_names


@pytest.mark.parametrize("uniform", [True, False])
def test_blockwise_fit_equals_single_pass(monkeypatch, uniform):
    """Long records are fitted in blocks (bounded scratch memory); the answer must not change."""
    import rotordiag.features._orders as orders

    rng = np.random.default_rng(8)
    n, step = 10_000, 2 * np.pi / 61.7
    th = step * np.arange(n)
    data = rng.normal(size=(4, n)) + 3 * np.cos(2 * th - 0.5) + np.sin(th)
    kw = dict(uniform_step_rad=step) if uniform else {}
    one = orders.fit_orders(th, data, 8, **kw)
    monkeypatch.setattr(orders, "BLOCK_SAMPLES", 1_237)
    many = orders.fit_orders(th, data, 8, **kw)
    for a, b in zip(one, many):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10)


def test_long_record_exact():
    """A 262 144-sample record (the service's limit) goes through the blockwise path exactly."""
    fr = extract_features(make_recording(n=262_144, fs=16384.0, components={2: DEFAULT_COMPONENTS[2]},
                                         speed_rpm=1953.7))
    _check_components(fr, {2: DEFAULT_COMPONENTS[2]})


@pytest.mark.parametrize("seed", range(20))
def test_random_configurations_recovered_exactly(seed):
    """Random speed, sample rate (8–400 samples/rev), length (≥ 8 revs), probe angles, units,
    amplitudes and phases: orders, forward/reverse and phase differences come back to 1e-6."""
    rng = np.random.default_rng(1000 + seed)
    rpm = float(rng.uniform(300, 6000))
    spr = float(rng.uniform(8.5, 400))
    fs = spr * rpm / 60
    n = int(rng.uniform(8.5, 60) * spr)
    a0 = float(rng.uniform(-180, 180))
    angles = (a0, a0 + float(rng.choice([-1, 1]) * rng.uniform(35, 145)))
    units = str(rng.choice(["um", "mm", "mil", "m"]))
    comps = {b: [(k, float(rng.uniform(0.5, 80)), float(rng.uniform(0, 360)),
                  float(rng.uniform(0.5, 80)), float(rng.uniform(0, 360))) for k in (1, 2, 3)]
             for b in (1, 2, 3, 4)}
    fr = extract_features(make_recording(fs=fs, n=n, rpm=rpm, components=comps, angles=angles,
                                         units=units, speed_rpm=rpm))
    _check_components(fr, comps, rtol=1e-6, phase_tol_deg=1e-5)
    for b, cs in comps.items():
        _, ax, phx, ay, phy = cs[0]
        cx, cy = ax * np.exp(-1j * np.deg2rad(phx)), ay * np.exp(-1j * np.deg2rad(phy))
        assert fr[f"b{b}_1x_fwd_um_pp"] == pytest.approx(abs(cx + 1j * cy), rel=1e-6)
        assert fr[f"b{b}_1x_rev_um_pp"] == pytest.approx(abs(cx - 1j * cy), rel=1e-6)
    expect = _wrap(comps[2][0][2] - comps[3][0][2])
    assert abs(_wrap(fr["dphase_1x_b2_b3_x_deg"] - expect)) < 1e-5
