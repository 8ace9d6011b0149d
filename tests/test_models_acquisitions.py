"""Bearings either side of the coupling recorded in separate acquisitions (models.checks.acquisitions): never confident."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotordiag.core.reasons import CATALOGUE
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
    do; the phase across the coupling is then not what the model read. (One take: both are confident with v0004; the
    aligned one was doubted for its Δ interval alone, reaching moderate, with v0002 and v0003.)"""
    from rotordiag.models.pipeline import diagnose_recording

    plain, _ = diagnose_recording(bundle, _recording(misalignment))
    assert [r["code"] for r in plain.reasons] == []
    assert plain.status == "confident"
    late = int(round(0.005 * 2048.0))
    stated, fr = diagnose_recording(bundle, _recording(misalignment, late, acquisitions="1,2;3,4"))
    assert stated.status == "uncertain"
    reason = next(r for r in stated.reasons if r["code"] == "separate_acquisitions")
    values = reason["message"].values
    assert reason["status"] == "uncertain" and values["acquisitions"] == "1,2;3,4"
    assert (values["bearing_a"], values["bearing_b"]) == (2, 3)
    assert np.isnan(fr["dphase_1x_b2_b3_x_deg"]) and np.isnan(fr["dphase_2x_b2_b3_y_deg"])


def test_other_pairs_split_leave_the_verdict(bundle):
    """Bearing 1 (or 4) alone in a take: the coupling's phase is measured, the model does not read the phase between
    bearings 1 and 2 (3 and 4) much, so the verdict is the one of the recording sampled together, without the
    reason."""
    from rotordiag.models.pipeline import diagnose_recording

    for misalignment in (0.0, 0.3):
        plain, _ = diagnose_recording(bundle, _recording(misalignment))
        for groups in ("1;2,3,4", "1,2,3;4", "1;2,3;4"):
            v, fr = diagnose_recording(bundle, _recording(misalignment, acquisitions=groups))
            assert "separate_acquisitions" not in [r["code"] for r in v.reasons]
            assert v.status == plain.status and v.severity == plain.severity
            assert v.probabilities == pytest.approx(plain.probabilities, abs=0.01)
            assert np.isfinite(fr["dphase_1x_b2_b3_x_deg"])


def test_the_reason_reads_the_recording_at_both_coupling_phases(bundle):
    """With the coupling's phase not measured, the reason gives the model's class with the shaft ends in phase (0°)
    and in anti-phase (180°) across the coupling — the healthy plant reads aligned in phase, the severely misaligned
    one the same either way — and those readings are the classifier's own on rows with that phase put in."""
    from rotordiag.models.checks.acquisitions import COUPLING_PHASES_DEG, coupling_phase_rows
    from rotordiag.models.pipeline import diagnose_recording
    from rotordiag.models.predict import _model_row, fast_predictor

    late = int(round(0.005 * 2048.0))
    messages = {}
    for misalignment in (0.0, 0.5):
        v, fr = diagnose_recording(bundle, _recording(misalignment, late, acquisitions="1,2;3,4"))
        msg = next(r["message"] for r in v.reasons if r["code"] == "separate_acquisitions")
        assert msg.template == CATALOGUE["separate_acquisitions"].templates[
            "phase_read_same" if msg.values["in_phase"] == msg.values["anti_phase"] else "phase_read"]
        m = _model_row(bundle, fr)
        rows = coupling_phase_rows(m.names, m.row)
        assert rows is not None and rows.shape == (len(COUPLING_PHASES_DEG), len(m.names))
        cols = [i for i, n in enumerate(m.names) if "dphase_" in n and "_b2_b3_" in n]
        assert np.isnan(m.row[cols]).all() and (rows[0, cols] == 0.0).all() and (rows[1, cols] == 180.0).all()
        fast = fast_predictor(m.model)
        called = [str(m.model.classes_[k]) for k in m.model.band_index(fast.predict_proba(rows), rows)]
        assert (msg.values["in_phase"], msg.values["anti_phase"]) == (called[0], called[1])
        messages[misalignment] = (called, msg)
    assert messages[0.0][0][0] == "aligned"
    severe_called, severe_msg = messages[0.5]
    assert severe_called[0] == severe_called[1] != "aligned"
    assert severe_msg.template == CATALOGUE["separate_acquisitions"].templates["phase_read_same"]
