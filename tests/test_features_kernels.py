"""The compiled kernels and fast paths of the feature extractor agree with the NumPy expressions
they replace (the feature values a model is trained on must not move)."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import _kernels as K
from rotordiag.features._lines import refine_line_hz
from rotordiag.features._orbit import orbit_arrays, orbit_shapes
from rotordiag.features._spectrum import hann, noise_rms, residual_psd


@pytest.mark.parametrize("shape", [(8, 2048), (8, 2049), (3, 7), (1, 1), (4, 100)])
def test_kth_smallest_rows_equals_partition(shape):
    rng = np.random.default_rng(shape[1])
    for a in (rng.random(shape), rng.integers(0, 3, shape).astype(float)):
        for k in {0, shape[1] // 2, shape[1] - 1}:
            assert np.array_equal(K.kth_smallest_rows(a, k), np.partition(a, k, axis=1)[:, k])
    a = rng.random(shape)
    a[0, 0] = np.nan
    k = shape[1] // 2
    np.testing.assert_array_equal(K.kth_smallest_rows(a, k), np.partition(a, k, axis=1)[:, k])
    strided = rng.random((shape[0], 4 * shape[1]))[:, 1::4]
    assert np.array_equal(K.kth_smallest_rows(strided, k), np.partition(strided, k, axis=1)[:, k])


def _numpy_powers(e1: np.ndarray, k_max: int) -> np.ndarray:
    basis = np.empty((k_max, e1.size), complex)
    basis[0] = e1
    for k in range(1, k_max):
        basis[k] = basis[k - 1] * e1
    out = np.empty((2 * k_max, e1.size))
    out[0::2], out[1::2] = basis.real, basis.imag
    return out


@pytest.mark.parametrize("n", [16_384, 16_352, 5])
def test_trig_rows_are_the_powers(n):
    e1 = np.exp(1j * 0.0399 * np.arange(n))
    out = np.empty((20, n))
    K.trig_rows(e1, 10, out)
    np.testing.assert_allclose(out, _numpy_powers(e1, 10), rtol=0, atol=1e-14)


def test_coarse_diameter_equals_numpy_argmax():
    rng = np.random.default_rng(3)
    theta = 2 * np.pi * np.arange(120) / 120
    cases = [rng.normal(size=(4, 120)), np.cos(theta)[None].repeat(3, 0), np.zeros((2, 120))]
    ys = [rng.normal(size=(4, 120)), np.sin(theta)[None].repeat(3, 0), np.zeros((2, 120))]
    nan_x = rng.normal(size=(2, 9))
    nan_x[1, 4] = np.nan
    cases.append(nan_x)
    ys.append(rng.normal(size=(2, 9)))
    for xs, y in zip(cases, ys):
        nb = xs.shape[0]
        arg, d2max = np.empty(nb, np.int64), np.empty(nb)
        K.coarse_diameter(xs, y, arg, d2max)
        d2 = ((xs[:, :, None] - xs[:, None, :]) ** 2 + (y[:, :, None] - y[:, None, :]) ** 2).reshape(nb, -1)
        assert np.array_equal(arg, d2.argmax(axis=1))
        np.testing.assert_array_equal(d2max, d2.max(axis=1))


def test_power_spectrum_equals_numpy():
    spec = np.fft.rfft(np.random.default_rng(4).normal(size=(3, 64)), axis=-1)
    for even in (True, False):
        ref = (spec.real ** 2 + spec.imag ** 2) * 0.37
        ref[:, 0] *= 0.5
        if even:
            ref[:, -1] *= 0.5
        assert np.array_equal(K.power_spectrum(spec, 0.37, even), ref)


def test_residual_psd_and_noise_match_the_numpy_definition():
    rng = np.random.default_rng(5)
    resid = rng.normal(0, 2.0, (4, 5001))
    freqs, psd = residual_psd(resid, 1000.0)
    w = hann(5001)
    n_fft = 5120 if freqs.size == 2561 else 2 * (freqs.size - 1)
    spec = np.fft.rfft(resid * w, n=n_fft, axis=-1)
    ref = (spec.real ** 2 + spec.imag ** 2) * (2.0 / (n_fft * float(np.dot(w, w))))
    ref[:, 0] *= 0.5
    if n_fft % 2 == 0:
        ref[:, -1] *= 0.5
    np.testing.assert_allclose(psd, ref, rtol=1e-12, atol=1e-14 * ref.max())
    np.testing.assert_array_equal(freqs, np.fft.rfftfreq(n_fft, 1e-3))
    sample = psd[:, 1::4]
    mid = sample.shape[1] // 2
    ref_noise = np.sqrt((psd.shape[1] - 1) * np.partition(sample, mid, axis=1)[:, mid] / np.log(2.0))
    assert np.array_equal(noise_rms(psd), ref_noise)
    assert np.all(np.abs(noise_rms(psd) / 2.0 - 1) < 0.1)


def _refine_reference(data, fs, f0, iterations):
    """The straightforward complex form of the phase-difference refinement."""
    n = data.shape[1]
    h = n // 2
    w = hann(h)
    t = np.arange(h) / fs
    f = float(f0)
    for _ in range(iterations):
        e = w * np.exp(-2j * np.pi * f * t)
        c1 = data[:, :h] @ e
        c2 = (data[:, h:2 * h] @ e) * np.exp(-2j * np.pi * f * h / fs)
        f = f + float(np.angle(np.vdot(c1, c2))) * fs / (2 * np.pi * h)
    return f


@pytest.mark.parametrize("n", [16_384, 4_001])
def test_refine_line_hz_equals_complex_reference(n):
    rng = np.random.default_rng(n)
    fs, f_true = 5120.0, 32.5617
    t = np.arange(n) / fs
    data = np.vstack([np.cos(2 * np.pi * f_true * t + p) + rng.normal(0, 0.05, n) for p in (0.2, 1.9, 4.0)])
    for iters in (1, 3):
        got = refine_line_hz(data, fs, 32.4, iterations=iters)
        assert got == pytest.approx(_refine_reference(data, fs, 32.4, iters), rel=1e-13, abs=0)
    assert refine_line_hz(data, fs, 32.4) == pytest.approx(f_true, rel=1e-4)


def test_orbit_arrays_and_shapes_agree():
    rng = np.random.default_rng(6)
    cx = rng.normal(size=(5, 2)) + 1j * rng.normal(size=(5, 2))
    cy = rng.normal(size=(5, 2)) + 1j * rng.normal(size=(5, 2))
    arr = orbit_arrays(cx, cy)
    for b, shp in enumerate(orbit_shapes(cx, cy)):
        assert (shp.pp_um, shp.area_um2, shp.turning_number) == (arr.pp[b], arr.area[b], arr.turning[b])
        assert shp.has_loop == (abs(int(arr.turning[b])) != 1)
        np.testing.assert_array_equal(shp.points_um, np.column_stack([arr.x[b], arr.y[b]]))


# Feature values of the benchmark recording (seed 0) computed before the speed work (commit 7d2d4f8):
# the optimisations change rounding only, so every value must agree to 1e-9 relative.
_GOLDEN = {
    "given": {
        "speed_rpm": 1953.7,
        "motion_period": 0.0,
        "motion_quasi_periodic": 1.0,
        "b1_x_1x_amp_um_pp": 80.00510437602422,
        "b1_x_1x_phase_deg": 229.30631742420533,
        "b2_y_2x_amp_um_pp": 24.002433364183922,
        "b3_x_3x_1x_ratio": 0.07496137624142125,
        "b4_y_direct_um_pp": 93.82556096972067,
        "b1_1x_rev_fwd_ratio": 0.43605685662099425,
        "b2_2x_major_um_pp": 31.179016201156777,
        "b3_1x_whirl_index": -0.5603299098873518,
        "b1_orbit12_um_pp": 114.69000382777452,
        "b2_orbit12_area_um2": -3267.3946395049156,
        "b3_orbit12_ellipticity": 0.5273322885085404,
        "b4_orbit12_concavity": 0.4999999999999998,
        "b4_orbit12_turning_number": 0.0,
        "b3_subsync_rms_um": 4.997906712452293,
        "b4_whirl_band_frac": 0.015350475302874653,
        "b3_half_x_rms_um": 0.01426355967375691,
        "b4_subsync_peak_order": 0.4499162595638343,
        "b1_nonsync_frac": 0.00011167612561936354,
        "b3_poincare_rms_um": 5.027430017966534,
        "b4_poincare_disp": 0.12409439361961531,
        "dphase_1x_b2_b3_x_deg": -112.89068376222349,
        "dphase_2x_b3_b4_y_deg": -172.43960541076854,
    },
    "keyphasor": {
        "speed_rpm": 1953.7,
        "motion_period": 0.0,
        "motion_quasi_periodic": 1.0,
        "b1_x_1x_amp_um_pp": 80.00510437602416,
        "b1_x_1x_phase_deg": 229.30631742420482,
        "b2_y_2x_amp_um_pp": 24.002433364183865,
        "b3_x_3x_1x_ratio": 0.07496137624142038,
        "b4_y_direct_um_pp": 93.82556096972067,
        "b1_1x_rev_fwd_ratio": 0.4360568566209941,
        "b2_2x_major_um_pp": 31.179016201156738,
        "b3_1x_whirl_index": -0.5603299098873517,
        "b1_orbit12_um_pp": 114.69000382777458,
        "b2_orbit12_area_um2": -3267.394639504916,
        "b3_orbit12_ellipticity": 0.5273322885085403,
        "b4_orbit12_concavity": 0.5,
        "b4_orbit12_turning_number": 0.0,
        "b3_subsync_rms_um": 4.9979067124522825,
        "b4_whirl_band_frac": 0.015350475302874526,
        "b3_half_x_rms_um": 0.014263559673632372,
        "b4_subsync_peak_order": 0.4499162595638342,
        "b1_nonsync_frac": 0.0001116761256193761,
        "b3_poincare_rms_um": 5.027430017966416,
        "b4_poincare_disp": 0.12409439361961641,
        "dphase_1x_b2_b3_x_deg": -112.89068376222335,
        "dphase_2x_b3_b4_y_deg": -172.43960541076876,
    },
    "estimated": {
        "speed_rpm": 1953.700619698258,
        "motion_period": 0.0,
        "motion_quasi_periodic": 1.0,
        "b1_x_1x_amp_um_pp": 80.00510482664683,
        "b1_x_1x_phase_deg": 229.31225495507198,
        "b2_y_2x_amp_um_pp": 24.002433636616164,
        "b3_x_3x_1x_ratio": 0.07496137064370095,
        "b4_y_direct_um_pp": 93.82556096972067,
        "b1_1x_rev_fwd_ratio": 0.4360568569967461,
        "b2_2x_major_um_pp": 31.17901607065341,
        "b3_1x_whirl_index": -0.5603299117402357,
        "b1_orbit12_um_pp": 114.68999981088085,
        "b2_orbit12_area_um2": -3267.3946170316294,
        "b3_orbit12_ellipticity": 0.5273322892641982,
        "b4_orbit12_concavity": 0.4999999999999999,
        "b4_orbit12_turning_number": 0.0,
        "b3_subsync_rms_um": 4.997906712041717,
        "b4_whirl_band_frac": 0.015350475302834902,
        "b3_half_x_rms_um": 0.014263557029314325,
        "b4_subsync_peak_order": 0.44991611685184435,
        "b1_nonsync_frac": 0.00011166478860354021,
        "b3_poincare_rms_um": 5.027417896634974,
        "b4_poincare_disp": 0.1241002110835943,
        "dphase_1x_b2_b3_x_deg": -112.8906842810998,
        "dphase_2x_b3_b4_y_deg": -172.43960664461298,
    },
}


def _bench_recording(**kw):
    """benchmarks/bench_features.py ``make_recording(seed=0)``: 4 bearings, 1953.7 r/min, 0.45X whirl on 3–4."""
    from benchmarks.bench_features import make_recording

    return make_recording(seed=0, **kw)


@pytest.mark.parametrize("source", ["given", "keyphasor", "estimated"])
def test_feature_values_unchanged_by_the_fast_paths(source):
    from rotordiag.features import extract_features

    kw = {"given": {"speed_rpm": 1953.7}, "estimated": {},
          "keyphasor": {"keyphasor_times_s": np.arange(0.0, 16_384 / 5120.0, 60.0 / 1953.7)}}[source]
    fr = extract_features(_bench_recording(**kw))
    assert fr.speed_source == source
    for name, want in _GOLDEN[source].items():
        assert fr[name] == pytest.approx(want, rel=1e-9, abs=1e-12), name
