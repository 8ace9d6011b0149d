"""Estimator tests: scikit-learn conventions, and behaviour on data whose answer is known."""
from __future__ import annotations

import numpy as np
import pytest
from sklearn.utils.estimator_checks import parametrize_with_checks
from threadpoolctl import threadpool_limits

from rotordiag.core.bands import SeverityBands
from rotordiag.models.estimators import (
    ConformalIntervalRegressor,
    KNNDistanceOOD,
    MisalignmentModel,
    SeverityClassifier,
)
from tests.models_synthetic import FEATURE_NAMES, make_table


@pytest.fixture(autouse=True)
def _one_openmp_thread():
    # HistGradientBoosting's OpenMP threads spin badly when the 2 shared cores are
    # oversubscribed (12x slower measured); one thread is fast and deterministic.
    with threadpool_limits(1):
        yield


@parametrize_with_checks(
    [
        SeverityClassifier(max_iter=10, cv=3),
        ConformalIntervalRegressor(max_iter=10),
        KNNDistanceOOD(),
    ]
)
def test_sklearn_conventions(estimator, check):
    check(estimator)


# ---------------------------------------------------------------- bands
def test_bands_edges_are_lower_inclusive():
    b = SeverityBands()
    got = b.label([0.0, 0.0499, 0.05, 0.1499, 0.15, 0.3499, 0.35, 0.9]).tolist()
    assert got == ["aligned", "aligned", "slight", "slight", "moderate", "moderate", "severe", "severe"]


@pytest.mark.parametrize(
    "edges,names,msg",
    [
        ((0.1, 0.05), ("a", "b", "c"), "strictly increasing"),
        ((0.0, 0.1), ("a", "b", "c"), "> 0"),
        ((0.1,), ("a", "b", "c"), "len\\(edges\\) \\+ 1"),
        ((0.1,), ("a", "a"), "unique"),
    ],
)
def test_bands_reject_bad_definitions(edges, names, msg):
    with pytest.raises(ValueError, match=msg):
        SeverityBands(edges, names)


def test_bands_reject_negative_delta():
    with pytest.raises(ValueError, match="misalignment"):
        SeverityBands().index([-0.01])


def test_band_representatives():
    rep = SeverityBands().representative(upper=0.55)
    assert rep.tolist() == pytest.approx([0.025, 0.10, 0.25, 0.45])


# ---------------------------------------------------------------- classifier
def test_classifier_learns_a_known_rule_and_is_calibrated():
    rng = np.random.default_rng(1)
    X = rng.normal(size=(3000, 4))
    # Label is a noisy threshold on feature 0: P(class 1 | x) = sigmoid(3 x0), known exactly.
    p_true = 1 / (1 + np.exp(-3 * X[:, 0]))
    y = (rng.random(3000) < p_true).astype(int)
    clf = SeverityClassifier(max_iter=100, learning_rate=0.05, class_weight=None).fit(X[:2000], y[:2000])
    p = clf.predict_proba(X[2000:])[:, 1]
    # Calibrated probabilities follow the known conditional probability.
    assert np.mean(np.abs(p - p_true[2000:])) < 0.06
    # ... and a classifier that ignores feature 0 could not do this:
    assert np.corrcoef(p, p_true[2000:])[0, 1] > 0.95


def test_classifier_calibration_folds_keep_groups_together():
    t = make_table(n_plants=20, per_plant=10, seed=3)
    labels = SeverityBands().label(t.misalignment)
    clf = SeverityClassifier(max_iter=20, cv=4).fit(t.X, labels, groups=t.plant_id)
    assert clf.calibrated_
    # sklearn stores the calibration splits it was given; no plant on both sides.
    for train, test in clf.model_.cv:
        assert not set(t.plant_id[train]) & set(t.plant_id[test])


def test_classifier_rejects_unknown_calibration():
    with pytest.raises(ValueError, match="calibration"):
        SeverityClassifier(calibration="platt").fit(np.zeros((10, 2)), [0, 1] * 5)


