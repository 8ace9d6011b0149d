"""Dataset specs of finite-element shaft trains (``[plant] model = "train"``): the plant values a family
varies, the spec's refusals, and a small dataset generated, checked against the train simulated directly,
and read as a feature table."""
from __future__ import annotations

import json
import math
from pathlib import Path

import h5py
import numpy as np
import pytest

from rotordiag.simulator import shaftline
from rotordiag.simulator.dataset import generate
from rotordiag.simulator.dataset.spec import SpecError, parse_spec
from rotordiag.simulator.train.plant import TRAIN_PERTURBABLE, TrainPlant, rotor_mass_kg

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

SPEC = """
[design]
method = "sobol"
n_samples = 2
seed = 3

[operating]
speed_rpm = [3000, 3000]
misalignment = [0.0, 0.4]
offset_angle_rad = -1.5707963267948966
mechanism = "rigid"

[plant]
model = "train"
preset = "gen50_2pole"

[measurement]
bearings = [1, 2, 3, 4]
probe_angles_deg = [45.0, 135.0]
sample_rate_hz = 6400
duration_revs = 10

[simulation]
transient_revs = 60
samples_per_rev = 64
classify_motion = false
"""


def test_a_plant_of_a_line_gives_the_line_back_and_records_real_values():
    line = shaftline.preset("gen200_2pole")
    tp = TrainPlant.of(line)
    assert tp.line() == line
    assert TrainPlant.from_dict(tp.to_dict()) == tp
    longer = tp.replace(generator_span_m=1.1 * tp.generator_span_m, generator_body_mass_kg=0.9 * tp.generator_body_mass_kg)
    g0, g1 = line.generator, longer.line().generator
    assert [s[0] for s in g1.segments] == pytest.approx([1.1 * s[0] for s in g0.segments])
    assert [s[1] for s in g1.segments] == [s[1] for s in g0.segments]          # diameters unchanged
    assert [b[0] for b in g1.body_masses] == pytest.approx([1.1 * b[0] for b in g0.body_masses])
    assert sum(b[1] for b in g1.body_masses) == pytest.approx(0.9 * sum(b[1] for b in g0.body_masses))
    assert longer.line().exciter == line.exciter
    with pytest.raises(ValueError, match="clearance_m"):
        tp.replace(clearance_m=-1e-3)
    with pytest.raises(ValueError, match="unknown train plant value"):
        tp.replace(asymmetry=0.1)   # the lumped plant's name, not the train's


def test_balance_grade_gives_the_iso_unbalance():
    """U = G·M/Ω (ISO 21940-11): G2.5 on a rotor of mass M at 3000 r/min, M summed by hand here."""
    line = shaftline.preset("gen50_2pole")
    g = line.generator
    steel = sum(math.pi * d * d / 4 * length * 7850.0 for length, d in (*g.segments, *g.overhang))
    mass = steel + sum(m for _, m in g.body_masses)
    assert rotor_mass_kg(g) == pytest.approx(mass)
    assert TrainPlant.of(line).unbalance_kg_m(3000.0) == pytest.approx(2.5e-3 * mass / (3000 * math.pi / 30))


@pytest.mark.parametrize("old, new, fragment", [
    ('mechanism = "rigid"', 'mechanism = "pin"', "not a shaft train's coupling"),
    ('mechanism = "rigid"', 'mechanism = "rigid"\nunbalance = 0.1', "balance grade"),
    ('preset = "gen50_2pole"', 'file = "plant.toml"', "not a lumped plant file"),
    ('preset = "gen50_2pole"', 'preset = "gen50_2pole"\nperturb = {asymmetry = 0.1}', "cannot be perturbed in a train"),
    ('preset = "gen50_2pole"', 'presets = ["gen50_2pole"]\nset = {rho = 1}', "unknown train plant value"),
])
def test_train_specs_refuse_what_a_train_does_not_have(old, new, fragment):
    assert old in SPEC
    with pytest.raises(SpecError, match=fragment):
        parse_spec(SPEC.replace(old, new))


