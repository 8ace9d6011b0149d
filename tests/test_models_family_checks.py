"""The checks that keep a confident verdict off a machine family the model never saw and off a verdict its own
evidence contradicts (issue 48): ``models.checks.family``, ``models.checks.attitude``,
``models.checks.contradiction``, and the training families of ``models.families``.

Each check has a unit case on a built context and an end-to-end case through ``diagnose_recording`` on a shipped
example that is confident without the check (asserted, so that each case fails when its check is removed).
"""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from rotordiag.features import FeatureResult
from rotordiag.features.examples import example_path
from rotordiag.models import pipeline
from rotordiag.models.checks import CheckContext
from rotordiag.models.checks.attitude import attitude_check
from rotordiag.models.checks.contradiction import contradiction_check
from rotordiag.models.checks.family import family_check
from rotordiag.models.families import (
    families_of_specs,
    machine_family,
    shaftline_key,
    specs_of_meta,
    trained_on,
    training_families,
)
from tests.service_util import shipped_registry_usable

needs_model = pytest.mark.skipif(not shipped_registry_usable(), reason="no usable shipped model registry")
BANDS = ("aligned", "slight", "moderate", "severe")


def _context(**kw) -> CheckContext:
    base = dict(fr=None, names=(), row=np.zeros(0), call="aligned", aligned_band="aligned", ood_score=0.5, ood=False,
                classes_of=lambda rows: pytest.fail("no class asked"), ood_of=lambda rows: pytest.fail("no OOD asked"),
                score=lambda fr: pytest.fail("no second reading asked"), band_names=BANDS)
    return CheckContext(**{**base, **kw})


# --- the families ---------------------------------------------------------------------------------------------

def test_a_spec_without_a_plant_is_the_default_lumped_family_and_presets_keep_their_simulation():
    assert families_of_specs({"plant": {}}) == ["lumped:default"]
    assert families_of_specs([{"plant": {"model": "train", "presets": ["gen50_2pole", "gen600_4pole"]}},
                              {"plant": {"presets": {"gen200_2pole": 1.0}}}]) == [
        "lumped:preset:gen200_2pole", "train:preset:gen50_2pole", "train:preset:gen600_4pole"]


def test_the_specs_of_a_concatenated_table_are_its_sources():
    one, two = {"plant": {}}, {"plant": {"model": "train", "preset": "gen50_2pole"}}
    assert specs_of_meta({"dataset_spec": one}) == [one]
    assert specs_of_meta({"sources": [{"dataset_spec": [one]}, {"dataset_spec": two}, {}]}) == [one, two]
    assert specs_of_meta({}) == []


def test_a_shaft_line_that_is_a_presets_is_that_preset_and_another_gets_a_stable_fingerprint():
    from rotordiag.simulator.shaftline import preset

    tables = preset("gen200_2pole").to_dict()
    assert shaftline_key(tables) == "preset:gen200_2pole"
    other = json.loads(json.dumps(tables))
    other["coupling"]["stiffness_n_m"] = 2 * float(other["coupling"].get("stiffness_n_m", 1e8))
    key = shaftline_key(other)
    assert key.startswith("shaftline:") and key == shaftline_key(dict(reversed(list(other.items()))))


def test_a_machine_is_matched_by_its_plant_and_by_its_simulation_only_when_it_names_one():
    fams = ["lumped:default", "lumped:preset:gen600_2pole"]
    assert trained_on(machine_family("gen600_2pole"), fams)
    assert not trained_on(machine_family("train:gen600_2pole"), fams)
    assert not trained_on(machine_family("gen50_2pole"), fams)
    assert machine_family(None) is None
    with pytest.raises(ValueError, match="use default or a preset"):
        machine_family("gen999")


@needs_model
def test_the_shipped_cards_families_are_derived_from_its_training_specs():
    """The shipped model was trained on the lumped 11-DOF model (MODEL.md's plant and the presets' reductions) and on
    the four presets' finite-element trains (models/default/dataset_*.toml); the card's families are its specs'."""
    from rotordiag.models.registry import shipped_registry_dir
    from rotordiag.simulator.shaftline import PRESETS

    root = shipped_registry_dir()
    card = json.loads((root / (root / "active").read_text().strip() / "card.json").read_text())
    fams = training_families(card)
    assert fams == families_of_specs(card["training_data"]["spec"])
    assert {f"{sim}:preset:{p}" for sim in ("lumped", "train") for p in PRESETS} | {"lumped:default"} == set(fams)


