"""End-to-end dataset generation with the real simulator: layout, labels, resume rules, Dask vs serial."""
from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

from rotordiag.simulator import Plant, build_system, simulate
from rotordiag.simulator.dataset.design import build_design
from rotordiag.simulator.dataset.generate import generate
from rotordiag.simulator.dataset.spec import load_spec
from rotordiag.simulator.dataset.store import StoreError, open_dataset
from rotordiag.simulator.steady.start import steady_start

from .dataset_support import differing_datasets, write_spec


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("ds")
    spec = write_spec(d / "spec.toml")
    out = d / "serial.h5"
    summary = generate(spec, out, n_workers=0, progress=False)
    return spec, out, summary


def test_layout_and_attributes(small):
    spec, out, summary = small
    assert summary.complete and summary.n_computed == 8 and not summary.resumed
    r = load_spec(spec)
    with h5py.File(out, "r") as f:  # a completed file opens with plain h5py
        w = f["waveforms"]
        assert w.shape == (8, 8, 164) and w.dtype == np.float32
        assert w.chunks == (1, 8, 164) and w.compression == "gzip"
        assert f["done"][...].tolist() == [1] * 8
        assert f["channels"]["bearing"].tolist() == [1, 1, 2, 2, 3, 3, 4, 4]
        assert f["channels"]["angle_deg"].tolist() == [45.0, 135.0] * 4
        assert f.attrs["spec_hash"] == r.spec_hash
        assert f.attrs["spec_toml"] == spec.read_text()
        assert f.attrs["code_version"].startswith("0.1.0")
        assert f.attrs["created_utc"]
        assert not any(f["resume_log"][...])  # never resumed
        assert f.attrs["sample_rate_hz"] == 1024.0 and f.attrs["n_points"] == 164
        for name in Plant.field_names():
            # the exciter span is stored only by specs with an angular offset (older files keep their layout)
            assert (f"parameters/plant/{name}" in f) == (name != "exciter_bearing_span_m")
        assert "parameters/angular_misalignment_mrad" not in f
        assert f["parameters/plant/bearing_offset_m"].shape == (8, 4, 2)
        assert np.all(np.isfinite(w[...]))


def test_parameters_and_labels_match_the_design(small):
    spec, out, _ = small
    design = build_design(load_spec(spec))
    with h5py.File(out, "r") as f:
        delta = f["parameters/misalignment"][...]
        for i in range(8):
            p = design[i]
            assert f["parameters/speed_rpm"][i] == p.speed_rpm
            assert f["parameters/sample_seed"][i] == p.sample_seed
            assert f["parameters/plant/generator_mass_kg"][i] == p.plant["generator_mass_kg"]
            assert f["parameters/plant_id"][i].decode() == Plant.from_dict(p.plant).plant_id()
            codes = json.loads(f["parameters/mechanism"].attrs["codes_json"])
            assert f["parameters/mechanism"][i] == codes[p.mechanism]
        # severity by the documented bands, computed here independently
        expected = np.select([delta < 0.05, delta < 0.15, delta < 0.35], [0, 1, 2], 3)
        assert f["labels/severity"][...].tolist() == expected.tolist()
        assert json.loads(f["labels/severity"].attrs["names_json"]) == ["aligned", "slight", "moderate", "severe"]
        assert np.array_equal(f["labels/misalignment"][...], delta)
        assert set(f["labels/status"][...].tolist()) == {0}
        kinds = {k.decode() for k in f["labels/motion_kind"][...]}
        assert kinds <= {"period-n", "quasi-periodic", "chaotic", "unresolved"}


