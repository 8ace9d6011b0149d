"""Metrics, baselines and the held-out evaluation."""
from __future__ import annotations

import json

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from rotordiag.models.baselines import RatioThresholdClassifier, RuleOfThumb, ratio_column
from rotordiag.models.config import TrainConfig
from rotordiag.models.evaluate import cross_validate, evaluate, plot_report
from rotordiag.models.metrics import classification_metrics, expected_calibration_error, regression_metrics
from rotordiag.models.table import FeatureTable
from tests.models_synthetic import make_table


@pytest.fixture(autouse=True)
def _one_openmp_thread():
    # HistGradientBoosting's OpenMP threads spin badly when the 2 shared cores are
    # oversubscribed (12x slower measured); one thread is fast and deterministic.
    with threadpool_limits(1):
        yield


NAMES = ("aligned", "slight", "moderate", "severe")
FAST = {"classifier": {"max_iter": 40, "cv": 3}, "regressor": {"max_iter": 40}, "evaluation": {"n_splits": 3}}


def _table(**kw) -> FeatureTable:
    t = make_table(**kw)
    return FeatureTable(t.X, t.feature_names, t.misalignment, t.plant_id, t.mechanism, t.speed_rpm)


# ---------------------------------------------------------------- metrics
def test_ece_known_value():
    proba = np.tile([0.8, 0.2], (10, 1))
    y = np.array([0] * 5 + [1] * 5)           # accuracy 0.5 at confidence 0.8
    assert expected_calibration_error(proba, y) == pytest.approx(0.3)
    perfect = np.eye(2)[y]
    assert expected_calibration_error(perfect, y) == pytest.approx(0.0)


def test_classification_metrics_known_values():
    y = ["aligned", "aligned", "slight", "severe"]
    p = ["aligned", "slight", "slight", "severe"]
    r = classification_metrics(y, p, NAMES)
    assert r["accuracy"] == pytest.approx(0.75)
    assert r["recall"] == {"aligned": 0.5, "slight": 1.0, "severe": 1.0}   # moderate absent
    # F1: aligned 2/3, slight 2/3, severe 1 -> macro over present bands
    assert r["macro_f1"] == pytest.approx((2 / 3 + 2 / 3 + 1) / 3)
    assert r["confusion_matrix"]["counts"][0] == [1, 1, 0, 0]
    assert r["ece"] == pytest.approx(0.25)         # hard labels: 1 - accuracy
    assert r["detection"] == {"recall": 1.0, "false_alarm_rate": 0.5}


def test_regression_metrics_known_values():
    t = np.array([0.0, 0.1, 0.2, 0.3])
    p = np.array([0.05, 0.1, 0.25, 0.2])
    iv = np.column_stack([p - 0.06, p + 0.06])
    r = regression_metrics(t, p, iv)
    assert r["delta_mae"] == pytest.approx(0.05)
    assert r["spearman"] == pytest.approx(0.8)
    assert r["interval_coverage"] == pytest.approx(0.75)
    assert r["interval_mean_width"] == pytest.approx(0.12)


# ---------------------------------------------------------------- baselines
def test_rule_of_thumb_mapping():
    rule = RuleOfThumb(NAMES)
    got = rule.predict(np.array([0.49, 0.5, 0.99, 1.0, 2.0, 5.0, np.nan])).tolist()
    assert got == ["aligned", "slight", "slight", "moderate", "severe", "severe", "aligned"]
    with pytest.raises(ValueError, match="rule_cuts"):
        RuleOfThumb(NAMES, (0.5, 1.0))


def test_ratio_threshold_recovers_separable_cuts():
    rng = np.random.default_rng(0)
    cls = rng.integers(0, 4, 400)
    ratio = cls + rng.uniform(0, 0.5, 400)          # class i lives in [i, i + 0.5)
    y = np.asarray(NAMES, dtype=object)[cls]
    thr = RatioThresholdClassifier(classes=NAMES).fit(ratio[:, None], y)
    assert thr.train_macro_f1_ == pytest.approx(1.0)
    assert np.all(thr.predict(ratio[:, None]) == y)
    for i, cut in enumerate(thr.thresholds_):
        assert i + 0.5 - 0.05 <= cut <= i + 1 + 1e-9


def test_ratio_column_takes_max_over_probes_and_names_missing_features():
    X = np.array([[0.2, 0.7, 1.0], [np.nan, 0.3, 2.0], [np.nan, np.nan, 0.0]])
    r = ratio_column(X, ("b2_2x_1x", "b3_2x_1x", "amp"), ("*2x_1x*",))
    np.testing.assert_array_equal(r[:2], [0.7, 0.3])
    assert np.isnan(r[2])
    with pytest.raises(ValueError, match="ratio_features"):
        ratio_column(X, ("a", "b", "c"), ("*2x_1x*",))


