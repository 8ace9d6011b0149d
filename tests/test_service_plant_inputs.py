"""The retraining and dataset endpoints take every simulator mechanism and a plant as a shaft-line
description (issue 13 items 3 and 5); bad plants are 422s that say what to fix, files on the server never."""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from rotordiag.service.main import create_app
from rotordiag.service.schemas import DatasetJobRequest, FieldRecord, RetrainRequest
from rotordiag.service.work import prepare_dataset_job, prepare_retrain_job
from rotordiag.simulator import shaftline
from rotordiag.simulator.dataset.spec import DESIGN_MECHANISMS, parse_spec
from tests.service_util import auth, make_settings

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "shaftline_200mw.toml"


def _line() -> dict:
    return tomllib.loads(EXAMPLE.read_text())


def test_retrain_builds_its_sweep_on_the_shaftline_plant_with_overrides(tmp_path):
    """A shaft line is retrained for on its finite-element train (issue 48 item 3): `plant` values are the train's,
    the user's sweep tables win, a lumped-only mechanism is a 4xx naming the train's couplings."""
    from rotordiag.service.errors import InputError
    from rotordiag.simulator.train.plant import TrainPlant

    body = RetrainRequest.model_validate({"shaftline": _line(), "plant": {"generator_asymmetry": 0.03},
                                          "sweep": {"plant": {"scale": {"viscosity_pa_s": {"min": 0.7, "max": 1.4}}},
                                                    "operating": {"mechanism": {"rigid": 2, "flexible": 1}}}})
    params = prepare_retrain_job(body, make_settings(tmp_path))
    resolved = parse_spec(params["spec_toml"])
    expect = TrainPlant.of(shaftline.ShaftLine.from_file(EXAMPLE)).replace(generator_asymmetry=0.03)
    assert resolved.base_plant == expect and resolved.sources.keys() == {"shaftline:inline"}
    assert resolved.spec.plant.model == "train"
    assert resolved.spec.operating.mechanism == {"rigid": 2.0, "flexible": 1.0}
    assert params["spec_hash"] == resolved.spec_hash and params["shaftline"] is True
    with pytest.raises(InputError, match="coupling"):
        prepare_retrain_job(RetrainRequest.model_validate({"shaftline": _line(), "sweep": {"operating": {
            "mechanism": {"offset": 1, "flexible": 1}}}}), make_settings(tmp_path))


def test_retrain_takes_a_preset_by_name_and_its_sweep_follows_the_rated_speed(tmp_path):
    """A preset by name (the API refused it before) gives its shaft line, and the default sweep trains around its
    rated speeds (0.8–1.05 ×), not at 1200–2200 r/min; a given rated speed does the same; the user's own speed range
    still wins; an unknown preset, or a preset with a shaft line, is a 4xx saying what to fix."""
    from rotordiag.service.errors import InputError
    from rotordiag.simulator.shaftline import preset
    from rotordiag.simulator.train.plant import TrainPlant

    params = prepare_retrain_job(RetrainRequest.model_validate({"preset": "gen600_4pole"}), make_settings(tmp_path))
    resolved = parse_spec(params["spec_toml"])
    assert resolved.base_plant == TrainPlant.of(preset("gen600_4pole")) and params["preset"] == "gen600_4pole"
    sp = resolved.spec.operating.speed_rpm
    assert (sp.min, sp.max) == (pytest.approx(0.8 * 1500), pytest.approx(1.05 * 1800))
    rated = parse_spec(prepare_retrain_job(RetrainRequest.model_validate({"shaftline": _line(), "rated_speed_rpm": 3000}),
                                           make_settings(tmp_path))["spec_toml"]).spec.operating.speed_rpm
    assert (rated.min, rated.max) == (pytest.approx(2400), pytest.approx(3150))
    own = parse_spec(prepare_retrain_job(RetrainRequest.model_validate(
        {"preset": "gen200_2pole", "sweep": {"operating": {"speed_rpm": {"min": 2900, "max": 3100}}}}),
        make_settings(tmp_path))["spec_toml"]).spec.operating.speed_rpm
    assert (own.min, own.max) == (2900, 3100)
    plain = parse_spec(prepare_retrain_job(RetrainRequest.model_validate({}), make_settings(tmp_path))["spec_toml"])
    assert (plain.spec.operating.speed_rpm.min, plain.spec.operating.speed_rpm.max) == (1200, 2200)
    with pytest.raises(InputError, match="gen200_2pole"):
        prepare_retrain_job(RetrainRequest.model_validate({"preset": "gen999"}), make_settings(tmp_path))
    with pytest.raises(InputError, match="one way"):
        prepare_retrain_job(RetrainRequest.model_validate({"preset": "gen200_2pole", "shaftline": _line()}),
                            make_settings(tmp_path))


def test_retrain_trains_on_the_shipped_recipe_with_the_requests_overrides(tmp_path):
    """A plant's retraining gets the shipped model's train.toml (physics priors, clearance heads, OOD and
    envelope features, measurement augmentation) and the direction heads, not the library defaults, which have none
    of them; the request's `training` tables override only the keys they name."""
    from rotordiag.models.config import TrainConfig

    shipped = TrainConfig.from_file(Path(__file__).resolve().parents[1] / "models" / "default" / "train.toml").to_dict()
    assert shipped != TrainConfig.from_dict({}).to_dict()
    plain = prepare_retrain_job(RetrainRequest.model_validate({}), make_settings(tmp_path))
    # … with the offset-direction heads a plant's shaft-train data teaches (models.plant_retrain.PLANT_TRAINING)
    assert shipped["direction"] == {"heads": True}  # the shipped recipe has them too (v0002 on)
    assert plain["training"] == shipped
    body = RetrainRequest.model_validate({"training": {"seed": 3, "classifier": {"max_iter": 30},
                                                       "features": {"clearance_heads": False}}})
    got = prepare_retrain_job(body, make_settings(tmp_path))["training"]
    assert got["seed"] == 3 and got["classifier"]["max_iter"] == 30 and got["features"]["clearance_heads"] is False
    assert got["classifier"]["min_samples_leaf"] == shipped["classifier"]["min_samples_leaf"]
    assert got["features"]["monotonic_increasing"] == shipped["features"]["monotonic_increasing"] != []
    assert got["features"]["envelope_features"] == shipped["features"]["envelope_features"] != []
    assert got["augment"] == shipped["augment"]