# --- family_untrained -----------------------------------------------------------------------------------------

def test_family_check_doubts_a_declared_machine_of_a_family_the_card_lacks():
    ctx = _context(machine_family="train:preset:gen600_2pole", model_families=["lumped:default"])
    (reason,) = family_check(ctx)
    assert reason.code == "family_untrained" and reason.status == "uncertain"
    assert "gen600_2pole (finite-element train)" in reason.message and "MODEL.md's plant" in reason.message
    assert family_check(_context(machine_family="default", model_families=["lumped:default"])) == []
    assert family_check(_context(machine_family=None, model_families=["lumped:default"])) == []
    assert family_check(_context(machine_family="train:preset:gen600_2pole", model_families=())) == []


# --- signature_contradicts_call -------------------------------------------------------------------------------

def _ratio_row(ratio: float) -> tuple[tuple[str, ...], np.ndarray]:
    names = ("b2_x_2x_1x_ratio", "b2_y_2x_1x_ratio", "b3_x_2x_1x_ratio", "b3_y_2x_1x_ratio")
    return names, np.array([0.1, 0.2, ratio, 0.1])


def test_contradiction_check_doubts_aligned_beside_a_strong_coupling_2x_inside_the_family_only():
    names, row = _ratio_row(1.3)                             # the rule reads "moderate": two bands above aligned
    (reason,) = contradiction_check(_context(names=names, row=row, call="aligned"))
    assert reason.code == "signature_contradicts_call" and reason.status == "uncertain" and "1.30" in reason.message
    assert contradiction_check(_context(names=names, row=row, call="slight")) == []      # one band: no contradiction
    assert contradiction_check(_context(names=names, row=row, call="aligned", ood=True)) == []   # signature_above_call
    names, row = _ratio_row(0.9)                             # "slight": one band above aligned
    assert contradiction_check(_context(names=names, row=row, call="aligned")) == []


def test_aligned_beside_a_severe_coupling_2x_shows_no_severity():
    """Three bands (a 2X/1X of 2 or more beside "aligned"): inconclusive, not "aligned, uncertain"; "slight" beside
    it is two bands: uncertain."""
    names, row = _ratio_row(2.5)
    (reason,) = contradiction_check(_context(names=names, row=row, call="aligned"))
    assert reason.code == "signature_contradicts_call" and reason.status == "inconclusive" and "2.50" in reason.message
    (reason,) = contradiction_check(_context(names=names, row=row, call="slight"))
    assert reason.status == "uncertain"
    names, row = _ratio_row(1.99)
    assert contradiction_check(_context(names=names, row=row, call="aligned"))[0].status == "uncertain"


# --- attitude_outside_training --------------------------------------------------------------------------------

@dataclasses.dataclass
class _Bearing:
    mean_um: tuple[float, float]
    clearance_um: float = float("nan")
    dc_removed: bool = False


def test_attitude_check_judges_the_dc_direction_without_the_clearance_and_only_for_a_confident_verdict():
    names = ("b1_centre_x_per_c", "b1_centre_y_per_c")
    fr = FeatureResult(names=names, values=np.full(2, np.nan), bearings={1: _Bearing((0.0, -120.0))},  # type: ignore[dict-item]
                       speed_rpm=3000.0, speed_source="given", phase_reference="none", n_revs=32, motion_type=None,
                       warnings=())
    seen: list[np.ndarray] = []

    def envelope_of(rows: np.ndarray) -> list[list[dict]]:
        seen.append(rows)
        x, y = rows[0]
        angle = float(np.degrees(np.arctan2(x, -y)))        # 0 on the load line (straight down)
        out = [{"feature": "b1_attitude_deg", "value": angle, "train_min": 11.0, "train_max": 93.0}]
        return [out if not 11.0 <= angle <= 93.0 else []]

    ctx = _context(fr=fr, names=names, row=np.full(2, np.nan), status="confident", envelope_of=envelope_of)
    (reason,) = attitude_check(ctx)
    assert reason.code == "attitude_outside_training" and "bearing 1 0°" in reason.message
    assert np.isclose(np.hypot(*seen[0][0]), 0.5)           # the direction put at a defined eccentricity
    assert attitude_check(dataclasses.replace(ctx, status="uncertain")) == []
    stated = dataclasses.replace(ctx, row=np.array([0.0, -0.4]))           # the clearance stated: the envelope judged it
    assert attitude_check(stated) == []
    no_dc = dataclasses.replace(fr, bearings={1: _Bearing((0.0, -120.0), dc_removed=True)})
    assert attitude_check(dataclasses.replace(ctx, fr=no_dc)) == []


