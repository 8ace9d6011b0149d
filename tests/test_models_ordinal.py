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
        band = model.band_index(model.predict_proba(X), X)
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


def test_tuned_thresholds_recover_a_rare_top_class_the_median_rule_never_calls():
    from rotordiag.models.ordinal import THRESHOLD_GRID, _macro_f1_thresholds

    rng = np.random.default_rng(5)
    y = np.repeat([0, 1, 2, 3], [400, 300, 250, 50])
    # P(class ≥ k) out of fold: well separated for edges 1 and 2; the rare top class only
    # reaches 0.3–0.45 (its calibrated probability never passes 0.5), the others stay below 0.2.
    cum = np.column_stack([
        np.where(y >= 1, rng.uniform(0.75, 0.95, y.size), rng.uniform(0.0, 0.4, y.size)),
        np.where(y >= 2, rng.uniform(0.6, 0.9, y.size), rng.uniform(0.0, 0.3, y.size)),
        np.where(y >= 3, rng.uniform(0.3, 0.45, y.size), rng.uniform(0.0, 0.2, y.size)),
    ])
    start = np.array([0.7, 0.5, 0.5])        # the first edge's false-alarm bound is 0.7
    t = _macro_f1_thresholds(cum, y, start)
    assert t[0] >= 0.7 and set(t[1:]) <= set(THRESHOLD_GRID)
    assert 0.2 <= t[2] <= 0.3                    # between the two groups of the top edge
    pred = np.cumprod(cum >= t[None, :] - 1e-12, axis=1).sum(axis=1)
    assert np.mean(pred[y == 3] == 3) == 1.0


def test_tuned_thresholds_keep_the_false_alarm_bound_and_monotonicity():
    t = make_table(n_plants=60, per_plant=10, seed=2, nan_rate=0.05)
    common = {"kind": "ordinal", "max_iter": 30, "max_false_alarm": 0.05}
    models = {}
    for tune in (False, True):
        cfg = TrainConfig.from_dict({"classifier": {**common, "tune_thresholds": tune}, "regressor": {"max_iter": 30},
                                     "features": {"monotonic_increasing": list(MONO)}})
        models[tune] = cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)
    bound = models[False].classifier_.thresholds_[0]
    assert models[True].classifier_.thresholds_[0] >= bound
    # The predicted band still never falls when a constrained 2X/1X grows.
    q = make_table(n_plants=10, per_plant=10, seed=9)
    j = list(q.feature_names).index(MONO[0])
    lo = models[True].band_index(models[True].predict_proba(q.X), q.X)
    Xs = q.X.copy()
    Xs[:, j] *= 3.0
    assert np.all(models[True].band_index(models[True].predict_proba(Xs), Xs) >= lo)


def test_ood_on_a_log_scaled_feature_subset_flags_a_machine_far_below_the_family():
    t = make_table(n_plants=60, per_plant=8, seed=3)
    cfg = TrainConfig.from_dict({"classifier": {"kind": "ordinal", "max_iter": 20}, "regressor": {"max_iter": 20},
                                 "ood": {"threshold_quantile": 0.99},
                                 "features": {"ood_features": ["b?_x_2x_1x_ratio", "b1_x_1x_amp_um"],
                                              "ood_log_scales": {"*_amp_um": 1.0, "*_ratio": 0.05}}})
    model = cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)
    assert model.ood_.reference_.shape[1] == 3            # only the selected columns
    q = make_table(n_plants=10, per_plant=8, seed=13)
    quiet = q.X.copy()
    j = list(q.feature_names).index("b1_x_1x_amp_um")
    quiet[:, j] /= 200.0                                  # 200x less vibration than the family
    assert np.mean(model.ood_ratio(q.X) > 1) <= 0.1
    assert np.all(model.ood_ratio(quiet) > 1)
    # The noise columns are not part of the distance: changing them changes nothing.
    noisy = q.X.copy()
    noisy[:, list(q.feature_names).index("noise_a")] += 100.0
    np.testing.assert_allclose(model.ood_ratio(noisy), model.ood_ratio(q.X))
    fast = CompiledModel(model)
    Xq = quiet.copy()
    Xq[0] = np.nan
    np.testing.assert_allclose(fast.ood_ratio(Xq), model.ood_ratio(Xq), rtol=1e-5)
    with pytest.raises(ValueError, match="ood_log_scales"):
        TrainConfig.from_dict({"features": {"ood_log_scales": {"*_um": -1.0}}})
    bad = TrainConfig.from_dict({"classifier": {"kind": "ordinal", "max_iter": 5},
                                 "features": {"ood_features": ["nothing_like_this"]}})
    with pytest.raises(ValueError, match="match no feature"):
        bad.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)
