"""Model registry: skops round trip with trusted types, atomic versions, activate/rollback."""
from __future__ import annotations

import json

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from rotordiag.models.config import TrainConfig
from rotordiag.models.registry import Registry, RegistryError, load_model_file
from rotordiag.models.table import FeatureTable
from rotordiag.models.train import train_and_register
from tests.models_synthetic import make_table


@pytest.fixture(autouse=True)
def _one_openmp_thread():
    # See tests/test_models_evaluation.py: OpenMP spinning on oversubscribed cores.
    with threadpool_limits(1):
        yield


class NotAModel:
    """A type that is not on the trusted list."""

    def __init__(self):
        self.x = 1


@pytest.fixture(scope="module")
def fitted():
    t = make_table(n_plants=16, per_plant=8, seed=0, nan_rate=0.01)
    cfg = TrainConfig.from_dict({"classifier": {"max_iter": 20, "cv": 3}, "regressor": {"max_iter": 20}})
    with threadpool_limits(1):
        m = cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)
    return m, t


def test_register_load_round_trip_predicts_identically(tmp_path, fitted):
    model, t = fitted
    reg = Registry(tmp_path / "reg")
    v = reg.register(model, {"note": "x"})
    assert v == "v0001" and reg.active_version() == "v0001"
    loaded, card = reg.load()
    np.testing.assert_array_equal(loaded.predict_proba(t.X), model.predict_proba(t.X))
    np.testing.assert_array_equal(loaded.predict_misalignment(t.X)[1], model.predict_misalignment(t.X)[1])
    np.testing.assert_array_equal(loaded.ood_ratio(t.X), model.ood_ratio(t.X))
    assert card["version"] == "v0001" and card["note"] == "x"
    assert card["code_version"].startswith("0.1.0")
    assert "created" in card
    assert not list((tmp_path / "reg").glob(".incoming-*"))


def test_a_pair_per_clearance_case_round_trips(tmp_path):
    t = make_table(n_plants=16, per_plant=8, seed=1, nan_rate=0.01)
    cfg = TrainConfig.from_dict({"classifier": {"max_iter": 20, "cv": 3}, "regressor": {"max_iter": 20},
                                 "features": {"clearance_features": ["*_per_clearance"], "clearance_heads": True}})
    with threadpool_limits(1):
        model = cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)
    reg = Registry(tmp_path)
    reg.register(model, {})
    loaded, _ = reg.load()
    X = t.X.copy()
    X[::2, model.clearance_columns_] = np.nan
    assert loaded.classifier_no_clearance_ is not None
    np.testing.assert_array_equal(loaded.predict_proba(X), model.predict_proba(X))
    np.testing.assert_array_equal(loaded.predict_misalignment(X)[1], model.predict_misalignment(X)[1])


def test_activate_and_rollback(tmp_path, fitted):
    model, _ = fitted
    reg = Registry(tmp_path)
    assert reg.register(model, {}) == "v0001"
    assert reg.register(model, {}) == "v0002"
    assert reg.register(model, {}, activate=False) == "v0003"
    assert reg.active_version() == "v0002"
    assert [m.name for m in reg.list()] == ["v0001", "v0002", "v0003"]
    assert [m.active for m in reg.list()] == [False, True, False]
    reg.activate("v0003")
    assert reg.rollback() == "v0002"
    assert reg.rollback() == "v0001"
    assert reg.active_version() == "v0001"
    with pytest.raises(RegistryError, match="nothing to roll back"):
        reg.rollback()


def test_a_version_name_is_never_given_to_a_second_model(tmp_path, fitted):
    """An asset's stored verdicts name the version that answered: a deleted version's name is not reused, nor one
    the activation history remembers (``make default-model`` carries the shipped history into its new registry)."""
    import shutil

    model, _ = fitted
    reg = Registry(tmp_path / "a")
    assert reg.register(model, {}) == "v0001" and reg.register(model, {}) == "v0002"
    shutil.rmtree(reg.root / "v0002")
    reg.activate("v0001")
    assert reg.register(model, {}) == "v0003"
    fresh = Registry(tmp_path / "b")
    fresh.root.mkdir()
    (fresh.root / "history.json").write_text('["v0001", "v0007"]\n')
    assert fresh.next_version() == "v0008" and fresh.register(model, {}) == "v0008"
    assert fresh.active_version() == "v0008" and fresh.versions() == ["v0008"]


def test_unknown_version_and_empty_registry_errors(tmp_path, fitted):
    reg = Registry(tmp_path)
    with pytest.raises(RegistryError, match="no active model"):
        reg.load()
    reg.register(fitted[0], {})
    with pytest.raises(RegistryError, match="v0009 is not in registry"):
        reg.activate("v0009")
    with pytest.raises(RegistryError, match="not a version name"):
        reg.activate("../etc")


def test_untrusted_types_are_refused(tmp_path):
    import skops.io as sio  # here, not at collection (0.9 s of import)

    p = tmp_path / "evil.skops"
    sio.dump({"payload": NotAModel()}, p)
    with pytest.raises(RegistryError, match="outside the trusted list"):
        load_model_file(p)
    (tmp_path / "junk.skops").write_bytes(b"not a zip")
    with pytest.raises(RegistryError, match="not a readable skops file"):
        load_model_file(tmp_path / "junk.skops")


def test_failed_register_leaves_nothing_behind(tmp_path, fitted):
    reg = Registry(tmp_path)
    with pytest.raises(RegistryError, match="extra_files"):
        reg.register(fitted[0], {}, extra_files={"../x": "y"})
    assert reg.versions() == [] and reg.active_version() is None
    assert not list(tmp_path.glob(".incoming-*"))
    with pytest.raises(RegistryError, match="trusted list"):
        reg.register(NotAModel(), {})
    assert reg.versions() == []


def test_train_and_register_writes_card_and_report(tmp_path):
    t = make_table(n_plants=12, per_plant=8, seed=1)
    tab = FeatureTable(t.X, t.feature_names, t.misalignment, t.plant_id, t.mechanism, t.speed_rpm,
                       meta={"dataset_hash": "abc", "plant_family": "default±20%",
                             "dataset_spec": [{"plant": {}}, {"plant": {"model": "train", "presets": ["gen50_2pole"]}}]})
    cfg = TrainConfig.from_dict({"classifier": {"max_iter": 15, "cv": 3}, "regressor": {"max_iter": 15},
                                 "evaluation": {"n_splits": 3}, "features": {"exclude": ["noise_*"]}})
    with threadpool_limits(1):
        v, report = train_and_register(tab, cfg, Registry(tmp_path))
    d = tmp_path / v
    card = json.loads((d / "card.json").read_text())
    assert card["training_data"]["hash"] == "abc"
    assert card["plant_family"] == "default±20%"
    # the machine families the family guard reads (models.families), one per plant and simulation of the specs
    assert card["training_families"] == ["lumped:default", "train:preset:gen50_2pole"]
    assert "noise_a" not in card["feature_names"] and len(card["feature_names"]) == 5
    assert card["bands"]["edges"] == [0.05, 0.15, 0.35]
    assert set(card["metrics"]["per_mechanism"]) == {"pin", "rigid"}
    assert card["metrics"]["per_mechanism"]["rigid"]["model"]["macro_f1"] == pytest.approx(
        report["results"]["mechanism"]["rigid"]["model"]["macro_f1"])
    assert json.loads((d / "report.json").read_text())["targets"] == json.loads(json.dumps(report["targets"]))
    assert (d / "report.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    model, _ = Registry(tmp_path).load(v)
    assert model.feature_names_ == tuple(card["feature_names"])
