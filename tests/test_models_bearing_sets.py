"""Which probe set a verdict reads (models.checks.bearing_sets): the model's training sets, and its figures on each."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from rotordiag.models.checks import bearing_sets as bs
from rotordiag.models.status import INCONCLUSIVE

ROOT = Path(__file__).resolve().parent.parent
REGISTRY = ROOT / "models" / "default_registry"
TRAINED = (((1, 2, 3, 4), 4.0), ((2, 3), 2.0), ((1, 2, 3), 1.0), ((2, 3, 4), 1.0), ((2,), 0.5), ((3,), 0.5))
CARD = {"version": "v0009", "created": "2026-01-01T00:00:00+00:00",
        "train_config": {"augment": {"bearing_sets": [{"bearings": list(s), "weight": w} for s, w in TRAINED]}}}


def test_trained_sets_come_from_the_cards_training_configuration():
    assert bs.trained_sets(CARD) == TRAINED
    assert bs.trained_sets({"train_config": {"augment": {}}}) is None
    assert bs.trained_sets({}) is None and bs.trained_sets(None) is None


@pytest.mark.parametrize("present, expect", [
    ((1, 2, 3, 4), (1, 2, 3, 4)), ((2, 3), (2, 3)), ((1, 3, 4), (3,)), ((1, 2, 4), (2,)), ((3, 4), (3,)),
    ((1, 2, 3), (1, 2, 3)), ((2, 3, 4), (2, 3, 4)), ((1, 4), None), ((1,), None), ((4,), None)])
def test_the_answering_set_is_the_largest_training_set_the_recording_has(present, expect):
    assert bs.answering_set(present, TRAINED) == expect


def test_ties_go_to_the_set_trained_with_the_larger_weight():
    assert bs.answering_set((2, 3), (((2,), 0.5), ((3,), 1.0))) == (3,)
    assert bs.answering_set((2, 3), (((2,), 1.0), ((3,), 1.0))) == (2,)      # then the first listed


def test_leaving_out_a_bearing_blanks_its_features_and_the_phase_differences_that_involve_it():
    names = ["speed_rpm", "b1_x_1x_amp_um_pp", "b3_2x_1x_major_ratio", "b4_centre_ecc_per_c",
             "dphase_1x_b2_b3_x_deg", "dphase_2x_b3_b4_y_deg", "b10_weird", "motion_period"]
    row = np.arange(1.0, len(names) + 1)
    out = bs.leave_out_bearings(names, row, (2, 3))
    kept = {n for n, v in zip(names, out) if np.isfinite(v)}
    assert kept == {"speed_rpm", "b3_2x_1x_major_ratio", "dphase_1x_b2_b3_x_deg", "motion_period"}
    assert np.isfinite(row).all()                                           # the input is not changed


def _plan(present, table):
    trained = bs.trained_sets(CARD)
    assert trained is not None
    return bs.BearingPlan(tuple(present), bs.answering_set(present, trained), tuple(s for s, _ in trained), table)


TABLE = {"1-2-3-4": {"n": 480, "macro_f1": 0.77, "false_alarm": 0.0}, "2-3": {"n": 480, "macro_f1": 0.78, "false_alarm": 0.0},
         "1-2-3": {"n": 480, "macro_f1": 0.76, "false_alarm": 0.01}, "2-3-4": {"n": 480, "macro_f1": 0.76, "false_alarm": 0.0},
         "2": {"n": 480, "macro_f1": 0.16, "false_alarm": 0.94}, "3": {"n": 480, "macro_f1": 0.71, "false_alarm": 0.104}}


def test_no_training_set_within_the_probes_is_inconclusive_and_says_what_to_add():
    (r,) = _plan((1, 4), TABLE).reasons()
    assert r.code == "bearing_set_untrained" and r.status == INCONCLUSIVE
    assert r.values["usable"] == "bearings 1 and 4" and r.values["left_out"] == ""


def test_a_set_that_misses_the_gate_is_inconclusive_and_names_the_sets_that_pass():
    (r,) = _plan((1, 2, 4), TABLE).reasons()
    assert r.code == "bearing_set_uninformative" and r.status == INCONCLUSIVE
    assert r.values["macro_f1"] == 0.16 and r.values["false_alarm"] == 0.94
    assert "within bearings 1, 2 and 4" in r.values["via"]
    assert r.values["good_sets"] == "1-2-3-4, 2-3, 1-2-3, 2-3-4"                       # 3 alone is only weak
    assert _plan((1, 2, 4), TABLE).warnings() == []                         # the reason says it all


def test_a_usable_subset_is_read_with_a_note():
    good = {**TABLE, "3": {"n": 480, "macro_f1": 0.71, "false_alarm": 0.08}}
    plan = _plan((1, 3, 4), good)
    assert plan.reasons() == [] and plan.left_out == (1, 4)
    (w,) = plan.warnings()
    assert w.startswith("bearings 1 and 4 not read by the model") and "macro-F1 0.71, false alarms 8.0%" in w
    assert _plan((1, 2, 3, 4), TABLE).warnings() == [] and _plan((2, 3), TABLE).reasons() == []


def test_a_set_with_too_many_false_alarms_is_never_confident():
    plan = _plan((1, 3, 4), TABLE)
    (r,) = plan.reasons()
    assert r.code == "bearing_set_weak" and r.status == "uncertain" and r.values["false_alarm"] == 0.104
    assert len(plan.warnings()) == 1                                        # the note stays


def test_without_figures_for_this_model_only_the_training_sets_decide():
    assert _plan((2,), None).reasons() == [] and _plan((1, 4), None).reasons()[0].code == "bearing_set_untrained"
    (w,) = _plan((1, 3, 4), None).warnings()
    assert "macro-F1" not in w


def test_the_table_applies_only_to_the_model_it_was_measured_for(tmp_path):
    p = tmp_path / "t.json"
    p.write_text(json.dumps({"model": {"version": CARD["version"], "created": CARD["created"]}, "figures": TABLE}))
    assert bs.load_capability(CARD, p) == TABLE
    assert bs.load_capability({**CARD, "created": "2026-02-02T00:00:00+00:00"}, p) is None
    assert bs.load_capability(CARD, tmp_path / "missing.json") is None


def test_the_shipped_table_was_measured_for_the_shipped_model():
    """A retrained default model needs its own figures: `benchmarks/bench_bearing_sets.py --write`."""
    from rotordiag.models.predict import load_bundle

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)
    table = json.loads(bs.CAPABILITY_PATH.read_text(encoding="utf-8"))
    sha = hashlib.sha256((REGISTRY / str(bundle.version) / "model.skops").read_bytes()).hexdigest()
    assert table["model"]["sha256"] == sha, (
        "models/default/bearing_sets.json was measured for another model file: run "
        "`.venv/bin/python benchmarks/bench_bearing_sets.py --write` after retraining the default model")
    assert bs.load_capability(bundle.card) is not None
    trained = bs.trained_sets(bundle.card)
    assert trained is not None and {bs.set_key(s) for s, _ in trained} == set(table["figures"])


def _shipped_figures(key: str) -> dict:
    """The shipped model's measured figures for one training probe set, as the check reads them
    (``load_capability`` of its card: models/default/bearing_sets.json when it was measured for that model)."""
    from rotordiag.models.predict import load_bundle

    table = bs.load_capability(load_bundle(REGISTRY).card)
    assert table is not None, "models/default/bearing_sets.json was measured for another model"
    return table[key]


def _shipped_verdict(bearings, misalignment=0.0, *, plan=True):
    from rotordiag.features import ProbeChannel, Recording, extract_features
    from rotordiag.models.pipeline import diagnose
    from rotordiag.models.predict import ModelBundle, load_bundle
    from tests.service_util import simulated_channels

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)
    if not plan:                                    # every bearing read, as before models.checks.bearing_sets
        bundle = ModelBundle(model=bundle.model, card={}, version=bundle.version)
    fs, ch = simulated_channels(misalignment=misalignment)
    rec = Recording(fs, [ProbeChannel(b, a, "um", d) for b, a, d in ch if b in bearings], speed_rpm=1800.0,
                    clearance_um=350.0)
    return diagnose(bundle, extract_features(rec))


def test_shipped_model_gives_no_severity_from_a_probe_set_it_cannot_read():
    for bearings, code in (((1, 4), "bearing_set_untrained"), ((2,), "bearing_set_uninformative"),
                           ((1, 2, 4), "bearing_set_uninformative")):
        v = _shipped_verdict(bearings)
        assert v.status == INCONCLUSIVE and v.severity == "inconclusive" and v.misalignment is None
        assert v.reasons[0]["code"] == code
        assert v.evidence == _shipped_verdict(bearings, plan=False).evidence       # the evidence reads every bearing


def test_shipped_model_reads_bearing_3_alone_when_the_probes_are_at_1_3_4():
    """The outboard bearings' features are left out: the verdict is the one from bearing 3 alone, with a note; or,
    where the shipped table finds bearing 3 alone uninformative, no severity, and the reason says which set it read."""
    full, alone = _shipped_verdict((1, 3, 4), 0.3), _shipped_verdict((3,), 0.3)
    np.testing.assert_allclose(list(full.probabilities.values()), list(alone.probabilities.values()), atol=0.02)
    assert full.model_severity == alone.model_severity
    figures = _shipped_figures("3")
    if not bs.informative(figures):           # v0004: 35.4 % false alarms from bearing 3 alone
        assert full.status == INCONCLUSIVE and full.reasons[0]["code"] == "bearing_set_uninformative"
        assert "the model reads bearing 3 (the largest of its training sets within bearings 1, 3 and 4)" in str(
            full.reasons[0]["message"])
        return
    assert any(w.code == "bearings_not_read" and w.values["detail"].startswith("bearings 1 and 4 not read by the model")
               for w in full.warnings)
    # the shipped table says whether bearing 3 alone may be confident (v0001: 10.4 % false alarms, never; v0002: 6.2 %)
    weak = figures["false_alarm"] > bs.MAX_FALSE_ALARM
    assert [r["code"] for r in full.reasons if r["code"].startswith("bearing_set")] == (["bearing_set_weak"] * weak)
    assert full.status == "uncertain" or not weak


def test_a_bearing_whose_1x_alone_whirls_backward_is_not_read():
    """Bearing 2's x probe inverted (a polarity or probe-order mistake) turns its 1X backward: the verdict reads
    the training set without it, and says why; with bearing 3 in doubt nothing informative is left."""
    plan = bs.BearingPlan((1, 2, 3, 4), bs.answering_set((1, 3, 4), TRAINED), tuple(s for s, _ in TRAINED), TABLE,
                          suspect=(2,))
    assert plan.answering == (3,) and plan.left_out == (1, 2, 4)
    (r,) = plan.reasons()
    assert r.code == "bearing_set_weak" and r.status == "uncertain" and r.values["false_alarm"] == 0.104
    (w,) = plan.warnings()
    assert "bearing 2: the 1X whirls backward" in w and "without it is 3" in w
    plan3 = bs.BearingPlan((1, 2, 3, 4), bs.answering_set((1, 2, 4), TRAINED), tuple(s for s, _ in TRAINED), TABLE,
                           suspect=(3,))
    (r3,) = plan3.reasons()
    assert r3.code == "bearing_set_uninformative" and "bearing 3 left out: the 1X whirls backward there" in r3.values["via"]


def test_shipped_model_leaves_out_a_bearing_with_an_inverted_probe():
    from rotordiag.features import ProbeChannel, Recording, extract_features
    from rotordiag.models.pipeline import diagnose
    from rotordiag.models.predict import load_bundle
    from tests.service_util import simulated_channels

    if not (REGISTRY / "active").exists():
        pytest.skip("no shipped registry in this checkout")
    bundle = load_bundle(REGISTRY)
    fs, ch = simulated_channels(misalignment=0.0)
    first = {b: min(a for bb, a, _ in ch if bb == b) for b, _, _ in ch}        # each bearing's first probe
    flipped = [ProbeChannel(b, a, "um", -d if (b == 2 and a == first[b]) else d) for b, a, d in ch]
    fr = extract_features(Recording(fs, flipped, speed_rpm=1800.0, clearance_um=350.0))
    assert [f.bearing for f in fr.sanity if f.code == "reverse_whirl"] == [2]
    v = diagnose(bundle, fr)
    codes = [r["code"] for r in v.reasons]
    figures = _shipped_figures("3")
    # reverse_whirl doubts it whatever the set; without bearing 2 the training set left is bearing 3 alone: no severity
    # (v0004: 35.4 % false alarms), weak or not as the shipped table says
    assert "reverse_whirl" in codes and v.status == ("uncertain" if bs.informative(figures) else INCONCLUSIVE)
    assert ("bearing_set_uninformative" in codes) == (not bs.informative(figures))
    assert ("bearing_set_weak" in codes) == (bs.informative(figures) and figures["false_alarm"] > bs.MAX_FALSE_ALARM)
    if bs.informative(figures):
        assert any(w.code == "bearings_not_read" and "bearing 2: the 1X whirls backward" in w.values["detail"]
                   for w in v.warnings)
    else:
        reason = next(r for r in v.reasons if r["code"] == "bearing_set_uninformative")
        assert "bearing 2 left out: the 1X whirls backward there" in reason["message"].values["via"]


def test_probe_sets_lists_each_training_set_with_its_figures_and_verdict(tmp_path, monkeypatch):
    p = tmp_path / "t.json"
    p.write_text(json.dumps({"model": {"version": CARD["version"], "created": CARD["created"]}, "figures": TABLE}))
    monkeypatch.setattr(bs, "CAPABILITY_PATH", p)
    monkeypatch.setattr(bs.load_capability, "__defaults__", (p,))
    out = {bs.set_key(x["bearings"]): x for x in bs.probe_sets(CARD)}
    assert [out[k]["verdict"] for k in ("1-2-3-4", "2", "3")] == ["reads", "no severity", "never confident"]
    assert out["2"]["false_alarm"] == 0.94 and out["2"]["n"] == 480
    assert {x["verdict"] for x in bs.probe_sets({**CARD, "created": "other"})} == {"not measured"}
    assert bs.probe_sets({}) is None