# --- end to end through diagnose_recording --------------------------------------------------------------------

@pytest.fixture(scope="module")
def bundle():
    from rotordiag.models.predict import load_bundle
    from rotordiag.service.core.config import SHIPPED_REGISTRY_DIR

    return load_bundle(SHIPPED_REGISTRY_DIR)


def _example(name: str):
    from rotordiag.models.diagnose_files import load_options, read_recording

    path = example_path(name)
    return read_recording(path, options=load_options(path, None, {})).recording


def _codes(verdict) -> list[str]:
    return [r["code"] for r in verdict.reasons]


@needs_model
def test_a_declared_family_the_model_never_saw_is_never_confident_and_its_own_families_stay_so(bundle):
    """The shipped model saw MODEL.md's plant only lumped: declared as a finite-element train it is doubted; the
    presets' trains it was trained on are not."""
    rec = _example("severe.csv")
    assert pipeline.diagnose_recording(bundle, rec)[0].status == "confident"
    for own in ("default", "train:gen600_2pole", "gen600_2pole"):
        assert pipeline.diagnose_recording(bundle, rec, plant_model=own)[0].status == "confident", own
    v, _ = pipeline.diagnose_recording(bundle, rec, plant_model="train:default")
    assert v.status == "uncertain" and _codes(v) == ["family_untrained"]
    with pytest.raises(ValueError, match="plant_model"):
        pipeline.diagnose_recording(bundle, rec, plant_model="gen999")


@needs_model
def test_a_dc_direction_no_training_journal_had_is_never_confident_without_the_clearance(bundle):
    """Every journal moved to straight above its centre (against gravity: no loaded bearing of the training sits
    there). Straight below — a tilting-pad bearing's load line — is inside the training of a model that saw trains."""
    rec = dataclasses.replace(_example("moderate.csv"), clearance_um=None)
    v, fr = pipeline.diagnose_recording(bundle, rec)
    assert v.status == "confident"

    def moved(sign: float):
        chans = []
        for c in rec.channels:
            mx, my = fr.bearings[c.bearing].mean_um
            th = np.radians(c.angle_deg)
            chans.append(dataclasses.replace(c, data=np.asarray(c.data) - mx * np.cos(th)
                                             + (sign * np.hypot(mx, my) - my) * np.sin(th)))
        return pipeline.diagnose_recording(bundle, dataclasses.replace(rec, channels=chans))[0]

    v = moved(+1.0)
    assert v.status == "uncertain" and _codes(v) == ["attitude_outside_training"]
    assert "attitude_outside_training" not in _codes(moved(-1.0))


@needs_model
def test_aligned_beside_a_strong_forward_coupling_2x_is_never_confident(bundle):
    rec = _example("aligned.csv")
    v, fr = pipeline.diagnose_recording(bundle, rec)
    assert v.severity == "aligned" and "signature_contradicts_call" not in _codes(v)
    t = np.arange(len(rec.channels[0].data)) / rec.sample_rate_hz
    w = 2 * np.pi * fr.speed_rpm / 60
    chans = []
    for c in rec.channels:                                   # a forward 2X of half the 1X at the coupling bearings
        if c.bearing in (2, 3):
            a1 = fr.bearings[c.bearing].features[f"b{c.bearing}_1x_major_um_pp"]
            c = dataclasses.replace(c, data=np.asarray(c.data) + 0.25 * a1 * np.cos(2 * w * t - np.radians(c.angle_deg)))
        chans.append(c)
    v, _ = pipeline.diagnose_recording(bundle, dataclasses.replace(rec, channels=chans))
    assert v.severity == "aligned" and v.status == "uncertain" and "signature_contradicts_call" in _codes(v)


@needs_model
def test_the_cli_takes_the_plant_model_and_refuses_an_unknown_one(tmp_path):
    from typer.testing import CliRunner

    from rotordiag.cli import app
    from rotordiag.models.registry import shipped_registry_dir

    path = str(example_path("severe.csv"))
    res = CliRunner().invoke(app, ["diagnose", path, "--registry", str(shipped_registry_dir()), "--json",
                                   "--plant-model", "train:default"])
    assert res.exit_code == 0, res.output
    v = json.loads(res.output)
    assert v["status"] == "uncertain" and [r["code"] for r in v["reasons"]] == ["family_untrained"]
    res = CliRunner().invoke(app, ["diagnose", path, "--plant-model", "gen999"])
    assert res.exit_code == 2 and "use default or a preset" in res.output and "Traceback" not in res.output