# ---------------------------------------------------------------- regressor
def test_conformal_interval_covers_at_the_requested_rate():
    rng = np.random.default_rng(2)
    n = 6000
    X = rng.uniform(-1, 1, size=(n, 3))
    # Heteroscedastic noise: an interval of constant width would over/under-cover locally.
    y = 2 * X[:, 0] + rng.normal(0, 0.05 + 0.3 * np.abs(X[:, 1]))
    reg = ConformalIntervalRegressor(alpha=0.2, max_iter=100).fit(X[:3000], y[:3000])
    iv = reg.predict_interval(X[3000:])
    covered = (iv[:, 0] <= y[3000:]) & (y[3000:] <= iv[:, 1])
    # 3000 test rows: binomial sd of the coverage ≈ 0.007 around ≥ 0.80.
    assert 0.78 <= covered.mean() <= 0.86
    width = iv[:, 1] - iv[:, 0]
    quiet = np.abs(X[3000:, 1]) < 0.2
    loud = np.abs(X[3000:, 1]) > 0.8
    assert width[loud].mean() > 2 * width[quiet].mean()   # adaptive: σ(x) follows the noise
    point = reg.predict(X[3000:])
    assert np.all((iv[:, 0] <= point) & (point <= iv[:, 1]))


def test_conformal_lower_bound_clips_point_and_interval():
    rng = np.random.default_rng(3)
    X = rng.uniform(size=(400, 2))
    y = np.abs(rng.normal(0, 0.02, 400))
    reg = ConformalIntervalRegressor(lower_bound=0.0, max_iter=30).fit(X, y)
    assert reg.predict(X).min() >= 0
    assert reg.predict_interval(X).min() >= 0


def test_conformal_too_small_calibration_gives_infinite_interval():
    X = np.arange(8.0)[:, None]
    reg = ConformalIntervalRegressor(alpha=0.05, max_iter=5).fit(X, X[:, 0])
    # 2 calibration rows cannot certify 95 %: the honest interval is unbounded.
    assert reg.n_calibration_ == 2
    assert np.isinf(reg.conformity_quantile_)
    assert np.all(np.isinf(reg.predict_interval(X)[:, 1]))


# ---------------------------------------------------------------- OOD
def test_ood_flags_the_requested_share_and_far_points():
    rng = np.random.default_rng(4)
    train = rng.normal(size=(2000, 6))
    ood = KNNDistanceOOD(threshold_quantile=0.95).fit(train)
    fresh = rng.normal(size=(4000, 6))
    rate = np.mean(ood.predict(fresh) == -1)
    assert 0.03 <= rate <= 0.08
    far = fresh[:100] + 8.0        # 8 sd away in every feature
    assert np.all(ood.predict(far) == -1)
    assert np.all(ood.ood_ratio(far) > 2)


def test_ood_reference_is_bounded_and_nan_tolerant():
    rng = np.random.default_rng(5)
    train = rng.normal(size=(500, 3))
    train[:, 2] = np.nan                               # a feature always missing
    ood = KNNDistanceOOD(max_reference=100).fit(train)
    assert ood.reference_.shape == (100, 3)
    assert np.isfinite(ood.distance(train[:10])).all()


# ---------------------------------------------------------------- bundle
def test_model_bundle_orders_probabilities_by_band_and_beats_chance():
    t = make_table(n_plants=80, per_plant=10, seed=6, nan_rate=0.02)
    train = t.plant_id < 60
    m = MisalignmentModel(
        classifier=SeverityClassifier(max_iter=60),
        regressor=ConformalIntervalRegressor(max_iter=60, lower_bound=0.0),
        feature_names=FEATURE_NAMES,
    ).fit(t.X[train], t.misalignment[train], groups=t.plant_id[train])
    proba = m.predict_proba(t.X[~train])
    assert proba.shape == (np.sum(~train), 4)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0, atol=1e-9)
    assert m.classes_.tolist() == ["aligned", "slight", "moderate", "severe"]
    truth = SeverityBands().label(t.misalignment[~train])
    pred = m.predict(t.X[~train])
    assert pred.tolist() == m.classes_[np.argmax(proba, axis=1)].tolist()
    assert np.mean(pred == truth) > 0.75       # chance is 0.25; the phase feature carries Δ
    point, iv = m.predict_misalignment(t.X[~train])
    assert np.mean(np.abs(point - t.misalignment[~train])) < 0.05
    assert m.feature_names_ == FEATURE_NAMES
    assert m.feature_median_.shape == (len(FEATURE_NAMES),)


def test_model_bundle_needs_every_band():
    t = make_table(n_plants=10, per_plant=10, seed=7)
    keep = t.misalignment < 0.3                       # no "severe" rows
    with pytest.raises(ValueError, match="severe"):
        MisalignmentModel().fit(t.X[keep], t.misalignment[keep])


