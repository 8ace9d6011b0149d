"""The verdict pipeline (models.pipeline, issue 43 item 1) and the warning codes of a verdict (item 2).

The pipeline's verdicts are pinned by tests/test_shipped_verdicts.py and compared before/after by
benchmarks/compare_verdicts.py; here: every check has the one signature and lives in models/checks/, the decision
policy stored with the model is the one applied, and every warning carries its catalogue code.
"""
from __future__ import annotations

import inspect
import typing
from dataclasses import replace

import numpy as np
import pytest

from rotordiag.core.notes import NOTES, Note
from rotordiag.features.examples import example_path
from rotordiag.models import pipeline
from rotordiag.models.checks import CheckContext
from rotordiag.models.checks.bearing_sets import bearing_set_check
from rotordiag.models.checks.one_position import one_position_check
from rotordiag.models.status import Reason
from tests.service_util import shipped_registry_usable

needs_model = pytest.mark.skipif(not shipped_registry_usable(), reason="no usable shipped model registry")


@pytest.fixture(scope="module")
def bundle():
    from rotordiag.models.predict import load_bundle
    from rotordiag.service.core.config import SHIPPED_REGISTRY_DIR

    return load_bundle(SHIPPED_REGISTRY_DIR)


@pytest.fixture(scope="module")
def confident_example():
    """The shipped severe example (with its clearance): a verdict the shipped model gives confidently, without a
    reason (the aligned example's Δ interval reaches moderate with v0002: tests/test_shipped_verdicts.py)."""
    from rotordiag.models.diagnose_files import load_options, read_recording

    path = example_path("severe.csv")
    return read_recording(path, options=load_options(path, None, {})).recording


@pytest.mark.parametrize("check", [bearing_set_check, one_position_check, *pipeline.SCORE_CHECKS,
                                   *pipeline.DOUBT_CHECKS],
                         ids=lambda c: c.__name__)
def test_every_check_has_the_one_signature_and_lives_in_the_checks_folder(check):
    assert check.__module__.startswith("rotordiag.models.checks.")
    params = list(inspect.signature(check).parameters.values())
    hints = typing.get_type_hints(check)
    assert len(params) == 1 and hints[params[0].name] is CheckContext
    assert hints["return"] == list[Reason]


def test_the_start_up_check_has_the_same_shape_with_its_own_context():
    """``models.checks.startup.startup_check``: a context in (its own, ``StartupContext``: two stored runs and a
    verdict's call, not a steady recording), the reasons out; it lives in the checks folder."""
    from rotordiag.models.checks.startup import StartupContext, startup_check

    assert startup_check.__module__ == "rotordiag.models.checks.startup"
    params = list(inspect.signature(startup_check).parameters.values())
    hints = typing.get_type_hints(startup_check)
    assert len(params) == 1 and hints[params[0].name] is StartupContext
    assert hints["return"] == list[Reason]


def _context(**kw) -> CheckContext:
    base = dict(fr=None, names=(), row=np.zeros(0), call="aligned", aligned_band="aligned", ood_score=0.5, ood=False,
                classes_of=lambda rows: pytest.fail("no class asked"), ood_of=lambda rows: pytest.fail("no OOD asked"),
                score=lambda fr: pytest.fail("no second reading asked"))
    return CheckContext(**{**base, **kw})


@pytest.mark.parametrize("check", pipeline.DOUBT_CHECKS, ids=lambda c: c.__name__)
def test_the_doubts_read_nothing_without_a_recording(check):
    """Given features alone (``pipeline.diagnose``), the checks that read the recording again find nothing and
    ask the model nothing (the stand-ins fail the test when called)."""
    assert check(_context(status="confident")) == []


@needs_model
def test_the_decision_policy_stored_with_the_model_is_the_one_applied(bundle, confident_example):
    """A card whose policy asks for more probability than the verdict's highest makes the same recording
    ``uncertain`` with ``low_probability``; the shipped card (no policy: the defaults) leaves it confident."""
    v, _ = pipeline.diagnose_recording(bundle, confident_example, clearance_um=350.0)
    assert v.status == "confident" and v.reasons == []
    pmax = max(v.probabilities.values())
    strict = replace(bundle, card={**bundle.card, "decision_policy": {"confident_min_probability": pmax + 1e-6}})
    w, _ = pipeline.diagnose_recording(strict, confident_example, clearance_um=350.0)
    assert w.status == "uncertain" and [r["code"] for r in w.reasons] == ["low_probability"]
    assert w.probabilities == v.probabilities and w.misalignment == v.misalignment     # the model's call unchanged


