"""Sub-harmonic and non-synchronous energy; Poincaré dispersion and motion type."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import extract_features

from .test_features_synth import DEFAULT_COMPONENTS, make_recording

RPM = 1953.7
F1 = RPM / 60


def _whirl(order, radius, bearings=(1, 2, 3, 4), phase=0.3):
    def extra(t, b):
        if b not in bearings:
            return 0.0 * t, 0.0 * t
        th = 2 * np.pi * order * F1 * t + phase
        return radius * np.cos(th), radius * np.sin(th)
    return extra


def _total_ms(b, extra_ms=0.0):
    return sum(ax ** 2 / 2 + ay ** 2 / 2 for _, ax, _, ay, _ in DEFAULT_COMPONENTS[b]) + extra_ms


def test_oil_whirl_at_045x_detected_in_whirl_band():
    """A forward circular whirl of radius 8 µm at 0.45X: band RMS 8 µm (x and y together)."""
    fr = extract_features(make_recording(extra=_whirl(0.45, 8.0), speed_rpm=RPM))
    for b in (1, 2, 3, 4):
        assert fr[f"b{b}_whirl_band_rms_um"] == pytest.approx(8.0, rel=0.01)
        assert fr[f"b{b}_subsync_rms_um"] == pytest.approx(8.0, rel=0.01)
        assert fr[f"b{b}_subsync_peak_order"] == pytest.approx(0.45, abs=0.003)
        assert fr[f"b{b}_half_x_rms_um"] < 0.05 and fr[f"b{b}_third_x_rms_um"] < 0.05
        assert fr[f"b{b}_whirl_band_frac"] == pytest.approx(64 / _total_ms(b, 64), rel=0.02)
        assert fr[f"b{b}_nonsync_frac"] == pytest.approx(64 / _total_ms(b, 64), rel=0.02)
        # the synchronous orders are unaffected
        assert fr[f"b{b}_x_1x_amp_um_pp"] == pytest.approx(2 * DEFAULT_COMPONENTS[b][0][1], rel=1e-3)
        # non-periodic once-per-rev points spread over the whirl circle (RMS = radius)
        assert fr[f"b{b}_poincare_rms_um"] == pytest.approx(8.0, rel=0.05)


def test_no_subsynchronous_content_gives_zero_bands():
    fr = extract_features(make_recording(speed_rpm=RPM))
    for b in (1, 2, 3, 4):
        assert fr[f"b{b}_subsync_rms_um"] < 1e-9
        assert fr[f"b{b}_poincare_rms_um"] < 1e-9
        assert np.isnan(fr[f"b{b}_subsync_peak_order"])
    assert fr["motion_period"] == 1.0


@pytest.mark.parametrize("order,key,other", [(0.5, "half_x", "third_x"), (1 / 3, "third_x", "half_x")])
def test_half_and_third_x_callouts(order, key, other):
    fr = extract_features(make_recording(extra=_whirl(order, 5.0), speed_rpm=RPM))
    assert fr[f"b2_{key}_rms_um"] == pytest.approx(5.0, rel=0.01)
    assert fr[f"b2_{other}_rms_um"] < 0.05
    # the whirl band ends at 0.49X, inside the Hann main lobe (±2/n_revs ≈ ±0.019X) of a 1/2X
    # line: it may see a tail of it (here < 25 % of the line's energy), never of a 1/3X line
    assert fr["b2_whirl_band_rms_um"] < (2.5 if order == 0.5 else 0.05)
    assert fr["b2_subsync_peak_order"] == pytest.approx(order, abs=0.003)


def test_period_2_motion_and_poincare_points():
    """An exact 1/2X component (period doubling) makes the once-per-rev points alternate."""
    rec = make_recording(extra=_whirl(0.5, 5.0, phase=0.0), speed_rpm=RPM)
    fr = extract_features(rec)
    assert fr["motion_period"] == 2.0
    assert fr["motion_quasi_periodic"] == 0.0 and fr["motion_chaotic"] == 0.0
    assert fr.motion_type.kind == "period-n" and fr.motion_type.period == 2
    # points alternate between ±5 µm along x about the synchronous position: RMS 5 µm
    assert fr["b2_poincare_rms_um"] == pytest.approx(5.0, rel=1e-3)
    pts = fr.bearings[2].poincare_um
    np.testing.assert_allclose(pts[2::2], pts[0:-2:2], atol=1e-3)


def test_period_3_motion():
    fr = extract_features(make_recording(extra=_whirl(1 / 3, 5.0), speed_rpm=RPM))
    assert fr["motion_period"] == 3.0


def test_quasi_periodic_motion():
    """An incommensurate whirl (0.4142X) fills a closed curve in the section: quasi-periodic."""
    fr = extract_features(make_recording(extra=_whirl(np.sqrt(2) - 1, 6.0), speed_rpm=RPM))
    assert fr["motion_period"] == 0.0
    assert fr["motion_quasi_periodic"] == 1.0
    assert fr["motion_chaotic"] == 0.0


def test_period_1_survives_measurement_noise():
    fr = extract_features(make_recording(noise_um=1.0, seed=2, speed_rpm=RPM))
    assert fr["motion_period"] == 1.0
    # the dispersion is then the noise: about √2·σ per bearing relative to the orbit RMS
    for b in (1, 2, 3, 4):
        assert fr[f"b{b}_poincare_rms_um"] == pytest.approx(np.sqrt(2), rel=0.25)


def test_motion_needs_32_revolutions():
    n = int(20 * 5120 / F1)  # 20 revolutions
    fr = extract_features(make_recording(n=n, speed_rpm=RPM))
    assert np.isnan(fr["motion_period"]) and fr.motion_type is None
    codes = {w.code: w.values for w in fr.warnings}
    assert codes["few_revolutions_motion"]["n_revs"] == fr.n_revs < codes["few_revolutions_motion"]["min_revs"]
    assert codes["few_revolutions_subharmonic"]["resolution_x"] == pytest.approx(1 / fr.n_revs)
