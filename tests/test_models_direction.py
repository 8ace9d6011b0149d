"""Which way the exciter sits, and the angular offset: the direction heads (models.direction), the verdict's
``direction`` / ``angular_offset``, and the plant report's direction accuracy."""
from __future__ import annotations

import copy
import math
from types import SimpleNamespace

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from rotordiag.core.notes import Note
from rotordiag.models.config import TrainConfig
from rotordiag.models.direction import (
    angle_error_deg,
    angle_halfwidth_deg,
    direction_answer,
    fit_direction_heads,
    offset_angle,
    predict_heads,
)
from rotordiag.models.estimators import ConformalIntervalRegressor
from rotordiag.models.pipeline import diagnose
from rotordiag.models.plant_retrain import _direction_figures, _figures, format_report
from rotordiag.models.predict import format_verdict
from rotordiag.models.robustness import Outcome
from rotordiag.models.table import FeatureTable
from rotordiag.models.train import direction_card, fit_final

NAMES = ("b2_centre_x_per_c", "b2_centre_y_per_c", "b3_centre_x_per_c", "b3_centre_y_per_c", "b4_centre_x_per_c",
         "b4_centre_y_per_c", "b2_x_2x_1x_ratio", "noise_a")
CENTRE = [0, 1, 2, 3, 4, 5]


@pytest.fixture(autouse=True)
def _one_openmp_thread():
    with threadpool_limits(1):
        yield


def journals(n_plants: int, per_plant: int, seed: int, informative: bool = True):
    """A family whose direction is recoverable by construction, built from what a lifted exciter does to the
    journals (not from the code under test): the exciter's bearings moved by Δ along φ leave the generator's
    coupling-end journal (b2) pushed along +φ in its bearing and the exciter's (b3) along −φ, by a plant's own
    share of Δ; an angular offset α (mrad) moves the far exciter journal (b4) along −φ; each journal sits at its
    gravity eccentricity (down, turned toward rotation; ±10 % from plant to plant, as one machine's draws) with
    scatter. ``informative`` False: the journals move
    along a direction drawn independently of φ (the control: nothing to recover)."""
    rng = np.random.default_rng(seed)
    X, delta, phi, alpha, plant = [], [], [], [], []
    for p in range(n_plants):
        k2, k3, k4 = rng.uniform(0.3, 0.5), rng.uniform(0.3, 0.5), rng.uniform(0.2, 0.4)
        ecc = rng.uniform(0.5, 0.6, size=3)           # one machine's journals within its tolerances
        att = np.deg2rad(rng.uniform(50, 60, size=3))
        for _ in range(per_plant):
            d = 0.0 if rng.random() < 0.2 else rng.uniform(0.02, 0.6)
            f = rng.uniform(0, 2 * np.pi)
            a = rng.uniform(-1.0, 1.0)
            seen = f if informative else rng.uniform(0, 2 * np.pi)
            e = np.array([np.cos(seen), np.sin(seen)])
            static = [ecc[j] * np.array([np.sin(att[j]), -np.cos(att[j])]) for j in range(3)]
            b2 = static[0] + k2 * d * e
            b3 = static[1] - k3 * d * e
            b4 = static[2] - k4 * (0.3 * a) * e
            row = [*b2, *b3, *b4, 0.3 + 1.5 * d, rng.normal()]
            row = np.asarray(row) + np.r_[rng.normal(0, 0.01, 6), rng.normal(0, 0.03), 0.0]
            X.append(row)
            delta.append(d)
            phi.append(f)
            alpha.append(a if d > 0 else 0.0)
            plant.append(p)
    return np.array(X), np.array(delta), np.array(phi), np.array(alpha), np.array(plant)


def _reg():
    return ConformalIntervalRegressor(max_iter=80, random_state=0)


def _accuracy(direction, X, delta, phi, min_delta=0.15):
    pred = predict_heads(direction, X)
    theta = np.degrees(np.arctan2(pred["vertical_per_c"][0], pred["horizontal_per_c"][0]))
    rows = delta >= min_delta
    errs = np.array([angle_error_deg(t, f) for t, f in zip(theta[rows], phi[rows])])
    return float(np.mean(errs <= 45.0)), pred


