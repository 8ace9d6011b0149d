"""The compiled predictor gives the same numbers as the fitted scikit-learn model."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from rotordiag.models.compiled import CompiledModel, compile_forest, occlusion_raw, raw_predict
from rotordiag.models.config import TrainConfig
from rotordiag.models.pipeline import diagnose
from rotordiag.models.predict import _contributions, fast_predictor
from tests.models_synthetic import FEATURE_NAMES, make_table


@pytest.fixture(autouse=True)
def _one_openmp_thread():
    with threadpool_limits(1):
        yield


def _fit(calibration: str, nan_rate: float = 0.1, seed: int = 0):
    t = make_table(n_plants=30, per_plant=8, seed=seed, nan_rate=nan_rate)
    cfg = TrainConfig.from_dict({"classifier": {"max_iter": 25, "calibration": calibration},
                                 "regressor": {"max_iter": 25}})
    return cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)


def _queries(seed: int = 7) -> np.ndarray:
    X = make_table(n_plants=8, per_plant=10, seed=seed).X.copy()
    rng = np.random.default_rng(seed)
    X[rng.random(X.shape) < 0.15] = np.nan            # missing values go the learned way
    X[0] = np.nan                                     # a row with nothing at all
    X[1] *= 1e3                                       # far outside the training range
    return X


@pytest.mark.parametrize("calibration", ["temperature", "sigmoid", "isotonic", "none"])
def test_same_predictions_as_scikit_learn(calibration):
    model = _fit(calibration)
    fast = CompiledModel(model)
    X = _queries()
    np.testing.assert_allclose(fast.predict_proba(X), model.predict_proba(X), rtol=0, atol=1e-12)
    p_fast, iv_fast = fast.predict_misalignment(X)
    p_ref, iv_ref = model.predict_misalignment(X)
    np.testing.assert_allclose(p_fast, p_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(iv_fast, iv_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fast.ood_ratio(X), model.ood_ratio(X), rtol=1e-5)


def test_infinity_is_refused_like_scikit_learn():
    model = _fit("temperature")
    X = _queries()[:3]
    X[2, 1] = np.inf
    for predict in (CompiledModel(model).predict_proba, model.predict_proba):
        with pytest.raises(ValueError, match="infinity"):
            predict(X)


def test_occlusion_equals_predicting_every_occluded_row():
    model = _fit("temperature")
    fast = CompiledModel(model)
    for row in _queries(seed=3)[:6]:
        base, occluded = fast.occlusion_proba(row)
        trial = np.repeat(row[None, :], row.size, axis=0)
        trial[np.arange(row.size), np.arange(row.size)] = model.feature_median_
        np.testing.assert_allclose(occluded, model.predict_proba(trial), rtol=0, atol=1e-12)
        np.testing.assert_allclose(base, model.predict_proba(row[None, :])[0], rtol=0, atol=1e-12)


def test_forest_walk_by_hand():
    """Two hand-made stumps: NaN follows missing_go_to_left, ties go left, baselines add."""
    class Stub:
        pass

    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.ensemble._hist_gradient_boosting.common import PREDICTOR_RECORD_DTYPE

    def stump(feature, threshold, nan_left, lo, hi):
        nodes = np.zeros(3, dtype=PREDICTOR_RECORD_DTYPE)
        nodes[0]["feature_idx"], nodes[0]["num_threshold"] = feature, threshold
        nodes[0]["missing_go_to_left"], nodes[0]["left"], nodes[0]["right"] = nan_left, 1, 2
        nodes[1]["is_leaf"], nodes[1]["value"] = 1, lo
        nodes[2]["is_leaf"], nodes[2]["value"] = 1, hi
        return SimpleNamespace(nodes=nodes)

    m = HistGradientBoostingRegressor()
    m._predictors = [[stump(0, 1.0, True, -1.0, 1.0)], [stump(1, 0.0, False, 10.0, 20.0)]]
    m._baseline_prediction = np.array([[0.5]])
    forest = compile_forest([m], n_features=2)
    X = np.array([[1.0, 0.0], [1.5, 0.1], [np.nan, np.nan], [0.0, np.nan]])
    np.testing.assert_array_equal(raw_predict(forest, X)[:, 0], [0.5 - 1 + 10, 0.5 + 1 + 20,
                                                                 0.5 - 1 + 20, 0.5 - 1 + 20])
    # Occluding feature 0 of row 1 (1.5 → 0.0) flips only the first stump.
    occ = occlusion_raw(forest, X[1], np.array([0.0, 0.5]))
    np.testing.assert_array_equal(occ[:, 0], [0.5 - 1 + 20, 0.5 + 1 + 20])
    assert forest.feature_ptr.tolist() == [0, 1, 2]


def test_diagnose_uses_the_compiled_path_and_matches_the_plain_one():
    model = _fit("temperature")
    fast = fast_predictor(model)
    assert isinstance(fast, CompiledModel)
    assert fast_predictor(model) is fast            # built once per model object
    row = _queries(seed=11)[4]
    verdict = diagnose(model, SimpleNamespace(names=FEATURE_NAMES, values=row))
    np.testing.assert_allclose(list(verdict.probabilities.values()), model.predict_proba(row[None])[0], atol=1e-12)
    # The explanation is the same as the plain occlusion on scikit-learn predictions.
    cls = int(np.argmax(model.predict_proba(row[None])[0]))
    plain = _contributions(model, model, row, cls, top_k=len(row))
    compiled = _contributions(model, fast, row, cls, top_k=len(row))
    assert {c.name: round(c.contribution, 10) for c in plain} == {c.name: round(c.contribution, 10) for c in compiled}


def test_a_pair_per_clearance_case_compiles_to_the_same_numbers():
    t = make_table(n_plants=30, per_plant=8, seed=2, nan_rate=0.05)
    cfg = TrainConfig.from_dict({
        "classifier": {"kind": "ordinal", "max_iter": 25, "cv": 3}, "regressor": {"max_iter": 25},
        "features": {"clearance_features": ["coupling_1x_phase_diff_deg", "*_per_clearance"],
                     "clearance_heads": True}})
    model = cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)
    fast = CompiledModel(model)
    X = _queries()
    X[2::3, model.clearance_columns_] = np.nan          # a third of the rows without the clearance
    stated = model.clearance_stated(X)
    assert stated.any() and not stated.all()
    np.testing.assert_allclose(fast.predict_proba(X), model.predict_proba(X), rtol=0, atol=1e-12)
    for a, b in zip(fast.predict_misalignment(X), model.predict_misalignment(X)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    # explanations: the compiled occlusion equals the plain one for both cases (a row without the
    # clearance is explained by its own pair, not moved to the other by a median clearance feature)
    for i in (2, 3, 5, 8):
        row = X[i]
        cls = int(model.band_index(model.predict_proba(row[None]), row[None])[0])
        plain = _contributions(model, model, row, cls, top_k=len(row))
        compiled = _contributions(model, fast, row, cls, top_k=len(row))
        assert {c.name: round(c.contribution, 10) for c in plain} == \
            {c.name: round(c.contribution, 10) for c in compiled}
        verdict = diagnose(model, SimpleNamespace(names=FEATURE_NAMES, values=row))
        np.testing.assert_allclose(list(verdict.probabilities.values()), model.predict_proba(row[None])[0],
                                   atol=1e-12)
