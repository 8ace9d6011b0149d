"""The verdict function shared by the CLI and the service."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from rotordiag.models.config import TrainConfig
from rotordiag.models.pipeline import diagnose
from rotordiag.models.predict import ModelBundle, format_verdict
from tests.models_synthetic import FEATURE_NAMES, make_table


@pytest.fixture(autouse=True)
def _one_openmp_thread():
    # See tests/test_models_evaluation.py: OpenMP spinning on oversubscribed cores.
    with threadpool_limits(1):
        yield


@pytest.fixture(scope="module")
def model():
    t = make_table(n_plants=60, per_plant=10, seed=0)
    cfg = TrainConfig.from_dict({"classifier": {"max_iter": 60}, "regressor": {"max_iter": 60}})
    with threadpool_limits(1):
        return cfg.make_model(t.feature_names).fit(t.X, t.misalignment, groups=t.plant_id)


def _fr(row, **kw):
    return SimpleNamespace(names=FEATURE_NAMES, values=np.asarray(row, float), **kw)


def test_verdict_agrees_with_the_model_and_converts_offset(model):
    t = make_table(n_plants=5, per_plant=10, seed=9)
    for row in t.X:
        v = diagnose(ModelBundle(model, {"version": "v0007"}, "v0007"), _fr(row, speed_rpm=1500.0),
                     clearance_um=350.0)
        assert v.severity == model.predict(row[None])[0]
        assert sum(v.probabilities.values()) == pytest.approx(1.0)
        point, iv = model.predict_misalignment(row[None])
        # the regressor's own estimate is kept; the Δ shown is it clipped into the class's band
        assert v.misalignment_model == pytest.approx(point[0])
        band = int(model.bands_.index([v.misalignment])[0])
        assert model.bands_.names[band] == v.severity
        lo_edge = ([0.0] + list(model.bands_.edges))[band]
        hi_edge = (list(model.bands_.edges) + [np.inf])[band]
        assert v.misalignment == pytest.approx(min(max(point[0], lo_edge), hi_edge), abs=1e-12)
        assert v.offset_um == pytest.approx(350.0 * v.misalignment)
        lo, hi = v.misalignment_interval
        assert lo <= v.misalignment <= hi and lo <= iv[0, 0] + 1e-12 and hi >= iv[0, 1] - 1e-12
        assert v.offset_interval_um == pytest.approx((350.0 * lo, 350.0 * hi))
        assert v.model_version == "v0007" and v.speed_rpm == 1500.0
        assert v.interval_level == pytest.approx(0.9)


def test_top_feature_is_the_informative_one(model):
    # A clearly severe row (Δ ≈ 0.5 in the synthetic family): the verdict must rest on the
    # Δ-bearing features, never on the pure-noise ones.
    row = np.array([1.1, 1.05, 150.0, 60.0, 60 / 350, 0.0, 0.0])
    v = diagnose(model, _fr(row))
    assert v.severity == "severe"
    assert v.top_features[0].name in ("coupling_1x_phase_diff_deg", "b2_x_2x_1x_ratio", "b3_x_2x_1x_ratio")
    assert v.top_features[0].contribution > 0.2
    noise = [f for f in v.top_features if f.name.startswith("noise")]
    assert all(abs(f.contribution) < 0.05 for f in noise)
    assert v.offset_um is None and "unknown" in format_verdict(v)


def test_missing_and_unknown_features_warn(model):
    row = np.array([0.5, 0.45, np.nan, 40.0, 40 / 350, 0.0, 0.0])
    fr = SimpleNamespace(names=FEATURE_NAMES[:-1] + ("renamed",), values=row, warnings=["speed estimated"])
    v = diagnose(model, fr)
    assert v.warnings[0] == "speed estimated"                        # the reading's own warnings lead
    by = {w.code: w.values for w in v.warnings[1:]}
    assert by["model_features_not_produced"]["n_missing"] == 1 and "noise_b" in by["model_features_not_produced"]["examples"]
    assert "coupling_1x_phase_diff_deg" in by["features_never_missing"]["examples"]
    with pytest.raises(ValueError, match="none of the model's features"):
        diagnose(model, SimpleNamespace(names=("a", "b"), values=[1.0, 2.0]))


def test_far_away_signal_is_flagged_ood(model):
    normal = diagnose(model, _fr([0.5, 0.45, 90.0, 40.0, 40 / 350, 0.0, 0.0]))
    far = diagnose(model, _fr([9.0, 9.0, -500.0, 4000.0, 11.0, 30.0, -30.0]))
    assert not normal.ood
    assert far.ood and far.ood_score > 3
    assert any(w.code == "signal_unlike_training" and w.values["ood_score"] == far.ood_score for w in far.warnings)
    d = far.to_dict()
    assert d["ood"] is True and isinstance(d["misalignment_interval"], list)


def test_bad_clearance_is_rejected(model):
    with pytest.raises(ValueError, match="clearance_um"):
        diagnose(model, _fr([0.5, 0.45, 90.0, 40.0, 0.1, 0.0, 0.0]), clearance_um=-3.0)


def test_motion_type_is_reported(model):
    row = [0.5, 0.45, 90.0, 40.0, 40 / 350, 0.0, 0.0]
    mt = SimpleNamespace(kind="period-n", period=3)
    assert diagnose(model, _fr(row, motion_type=mt)).motion_type == "period-3"
    assert diagnose(model, _fr(row, motion_type=SimpleNamespace(kind="chaotic", period=0))).motion_type == "chaotic"
    assert diagnose(model, _fr(row)).motion_type is None