def test_a_recoverable_direction_is_recovered_on_held_out_plants():
    """Fitted on 80 plants, judged on 30 others: ≥ 90 % of offsets with Δ ≥ 0.15 get their direction within ±45°;
    the calibrated 90 % arcs hold 80–98 % of the true directions and are narrower for large offsets than for small
    ones; α's estimate ranks the true α."""
    X, d, f, a, g = journals(80, 8, seed=1)
    heads = fit_direction_heads(X, NAMES, d, f, a, g, _reg())
    assert heads["heads"]["angular_mrad"] is not None and heads["n_plants"] == 80
    Xt, dt, ft, at, _ = journals(30, 8, seed=2)
    acc, pred = _accuracy(heads, Xt, dt, ft)
    assert acc >= 0.9
    theta, size = offset_angle(heads, Xt)
    moved = dt > 0
    half = np.array([angle_halfwidth_deg(heads, m) for m in size[moved]])
    err = np.array([angle_error_deg(math.degrees(t), p) for t, p in zip(theta[moved], ft[moved])])
    assert 0.8 <= np.mean(err <= half) <= 0.98
    small, large = heads["angle_halfwidth_deg"][0], heads["angle_halfwidth_deg"][-1]
    assert large < 45.0 and large < small
    from scipy.stats import spearmanr
    moved = dt > 0.15
    assert spearmanr(pred["angular_mrad"][0][moved], at[moved]).statistic > 0.6


def test_a_direction_the_journals_do_not_carry_is_not_recovered():
    """The control that lets the test above fail: the same family with the journals moving along a direction
    unrelated to φ — the heads' directions are right about as often as chance (±45° is a quarter of the circle), and
    the calibrated arcs are nearly the whole circle."""
    X, d, f, a, g = journals(80, 8, seed=1, informative=False)
    heads = fit_direction_heads(X, NAMES, d, f, a, g, _reg())
    Xt, dt, ft, _, _ = journals(30, 8, seed=2, informative=False)
    acc, _ = _accuracy(heads, Xt, dt, ft)
    assert acc < 0.45
    assert min(heads["angle_halfwidth_deg"]) > 120.0          # and the calibrated arcs say so: nearly any direction


def test_heads_need_rows_with_the_centreline():
    X, d, f, a, g = journals(10, 8, seed=3)
    X[:, CENTRE] = np.nan                    # AC-coupled training data: no centreline anywhere
    with pytest.raises(ValueError, match="centreline"):
        fit_direction_heads(X, NAMES, d, f, a, g, _reg())


# --- the verdict -----------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def trained():
    """A model with direction heads, fitted through ``fit_final`` as a plant's retraining does."""
    X, d, f, a, g = journals(80, 8, seed=1)
    table = FeatureTable(X, NAMES, d, g.astype(str), np.where(d > 0, "rigid", "aligned"), np.full(len(d), 1500.0),
                         offset_angle_rad=f, angular_mrad=a)
    cfg = TrainConfig.from_dict({"classifier": {"max_iter": 60}, "regressor": {"max_iter": 60},
                                 "features": {"clearance_features": []}, "direction": {"heads": True}})
    with threadpool_limits(1):
        return fit_final(table, cfg)


def _fr(row, warnings=()):
    return SimpleNamespace(names=NAMES, values=np.asarray(row, float), warnings=list(warnings))


def _row(delta, phi_rad, alpha=0.0):
    """A row of the synthetic family's typical plant (the journals' mean responses)."""
    e = np.array([math.cos(phi_rad), math.sin(phi_rad)])
    att = math.radians(55.0)
    static = 0.55 * np.array([math.sin(att), -math.cos(att)])
    return np.r_[static + 0.4 * delta * e, static - 0.4 * delta * e, static - 0.3 * 0.3 * alpha * e,
                 0.3 + 1.5 * delta, 0.0]