def test_waveform_equals_the_simulator_seen_through_the_probes(small):
    """Rebuild sample 0 from simulate() and the documented measurement model by hand."""
    from scipy.interpolate import CubicSpline

    spec, out, _ = small
    p = build_design(load_spec(spec))[0]
    with h5py.File(out, "r") as f:
        revs = int(f["parameters/record_revs"][0])
        theta0 = f["measurement/start_angle_rad"][0]
        phi_m = f["measurement/speed_fluctuation_phase_rad"][0]
        r1, p1 = f["measurement/runout_1x_um"][0], f["measurement/runout_1x_phase_rad"][0]
        r2, p2 = f["measurement/runout_2x_um"][0], f["measurement/runout_2x_phase_rad"][0]
        snr = f["measurement/snr_db"][0]
        stored = f["waveforms"][0].astype(float)
        path = f["diagnostics/steady_start"][0].decode()
    kw = dict(mechanism=p.mechanism, unbalance_phase_rad=p.unbalance_phase_rad, offset_angle_rad=p.offset_angle_rad)
    plant = Plant.from_dict(p.plant)
    # the record starts where the file says: on the shot orbit, or after the transient
    start = steady_start(build_system(plant, p.speed_rpm, p.misalignment, p.unbalance, **kw), 30)
    assert start.path == path
    res = simulate(plant, p.speed_rpm, p.misalignment, p.unbalance, transient_revs=start.transient_revs,
                   record_revs=revs, samples_per_rev=128, initial_state=start.state, **kw)
    t = np.arange(164) / 1024.0
    w = p.speed_rpm * np.pi / 30
    wm = 2 * np.pi * 0.5
    theta = theta0 + w * t + w * 0.002 / wm * (np.cos(phi_m) - np.cos(wm * t + phi_m))
    tau = 2 * np.pi / 128 * np.arange(res.journal_displacements_m.shape[0])
    xy = CubicSpline(tau, res.journal_displacements_m, axis=0)(theta) * 1e6
    for c in range(8):
        b, alpha = c // 2, np.radians((45.0, 135.0)[c % 2])
        psi = alpha - theta
        clean = (xy[:, b, 0] * np.cos(alpha) + xy[:, b, 1] * np.sin(alpha)
                 + r1[b] * np.cos(psi - p1[b]) + r2[b] * np.cos(2 * psi - p2[b]))
        noise_sd = np.sqrt(clean.var() / 10 ** (snr / 10))
        resid = stored[c] - clean
        assert abs(resid.mean()) < 4 * noise_sd / np.sqrt(164) + 1e-3
        assert resid.std() == pytest.approx(noise_sd, rel=0.25)


def test_recorded_runout_is_the_runout_the_measurement_model_added(small):
    """``recorded_runout_um`` rebuilds step 3 of the measurement model from the stored draws (what the
    training augmentation subtracts to make a runout-free copy): checked against the formula by hand."""
    from rotordiag.simulator.dataset import DatasetReader
    from rotordiag.simulator.dataset.read import recorded_runout_um

    _, out, _ = small
    with h5py.File(out, "r") as f:
        for i in (0, 3):
            speed = f["parameters/speed_rpm"][i]
            theta0 = f["measurement/start_angle_rad"][i]
            phi_m = f["measurement/speed_fluctuation_phase_rad"][i]
            r1, p1 = f["measurement/runout_1x_um"][i], f["measurement/runout_1x_phase_rad"][i]
            r2, p2 = f["measurement/runout_2x_um"][i], f["measurement/runout_2x_phase_rad"][i]
            t = np.arange(164) / 1024.0
            w, wm = speed * np.pi / 30, 2 * np.pi * 0.5
            theta = theta0 + w * t + w * 0.002 / wm * (np.cos(phi_m) - np.cos(wm * t + phi_m))
            got = recorded_runout_um(f, i)
            assert got.shape == (8, 164)
            for c in range(8):
                b, alpha = c // 2, np.radians((45.0, 135.0)[c % 2])
                psi = alpha - theta
                hand = r1[b] * np.cos(psi - p1[b]) + r2[b] * np.cos(2 * psi - p2[b])
                np.testing.assert_allclose(got[c], hand, rtol=0, atol=1e-9)
            assert np.abs(got).max() > 0.05          # the spec draws runout: not a zero array
    with DatasetReader(out) as ds:
        np.testing.assert_array_equal(ds.runout_um(3), got)


