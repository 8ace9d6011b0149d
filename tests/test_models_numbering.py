"""Bearings numbered from the other end (models.checks.numbering)."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording, extract_features
from rotordiag.models.checks.numbering import NUMBERING_OOD_RATIO, has_every_bearing, mirrored_row, numbering_reason

REGISTRY = Path(__file__).resolve().parent.parent / "models" / "default_registry"


def _renumbered(rec: Recording) -> Recording:
    """The recording itself with every bearing b numbered 5 − b (the reference mirrored_row must match)."""
    return dataclasses.replace(rec, channels=[dataclasses.replace(c, bearing=5 - c.bearing) for c in rec.channels])


@pytest.fixture(scope="module")
def recording():
    from tests.service_util import simulated_channels

    fs, ch = simulated_channels(misalignment=0.3)
    return Recording(fs, [ProbeChannel(b, a, "um", d) for b, a, d in ch], speed_rpm=1800.0, clearance_um=350.0)


def test_the_renumbered_row_is_the_renumbered_recordings_features(recording):
    """mirrored_row on the features equals the features of the recording renumbered 4-3-2-1 (every feature, the
    phase differences across bearings included; the motion type and speed are the same computation)."""
    fr, fr_m = extract_features(recording), extract_features(_renumbered(recording))
    names = list(fr.names)
    got, want = mirrored_row(names, np.asarray(fr.values, dtype=float)), np.asarray(fr_m.values, dtype=float)
    assert np.array_equal(np.isnan(got), np.isnan(want))
    ok = np.isfinite(want)
    np.testing.assert_allclose(got[ok], want[ok], rtol=1e-9, atol=1e-9)
    assert any(n.startswith("dphase_") and np.isfinite(v) for n, v in zip(names, want))
    assert has_every_bearing(names, want)
    three = np.asarray(want, dtype=float).copy()
    three[names.index("b4_1x_major_um_pp")] = np.nan
    assert not has_every_bearing(names, three)


def test_the_numbering_is_doubted_only_when_the_other_one_is_markedly_more_like_the_family():
    r = numbering_reason(0.6, NUMBERING_OOD_RATIO * 0.6, "moderate", "aligned")
    assert r is not None and r.code == "bearing_numbering" and r.status == "uncertain"
    assert r.variant == "default" and r.values == {"ood_score": 0.6, "other_ood_score": NUMBERING_OOD_RATIO * 0.6,
                                                   "call": "moderate", "other_call": "aligned"}
    assert numbering_reason(0.6, 0.58, "moderate", "aligned") is None
    same = numbering_reason(0.6, 0.3, "slight", "slight")                  # was "called slight instead of slight"
    assert same is not None and same.variant == "same_call" and same.values["call"] == "slight"
    assert "other_call" not in same.values
    assert numbering_reason(0.0, 0.0, "aligned", "aligned") is None


def test_shipped_model_doubts_a_train_numbered_from_the_exciter_end(recording):
    """The simulated default plant numbered 4-3-2-1: never confident — out of distribution already, or doubted for
    its numbering; numbered right, no such reason."""
    from rotordiag.models.pipeline import diagnose
    from rotordiag.models.predict import load_bundle

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)
    right = diagnose(bundle, extract_features(recording))
    assert "bearing_numbering" not in [r["code"] for r in right.reasons]
    wrong = diagnose(bundle, extract_features(_renumbered(recording)))
    assert wrong.status != "confident"
    assert wrong.ood or "bearing_numbering" in [r["code"] for r in wrong.reasons]