def test_a_severe_offset_gets_its_direction_sized_by_the_verdicts_own_offset(trained):
    """Exciter lifted (φ = 90°) by Δ = 0.45: the answer says high, with an angle within its own arc and within ±45°
    of 90°, and its components are the verdict's own δ = Δ·c split along the estimated angle (so direction and Δ never
    disagree); each component's interval is its range over the Δ interval and the arc (checked on a fine grid), and
    a side is named only where the whole arc lies on it."""
    v = diagnose(trained, _fr(_row(0.45, math.pi / 2)), clearance_um=300.0)
    assert v.severity in ("moderate", "severe")
    d = v.direction
    assert d["estimated"] and d["unit"] == "um"
    assert angle_error_deg(d["angle_deg"], math.pi / 2) <= min(45.0, d["angle_halfwidth_deg"])
    h, vert = d["horizontal"], d["vertical"]
    assert math.hypot(h["value"], vert["value"]) == pytest.approx(v.offset_um)
    t = np.radians(d["angle_deg"] + np.linspace(-d["angle_halfwidth_deg"], d["angle_halfwidth_deg"], 2001))
    offsets = 300.0 * np.array(v.misalignment_interval)
    for comp, fn in ((h, np.cos), (vert, np.sin)):
        grid = np.outer(offsets, fn(t))
        assert comp["interval"] == pytest.approx([grid.min(), grid.max()], abs=1e-3)
        assert comp["interval"][0] <= comp["value"] <= comp["interval"][1]
        assert comp["side"] == (1 if fn(t).min() > 0 else -1 if fn(t).max() < 0 else 0)
    assert vert["side"] == 1 and "high by" in d["text"]
    assert ("to the right by" in d["text"] or "to the left by" in d["text"]) == (h["side"] != 0)
    assert v.angular_offset["estimated"] and v.angular_offset["interval_mrad"][0] <= v.angular_offset["interval_mrad"][1]
    text = format_verdict(v)
    assert "direction: exciter toward" in text and "high by" in text and "angular offset α:" in text


def test_ac_only_input_gets_no_direction_and_says_why(trained):
    row = _row(0.45, math.pi / 2)
    row[CENTRE] = np.nan                      # what the features give for AC-coupled probes: no centreline
    v = diagnose(trained, _fr(row, [Note("no_dc_position", why="dc_removed")]), clearance_um=300.0)
    assert v.direction["estimated"] is False and v.direction["code"] == "no_dc_position"
    assert "AC-coupled" in v.direction["why_not"]
    assert v.angular_offset["estimated"] is False
    # the same row without the DC note: the centreline is missing for want of the clearance
    v = diagnose(trained, _fr(row), clearance_um=None)
    assert v.direction["code"] == "no_centreline" and "clearance" in v.direction["why_not"]


def test_an_aligned_call_gets_no_direction(trained):
    v = diagnose(trained, _fr(_row(0.0, 0.0)), clearance_um=300.0)
    assert v.severity == "aligned"
    assert v.direction == {"estimated": False, "code": "aligned",
                           "why_not": "the call is aligned: there is no offset to give a direction to"}


def test_an_inconclusive_verdict_gets_no_direction():
    heads = {"heads": {}, "dc_columns": np.array([0]), "interval_level": 0.9}
    d, a = direction_answer(heads, np.array([0.1]), aligned_call=False, inconclusive=True, delta=None,
                            delta_interval=(None, None), clearance_um=300.0, dc_removed=False)
    assert d["code"] == a["code"] == "inconclusive"


def test_direction_heads_change_nothing_else_in_the_answer(trained):
    """The heads only add: the same model without them gives the same class, Δ, status, reasons and features."""
    bare = copy.deepcopy(trained)
    del bare.direction_heads_
    for delta, phi in ((0.45, 1.0), (0.2, 4.0), (0.0, 0.0)):
        fr = _fr(_row(delta, phi))
        with_heads = diagnose(trained, fr, clearance_um=300.0).to_dict()
        without = diagnose(bare, fr, clearance_um=300.0).to_dict()
        assert without["direction"]["code"] == "model_without_direction"
        for key in ("direction", "angular_offset"):
            with_heads.pop(key)
            without.pop(key)
        assert with_heads == without
    card = direction_card(trained)
    assert card["estimated"] and card["angular"] and card["n_plants"] == 80
    assert direction_card(bare)["estimated"] is False


