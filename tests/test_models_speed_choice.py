"""A doubtful estimated speed judged by the model (models.checks.speed_choice; issue 15, item 6).

The choice's logic is tested with a stand-in for the model's judgement that calls a recording out of distribution
at every speed but the one it is told is the machine's; the pipeline's cost (features once per speed hypothesis)
and the verdict's honesty (``speed_ambiguous``, never ``confident``) with the shipped model.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

import rotordiag.models.checks.speed_choice as sc
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
    """A stand-in for the model's judgement (``models.checks.speed_choice.Judge``): in distribution (score
    ``score_in``) only within 0.5 % of ``in_family_rpm``; records each speed it was asked about."""
    asked: list[float] = []

    def judge(rpm):
        asked.append(rpm)
        inside = in_family_rpm is not None and abs(rpm / in_family_rpm - 1) <= 5e-3
        return (score_in if inside else score_out), not inside

    return judge, asked


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


def test_an_out_of_distribution_verdict_at_a_doubtful_estimate_moves_to_the_in_family_reading(whip):
    rec, fr = whip
    judge, asked = _judge(TRUE_RPM)
    choice = sc.choose_speed(rec, fr, 2.0, True, judge)
    assert choice is not None and choice.chosen_rpm == pytest.approx(TRUE_RPM, rel=5e-3)
    assert choice.chosen_ood_score == 0.6 and choice.estimate_ood_score == 2.0
    assert choice.estimate_rpm == fr.speed_rpm and len(choice.tried) == len(speed_alternatives_rpm(rec, fr.speed_rpm))
    assert asked == [t[0] for t in choice.tried]                          # each reading judged once
    notes = sc.chosen_speed_notes(fr, choice)
    chosen = notes[0]
    assert chosen.code == "speed_chosen_by_model" and speed_in_doubt(chosen)
    assert chosen.values["estimate_rpm"] == fr.speed_rpm and chosen.values["speed_rpm"] == choice.chosen_rpm
    assert chosen.values["n_tried"] == len(choice.tried) and chosen.values["chosen_ood"] == 0.6
    # the estimator's own doubt is kept, marked as about the estimate
    kept = [w for w in notes if w.code == "speed_doubt_at_estimate"]
    assert kept and [w.values["note"] for w in kept] == [w for w in fr.warnings if speed_in_doubt(w)]
    assert all(w.values["estimate_rpm"] == fr.speed_rpm for w in kept)


@pytest.mark.parametrize("case", ["in distribution", "every reading out", "gain too small", "speed given"])
def test_the_estimate_stays_when_there_is_no_case_for_another_reading(whip, case):
    rec, fr = whip
    estimate_score, ood = 2.0, True
    if case == "in distribution":                   # the verdict at the estimate is in family: nothing is tried
        judge, asked = _judge(fr.speed_rpm)
        estimate_score, ood = 0.6, False
    elif case == "every reading out":               # another design: out of distribution at every speed
        judge, asked = _judge(None)
    elif case == "gain too small":                  # in family elsewhere, but hardly better than the estimate
        judge, asked = _judge(TRUE_RPM, score_in=0.95, score_out=1.0)
        estimate_score = 1.0
    else:
        rec = replace(rec, speed_rpm=1230.0)
        fr = extract_features(rec)
        judge, asked = _judge(TRUE_RPM)
    choice = sc.choose_speed(rec, fr, estimate_score, ood, judge)
    if case in ("in distribution", "speed given"):
        assert choice is None and asked == []
    else:
        assert choice is not None and choice.chosen_rpm is None and len(choice.tried) >= 4


def _count_extractions(monkeypatch):
    """Wrap the pipeline's ``extract_features``; returns the list of speeds it was called at."""
    from rotordiag.models import pipeline

    calls: list[float | None] = []
    real = pipeline.extract_features

    def counted(recording, **kw):
        calls.append(kw.get("speed_estimate_rpm"))
        return real(recording, **kw)

    monkeypatch.setattr(pipeline, "extract_features", counted)
    return calls


def test_the_pipeline_extracts_features_once_per_speed_hypothesis(whip, monkeypatch):
    """Every reading the speed choice judges is extracted once, the chosen one not again (its notes are changed,
    ``features.with_speed_notes``), and the verdict at it is never confident (``speed_ambiguous``)."""
    from rotordiag.models import pipeline
    from rotordiag.models.predict import load_bundle

    rec, fr = whip
    alts = speed_alternatives_rpm(rec, fr.speed_rpm)
    pick = min(alts, key=lambda a: abs(a / TRUE_RPM - 1))
    judged: list[tuple[float, bool] | None] = []

    def choose(recording, fr_, ood_score, ood, judge):    # the model's judgement asked at every reading
        for rpm in alts:
            judged.append(judge(rpm))
        return sc.SpeedChoice(fr_.speed_rpm, 2.0, tuple((a, 0.5, False) for a in alts), pick, 0.5)

    monkeypatch.setattr(pipeline, "choose_speed", choose)
    calls = _count_extractions(monkeypatch)
    v, fr2 = pipeline.diagnose_recording(load_bundle(REGISTRY), rec)
    assert sorted(calls, key=str) == sorted([None, *alts], key=str)         # once per hypothesis, never more
    assert all(j is not None for j in judged)
    assert fr2.speed_rpm == pytest.approx(pick) and v.speed_rpm == pytest.approx(pick)
    assert fr2.warnings[0].code == "speed_chosen_by_model" and v.speed_source == "estimated"
    assert "speed_ambiguous" in [r["code"] for r in v.reasons] and v.status != "confident"


def test_given_features_are_not_extracted_again(whip, monkeypatch):
    """Features handed in (the service checks them before the verdict) are the estimate's: no extraction at all
    when the speed is not in doubt out of distribution."""
    from rotordiag.models import pipeline
    from rotordiag.models.predict import load_bundle

    rec, fr = whip
    monkeypatch.setattr(pipeline, "choose_speed", lambda *a: None)
    calls = _count_extractions(monkeypatch)
    v, fr2 = pipeline.diagnose_recording(load_bundle(REGISTRY), rec, fr=fr)
    assert calls == [] and fr2 is fr and v.speed_rpm == fr.speed_rpm


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
