"""Ordinal severity classifier with monotonic constraints (issue 15, item 4), and the
held-out-plant OOD threshold (item 7)."""
from __future__ import annotations

import numpy as np
import pytest
from sklearn.utils.estimator_checks import parametrize_with_checks
from threadpoolctl import threadpool_limits

from rotordiag.models.compiled import CompiledModel
from rotordiag.models.config import TrainConfig
from rotordiag.models.estimators import KNNDistanceOOD, MisalignmentModel
from rotordiag.models.ordinal import OrdinalSeverityClassifier, cumulative_to_proba
from tests.models_synthetic import make_table

MONO = ("b2_x_2x_1x_ratio", "b3_x_2x_1x_ratio")


@pytest.fixture(autouse=True)
def _one_openmp_thread():
    with threadpool_limits(1):
        yield


@parametrize_with_checks([OrdinalSeverityClassifier(max_iter=10, cv=3)])
def test_sklearn_conventions(estimator, check):
    check(estimator)


def test_cumulative_to_proba_is_a_distribution_and_repairs_crossing_edges():
    cum = np.array([[0.9, 0.95, 0.1], [0.2, 0.1, 0.0], [1.0, 1.0, 1.0]])
    p = cumulative_to_proba(cum)
    assert p.shape == (3, 4)
    np.testing.assert_allclose(p.sum(axis=1), 1.0)
    assert (p >= 0).all()                       # P(≥2) > P(≥1) repaired by the running minimum
    np.testing.assert_allclose(p[0], [0.1, 0.0, 0.8, 0.1])
    # Thresholds 0.5 (an unfitted classifier's default): the median band.
    assert OrdinalSeverityClassifier().class_index(p).tolist() == [2, 0, 3]
    # A first-edge threshold of 0.95 keeps row 0 (P(≥1) = 0.9) aligned although P(≥2) = 0.9 too:
    # edges are passed in order.
    clf = OrdinalSeverityClassifier()
    clf.thresholds_ = np.array([0.95, 0.5, 0.5])
    assert clf.class_index(p).tolist() == [0, 0, 3]


def _ordinal_model(seed: int = 0, mono=MONO) -> tuple[MisalignmentModel, object]:
    t = make_table(n_plants=40, per_plant=10, seed=seed, nan_rate=0.05)
    cfg = TrainConfig.from_dict({"classifier": {"kind": "ordinal", "max_iter": 40, "max_false_alarm": 0.05},
                                 "regressor": {"max_iter": 40},
                                 "features": {"monotonic_increasing": list(mono)}})
    return cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id), t


def test_severity_and_delta_never_fall_when_the_coupling_2x_1x_grows():
    model, t = _ordinal_model()
    assert model.monotonic_cst_.tolist() == [1, 1, 0, 0, 0, 0, 0]
    rng = np.random.default_rng(3)
    rows = t.X[rng.choice(len(t.X), 60, replace=False)]
    cols = [t.feature_names.index(n) for n in MONO]
    factors = np.array([1.0, 1.2, 1.5, 2, 3, 5, 10, 20, 100])
    for row in rows:
        X = np.repeat(row[None, :], len(factors), axis=0)
        X[:, cols] = row[cols] * factors[:, None]
        band = model.band_index(model.predict_proba(X))
        delta, _ = model.predict_misalignment(X)
        assert np.all(np.diff(band) >= 0), band
        assert np.all(np.diff(delta) >= -1e-12), delta


def test_without_constraints_the_same_check_can_fail():
    # The property is not an accident of the data: an unconstrained classifier violates it
    # somewhere on this table (trees fit noise in the ratio columns).
    t = make_table(n_plants=40, per_plant=10, seed=0, nan_rate=0.05)
    cfg = TrainConfig.from_dict({"classifier": {"kind": "ordinal", "max_iter": 40, "min_samples_leaf": 2},
                                 "regressor": {"max_iter": 40}})
    model = cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)
    cols = [t.feature_names.index(n) for n in MONO]
    factors = np.linspace(0.2, 3.0, 60)
    violations = 0
    for row in t.X[:200]:
        X = np.repeat(row[None, :], len(factors), axis=0)
        X[:, cols] = row[cols] * factors[:, None]
        delta, _ = model.predict_misalignment(X)
        violations += int(np.any(np.diff(delta) < -1e-9))
    assert violations > 0