def test_model_bundle_checks_feature_names():
    with pytest.raises(ValueError, match="feature_names"):
        MisalignmentModel(feature_names=("a",)).fit(np.zeros((8, 2)), np.linspace(0, 0.5, 8))


def test_sparse_and_all_nan_columns_are_tolerated():
    # scikit-learn's boosted trees refuse an all-NaN column; a feature defined on only a
    # few rows (e.g. a sub-synchronous peak order) must not break training in any fold.
    rng = np.random.default_rng(8)
    X = rng.normal(size=(120, 4))
    X[:, 1] = np.nan
    X[3:, 2] = np.nan                       # 3 finite values
    y = (X[:, 0] > 0).astype(int)
    clf = SeverityClassifier(max_iter=10, cv=3).fit(X, y)
    assert clf.sparse_columns_.tolist() == [False, True, True, False]
    assert np.mean(clf.predict(X) == y) > 0.9
    reg = ConformalIntervalRegressor(max_iter=10).fit(X, X[:, 0])
    assert np.isfinite(reg.predict_interval(X)).all()


def test_classifier_falls_back_to_the_trees_when_temperature_scaling_fails(monkeypatch):
    import sklearn.calibration

    def fail(self, X, y, **kw):
        raise RuntimeError("Temperature scaling fails to optimize during calibration. Reason: NaN result encountered.")

    monkeypatch.setattr(sklearn.calibration.CalibratedClassifierCV, "fit", fail)
    t = make_table(n_plants=20, per_plant=6)
    labels = SeverityBands().label(t.misalignment)
    clf = SeverityClassifier(max_iter=10, cv=3).fit(t.X, labels, groups=t.plant_id)
    assert clf.calibrated_ is False and "Temperature scaling" in clf.calibration_note_
    p = clf.predict_proba(t.X[:5])
    np.testing.assert_allclose(p.sum(axis=1), 1.0)

    def other(self, X, y, **kw):
        raise RuntimeError("something else")

    monkeypatch.setattr(sklearn.calibration.CalibratedClassifierCV, "fit", other)
    with pytest.raises(RuntimeError, match="something else"):
        SeverityClassifier(max_iter=10, cv=3).fit(t.X, labels, groups=t.plant_id)


# ----------------------------------------------------------------------------- feature envelope (issue 15, item 7)
def _envelope_data(n_groups=200, per_group=3, seed=0):
    rng = np.random.default_rng(seed)
    groups = np.repeat(np.arange(n_groups), per_group)
    centre = rng.normal(size=(n_groups, 4))[groups]
    X = centre + 0.05 * rng.normal(size=(len(groups), 4))
    return X, groups


def test_envelope_flags_few_new_plants_of_the_family_and_names_the_extreme_column():
    from rotordiag.models.estimators import FeatureEnvelope

    X, groups = _envelope_data()
    env = FeatureEnvelope(quantile=0.99).fit(X, groups=groups)
    new, _ = _envelope_data(seed=1)                          # other plants of the same family
    rate = np.mean(env.predict(new) == -1)
    assert rate <= 0.05, rate
    row = new[:1].copy()
    row[0, 2] = X[:, 2].min() - 3 * (X[:, 2].max() - X[:, 2].min())
    assert env.predict(row)[0] == -1
    assert env.outside(row)[0].tolist() == [False, False, True, False]
    assert env.excess(np.full((1, 4), np.nan))[0].tolist() == [0, 0, 0, 0]     # missing is never outside


def test_envelope_checks_only_the_high_side_where_told():
    from rotordiag.models.estimators import FeatureEnvelope

    X, groups = _envelope_data()
    env = FeatureEnvelope().fit(X, groups=groups, check_low=[True, False, True, True])
    low, high = X[:1].copy(), X[:1].copy()
    low[0, 1], high[0, 1] = -100.0, 100.0
    assert env.predict(low)[0] == 1 and env.predict(high)[0] == -1
    with pytest.raises(ValueError, match="check_low"):
        FeatureEnvelope().fit(X, groups=groups, check_low=[True])
    with pytest.raises(ValueError, match="2 groups"):
        FeatureEnvelope().fit(X, groups=np.zeros(len(X)))