def test_dataset_job_takes_an_inline_shaftline_and_a_preset_family(tmp_path):
    spec = {"design": {"method": "sobol", "n_samples": 8, "seed": 1},
            "operating": {"speed_rpm": {"min": 1500, "max": 2100}, "misalignment": {"min": 0, "max": 0.4},
                          "mechanism": "flexible"},
            "measurement": {"sample_rate_hz": 1024.0, "duration_revs": 8}}
    inline = prepare_dataset_job(DatasetJobRequest(spec={**spec, "plant": {"shaftline": _line()}}),
                                 make_settings(tmp_path))
    assert parse_spec(inline["spec_toml"]).base_plant == shaftline.to_plant(shaftline.ShaftLine.from_file(EXAMPLE))
    fam = prepare_dataset_job(DatasetJobRequest(spec={**spec, "plant": {"presets": ["gen50_2pole", "gen600_2pole"]}}),
                              make_settings(tmp_path))
    assert parse_spec(fam["spec_toml"]).source_weights == {"preset:gen50_2pole": 0.5, "preset:gen600_2pole": 0.5}


@pytest.mark.parametrize("mechanism", DESIGN_MECHANISMS)
def test_field_records_accept_every_mechanism(mechanism):
    rec = {"misalignment": 0.2, "mechanism": mechanism,
           "recording": {"sample_rate_hz": 1024.0, "channels": [{"bearing": 1, "angle_deg": 45.0, "units": "um", "data": [0.0] * 64}]}}
    assert FieldRecord.model_validate(rec).mechanism == mechanism


def _bad_line(**changes) -> dict:
    d = _line()
    for path, value in changes.items():
        table, key = path.split("__")
        d[table][key] = value
    return d


@pytest.mark.parametrize("body, expect", [
    ({"shaftline": _bad_line(generator__segments=[[1.0, -0.3]])}, "shaftline: generator.segments[0] diameter_m"),
    ({"shaftline": _bad_line(generator__segments=[[500.0, 0.5]])}, "span of at most 40 m"),
    ({"shaftline": _bad_line(coupling__type="gear")}, "coupling.type must be one of"),
    ({"shaftline": {**_line(), "oil": [1, 2]}}, "[oil] must be a table"),
    ({"shaftline": {**_line(), "plant": {"asymmetry": 0.9}}}, "asymmetry must be in"),
    ({"shaftline": {"generator": {"segments": [[1.0, 0.3]]}}}, "needs a [exciter] table"),
    ({"shaftline": _line(), "plant": {"clearance_m": -1.0}}, "plant: "),
    ({"sweep": {"plant": {"file": "/etc/passwd"}}}, "sweep.plant: only perturb and scale"),
    ({"sweep": {"plant": {"shaftline": "/etc/passwd"}}}, "sweep.plant: only perturb and scale"),
    ({"sweep": {"plant": {"scale": {"clearance_m": {"min": 0.01, "max": 1}}}}}, "factors within [0.1, 10]"),
    ({"field_data": [{"misalignment": 0.2, "mechanism": "wobbly",
                      "recording": {"sample_rate_hz": 1024.0,
                                    "channels": [{"bearing": 1, "angle_deg": 45.0, "units": "um", "data": [0.0] * 64}]}}]},
     "unknown mechanism 'wobbly'"),
    ({"shaftline": "/etc/passwd"}, "shaftline"),
])
def test_bad_retrain_plant_input_is_422_with_what_to_fix(tmp_path, body, expect):
    with TestClient(create_app(make_settings(tmp_path))) as c:
        r = c.post("/models/retrain", json=body, headers=auth())
        assert r.status_code == 422, r.text
        detail = r.json()["detail"]
        assert expect in (detail if isinstance(detail, str) else str(detail)), detail
        assert c.get("/jobs").json()["count"] == 0


@pytest.mark.parametrize("plant, expect", [
    ({"shaftline": "/etc/passwd"}, "plant.shaftline: a spec sent over HTTP cannot name a file"),
    ({"shaftlines": ["/etc/passwd"]}, "plant.shaftlines: a spec sent over HTTP cannot name a file"),
    ({"presets": ["gen1000"]}, "unknown shaft-line preset 'gen1000'"),
    ({"shaftline": {"generator": {"segments": [[1.0, 0.3]] * 500}, "exciter": {"segments": [[1.0, 0.3]]}}},
     "at most 200 segments"),
])
def test_bad_dataset_plant_is_422_and_no_server_file_is_read(tmp_path, plant, expect):
    spec = {"design": {"method": "sobol", "n_samples": 4, "seed": 1},
            "operating": {"speed_rpm": 1800, "misalignment": 0.1, "mechanism": "offset"},
            "measurement": {"sample_rate_hz": 1024.0, "duration_revs": 8}, "plant": plant}
    with TestClient(create_app(make_settings(tmp_path))) as c:
        r = c.post("/datasets", json={"spec": spec}, headers=auth())
        assert r.status_code == 422 and expect in r.json()["detail"], r.text
        assert "root:" not in r.json()["detail"]   # nothing of /etc/passwd comes back
        assert c.get("/jobs").json()["count"] == 0