def test_the_shipped_model_gives_a_direction_only_where_the_recording_carries_one():
    """v0002 has direction heads (fitted on every training row: each carries the centreline). A DC-coupled moderate
    recording with its clearance gets a direction whose components are the verdict's own offset; the same recording
    with its means removed (AC-coupled) gets none and says why; α is not estimated (its lumped parts vary none)."""
    import dataclasses

    from rotordiag.features.examples import example_path
    from rotordiag.models import predict as predict_mod
    from rotordiag.models.diagnose_files import load_options, read_recording
    from rotordiag.models.pipeline import diagnose_recording
    from rotordiag.models.registry import shipped_registry_dir

    bundle = predict_mod.load_bundle(shipped_registry_dir())
    card = direction_card(bundle.model)
    assert card["estimated"] and card["n_plants"] > 9000 and card["angular"] is False
    path = example_path("moderate.csv")
    rec = read_recording(path, options=load_options(path, None, {})).recording
    v, _ = diagnose_recording(bundle, rec, clearance_um=350.0)
    assert v.severity == "moderate" and v.direction["estimated"] and v.direction["unit"] == "um"
    d = v.direction
    assert math.hypot(d["horizontal"]["value"], d["vertical"]["value"]) == pytest.approx(v.offset_um)
    assert 0.0 < d["angle_halfwidth_deg"] <= 180.0
    assert v.angular_offset["code"] == "angular_not_trained"
    ac = dataclasses.replace(rec, channels=[dataclasses.replace(c, data=np.asarray(c.data) - np.mean(c.data))
                                            for c in rec.channels], dc_removed=True)
    v_ac, _ = diagnose_recording(bundle, ac, clearance_um=350.0)
    assert v_ac.direction["estimated"] is False and v_ac.direction["code"] == "no_dc_position"


def test_mil_output_converts_the_direction(trained):
    from rotordiag.models.output_units import verdict_in_units

    v = diagnose(trained, _fr(_row(0.45, math.pi / 2)), clearance_um=300.0).to_dict()
    mil = verdict_in_units(v, "mil")["direction"]
    assert mil["unit"] == "mil"
    assert mil["vertical"]["value"] == pytest.approx(v["direction"]["vertical"]["value"] / 25.4)
    assert " mil" in mil["text"] and "µm" not in mil["text"] and mil["angle_deg"] == v["direction"]["angle_deg"]
    assert v["direction"]["unit"] == "um"                     # the µm answer is not changed


# --- the plant report --------------------------------------------------------------------------------------

def _o(delta, true_deg, est_deg, *, status="confident", dc=True, code="estimated", half=40.0):
    return Outcome(delta, "rigid" if delta > 0 else "aligned", model_class="moderate", severity="moderate",
                   status=status, interval=(0.0, 1.0), delta_model=delta, true_angle_rad=math.radians(true_deg),
                   dc_available=dc, direction_deg=math.nan if est_deg is None else est_deg, direction_code=code,
                   direction_halfwidth_deg=half)


def test_direction_accuracy_counts_answers_within_45_degrees():
    outs = [_o(0.3, 350.0, 20.0),                     # 30° off across 0°: right
            _o(0.3, 90.0, 140.0),                     # 50° off: wrong
            _o(0.1, 180.0, 200.0),                    # right, but Δ < 0.15: not in the confident subset
            _o(0.3, 0.0, None, code="inconclusive"),   # no direction given: not right
            _o(0.3, 0.0, 0.0, status="uncertain"),     # right, not confident
            _o(0.3, 0.0, 180.0, dc=False),            # no DC: outside both scopes
            _o(0.0, 0.0, None, code="aligned")]        # healthy: no direction to judge
    conf = np.array([o.status == "confident" for o in outs])
    f = _direction_figures(outs, conf)
    assert f["direction_estimated"] is True
    assert f["direction_n"] == 5 and f["direction_accuracy"] == pytest.approx(3 / 5)
    assert f["direction_given_share"] == pytest.approx(4 / 5) and f["direction_accuracy_given"] == pytest.approx(3 / 4)
    assert f["direction_interval_coverage"] == pytest.approx(3 / 4)        # 30°, 50°, 20°, 0° off against ±40°
    assert f["direction_confident_n"] == 3 and f["direction_accuracy_confident"] == pytest.approx(1 / 3)
    lo, hi = f["direction_accuracy_interval"]
    assert lo < 0.6 < hi