def test_model_envelope_findings_name_the_feature_and_the_training_range():
    from rotordiag.models.estimators import FeatureEnvelope, MisalignmentModel

    from .models_synthetic import make_table

    t = make_table(n_plants=60, per_plant=8, seed=3)
    small = {"classifier": SeverityClassifier(max_iter=20, cv=3),       # the envelope is under test, not the trees
             "regressor": ConformalIntervalRegressor(max_iter=20, lower_bound=0.0)}
    m = MisalignmentModel(feature_names=t.feature_names, envelope_features=["b1_x_1x_amp_um", "b2_*"],
                          ood_log_scales={"b1_x_1x_amp_um": 1.0}, envelope=FeatureEnvelope(quantile=0.99), **small)
    m.fit(t.X, t.misalignment, groups=t.plant_id)
    assert m.envelope_names_ == ("b2_x_2x_1x_ratio", "b1_x_1x_amp_um")
    j = list(t.feature_names).index("b1_x_1x_amp_um")
    row = t.X[:1].copy()
    assert m.envelope_findings(row) == [[]] and not m.ood_flags(row)[0]
    row[0, j] = np.nanmin(t.X[:, j]) / 100.0                   # one amplitude ×1/100 below the training minimum
    (found,) = m.envelope_findings(row)
    assert m.ood_flags(row)[0]
    assert [f["feature"] for f in found] == ["b1_x_1x_amp_um"]
    f = found[0]
    assert f["side"] == "below" and f["value"] == pytest.approx(row[0, j])
    assert f["train_min"] == pytest.approx(np.nanmin(t.X[:, j]), rel=1e-9) and f["factor"] == pytest.approx(100, rel=1e-6)
    with pytest.raises(ValueError, match="envelope_features"):
        MisalignmentModel(feature_names=t.feature_names, envelope_features=["nope_*"], **small).fit(
            t.X, t.misalignment, groups=t.plant_id)


def test_the_speed_is_outside_the_training_range_only_beyond_its_tolerance():
    """A running speed is known to ±1 % (a stated one locked to the signal, an estimate): 0.5 % above the fastest
    training recording is inside the envelope, 2 % above is a finding (and OOD)."""
    from rotordiag.models.estimators import ENVELOPE_REL_TOLERANCE, FeatureEnvelope, MisalignmentModel

    from .models_synthetic import make_table

    t = make_table(n_plants=60, per_plant=8, seed=3)                 # its rows have no speed: one is added
    X = np.column_stack([t.X, np.random.default_rng(0).uniform(1200, 3600, len(t.X))])
    names = [*t.feature_names, "speed_rpm"]
    j = len(names) - 1
    small = {"classifier": SeverityClassifier(max_iter=20, cv=3),
             "regressor": ConformalIntervalRegressor(max_iter=20, lower_bound=0.0)}
    m = MisalignmentModel(feature_names=names, envelope_features=["speed_rpm"], envelope=FeatureEnvelope(quantile=0.99),
                          **small)
    m.fit(X, t.misalignment, groups=t.plant_id)
    assert ENVELOPE_REL_TOLERANCE["speed_rpm"] == 0.01
    top = float(np.nanmax(X[:, j]))
    row = X[:1].copy()
    row[0, j] = top * 1.005
    assert m.envelope_findings(row) == [[]] and not m.ood_flags(row)[0]
    row[0, j] = top * 1.02
    (found,) = m.envelope_findings(row)
    assert [f["feature"] for f in found] == ["speed_rpm"] and found[0]["side"] == "above" and m.ood_flags(row)[0]
    row[0, j] = float(np.nanmin(X[:, j])) * 0.98
    assert [f["side"] for f in m.envelope_findings(row)[0]] == ["below"]