# ---------------------------------------------------------------- evaluation
def test_folds_hold_out_whole_plants():
    tab = _table(n_plants=12, per_plant=8, seed=1)
    oof = cross_validate(tab, TrainConfig.from_dict(FAST))
    assert np.all(oof.fold >= 0)
    for p in np.unique(tab.plant_id):
        assert len(set(oof.fold[tab.plant_id == p])) == 1


def test_evaluation_cannot_memorise_plants():
    # Severity is a property of the plant, and one feature is a plant fingerprint that
    # carries no physics. A row-wise split would memorise it; the group split must not.
    rng = np.random.default_rng(2)
    n_plants, per = 40, 10
    plant = np.repeat(np.arange(n_plants), per)
    plant_delta = rng.choice([0.0, 0.1, 0.25, 0.5], n_plants)
    delta = plant_delta[plant]
    fingerprint = rng.normal(size=n_plants)[plant] * 10
    ratio = rng.uniform(0.2, 0.8, plant.size)         # uninformative
    X = np.column_stack([fingerprint, ratio, rng.normal(size=plant.size)])
    tab = FeatureTable(X, ("fingerprint", "b2_x_2x_1x_ratio", "noise"), delta, plant,
                       np.where(delta > 0, "rigid", "aligned"), np.full(plant.size, 1500.0))
    report, _ = evaluate(tab, TrainConfig.from_dict(FAST))
    assert report["results"]["all"]["all"]["model"]["macro_f1"] < 0.45   # ~chance (0.25)


def test_report_per_mechanism_and_speed_band_beats_baselines(tmp_path):
    tab = _table(n_plants=30, per_plant=10, seed=3, nan_rate=0.01)
    cfg = TrainConfig.from_dict(FAST)
    report, oof = evaluate(tab, cfg)
    res = report["results"]
    assert set(res["mechanism"]) == {"pin", "rigid"}
    assert set(res["speed_band_rpm"]) == {"1200-1800", "1800-2400", "2400-3000"}
    for mech, r in res["mechanism"].items():
        n_aligned = int(np.sum(tab.mechanism == "aligned"))
        assert r["n_rows"] == int(np.sum(tab.mechanism == mech)) + n_aligned
        best = max(r["rule_of_thumb"]["macro_f1"], r["ratio_threshold"]["macro_f1"])
        assert r["model"]["macro_f1"] > best + 0.15
        # The aligned plants' own 2X fools the rule, by construction of the data.
        assert r["aligned_high_2x"]["false_alarm_rate"]["rule_of_thumb"] == 1.0
        assert r["aligned_high_2x"]["false_alarm_rate"]["model"] < 0.2
    assert set(report["targets"]) == {"pin", "rigid"}
    json.dumps(report)                                    # JSON-able
    png = tmp_path / "r.png"
    plot_report(report, oof, tab, png)
    assert png.stat().st_size > 10_000


def test_evaluation_needs_two_plants():
    tab = _table(n_plants=1, per_plant=20, seed=4)
    with pytest.raises(ValueError, match="plant_id"):
        cross_validate(tab, TrainConfig.from_dict(FAST))


# ---------------------------------------------------------------- config
@pytest.mark.parametrize(
    "cfg,msg",
    [
        ({"bogus": {}}, "unknown section"),
        ({"classifier": {"depth": 3}}, r"\[classifier\]: unknown key"),
        ({"evaluation": {"n_splits": 1}}, "n_splits"),
        ({"bands": {"edges": [0.1, 0.2]}}, "bands.names"),
        ({"bands": {"edges": [0.1], "names": ["ok", "bad"]}}, "rule_cuts"),
        ({"classifier": {"calibration": "x"}}, "calibration"),
        ({"features": {"clearance_heads": "yes"}}, r"\[features\] clearance_heads"),
        ({"features": {"clearance_dropout": 2}}, r"\[features\] clearance_dropout"),
    ],
)
def test_config_errors_name_the_key(cfg, msg):
    with pytest.raises(ValueError, match=msg):
        TrainConfig.from_dict(cfg)


def test_config_round_trips(tmp_path):
    import tomli_w

    cfg = TrainConfig.from_dict({"seed": 3, "classifier": {"max_iter": 50},
                                 "features": {"exclude": ["*_um"], "clearance_heads": True}})
    p = tmp_path / "t.toml"
    p.write_bytes(tomli_w.dumps(cfg.to_dict()).encode())
    assert TrainConfig.from_file(p) == cfg
    model = cfg.make_model(("a_per_c", "b"))
    assert model.clearance_heads and model.clearance_features == cfg.clearance_features
