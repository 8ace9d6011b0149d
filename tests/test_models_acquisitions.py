"""Bearings either side of the coupling recorded in separate acquisitions (models.acquisitions): never confident."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording

REGISTRY = Path(__file__).resolve().parent.parent / "models" / "default_registry"


@pytest.fixture(scope="module")
def bundle():
    from rotordiag.models.predict import load_bundle

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    return load_bundle(REGISTRY)


def _recording(misalignment: float, late_samples: int = 0, **kw) -> Recording:
    """The default plant at 1800 r/min; bearings 3 and 4 read ``late_samples`` later (a second take)."""
    from tests.service_util import simulated_channels

    fs, ch = simulated_channels(misalignment=misalignment, record_revs=48)
    n = len(ch[0][2]) - late_samples
    chans = [ProbeChannel(b, a, "um", np.asarray(d)[late_samples:late_samples + n] if b >= 3 else np.asarray(d)[:n])
             for b, a, d in ch]
    return Recording(fs, chans, speed_rpm=1800.0, clearance_um=350.0, **kw)


@pytest.mark.parametrize("misalignment", [0.0, 0.3])
def test_coupling_bearings_in_separate_takes_are_never_confident(bundle, misalignment):
    """Bearings 3 and 4 taken 5 ms later: stated as a second take, the verdict is uncertain and says why and what to
    do; the phase across the coupling is then not what the model read."""
    from rotordiag.models.diagnosis import diagnose_recording

    plain, _ = diagnose_recording(bundle, _recording(misalignment))
    assert plain.status == "confident" and not plain.reasons
    late = int(round(0.005 * 2048.0))
    stated, fr = diagnose_recording(bundle, _recording(misalignment, late, acquisitions="1,2;3,4"))
    assert stated.status == "uncertain"
    reason = next(r for r in stated.reasons if r["code"] == "separate_acquisitions")
    assert reason["status"] == "uncertain" and "(1,2;3,4)" in reason["message"]
    assert "record bearings 2 and 3 in one acquisition" in reason["message"]
    assert np.isnan(fr["dphase_1x_b2_b3_x_deg"]) and np.isnan(fr["dphase_2x_b2_b3_y_deg"])


def test_other_pairs_split_leave_the_verdict(bundle):
    """Bearing 1 (or 4) alone in a take: the coupling's phase is measured, the model does not read the phase between
    bearings 1 and 2 (3 and 4) much, so the verdict is the one of the recording sampled together, without the
    reason."""
    from rotordiag.models.diagnosis import diagnose_recording

    for misalignment in (0.0, 0.3):
        plain, _ = diagnose_recording(bundle, _recording(misalignment))
        for groups in ("1;2,3,4", "1,2,3;4", "1;2,3;4"):
            v, fr = diagnose_recording(bundle, _recording(misalignment, acquisitions=groups))
            assert "separate_acquisitions" not in [r["code"] for r in v.reasons]
            assert v.status == plain.status and v.severity == plain.severity
            assert v.probabilities == pytest.approx(plain.probabilities, abs=0.01)
            assert np.isfinite(fr["dphase_1x_b2_b3_x_deg"])