def test_recorded_runout_of_a_merged_file_uses_each_rows_source_spec(small, tmp_path):
    """A merged file has no spec of its own (spec_json ""): the runout of a row is rebuilt with its source's."""
    from rotordiag.simulator.dataset import merge
    from rotordiag.simulator.dataset.read import recorded_runout_um

    _, out, _ = small
    spec = write_spec(tmp_path / "other.toml", n_samples=2, seed=8)
    spec.write_text(spec.read_text().replace("speed_fluctuation = 0.002", "speed_fluctuation = 0.02"))
    other = tmp_path / "other.h5"
    generate(spec, other, n_workers=0, progress=False)
    merged = tmp_path / "merged.h5"
    merge([out, other], merged)
    with h5py.File(out, "r") as a, h5py.File(other, "r") as b, h5py.File(merged, "r") as m:
        assert m.attrs["spec_json"] == "" and m.attrs["merged"]
        src = m["source"][...]
        for k in (0, 5, int(np.flatnonzero(src == 1)[0]), int(np.flatnonzero(src == 1)[-1])):
            f, row = (a, k) if src[k] == 0 else (b, k - int(np.flatnonzero(src == 1)[0]))
            np.testing.assert_array_equal(m["waveforms"][k], f["waveforms"][row])
            # (the second source's speed fluctuation is 10× the first's: its rows match only with its own spec)
            np.testing.assert_allclose(recorded_runout_um(m, k), recorded_runout_um(f, row), rtol=0, atol=1e-12)



def _capture_extractions(monkeypatch) -> list:
    """Replace ``features.extract_features`` by a recorder: the returned list receives every Recording a table
    build extracts (their features are zeros)."""
    import rotordiag.features as feats

    seen: list = []

    class Result:
        values = np.zeros(len(feats.FEATURE_NAMES))

    monkeypatch.setattr(feats, "extract_features", lambda rec: seen.append(rec) or Result)
    return seen

def test_runout_scaled_training_copies_subtract_the_recorded_runout(small, monkeypatch):
    """[augment] runout_scaled: a copy's waveforms are the stored ones minus (1 − s) × the recorded runout,
    s ~ U(0, 1); the other draws of a copy (gains, bearings, speed) are the same as without it."""
    from rotordiag.models.augment import Augmentation
    from rotordiag.models.dataset import _extract_rows
    from rotordiag.simulator.dataset.read import recorded_runout_um

    _, out, _ = small
    seen = _capture_extractions(monkeypatch)
    aug = Augmentation(copies=6, gain_mismatch=0.1, runout_scaled=0.5, seed=1)
    with h5py.File(out, "r") as f:
        bearings = [int(b) for b in f["channels"]["bearing"]]
        _extract_rows(f, np.array([2]), None, aug)
        w = f["waveforms"][2].astype(float)
        r = recorded_runout_um(f, 2)
    variants = aug.variants(2, bearings)
    scales = [v.runout_scale for v in variants]
    assert any(s == 1.0 for s in scales) and any(s < 1.0 for s in scales) and all(0 <= s <= 1 for s in scales)
    assert len(seen) == 6
    for rec, v in zip(seen, variants):
        for j, ch in enumerate(rec.channels):
            np.testing.assert_allclose(ch.data, (w[j] - (1 - v.runout_scale) * r[j]) * v.gains[j], rtol=1e-6, atol=1e-6)
    plain = Augmentation(copies=6, gain_mismatch=0.1, seed=1).variants(2, bearings)
    for a, b in zip(plain, variants):
        np.testing.assert_array_equal(a.gains, b.gains)
        assert a.speed_known == b.speed_known and a.runout_scale == 1.0
    with pytest.raises(ValueError, match="runout_scaled"):
        Augmentation(runout_scaled=1.5)