def test_a_probe_at_a_bearing_the_train_lacks_is_refused(tmp_path):
    text = (EXAMPLES / "shaftline_200mw.toml").read_text()
    old = 'type = ["tilting_pad", "tilting_pad", "elliptical", "elliptical"]'
    assert old in text
    (tmp_path / "line.toml").write_text(text.replace(old, 'type = ["tilting_pad", "tilting_pad", "elliptical", "none"]'))
    spec = SPEC.replace('preset = "gen50_2pole"', 'shaftline = "line.toml"')  # the exciter overhung on bearing 3
    with pytest.raises(SpecError, match="bearings 1..3 only"):
        parse_spec(spec, base_dir=tmp_path)
    assert len(parse_spec(spec.replace("bearings = [1, 2, 3, 4]", "bearings = [1, 2, 3]"), base_dir=tmp_path).sources) == 1


def test_lumped_specs_keep_their_hash_and_perturbable_names():
    lumped = SPEC.replace('model = "train"\n', "").replace('preset = "gen50_2pole"', 'preset = "gen50_2pole"')
    assert parse_spec(lumped).spec_hash == parse_spec(lumped.replace("[plant]", '[plant]\nmodel = "lumped"')).spec_hash
    assert "clearance_m" in TRAIN_PERTURBABLE


def _direct_probe_um(tp: TrainPlant, spec_text: str, index: int, path) -> tuple[np.ndarray, np.ndarray]:
    """The stored sample beside the train simulated here directly (no noise, runout or fluctuation)."""
    from rotordiag.core.conventions import project_on_probe
    from rotordiag.simulator.train.dynamics import simulate_train
    from rotordiag.simulator.train.model import misaligned
    from rotordiag.simulator.train.shaftline import train_from_shaftline
    from rotordiag.simulator.train.transient import unbalanced

    with h5py.File(path, "r") as f:
        delta = float(f["parameters/misalignment"][index])
        phase = float(f["parameters/unbalance_phase_rad"][index])
        theta0 = float(f["measurement/start_angle_rad"][index])
        revs = int(f["parameters/record_revs"][index])
        stored = f["waveforms"][index]
        fs = float(f.attrs["sample_rate_hz"])
    train = train_from_shaftline(tp.line(coupling="rigid"))
    if delta:
        train = misaligned(train, offset_m=delta * tp.clearance_m, direction_rad=-math.pi / 2)
    train = unbalanced(train, tp.unbalance_kg_m(3000.0), angle_rad=phase, replace_own=True)  # not added to the preset's
    run = simulate_train(train, 3000.0, transient_revs=60, record_revs=revs, samples_per_rev=64)
    t = np.arange(stored.shape[1]) / fs
    theta = theta0 + 100 * math.pi * t                # shaft angle from the record's start (module measurement)
    tau = 2 * math.pi / 64 * np.arange(run.journal_m.shape[0])
    from scipy.interpolate import CubicSpline

    xy = CubicSpline(tau, run.journal_m.reshape(len(tau), -1), axis=0)(theta).reshape(len(t), -1, 2) * 1e6
    direct = np.stack([project_on_probe(xy[:, b - 1, 0], xy[:, b - 1, 1], a)
                       for b in (1, 2, 3, 4) for a in (45.0, 135.0)])
    return stored, direct