def test_derived_attitude_features_follow_the_centreline():
    from rotordiag.core.journal import attitude_angle_deg, short_bearing_attitude_deg
    from rotordiag.models.estimators import MisalignmentModel

    assert short_bearing_attitude_deg(0.0) == pytest.approx(90.0)
    e = 0.5
    assert np.tan(np.radians(short_bearing_attitude_deg(e))) == pytest.approx(np.pi * np.sqrt(1 - e * e) / (4 * e))
    assert attitude_angle_deg(0.0, -1.0) == pytest.approx(0.0)          # on the load line, below the centre
    assert attitude_angle_deg(1.0, 0.0) == pytest.approx(90.0)          # toward rotation (+x)
    m = MisalignmentModel(feature_names=("b1_centre_x_per_c", "b1_centre_y_per_c"))
    m.feature_names_ = m.feature_names
    m.envelope_names_ = ("b1_attitude_deg", "b1_attitude_offset_deg")
    x, y = 0.3 * np.sin(np.radians(40)), -0.3 * np.cos(np.radians(40))
    vals = m.envelope_values(np.array([[x, y], [0.0, -1.5], [0.002, 0.001], [0.0, -0.06]]))
    assert vals[0, 0] == pytest.approx(40.0)
    assert vals[0, 1] == pytest.approx(40.0 - short_bearing_attitude_deg(0.3))
    assert np.isnan(vals[1]).all()                                     # ε > 1: not a position inside the bearing
    assert np.isnan(vals[2]).all()                                     # ε = 0.002: centred, no attitude to read
    assert vals[3, 0] == pytest.approx(0.0)                            # ε = 0.06 ≥ ATTITUDE_MIN_ECC: read


# ---------------------------------------------------------------- a pair per clearance case
CLEARANCE = ("coupling_1x_phase_diff_deg", "*_per_clearance")   # the phase feature carries Δ: the cases differ


def _clearance_model(heads: bool, dropout: float = 0.5, seed: int = 3, **clearance):
    from rotordiag.models.ordinal import OrdinalSeverityClassifier

    t = make_table(n_plants=40, per_plant=10, seed=11, nan_rate=0.02)
    m = MisalignmentModel(
        classifier=OrdinalSeverityClassifier(max_iter=40, cv=3),
        regressor=ConformalIntervalRegressor(max_iter=40, lower_bound=0.0),
        feature_names=FEATURE_NAMES,
        **({"clearance_features": CLEARANCE, "clearance_dropout": dropout, "clearance_heads": heads,
            "random_state": seed} | clearance),
    ).fit(t.X, t.misalignment, groups=t.plant_id)
    return m, t


def _mixed_queries(model):
    from rotordiag.models.estimators import blank_clearance

    q = make_table(n_plants=10, per_plant=8, seed=12)
    Xn = blank_clearance(q.X, model.clearance_columns_, 1.0, 0)
    X = q.X.copy()
    X[1::2] = Xn[1::2]                                   # every other recording without the clearance
    return X, q


def test_each_recording_is_answered_by_its_clearance_cases_pair():
    m, _ = _clearance_model(heads=True)
    assert m.classifier_no_clearance_ is not None and m.regressor_no_clearance_ is not None
    X, q = _mixed_queries(m)
    stated = m.clearance_stated(X)
    assert stated.tolist() == [i % 2 == 0 for i in range(len(X))]
    proba = m.predict_proba(X)
    np.testing.assert_array_equal(proba[stated], m.classifier_.predict_proba(X[stated]))
    np.testing.assert_array_equal(proba[~stated], m.classifier_no_clearance_.predict_proba(X[~stated]))
    point, iv = m.predict_misalignment(X)
    np.testing.assert_array_equal(point[~stated], m.regressor_no_clearance_.predict(X[~stated]))
    np.testing.assert_array_equal(iv[stated], m.regressor_.predict_interval(X[stated]))
    # each case's own thresholds; without the rows' features the band cannot be read
    band = m.band_index(proba, X)
    assert band[stated].tolist() == m.classifier_.class_index(proba[stated]).tolist()
    assert band[~stated].tolist() == m.classifier_no_clearance_.class_index(proba[~stated]).tolist()
    assert m.predict(X).tolist() == m.classes_[band].tolist()
    with pytest.raises(ValueError, match="pass X"):
        m.band_index(proba)
    # the no-clearance pair never reads the clearance features, even when a row has them
    np.testing.assert_array_equal(m.classifier_no_clearance_.predict_proba(q.X),
                                  m.classifier_no_clearance_.predict_proba(np.where(m.clearance_columns_, np.nan, q.X)))
    # and the stated case is what the clearance buys: its Δ error is smaller than the other pair's
    err_stated = np.mean(np.abs(m.regressor_.predict(q.X) - q.misalignment))
    err_none = np.mean(np.abs(m.regressor_no_clearance_.predict(q.X) - q.misalignment))
    assert err_stated < 0.7 * err_none