def test_ordinal_model_learns_and_the_compiled_path_agrees():
    model, _ = _ordinal_model()
    q = make_table(n_plants=10, per_plant=10, seed=9)
    acc = np.mean(model.predict(q.X) == model.bands_.label(q.misalignment))
    assert acc > 0.6
    fast = CompiledModel(model)
    Xq = q.X.copy()
    Xq[0] = np.nan
    np.testing.assert_allclose(fast.predict_proba(Xq), model.predict_proba(Xq), rtol=0, atol=1e-12)
    p1, iv1 = fast.predict_misalignment(Xq)
    p2, iv2 = model.predict_misalignment(Xq)
    np.testing.assert_allclose(p1, p2, atol=1e-12)
    np.testing.assert_allclose(iv1, iv2, atol=1e-12)


def test_config_refuses_constraints_without_an_ordinal_classifier():
    with pytest.raises(ValueError, match="ordinal"):
        TrainConfig.from_dict({"features": {"monotonic_increasing": ["b2_*"]}})
    with pytest.raises(ValueError, match="kind"):
        TrainConfig.from_dict({"classifier": {"kind": "softmax"}})
    t = make_table(n_plants=10, per_plant=6)
    cfg = TrainConfig.from_dict({"classifier": {"kind": "ordinal", "max_iter": 5},
                                 "features": {"monotonic_increasing": ["nothing_like_this"]}})
    with pytest.raises(ValueError, match="match no feature"):
        cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)


def test_ood_threshold_is_calibrated_on_held_out_groups_not_on_near_duplicates():
    rng = np.random.default_rng(11)
    plants = rng.normal(size=(300, 6))
    # Eight near-identical rows per plant (augmented copies of one recording).
    X = np.repeat(plants, 8, axis=0) + rng.normal(scale=1e-3, size=(2400, 6))
    groups = np.repeat(np.arange(300), 8)
    ood = KNNDistanceOOD(threshold_quantile=0.95, max_reference=1200).fit(X, groups=groups)
    assert ood.calibration_ == "held-out groups"
    fresh = rng.normal(size=(3000, 6))
    rate = float(np.mean(ood.predict(fresh) == -1))
    assert 0.02 <= rate <= 0.10, rate     # 150 calibration plants: the 95 % quantile is ±2 %
    # Row-wise leave-one-out would find each row's twin and set a tiny threshold.
    naive = KNNDistanceOOD(threshold_quantile=0.95, max_reference=3000).fit(X)
    assert np.mean(naive.predict(fresh) == -1) > 0.3     # 6x the requested share
    small = KNNDistanceOOD(threshold_quantile=0.95).fit(X[:400], groups=groups[:400])
    assert small.calibration_ == "group k-fold"
    assert np.mean(small.predict(rng.normal(size=(2000, 6))) == -1) < 0.25


def test_max_false_alarm_bounds_false_alarms_on_new_plants():
    t = make_table(n_plants=60, per_plant=10, seed=2, nan_rate=0.05)
    q = make_table(n_plants=40, per_plant=10, seed=12, nan_rate=0.05)
    rates = {}
    for fa in (None, 0.03):
        cfg = TrainConfig.from_dict({"classifier": {"kind": "ordinal", "max_iter": 40, "max_false_alarm": fa}
                                     if fa else {"kind": "ordinal", "max_iter": 40},
                                     "regressor": {"max_iter": 40}})
        model = cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)
        aligned = q.misalignment < 0.05
        rates[fa] = float(np.mean(model.predict(q.X[aligned]) != "aligned"))
        if fa:
            assert model.classifier_.thresholds_[0] >= 0.5 and np.all(model.classifier_.thresholds_[1:] == 0.5)
    assert rates[0.03] <= 0.08 and rates[0.03] <= rates[None]
