"""A doubtful estimated speed judged by the model (models.speed_choice; issue 15, item 6).

The choice's logic is tested with a stand-in for ``diagnose`` that calls a recording out of distribution
at every speed but the one it is told is the machine's; the verdict's honesty (``speed_ambiguous``, never
``confident``) with the shipped model's own ``diagnose``.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import pytest

import rotordiag.models.speed_choice as sc
from rotordiag.features import Note, extract_features, speed_alternatives_rpm, speed_in_doubt

from .test_features_speed import _whip_recording

TRUE_RPM = 3075.0
REGISTRY = Path(__file__).resolve().parent.parent / "models" / "default_registry"


@pytest.fixture(scope="module")
def whip():
    """Oil whip at 20.5 Hz, 60 µm, over a 1X of 0.08 µm at 3075 r/min in 0.3 µm noise: the estimator reads
    the whip (1230 r/min) and says it is in doubt."""
    rec = _whip_recording(TRUE_RPM, 20.5, one_x_um=0.08, comb_um=0.0, noise_um=0.3)
    fr = extract_features(rec)
    assert fr.speed_rpm == pytest.approx(60 * 20.5, rel=5e-3)
    assert any(speed_in_doubt(w) for w in fr.warnings)
    return rec, fr


def _judge(in_family_rpm: float | None, *, score_in: float = 0.6, score_out: float = 2.0):
    """A stand-in for ``models.predict.diagnose``: in distribution (score ``score_in``) only within 0.5 % of
    ``in_family_rpm``; records each speed it was asked about."""
    asked: list[float] = []

    def diagnose(bundle, fr, *, clearance_um=None, top_k=5):
        asked.append(fr.speed_rpm)
        inside = in_family_rpm is not None and abs(fr.speed_rpm / in_family_rpm - 1) <= 5e-3
        return SimpleNamespace(ood=not inside, ood_score=score_in if inside else score_out, speed_rpm=fr.speed_rpm)

    return diagnose, asked


def test_alternatives_hold_the_running_speed_and_the_estimates_double_and_half(whip):
    rec, fr = whip
    alts = speed_alternatives_rpm(rec, fr.speed_rpm)
    assert alts[:2] == pytest.approx([2 * fr.speed_rpm, fr.speed_rpm / 2])
    assert any(abs(a / TRUE_RPM - 1) <= 5e-3 for a in alts)
    assert all(abs(a / fr.speed_rpm - 1) > 5e-3 for a in alts)                  # the estimate itself is not offered
    assert all(abs(a / b - 1) > 5e-3 for i, a in enumerate(alts) for b in alts[:i])


def test_alternatives_respect_the_stated_range_and_a_known_speed(whip):
    rec, fr = whip
    ranged = replace(rec, speed_range_rpm=(2000.0, 3500.0))
    alts = speed_alternatives_rpm(ranged, fr.speed_rpm)
    assert alts and all(2000.0 <= a <= 3500.0 for a in alts)
    assert speed_alternatives_rpm(replace(rec, speed_rpm=TRUE_RPM), fr.speed_rpm) == []


def test_features_at_a_speed_estimated_elsewhere(whip):
    rec, _ = whip
    note = Note("speed_varies", variation_pct=0.5)
    fr = extract_features(rec, speed_estimate_rpm=TRUE_RPM, speed_notes=[note])
    assert fr.speed_rpm == TRUE_RPM and fr.speed_source == "estimated"
    assert fr.warnings[0] is note or fr.warnings[0] == note
    with pytest.raises(TypeError, match="speed_notes"):                   # words are no note
        extract_features(rec, speed_estimate_rpm=TRUE_RPM, speed_notes=["speed estimate ambiguous: a note"])
    # a speed from elsewhere is never the signal's own reading: put in doubt unless a note already does
    assert fr.warnings[1].code == "speed_estimated_elsewhere" and fr.warnings[1].values == {"speed_rpm": TRUE_RPM}
    doubtful = extract_features(rec, speed_estimate_rpm=TRUE_RPM,
                                speed_notes=[Note("speed_estimate_ambiguous", detail="chosen")])
    assert sum(speed_in_doubt(w) for w in doubtful.warnings) == 1
    assert [w.code for w in doubtful.warnings] == ["speed_estimate_ambiguous"]
    given = extract_features(replace(rec, speed_rpm=2999.0), speed_estimate_rpm=TRUE_RPM)
    assert given.speed_rpm == 2999.0 and given.speed_source == "given"          # a given speed wins
    with pytest.raises(ValueError, match="speed_estimate_rpm"):
        extract_features(rec, speed_estimate_rpm=-1.0)


def test_an_out_of_distribution_verdict_at_a_doubtful_estimate_moves_to_the_in_family_reading(whip, monkeypatch):
    rec, fr = whip
    diagnose, asked = _judge(TRUE_RPM)
    monkeypatch.setattr(sc, "diagnose", diagnose)
    v, fr2, choice = sc.choose_speed(None, rec, fr, diagnose(None, fr))
    assert fr2.speed_rpm == pytest.approx(TRUE_RPM, rel=5e-3) and v.speed_rpm == fr2.speed_rpm
    assert fr2.speed_source == "estimated"
    chosen = fr2.warnings[0]
    assert chosen.code == "speed_chosen_by_model" and speed_in_doubt(chosen)
    assert chosen.values["estimate_rpm"] == fr.speed_rpm and chosen.values["speed_rpm"] == choice.chosen_rpm
    assert chosen.values["n_tried"] == len(choice.tried)
    assert choice is not None and choice.chosen_rpm == pytest.approx(TRUE_RPM, rel=5e-3)
    assert choice.estimate_rpm == fr.speed_rpm and len(choice.tried) == len(speed_alternatives_rpm(rec, fr.speed_rpm))
    # the estimator's own doubt is kept, marked as about the estimate
    kept = [w for w in fr2.warnings if w.code == "speed_doubt_at_estimate"]
    assert kept and [w.values["note"] for w in kept] == [w for w in fr.warnings if speed_in_doubt(w)]
    assert all(w.values["estimate_rpm"] == fr.speed_rpm for w in kept)


@pytest.mark.parametrize("case", ["in distribution", "every reading out", "gain too small", "speed given"])
def test_the_estimate_stays_when_there_is_no_case_for_another_reading(whip, monkeypatch, case):
    rec, fr = whip
    if case == "in distribution":                   # the verdict at the estimate is in family: nothing is tried
        diagnose, asked = _judge(fr.speed_rpm)
    elif case == "every reading out":               # another design: out of distribution at every speed
        diagnose, asked = _judge(None)
    elif case == "gain too small":                  # in family elsewhere, but hardly better than the estimate
        diagnose, asked = _judge(TRUE_RPM, score_in=0.95, score_out=1.0)
    else:
        rec = replace(rec, speed_rpm=1230.0)
        fr = extract_features(rec)
        diagnose, asked = _judge(TRUE_RPM)
    monkeypatch.setattr(sc, "diagnose", diagnose)
    v0 = diagnose(None, fr)
    v, fr2, choice = sc.choose_speed(None, rec, fr, v0)
    assert v is v0 and fr2 is fr
    if case in ("in distribution", "speed given"):
        assert choice is None and asked == [fr.speed_rpm]
    else:
        assert choice is not None and choice.chosen_rpm is None and len(choice.tried) >= 4


def test_the_verdict_at_a_chosen_speed_is_never_confident(whip, monkeypatch):
    """The features the choice hands on carry the doubt: the shipped model's own ``diagnose`` gives the
    ``speed_ambiguous`` reason, so the verdict is at best ``uncertain``."""
    from rotordiag.models.predict import diagnose as real_diagnose
    from rotordiag.models.predict import load_bundle

    rec, fr = whip
    fake, _ = _judge(TRUE_RPM)
    monkeypatch.setattr(sc, "diagnose", fake)
    _, fr2, _ = sc.choose_speed(None, rec, fr, fake(None, fr))
    v = real_diagnose(load_bundle(REGISTRY), fr2)
    assert v.speed_rpm == pytest.approx(TRUE_RPM, rel=5e-3) and v.speed_source == "estimated"
    assert "speed_ambiguous" in [r["code"] for r in v.reasons] and v.status != "confident"


def test_diagnose_recording_is_extract_diagnose_and_choose(whip, monkeypatch):
    from rotordiag.models import diagnosis

    rec, fr = whip
    diagnose, _ = _judge(TRUE_RPM)
    monkeypatch.setattr(sc, "diagnose", diagnose)
    monkeypatch.setattr(diagnosis, "diagnose", diagnose)
    v, fr2 = diagnosis.diagnose_recording(None, rec)
    assert fr2.speed_rpm == pytest.approx(TRUE_RPM, rel=5e-3) and v.speed_rpm == fr2.speed_rpm


def test_speed_notes_changed_without_extracting_again_give_the_extracted_result(whip):
    """``features.with_speed_notes`` (the chosen reading's notes, issue 43: features once per speed hypothesis)
    gives what extracting again with those notes gives, field for field."""
    import pickle

    from rotordiag.features import with_speed_notes

    rec, _ = whip
    notes = [Note("speed_estimate_ambiguous", detail="chosen by the model"),
             Note("speed_doubt_at_estimate", estimate_rpm=1230.0, note=Note("speed_not_converged", speed_rpm=1230.0))]
    fr = extract_features(rec, speed_estimate_rpm=TRUE_RPM)
    noted = with_speed_notes(fr, notes)
    again = extract_features(rec, speed_estimate_rpm=TRUE_RPM, speed_notes=notes)
    assert noted is not None and list(noted.warnings[:2]) == notes
    assert pickle.dumps(noted) == pickle.dumps(again)
    assert with_speed_notes(extract_features(replace(rec, speed_rpm=TRUE_RPM)), notes) is None   # a given speed