def test_a_train_dataset_is_the_train_simulated_directly_and_reads_as_features(tmp_path):
    spec = tmp_path / "trains.toml"
    spec.write_text(SPEC)
    out = tmp_path / "trains.h5"
    summary = generate(spec, out, n_workers=0, progress=False)
    assert summary.status_counts == {"ok": 2}
    tp = TrainPlant.of(shaftline.preset("gen50_2pole"))
    with h5py.File(out, "r") as f:
        delta = f["parameters/misalignment"][...]
        np.testing.assert_allclose(f["labels/offset_um"][...], delta * tp.clearance_m * 1e6)
        assert sorted(delta) == [0.0, 0.4]
        codes = {v: k for k, v in json.loads(f["parameters/simulated_mechanism"].attrs["codes_json"]).items()}
        assert [codes[int(c)] for c in f["parameters/simulated_mechanism"][...]] == [
            "aligned" if d == 0 else "rigid" for d in delta]
        assert f["parameters/plant/model"][0] == b"train"
        np.testing.assert_allclose(f["parameters/plant/clearance_m"][...], tp.clearance_m)
        assert np.isnan(f["parameters/unbalance"][...]).all()          # the lumped input does not apply
        np.testing.assert_allclose(f["labels/unbalance_kg_m"][...], tp.unbalance_kg_m(3000.0))
        assert (f["diagnostics/log_decrement"][...] > 0).all()            # gen50 is stable at 3000 r/min
        assert np.isfinite(f["waveforms"][...]).all()
    for i in range(2):
        stored, direct = _direct_probe_um(tp, SPEC, i, out)
        np.testing.assert_allclose(stored, direct, atol=1e-3 * np.abs(direct).max())
    # misaligned downward by 0.4 c: the exciter's bearings moved down, so its journals sit higher in them
    # than the aligned train's (DC of the 45°/135° probes: y = (d45 + d135)/√2)
    with h5py.File(out, "r") as f:
        wf, delta = f["waveforms"][...], f["parameters/misalignment"][...]
    y_um = (wf[:, 0::2].mean(axis=2) + wf[:, 1::2].mean(axis=2)) / math.sqrt(2)   # (sample, bearing)
    mis, ali = int(np.argmax(delta)), int(np.argmin(delta))
    assert y_um[mis, 2] > y_um[ali, 2] + 5.0

    from rotordiag.models.dataset import load_feature_table

    table = load_feature_table(out, cache=False)
    assert table.X.shape[0] == 2 and np.isfinite(table.X).mean() > 0.9
    # [augment] journals_apart_models = ["lumped"]: a train file's copies are those without the journals' shift
    from rotordiag.models.augment import Augmentation

    plain = load_feature_table(out, cache=False, augment=Augmentation(copies=1, seed=3)).X
    lumped_only = Augmentation(copies=1, journals_apart=1.0, journals_apart_models=("lumped",), seed=3)
    np.testing.assert_array_equal(load_feature_table(out, cache=False, augment=lumped_only).X, plain)
    every = Augmentation(copies=1, journals_apart=1.0, seed=3)           # the shift does reach a train's columns
    assert not np.array_equal(load_feature_table(out, cache=False, augment=every).X, plain, equal_nan=True)
    np.testing.assert_allclose(table.misalignment, delta)
    # the direction labels of models.direction: the spec's offset direction per row; no α (the spec keeps it 0)
    np.testing.assert_allclose(table.offset_angle_rad, -math.pi / 2)
    assert table.has_direction_labels and table.angular_mrad is None


def test_a_flexible_samples_coupling_carries_the_offsets_kinematic_forcing():
    """As ``simulate --train`` (train_recording): a flexible coupling under a parallel offset is given the
    double-engagement coupling's kinematic 2X forcing of that offset, in its direction; a rigid one is not."""
    from dataclasses import replace

    from rotordiag.simulator.dataset import build_design
    from rotordiag.simulator.dataset.worker import sample_train

    tp = TrainPlant.of(shaftline.preset("gen50_2pole"))
    p = next(q for q in (build_design(parse_spec(SPEC))[i] for i in range(2)) if q.misalignment > 0)
    flex = sample_train(tp, replace(p, mechanism="flexible")).couplings[0]
    assert flex.kind == "flexible"
    assert flex.kinematic_offset_m == pytest.approx(0.4 * tp.clearance_m)
    assert math.sin(flex.kinematic_direction_rad) == pytest.approx(-1.0)          # downward, as offset_angle_rad
    rigid = sample_train(tp, p).couplings[0]
    assert rigid.kind == "rigid" and rigid.kinematic_offset_m == 0.0