def test_a_model_without_direction_is_reported_as_such_not_as_zero():
    outs = [_o(0.3, 90.0, None, code="model_without_direction") for _ in range(4)]
    f = _figures(outs, ["aligned", "slight", "moderate", "severe"], np.array([0.05, 0.15, 0.35]))
    assert f["direction_estimated"] is False and f["direction_accuracy"] is None
    pooled = {"n": 4, "macro_f1": 0.5, "false_alarm_rate": 0.0, "confident_share": 1.0, "interval_coverage": 1.0,
              "confident_two_bands_off": 0}
    report = {"plant": "p", "held_out": {"n_cases": 4}, "conditions": ["clean"], "models": {"new": "v2", "active": "v1"},
              "per_condition": {}, "pooled": {"new": {**pooled, **_direction_figures(
                  [_o(0.3, 90.0, 80.0)], np.array([True]))}, "active": {**pooled, **f}},
              "paired_bootstrap": {"macro_f1_diff_point": 0.0, "macro_f1_diff": [0, 0], "false_alarm_diff_point": 0.0,
                                   "false_alarm_diff": [0, 0]},
              "decision": {"better": False, "failed": ["x"]}}
    text = format_report(report)
    assert "direction (active): not estimated" in text and "direction (new, within ±45°" in text


# --- table and configuration -------------------------------------------------------------------------------

def test_the_tables_direction_labels_follow_its_rows():
    X, d, f, a, g = journals(3, 4, seed=5)
    t = FeatureTable(X, NAMES, d, g, np.full(len(d), "rigid"), np.full(len(d), 1500.0), offset_angle_rad=f,
                     angular_mrad=a)
    sub = t.subset(np.arange(len(d)) % 2 == 0)
    assert np.array_equal(sub.offset_angle_rad, f[::2]) and np.array_equal(sub.angular_mrad, a[::2])
    assert np.array_equal(t.without_features(["noise_a"]).offset_angle_rad, f)
    both = FeatureTable.concat([t, sub])
    assert both.has_direction_labels and len(both.offset_angle_rad) == len(d) + len(sub)
    plain = FeatureTable(X, NAMES, d, g, np.full(len(d), "rigid"), np.full(len(d), 1500.0))
    assert not plain.has_direction_labels and FeatureTable.concat([t, plain]).offset_angle_rad is None
    with pytest.raises(ValueError, match="offset_angle_rad"):
        FeatureTable(X, NAMES, d, g, np.full(len(d), "rigid"), np.full(len(d), 1500.0), offset_angle_rad=f[:-1])


def test_direction_config_is_validated_and_recorded():
    assert TrainConfig().direction_heads is False
    cfg = TrainConfig.from_dict({"direction": {"heads": True}})
    assert cfg.direction_heads and cfg.to_dict()["direction"] == {"heads": True}
    assert TrainConfig.from_dict(cfg.to_dict()).direction_heads
    with pytest.raises(ValueError, match=r"\[direction\] heads"):
        TrainConfig.from_dict({"direction": {"heads": "yes"}})
    with pytest.raises(ValueError, match=r"\[direction\]: unknown"):
        TrainConfig.from_dict({"direction": {"head": True}})


def test_a_plants_training_config_asks_for_direction_heads():
    from rotordiag.models.plant_retrain import plant_train_config

    assert plant_train_config({"seed": 3}).direction_heads and plant_train_config().seed == 0
    assert TrainConfig.shipped().direction_heads is True         # the shipped recipe has them too (v0002 on)


def test_the_compiled_heads_give_scikit_learns_numbers():
    """The heads are walked by models.compiled's flattened trees: the same points, intervals and angles as the
    fitted regressors' own scikit-learn methods (NaN rows included)."""
    X, d, f, a, g = journals(40, 6, seed=7)
    heads = fit_direction_heads(X, NAMES, d, f, a, g, _reg())
    Xt = journals(5, 6, seed=8)[0]
    Xt[::3, 2:4] = np.nan
    got = predict_heads(heads, Xt)
    for name in ("horizontal_per_c", "vertical_per_c", "angular_mrad"):
        reg = heads["heads"][name]
        np.testing.assert_allclose(got[name][0], reg.predict(Xt), rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(got[name][1], reg.predict_interval(Xt), rtol=1e-10, atol=1e-12)
    for calibration, model in ((False, "point_model_"), (True, "center_model_")):
        theta, size = offset_angle(heads, Xt, calibration=calibration)
        h = getattr(heads["heads"]["horizontal_per_c"], model).predict(Xt)
        v = getattr(heads["heads"]["vertical_per_c"], model).predict(Xt)
        np.testing.assert_allclose(theta, np.arctan2(v, h), atol=1e-10)
        np.testing.assert_allclose(size, np.hypot(h, v), atol=1e-12)