# --- which model answered, judged as which plant ---------------------------------------------------------------

def test_answered_by_names_the_model_its_families_the_plant_retrained_for_and_the_declared_plant():
    from rotordiag.models.families import answered_by

    card = {"training_families": ["lumped:default", "train:preset:gen600_4pole"],
            "plant": {"name": "preset:gen600_4pole", "rated_speed_rpm": [1500.0]}}
    a = answered_by("v0007", card, "train:preset:gen600_4pole", "asset")
    assert a["model_version"] == "v0007" and a["retrained_for"] == "preset:gen600_4pole"
    assert a["training_families"] == ["lumped:default", "train:preset:gen600_4pole"]
    assert a["training_families_text"] == ["MODEL.md's plant (lumped 11-DOF)", "gen600_4pole (finite-element train)"]
    assert (a["plant_model"], a["declared_by"], a["plant_model_trained"]) == ("train:preset:gen600_4pole", "asset", True)
    assert a["text"] == ("model v0007, retrained for preset:gen600_4pole, trained on MODEL.md's plant (lumped 11-DOF), "
                         "gen600_4pole (finite-element train); judged as gen600_4pole (finite-element train), declared "
                         "by the asset's stored plant model, a family it was trained on")
    other = answered_by("v0007", card, "preset:gen50_2pole", "request")
    assert other["plant_model_trained"] is False and "NOT trained on (never confident)" in other["text"]
    none = answered_by("v0001", {"training_families": ["lumped:default"]}, None, "request")
    assert none["plant_model"] is None and none["declared_by"] is None and none["plant_model_trained"] is None
    assert none["retrained_for"] is None and none["text"].endswith("no plant model declared (the asset's, "
                                                                    "?plant_model= or --plant-model): no family check")
    bare = answered_by(None, None, "default")
    assert bare["declared_by"] == "given" and bare["plant_model_trained"] is None
    assert "its training families not recorded" in bare["text"]
    with pytest.raises(ValueError, match="declared_by"):
        answered_by("v1", None, "default", "somebody")


@needs_model
def test_the_verdict_says_which_model_answered_and_as_which_plant(bundle):
    from rotordiag.models.families import training_families

    rec = _example("aligned.csv")
    v, _ = pipeline.diagnose_recording(bundle, rec, plant_model="train:default", declared_by="request")
    a = v.answered_by
    assert a["model_version"] == bundle.version == v.model_version
    assert a["training_families"] == training_families(bundle.card) and a["training_families"]
    assert (a["plant_model"], a["declared_by"], a["plant_model_trained"]) == ("train:default", "request", False)
    assert v.to_dict()["answered_by"] == a
    v, _ = pipeline.diagnose_recording(bundle, rec)
    assert v.answered_by["plant_model"] is None and v.answered_by["declared_by"] is None
    v, _ = pipeline.diagnose_recording(bundle, rec, plant_model="default")
    assert v.answered_by["plant_model_trained"] is True and v.answered_by["declared_by"] == "given"


@needs_model
def test_the_cli_says_which_model_answered_and_that_the_plant_model_is_its_own(tmp_path):
    from typer.testing import CliRunner

    from rotordiag.cli import app
    from rotordiag.models.registry import shipped_registry_dir

    path = str(example_path("aligned.csv"))
    reg = str(shipped_registry_dir())
    res = CliRunner().invoke(app, ["diagnose", path, "--registry", reg, "--json", "--plant-model", "gen600_2pole"])
    assert res.exit_code == 0, res.output
    a = json.loads(res.output)["answered_by"]
    assert (a["plant_model"], a["declared_by"], a["plant_model_trained"]) == ("preset:gen600_2pole", "command line",
                                                                              True)
    res = CliRunner().invoke(app, ["diagnose", path, "--registry", reg])
    assert res.exit_code == 0, res.output
    (line,) = [x for x in res.output.splitlines() if x.startswith("answered by: ")]
    assert line.startswith("answered by: model v") and "trained on MODEL.md's plant (lumped 11-DOF)" in line
    assert line.endswith("no plant model declared (the asset's, ?plant_model= or --plant-model): no family check")
