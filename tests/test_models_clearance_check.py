"""A stated clearance that may be the diametral one (models.checks.clearance_check)."""
from __future__ import annotations

from pathlib import Path

import pytest

from rotordiag.features import ProbeChannel, Recording

REGISTRY = Path(__file__).resolve().parent.parent / "models" / "default_registry"
CLEARANCE_UM = 350.0            # the default plant's radial clearance


@pytest.mark.parametrize("delta", [0.1, 0.4])
def test_shipped_model_doubts_a_confident_verdict_at_the_diametral_clearance(delta):
    """The default plant (slight and moderate misalignment) is a confident verdict at its radial clearance and has
    no such reason; stated at twice it (the diametral clearance), half of that is at least as like the training
    family, so the verdict is uncertain and says to check which clearance was given."""
    from rotordiag.models.pipeline import diagnose_recording
    from rotordiag.models.predict import load_bundle
    from tests.service_util import simulated_channels

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)
    fs, ch = simulated_channels(misalignment=delta, record_revs=48)
    chans = [ProbeChannel(b, a, "um", d) for b, a, d in ch]
    right, _ = diagnose_recording(bundle, Recording(fs, chans, speed_rpm=1800.0, clearance_um=CLEARANCE_UM))
    assert right.status == "confident" and not right.reasons
    slip, _ = diagnose_recording(bundle, Recording(fs, chans, speed_rpm=1800.0, clearance_um=2 * CLEARANCE_UM))
    codes = [r["code"] for r in slip.reasons]
    assert "clearance_diametral" in codes and slip.status == "uncertain"
    msg = next(r["message"] for r in slip.reasons if r["code"] == "clearance_diametral")
    assert [v.value_um for v in msg.values["clearance"].values.values()] == [700.0]     # the stated one, typed
    assert msg.values["ood_half"] < msg.values["ood_score"]
    # given per bearing, every bearing's is halved
    per_bearing, _ = diagnose_recording(bundle, Recording(fs, chans, speed_rpm=1800.0,
                                                          clearance_um={b: 2 * CLEARANCE_UM for b in (1, 2, 3, 4)}))
    assert "clearance_diametral" in [r["code"] for r in per_bearing.reasons]


@pytest.mark.parametrize("clearance", [CLEARANCE_UM, {1: 300.0, 2: 350.0, 3: 140.0, 4: 400.0}])
def test_the_scaled_row_is_the_features_at_that_clearance(clearance):
    """features.with_scale(fr, clearance_factor=0.5) equals a second extraction at half the clearance, every feature
    (bearing 3 at 140 µm: its centreline, at an eccentricity of 1.24, is beyond CENTRELINE_MAX_ECC at 70 µm)."""
    import numpy as np

    from rotordiag.features import extract_features, with_scale
    from tests.service_util import simulated_channels

    fs, ch = simulated_channels(misalignment=0.3, record_revs=48)
    chans = [ProbeChannel(b, a, "um", d) for b, a, d in ch]
    fr = extract_features(Recording(fs, chans, speed_rpm=1800.0, clearance_um=clearance))
    half = clearance / 2 if not isinstance(clearance, dict) else {b: c / 2 for b, c in clearance.items()}
    again = extract_features(Recording(fs, chans, speed_rpm=1800.0, clearance_um=half))
    scaled = with_scale(fr, clearance_factor=0.5)
    np.testing.assert_allclose(scaled.values, again.values, rtol=1e-12, atol=0, equal_nan=True)
    if isinstance(clearance, dict):
        assert np.isfinite(fr["b3_centre_ecc_per_c"]) and np.isnan(again["b3_centre_ecc_per_c"])


def test_the_second_reading_scores_as_the_verdict_does():
    """rotordiag.models.predict.ood_score_and_class is the verdict's OOD score and class, without the rest of the verdict."""
    from rotordiag.features import extract_features
    from rotordiag.models.pipeline import diagnose
    from rotordiag.models.predict import load_bundle, ood_score_and_class
    from tests.service_util import simulated_channels

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)
    fs, ch = simulated_channels(misalignment=0.3, record_revs=48)
    chans = [ProbeChannel(b, a, "um", d) for b, a, d in ch]
    for bearings in ((1, 2, 3, 4), (1, 2, 4)):            # the second: answered from a probe set, bearing 4 left out
        fr = extract_features(Recording(fs, [c for c in chans if c.bearing in bearings], speed_rpm=1800.0,
                                        clearance_um=CLEARANCE_UM))
        v = diagnose(bundle, fr)
        assert ood_score_and_class(bundle, fr) == (pytest.approx(v.ood_score, rel=1e-12), v.model_severity)


def test_the_scaled_row_is_the_features_of_scaled_numbers():
    """features.with_scale(fr, length_factor=2) equals a second extraction of the channels × 2 (with 0.2 µm of
    noise scaled along: the phase-noise gate and every ratio are scale-free), and both at once compose."""
    import numpy as np

    from rotordiag.features import extract_features, with_scale
    from tests.service_util import simulated_channels

    fs, ch = simulated_channels(misalignment=0.3, record_revs=48)
    rng = np.random.default_rng(3)
    noisy = [(b, a, d + rng.normal(0.0, 0.2, d.size)) for b, a, d in ch]
    fr = extract_features(Recording(fs, [ProbeChannel(b, a, "um", d) for b, a, d in noisy], speed_rpm=1800.0,
                                    clearance_um=CLEARANCE_UM))
    doubled = extract_features(Recording(fs, [ProbeChannel(b, a, "um", 2.0 * d) for b, a, d in noisy],
                                         speed_rpm=1800.0, clearance_um=CLEARANCE_UM))
    np.testing.assert_allclose(with_scale(fr, length_factor=2.0).values, doubled.values, rtol=1e-9, atol=1e-9,
                               equal_nan=True)
    both = extract_features(Recording(fs, [ProbeChannel(b, a, "um", 2.0 * d) for b, a, d in noisy],
                                      speed_rpm=1800.0, clearance_um=CLEARANCE_UM / 2))
    np.testing.assert_allclose(with_scale(fr, length_factor=2.0, clearance_factor=0.5).values, both.values,
                               rtol=1e-9, atol=1e-9, equal_nan=True)