def test_journals_apart_copies_move_bearing_3s_static_reading_only(small, monkeypatch):
    """[augment] journals_apart: a copy's bearing-3 channels read a static shift of ≤ journals_apart_c clearances
    (projected on each probe's axis); the other channels, and the copy's other draws, are as without it."""
    from rotordiag.models.augment import Augmentation
    from rotordiag.models.dataset import _extract_rows

    _, out, _ = small
    seen = _capture_extractions(monkeypatch)
    aug = Augmentation(copies=8, journals_apart=0.5, journals_apart_c=0.3, seed=3)
    with h5py.File(out, "r") as f:
        bearings = [int(b) for b in f["channels"]["bearing"]]
        angles = [float(a) for a in f["channels"]["angle_deg"]]
        clearance_um = float(f["parameters/plant/clearance_m"][1]) * 1e6
        _extract_rows(f, np.array([1]), None, aug)
        w = f["waveforms"][1].astype(float)
    variants = aug.variants(1, bearings)
    shifts = [np.hypot(*v.journal3_shift_c) for v in variants]
    assert any(s == 0.0 for s in shifts) and any(s > 0.0 for s in shifts) and max(shifts) <= 0.3
    for rec, v in zip(seen, variants):
        sx, sy = (clearance_um * s for s in v.journal3_shift_c)
        kept = [j for j in range(len(bearings)) if v.keep[j]]
        for ch, j in zip(rec.channels, kept):
            move = sx * np.cos(np.deg2rad(angles[j])) + sy * np.sin(np.deg2rad(angles[j])) if bearings[j] == 3 else 0.0
            np.testing.assert_allclose(ch.data, (w[j] + move) * v.gains[j], rtol=1e-6, atol=1e-6)
    plain = Augmentation(copies=8, seed=3).variants(1, bearings)
    for a, b in zip(plain, variants):
        np.testing.assert_array_equal(a.gains, b.gains)
        np.testing.assert_array_equal(a.keep, b.keep)
        assert a.speed_known == b.speed_known and a.journal3_shift_c == (0.0, 0.0)
    assert "journals_apart" not in Augmentation(copies=2).to_dict()      # the shipped key (feature caches) unchanged
    with pytest.raises(ValueError, match="journals_apart"):
        Augmentation(journals_apart=2.0)


def test_journals_apart_models_shift_only_the_named_simulations_samples(small):
    """[augment] journals_apart_models = ["lumped"]: a lumped file's copies get the journals' shift; for a train
    file the augmentation, and so its rows and cache key, is the one without it (a train's journals already sit
    apart). The train file's rows: tests/test_dataset_trains.py."""
    from rotordiag.models.augment import Augmentation
    from rotordiag.models.dataset import _simulation

    _, out, _ = small
    with h5py.File(out, "r") as f:
        assert _simulation(f) == "lumped"                 # the small spec simulates the paper's model
    only_trains = Augmentation(copies=2, journals_apart=1.0, journals_apart_models=("train",), seed=3)
    only_lumped = Augmentation(copies=2, journals_apart=1.0, journals_apart_models=("lumped",), seed=3)
    plain = Augmentation(copies=2, seed=3)
    assert only_trains.for_simulation("lumped") == plain and only_trains.for_simulation("lumped").key == plain.key
    assert only_lumped.for_simulation("lumped") is only_lumped and only_lumped.key != plain.key
    assert only_lumped.for_simulation(None) == plain                  # a file that does not say: not shifted
    assert Augmentation(copies=2, journals_apart=1.0, seed=3).for_simulation("train").journals_apart == 1.0  # all
    shifts = [v.journal3_shift_c for v in only_lumped.variants(1, [1, 1, 2, 2, 3, 3, 4, 4])]
    assert all(s != (0.0, 0.0) for s in shifts)                       # share 1: every copy
    assert "journals_apart_models" not in Augmentation(copies=2, journals_apart_models=("lumped",)).to_dict()
    with pytest.raises(ValueError, match="journals_apart_models"):
        Augmentation(journals_apart=1.0, journals_apart_models=("ross",))