def test_one_pair_for_both_cases_is_the_pair_fitted_on_the_dropout_rows():
    from rotordiag.models.estimators import blank_clearance

    one, t = _clearance_model(heads=False)
    assert one.classifier_no_clearance_ is None
    plain = MisalignmentModel(**{k: v for k, v in one.get_params(deep=False).items()
                                 if not k.startswith("clearance") and k != "random_state"})
    plain.fit(blank_clearance(t.X, one.clearance_columns_, 0.5, 3), t.misalignment, groups=t.plant_id)
    X, _ = _mixed_queries(one)
    np.testing.assert_array_equal(one.predict_proba(X), plain.predict_proba(X))
    np.testing.assert_array_equal(one.predict_misalignment(X)[1], plain.predict_misalignment(X)[1])
    np.testing.assert_array_equal(one.ood_ratio(X), plain.ood_ratio(X))
    np.testing.assert_array_equal(one.feature_nan_rate_, plain.feature_nan_rate_)
    # with a pair per case, the OOD scorer and the medians stay those of the dropout rows
    two, _ = _clearance_model(heads=True)
    np.testing.assert_array_equal(two.ood_ratio(X), one.ood_ratio(X))
    np.testing.assert_array_equal(two.feature_median_, one.feature_median_)
    assert not np.array_equal(two.predict_misalignment(X)[0], one.predict_misalignment(X)[0])


def test_clearance_heads_need_clearance_features():
    with pytest.raises(ValueError, match="clearance_heads"):
        _clearance_model(heads=True, clearance_features=("nothing_matches_*",))
    with pytest.raises(ValueError, match="clearance_dropout"):
        _clearance_model(heads=False, dropout=1.5)


def test_the_training_journals_attitude_is_kept_per_bearing():
    """``attitude_offset_reference_deg_``: the training rows' median attitude minus a plain short bearing's, per
    bearing; journals held on the load line (linear or tilting-pad bearings) give minus the plain bearing's angle,
    bearings the training never had NaN."""
    from rotordiag.core.journal import short_bearing_attitude_deg

    t = make_table(n_plants=20, per_plant=10, seed=3)
    rng = np.random.default_rng(0)
    ecc = rng.uniform(0.3, 0.6, size=(len(t.misalignment), 2))
    centres = np.column_stack([np.zeros_like(ecc[:, 0]), -ecc[:, 0],          # bearing 1: on the load line
                               np.zeros_like(ecc[:, 1]), -ecc[:, 1]])         # bearing 3
    names = (*FEATURE_NAMES, "b1_centre_x_per_c", "b1_centre_y_per_c", "b3_centre_x_per_c", "b3_centre_y_per_c")
    m = MisalignmentModel(classifier=SeverityClassifier(max_iter=20),
                          regressor=ConformalIntervalRegressor(max_iter=20, lower_bound=0.0), feature_names=names,
                          ).fit(np.column_stack([t.X, centres]), t.misalignment, groups=t.plant_id)
    ref = m.attitude_offset_reference_deg_
    assert ref.shape == (9,)
    assert np.isnan(ref[1]) and np.isnan(ref[3]) and np.isnan(ref[8])
    expected = -short_bearing_attitude_deg(np.median(ecc, axis=0))
    np.testing.assert_allclose(ref[[0, 2]], expected, atol=3.0)
    assert (ref[[0, 2]] < -40).all()


def test_attitude_offset_is_zero_where_a_plain_bearing_holds_the_journal_and_wraps():
    """``core.journal.attitude_offset_deg``: a journal where the Ocvirk short bearing puts it reads 0°, one on the
    load line minus the short bearing's angle, and a difference beyond ±180° comes back into [−180, 180)."""
    from rotordiag.core.journal import attitude_offset_deg, short_bearing_attitude_deg

    ecc = np.array([0.2, 0.5, 0.8])
    phi = np.radians(short_bearing_attitude_deg(ecc))
    np.testing.assert_allclose(attitude_offset_deg(ecc * np.sin(phi), -ecc * np.cos(phi)), 0.0, atol=1e-9)
    np.testing.assert_allclose(attitude_offset_deg(np.zeros(3), -ecc), -short_bearing_attitude_deg(ecc))
    # journal above the centre, just past the rotation side of 180°: −170° − φ_short wraps to the positive side
    x, y = 0.5 * np.sin(np.radians(-170.0)), -0.5 * np.cos(np.radians(-170.0))
    off = float(attitude_offset_deg(np.array([x]), np.array([y]))[0])
    assert -180.0 <= off < 180.0
    assert off == pytest.approx(360.0 - 170.0 - float(short_bearing_attitude_deg(0.5)))