def test_no_status_threshold_lives_in_the_estimators():
    """The decision policy is one object outside the estimators (``models.status.DecisionPolicy``): the estimator
    module neither imports the status module nor names any of the policy's thresholds (its own thresholds are fitted
    parts of what it scores: the OOD distance's calibration, the envelope's margin, the ordinal false-alarm
    thresholds)."""
    import ast
    from dataclasses import fields
    from pathlib import Path

    import rotordiag.models.estimators as est
    from rotordiag.models.status import DecisionPolicy

    source = Path(est.__file__).read_text(encoding="utf-8")
    tree = ast.parse(source)
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert not any(m and m.endswith("status") for m in imported)
    policy_names = {f.name for f in fields(DecisionPolicy)} | {f.name.upper() for f in fields(DecisionPolicy)}
    named = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} | \
            {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    assert not (named & policy_names), sorted(named & policy_names)


@needs_model
def test_a_verdict_from_given_features_is_the_recordings_when_nothing_reads_it_again(bundle, confident_example):
    """``pipeline.diagnose`` (features in) is the pipeline without the recording: on a recording no speed choice
    or doubt changes, the same verdict."""
    from rotordiag.features import extract_features

    v, fr = pipeline.diagnose_recording(bundle, confident_example, clearance_um=350.0)
    w = pipeline.diagnose(bundle, extract_features(confident_example), clearance_um=350.0)
    assert w.to_dict() == v.to_dict()


@needs_model
def test_sanity_is_a_stage_of_its_own_run_once_per_reading(bundle, confident_example, monkeypatch):
    """The pipeline extracts without the sanity checks and runs them as their own stage (``read_features``): once
    per extraction, and the verdict's features carry exactly ``check_recording``'s findings."""
    from rotordiag.features import check_recording

    seen: list[str] = []
    real_extract, real_sanity = pipeline.extract_features, pipeline.with_sanity

    def extract(recording, **kw):
        assert kw.get("sanity") is False
        seen.append("features")
        return real_extract(recording, **kw)

    def sanity(recording, fr):
        assert fr.sanity == ()
        seen.append("sanity")
        return real_sanity(recording, fr)

    monkeypatch.setattr(pipeline, "extract_features", extract)
    monkeypatch.setattr(pipeline, "with_sanity", sanity)
    v, fr = pipeline.diagnose_recording(bundle, confident_example, clearance_um=350.0)
    assert seen and seen == ["features", "sanity"] * (len(seen) // 2)
    assert fr.sanity == check_recording(confident_example, fr)
    assert v.status == "confident"


@needs_model
def test_every_warning_carries_its_catalogue_code(bundle):
    """``warning_codes`` (new in the answer) holds the code of each warning, in order; each is the catalogue's and
    the warning's text is its template rendered."""
    from rotordiag.models.diagnose_files import load_options, read_recording

    path = example_path("whirl.csv")
    rec = read_recording(path, options=load_options(path, None, {})).recording
    v, _ = pipeline.diagnose_recording(bundle, rec)
    d = v.to_dict()
    assert d["warning_codes"] and len(d["warning_codes"]) == len(d["warnings"])
    assert d["warning_codes"] == [w.code for w in v.warnings]
    assert all(c in NOTES for c in d["warning_codes"])
    assert "speed_estimate_ambiguous" in d["warning_codes"]            # whirl.csv: the speed estimate in doubt
    assert [Note(w.code, **w.values) for w in v.warnings] == d["warnings"]


def test_a_warning_without_a_code_is_refused_in_the_answer():
    from rotordiag.models.predict import Verdict

    v = Verdict(severity="aligned", probabilities={"aligned": 1.0}, misalignment=0.0, misalignment_interval=(0.0, 0.1),
                interval_level=0.9, offset_um=None, offset_interval_um=None, motion_type=None, top_features=[],
                ood=False, ood_score=0.1, speed_rpm=1800.0, model_version="v", bands={},
                warnings=[Note("speed_varies", variation_pct=0.5)])
    assert v.to_dict()["warning_codes"] == ["speed_varies"]
    with pytest.raises(TypeError, match="catalogue notes"):
        replace(v, warnings=["a sentence with no code"]).to_dict()


def test_the_schema_enumerates_the_warning_catalogue_and_refuses_other_codes():
    from pydantic import ValidationError

    from rotordiag.service.schemas import DiagnoseResponse

    schema = DiagnoseResponse.model_json_schema()
    assert schema["properties"]["warning_codes"]["items"]["enum"] == list(NOTES)
    field = DiagnoseResponse.model_fields["warning_codes"]
    adapter = __import__("pydantic").TypeAdapter(field.annotation)
    assert adapter.validate_python(["speed_varies"]) == ["speed_varies"]
    with pytest.raises(ValidationError):
        adapter.validate_python(["speed_guessed"])                     # a code the catalogue lacks


@needs_model
def test_a_recording_read_by_take_is_extracted_once_per_speed_hypothesis(bundle, monkeypatch):
    """A speed chosen for a recording read take by take (each take with its own keyphasor) takes the reading made
    at that hypothesis: no extraction repeated for its speed notes (``extract_by_take`` reads neither)."""
    from rotordiag.features import Recording
    from rotordiag.models.checks.speed_choice import SpeedChoice
    from tests.test_features_takes import FS_HZ, _channels, _pulses

    delay = 0.0073
    rec = Recording(FS_HZ, _channels(delay), keyphasor_times_s=[_pulses(), _pulses(delay)], acquisitions="1,2;3,4",
                    clearance_um=350.0)
    calls: list[tuple[float | None, int]] = []
    real_extract = pipeline.extract_features

    def extract(recording, **kw):
        calls.append((kw.get("speed_estimate_rpm"), len(kw.get("speed_notes", ()))))
        return real_extract(recording, **kw)

    monkeypatch.setattr(pipeline, "extract_features", extract)
    monkeypatch.setattr(pipeline, "choose_speed", lambda rec, fr, score, ood, judge: SpeedChoice(
        estimate_rpm=float(fr.speed_rpm), estimate_ood_score=score, tried=((2900.0, 0.5, False),), chosen_rpm=2900.0,
        chosen_ood_score=0.5))
    v, fr = pipeline.diagnose_recording(bundle, rec)
    assert sorted(calls, key=repr) == sorted([(None, 0), (2900.0, 0)], key=repr)
    assert fr.speed_source == "keyphasor" and v.speed_rpm == pytest.approx(3000.0, rel=1e-3)