def test_contact_samples_are_kept_with_their_status(tmp_path):
    spec = write_spec(tmp_path / "spec.toml", n_samples=2)
    text = spec.read_text().replace("misalignment = {min = 0.0, max = 0.5}", "misalignment = 0.9") \
        .replace("mechanism = {pin = 1, rigid = 1}", 'mechanism = "rigid"') \
        .replace("speed_rpm = {min = 1500, max = 2100}", "speed_rpm = 3000") \
        .replace("offset_angle_rad = {min = 0.0, max = 6.283185307179586}", "offset_angle_rad = 0.0")
    spec.write_text(text.replace("sample_rate_hz = 1024.0", "sample_rate_hz = 2048.0"))
    summary = generate(spec, tmp_path / "c.h5", n_workers=0, progress=False)
    assert summary.status_counts == {"contact": 2}
    with open_dataset(tmp_path / "c.h5") as f:
        assert f["done"][...].tolist() == [1, 1]
        assert f["labels/status"][...].tolist() == [1, 1]
        assert b"journal reached its bushing" in f["diagnostics/message"][0]
        assert np.all(np.isnan(f["waveforms"][...]))  # contact at the start: nothing recorded
        assert f["labels/severity"][...].tolist() == [3, 3]


def test_rerun_of_a_complete_file_computes_nothing_and_other_specs_are_refused(small, tmp_path, monkeypatch):
    spec, out, _ = small

    def no_cluster(*args, **kwargs):
        raise AssertionError("a complete file must not start a cluster")

    with monkeypatch.context() as m:
        m.setattr("rotordiag.simulator.runner.run_tasks", no_cluster)
        again = generate(spec, out, progress=False)  # default: local cluster, if there were work
    assert again.resumed and again.n_computed == 0 and again.complete
    other = write_spec(tmp_path / "other.toml", seed=8)
    with pytest.raises(StoreError, match="different spec"):
        generate(other, out, n_workers=0, progress=False)
    # a comment-only edit is the same spec
    same = tmp_path / "same.toml"
    same.write_text("# edited comment\n" + spec.read_text())
    assert generate(same, out, n_workers=0, progress=False).n_computed == 0


def test_output_that_is_not_a_dataset_is_refused(tmp_path):
    spec = write_spec(tmp_path / "spec.toml")
    with h5py.File(tmp_path / "x.h5", "w") as f:
        f["a"] = 1
    with pytest.raises(StoreError, match="not a rotordiag dataset"):
        generate(spec, tmp_path / "x.h5", n_workers=0, progress=False)
    (tmp_path / "y.h5").write_text("hello")
    with pytest.raises(StoreError, match="not a readable HDF5 file"):
        generate(spec, tmp_path / "y.h5", n_workers=0, progress=False)


def test_a_second_writer_is_refused_while_the_first_holds_the_file(tmp_path):
    from rotordiag.simulator.dataset.store import _Lock

    spec = write_spec(tmp_path / "spec.toml")
    lock = _Lock(tmp_path / "o.h5")
    lock.acquire()
    try:
        with pytest.raises(StoreError, match="another process"):
            generate(spec, tmp_path / "o.h5", n_workers=0, progress=False)
    finally:
        lock.release()


def test_dask_cluster_via_a_client_gives_the_serial_values(small, tmp_path):
    """(The runner's own LocalCluster path is exercised by the SIGKILL test with --workers 1.)"""
    from distributed import Client, LocalCluster

    spec, serial, _ = small
    out = tmp_path / "dask.h5"
    calls = []
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster, set_as_default=False) as client:
        s = generate(spec, out, client=client, progress=False, on_progress=lambda d, n: calls.append((d, n)))
        assert client.status == "running"  # the caller's client is left open
    assert s.complete
    assert calls == [(k, 8) for k in range(9)]
    assert differing_datasets(serial, out) == []


