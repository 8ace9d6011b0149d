"""Running speed: keyphasor, given, and estimated from the signal."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.features import extract_features

from .test_features_synth import DEFAULT_COMPONENTS, keyphasor_times, make_recording


@pytest.mark.parametrize("rpm,fs,n", [(1953.7, 5120.0, 16384), (3000.0, 12800.0, 16384), (1234.5, 2560.0, 8192)])
def test_speed_estimate_noise_free(rpm, fs, n):
    fr = extract_features(make_recording(rpm=rpm, fs=fs, n=n))
    assert fr.speed_source == "estimated"
    assert fr.speed_rpm == pytest.approx(rpm, rel=1e-6)


def test_speed_estimate_with_noise_and_orders_follow():
    rpm = 1953.7
    fr = extract_features(make_recording(rpm=rpm, noise_um=2.0, seed=11))
    assert fr.speed_rpm == pytest.approx(rpm, rel=2e-5)
    ref = extract_features(make_recording(rpm=rpm, noise_um=2.0, seed=11, speed_rpm=rpm))
    for name in ("b2_x_1x_amp_um_pp", "b3_y_2x_amp_um_pp", "b1_x_3x_amp_um_pp"):
        assert fr[name] == pytest.approx(ref[name], rel=2e-3)
    # phase differences do not depend on the (arbitrary) first-sample reference
    assert fr["dphase_1x_b2_b3_x_deg"] == pytest.approx(ref["dphase_1x_b2_b3_x_deg"], abs=0.1)


def test_speed_estimate_when_2x_dominates():
    """A generator whose 2X is three times its 1X: the estimate is still 1X, not 2X."""
    comps = {b: [(1, 10.0, 20.0 * b, 9.0, 110.0), (2, 30.0, 40.0, 28.0, 130.0), (3, 4.0, 0.0, 3.0, 90.0)]
             for b in (1, 2, 3, 4)}
    fr = extract_features(make_recording(components=comps, rpm=2100.0, noise_um=0.5, seed=1))
    assert fr.speed_rpm == pytest.approx(2100.0, rel=1e-5)
    assert fr["b2_x_2x_1x_ratio"] == pytest.approx(3.0, rel=5e-3)  # 5 standard errors


def test_speed_estimate_with_dominant_subsynchronous_whirl():
    """An oil whirl at 0.44X larger than 1X is not taken for the running speed, and is flagged."""
    rpm = 2400.0
    f_w = 0.44 * rpm / 60

    def whirl(t, b):
        return 80 * np.cos(2 * np.pi * f_w * t), 80 * np.sin(2 * np.pi * f_w * t)

    fr = extract_features(make_recording(rpm=rpm, extra=whirl))
    assert fr.speed_rpm == pytest.approx(rpm, rel=1e-5)
    assert any("not synchronous" in w for w in fr.warnings)


def test_keyphasor_overrides_speed_and_warns_on_disagreement():
    rpm = 1953.7
    rec = make_recording(rpm=rpm, keyphasor_times_s=keyphasor_times(rpm, 3.2), speed_rpm=2100.0)
    fr = extract_features(rec)
    assert fr.speed_source == "keyphasor"
    assert fr.speed_rpm == pytest.approx(rpm, rel=1e-9)
    assert any("disagrees with the keyphasor" in w for w in fr.warnings)


def test_wrong_given_speed_is_flagged():
    rpm = 1953.7
    fr = extract_features(make_recording(rpm=rpm, speed_rpm=rpm * 1.004))
    assert fr.speed_source == "given"
    assert any("differs from the signal" in w for w in fr.warnings)
    fr_ok = extract_features(make_recording(rpm=rpm, speed_rpm=rpm))
    assert not any("differs from the signal" in w for w in fr_ok.warnings)


def test_pure_noise_without_speed_is_refused():
    rng = np.random.default_rng(0)
    from rotordiag.features import ProbeChannel, Recording
    chans = [ProbeChannel(b, a, "um", rng.normal(size=8192)) for b in (2, 3) for a in (45.0, 135.0)]
    with pytest.raises(ValueError, match="speed_rpm or keyphasor_times_s"):
        extract_features(Recording(5120.0, chans))


def test_speed_estimate_is_deterministic():
    a = extract_features(make_recording(noise_um=1.0, seed=5))
    b = extract_features(make_recording(noise_um=1.0, seed=5))
    assert a.speed_rpm == b.speed_rpm
    np.testing.assert_array_equal(a.values, b.values)


def test_default_components_have_distinct_bearings():
    # guard for the tests above: the synthetic record has all four bearings
    assert sorted(DEFAULT_COMPONENTS) == [1, 2, 3, 4]
