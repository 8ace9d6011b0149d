"""Bearings numbered from the other end (models.numbering)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rotordiag.features import ProbeChannel, Recording
from rotordiag.models.numbering import mirrored

REGISTRY = Path(__file__).resolve().parent.parent / "models" / "default_registry"


def test_mirrored_numbers_each_bearing_from_the_other_end_with_its_clearance():
    t = np.arange(512) / 512.0
    chans = [ProbeChannel(b, a, "um", np.sin(2 * np.pi * (b + a / 90) * t), slow_roll_um_pp={1: (1.0, 0.0)})
             for b in (1, 2, 3, 4) for a in (45.0, 135.0)]
    rec = Recording(512.0, chans, keyphasor_times_s=np.arange(0.0, 1.0, 1 / 30), speed_rpm=1800.0,
                    clearance_um={1: 300.0, 2: 310.0, 3: 120.0, 4: 110.0})
    m = mirrored(rec)
    assert [c.bearing for c in m.channels] == [4, 4, 3, 3, 2, 2, 1, 1]
    assert [c.angle_deg for c in m.channels] == [c.angle_deg for c in rec.channels]
    assert all(a.data is b.data and a.slow_roll_um_pp == b.slow_roll_um_pp for a, b in zip(m.channels, rec.channels))
    assert m.clearance_um == {4: 300.0, 3: 310.0, 2: 120.0, 1: 110.0}
    assert mirrored(m).channels == rec.channels and m.speed_rpm == rec.speed_rpm


def test_shipped_model_doubts_a_train_numbered_from_the_exciter_end():
    """The simulated default plant numbered 4-3-2-1 is more like the training family read the other way round: the
    verdict is never confident and says what to check; numbered right, no such reason."""
    from rotordiag.models.predict import load_bundle
    from rotordiag.models.speed_choice import diagnose_recording
    from tests.service_util import simulated_channels

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)
    fs, ch = simulated_channels(misalignment=0.3)
    rec = Recording(fs, [ProbeChannel(b, a, "um", d) for b, a, d in ch], speed_rpm=1800.0, clearance_um=350.0)
    right, _ = diagnose_recording(bundle, rec)
    assert "bearing_numbering" not in [r["code"] for r in right.reasons]
    wrong, _ = diagnose_recording(bundle, mirrored(rec))
    # out of distribution already (never confident), or doubted for its numbering
    assert wrong.status != "confident"
    assert wrong.ood or "bearing_numbering" in [r["code"] for r in wrong.reasons]


def _verdict(*, ood, ood_score, status="confident"):
    from rotordiag.models.predict import Verdict

    return Verdict(severity="moderate", probabilities={"moderate": 0.9}, misalignment=0.2,
                   misalignment_interval=(0.15, 0.3), interval_level=0.9, offset_um=None, offset_interval_um=None,
                   motion_type=None, top_features=[], ood=ood, ood_score=ood_score, speed_rpm=1800.0,
                   model_version=None, bands={}, status=status, model_severity="moderate")


def test_the_numbering_is_doubted_when_the_other_one_is_markedly_more_like_the_family(monkeypatch):
    """check_numbering's rule with stand-in verdicts: the mirrored reading's OOD score at or below 0.95 of the
    recording's own adds the reason (a confident verdict becomes uncertain); above it, or for an out-of-distribution
    verdict or fewer than four bearings, the verdict is returned as it is."""
    from types import SimpleNamespace

    from rotordiag.models import numbering

    rec = Recording(512.0, [ProbeChannel(b, a, "um", np.sin(np.arange(512) * (0.1 + b))) for b in (1, 2, 3, 4)
                            for a in (45.0, 135.0)], speed_rpm=1800.0)
    fr = SimpleNamespace(bearings={1: 0, 2: 0, 3: 0, 4: 0}, speed_rpm=1800.0, speed_source="given")
    for other_score, expect in ((0.57, True), (0.58, False)):
        monkeypatch.setattr(numbering, "extract_features", lambda r, speed_estimate_rpm=None: r)
        monkeypatch.setattr(numbering, "diagnose", lambda bundle, r, clearance_um=None, top_k=5, s=other_score:
                            SimpleNamespace(ood_score=s, model_severity="aligned"))
        v = _verdict(ood=False, ood_score=0.6)
        out = numbering.check_numbering(None, rec, fr, v)                 # type: ignore[arg-type]
        assert ([r["code"] for r in out.reasons] == ["bearing_numbering"]) is expect
        assert out.status == ("uncertain" if expect else "confident")
    v_ood = _verdict(ood=True, ood_score=1.6, status="uncertain")
    assert numbering.check_numbering(None, rec, fr, v_ood) is v_ood       # type: ignore[arg-type]
    three = SimpleNamespace(bearings={1: 0, 2: 0, 3: 0}, speed_rpm=1800.0, speed_source="given")
    assert numbering.check_numbering(None, rec, three, v) is v             # type: ignore[arg-type]