def test_a_sample_the_simulator_refuses_is_labelled_error_not_dropped(small):
    import dataclasses

    from rotordiag.simulator.dataset.measurement import MeasurementSettings
    from rotordiag.simulator.dataset.worker import SampleTask, SimulationSettings, run_sample

    spec, _, _ = small
    r = load_spec(spec)
    p = dataclasses.replace(build_design(r)[0], misalignment=0.95)  # outside MODEL.md's range
    out = run_sample(SampleTask(p, SimulationSettings.from_spec(r.spec), MeasurementSettings.from_spec(r.spec)))
    assert out.status == "error" and "misalignment" in out.message
    assert out.waveforms_um.shape == (8, 164) and np.all(np.isnan(out.waveforms_um))


def test_conflicting_execution_options_are_refused_before_any_file_is_made(tmp_path):
    spec = write_spec(tmp_path / "spec.toml")
    with pytest.raises(ValueError, match="at most one of n_workers, scheduler_address"):
        generate(spec, tmp_path / "o.h5", n_workers=2, scheduler_address="tcp://127.0.0.1:1")
    with pytest.raises(ValueError, match="n_workers must be >= 0"):
        generate(spec, tmp_path / "o.h5", n_workers=-1)
    assert not (tmp_path / "o.h5").exists()


def test_angular_offset_dataset_records_alpha_and_simulates_it(tmp_path):
    """A spec with an angular offset: the column and the exciter span are written, α is applied to the
    offset/flexible samples only, and a stored waveform equals the simulator run with that α."""
    from .dataset_support import SMALL_SPEC

    text = SMALL_SPEC.format(n_samples=4, seed=11, sample_rate_hz=1024.0, transient_revs=30)
    text = text.replace("mechanism = {pin = 1, rigid = 1}", "angular_misalignment_mrad = {min = 0.02, max = 0.08}\n"
                        "mechanism = {pin = 1, offset = 1}")
    spec = tmp_path / "spec.toml"
    spec.write_text(text)
    out = tmp_path / "ang.h5"
    generate(spec, out, n_workers=0, progress=False)
    design = build_design(load_spec(spec))
    mechs = {design[i].mechanism for i in range(4)}
    assert mechs == {"pin", "offset"}  # both kinds present, so the 'applied to offset only' rule is exercised
    with h5py.File(out, "r") as f:
        assert "parameters/plant/exciter_bearing_span_m" in f
        alpha = f["parameters/angular_misalignment_mrad"][...]
        assert set(f["labels/status"][...].tolist()) == {0}
        for i in range(4):
            p = design[i]
            assert alpha[i] == p.angular_misalignment_mrad and 0.02 <= alpha[i] <= 0.08
            assert f["parameters/plant/exciter_bearing_span_m"][i] == 3.4
        # the offset sample really ran with its α: the DC of its bearing-4 probes (the static journal position
        # relative to the moved bearing centre; noise and runout have zero mean) is the simulator's with α
        i = next(k for k in range(4) if design[k].mechanism == "offset")
        stored = f["waveforms"][i].astype(float)
    p = design[i]
    plant = Plant.from_dict(p.plant)
    kw = dict(mechanism="offset", unbalance_phase_rad=p.unbalance_phase_rad, offset_angle_rad=p.offset_angle_rad,
              transient_revs=200, record_revs=8, samples_per_rev=64, settle_tol=1e-9)
    dc = {}
    for label, a in (("with", p.angular_misalignment_mrad), ("without", 0.0)):
        r = simulate(plant, p.speed_rpm, p.misalignment, p.unbalance, angular_misalignment_mrad=a, **kw)
        assert r.ok
        mean_xy = r.journal_displacements_m[:, 3, :].mean(axis=0) * 1e6
        dc[label] = np.array([mean_xy @ [np.cos(np.radians(g)), np.sin(np.radians(g))] for g in (45.0, 135.0)])
    got = stored[6:8].mean(axis=1)
    assert np.abs(dc["with"] - dc["without"]).max() > 5.0  # α moves the static position measurably
    assert np.abs(got - dc["with"]).max() < 0.2 * np.abs(dc["with"] - dc["without"]).max()
