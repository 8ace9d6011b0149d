"""Run-ups and coast-downs in dataset specs (issue 46): a ``[transient]`` spec generates samples with the transient
simulator, they read back with their profile and keyphasor, are deterministic per seed, and their 1X Bode peaks
at the plant's linear critical speeds; bad profiles are refused before anything is written, and steady and
transient readers refuse each other's files."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from rotordiag.simulator.dataset import DatasetReader, StoreError, generate, parse_spec, summarize
from rotordiag.simulator.dataset.spec import SpecError
from tests.dataset_support import differing_datasets, write_spec

#: Three run-ups of the paper's model 800 → 1600 r/min in 16 s (50 r/min/s, through its ~1100 and ~1250 r/min
#: criticals), horizontal and vertical probes, measurement noise and runout as steady datasets have them.
RUNUP_SPEC = """\
[design]
method = "sobol"
n_samples = 3
seed = {seed}

[operating]
misalignment = [0.0, 0.2]
unbalance = {{min = 0.04, max = 0.06}}
unbalance_phase_rad = {{min = 0.0, max = 6.283185307179586}}
mechanism = "rigid"

[transient]
start_rpm = 800
end_rpm = 1600
duration_s = 16
settle_revs = 100

[measurement]
bearings = [1, 2]
probe_angles_deg = [0.0, 90.0]
sample_rate_hz = 2560.0
snr_db = 40.0
runout_1x_um = {{min = 0.0, max = 1.0}}
runout_2x_um = {{min = 0.0, max = 0.5}}
"""


@pytest.fixture(scope="module")
def runups(tmp_path_factory) -> tuple[Path, Path, Path]:
    """The spec generated twice with seed 46 (serial and on two workers) and once with seed 47."""
    d = tmp_path_factory.mktemp("runups")
    out = []
    for name, seed, workers in (("a.h5", 46, 0), ("b.h5", 46, 2), ("c.h5", 47, 0)):
        spec = d / f"{name}.toml"
        spec.write_text(RUNUP_SPEC.format(seed=seed))
        s = generate(spec, d / name, n_workers=workers, progress=False)
        assert s.complete and s.status_counts == {"ok": 3}, s
        out.append(d / name)
    return out[0], out[1], out[2]


def test_runups_read_back_with_their_profile_and_keyphasor(runups):
    from rotordiag.simulator.transient import SpeedProfile

    with DatasetReader(runups[0]) as ds:
        assert ds.kind == "transient" and len(ds) == 3
        lab = ds.labels()
        assert sorted(set(lab["misalignment"].tolist())) == [0.0, 0.2]
        assert set(lab["mechanism"]) <= {"aligned", "rigid"} and all(
            (m == "aligned") == (d == 0.0) for m, d in zip(lab["mechanism"], lab["misalignment"]))
        assert len(set(lab["sample_seed"].tolist())) == 3
        marks = SpeedProfile.linear(800, 1600, 16).revolution_times_s()  # the profile's exact marks: 320 revs
        for i in ds.indices:
            s = ds.transient_sample(i)
            assert s.status == "ok" and s.waveforms_um.shape == (4, 16 * 2560)
            assert s.n_valid_points == 16 * 2560 and np.all(np.isfinite(s.waveforms_um))
            assert s.keyphasor_times_s.size == 320 and np.allclose(s.keyphasor_times_s, marks[:320], atol=1e-12)
            assert s.speed_rpm[0] == 800.0 and s.speed_rpm[-1] == pytest.approx(1600.0, abs=0.05)
            assert s.channels == [(1, 0.0), (1, 90.0), (2, 0.0), (2, 90.0)]
            # the journals' static position is kept (DC-coupled probes): the vertical probes read the sag
            assert np.mean(s.waveforms_um[1]) < 0
            kp = s.keyphasor_signal()
            assert kp.shape == (16 * 2560,) and np.count_nonzero(np.diff((kp < -0.5).astype(int)) == 1) >= 318
        # parameters, code version and seed per sample, as for steady samples
        assert ds.attrs["sample_kind"] == "transient" and ds.attrs["code_version"]
        assert np.all(np.isnan(ds.parameters("measurement/start_angle_rad")))  # not used: the angle is the profile's
    info = summarize(runups[0])
    assert info["sample_kind"] == "transient" and info["transient"]["keyphasor_marks"] == 320
    assert info["transient"]["profiles"] == [{"times_s": [0.0, 16.0], "speeds_rpm": [800.0, 1600.0]}]
    assert "speed_rpm" not in info["parameter_ranges"]
    from rotordiag.cli import app

    r = CliRunner().invoke(app, ["dataset", "info", str(runups[0])])
    assert r.exit_code == 0 and "samples are run-ups / coast-downs with a keyphasor: profile 0 s 800 r/min, " \
        "16 s 1600 r/min" in r.output and "320 keyphasor marks, 0 stopped early" in r.output, r.output


def test_runups_are_deterministic_per_seed(runups):
    a, b, c = runups
    assert differing_datasets(a, b) == []                      # serial and two workers: the same values
    diff = differing_datasets(a, c)
    assert "waveforms" in diff and "parameters/sample_seed" in diff


def test_each_runups_1x_bode_peaks_at_a_linear_critical_speed(runups):
    """Each sample's 1X Bode, order-tracked by features.transient from its stored probes and keyphasor, peaks
    within the half-power half-width ζ·n_c of a damped critical of the linearised plant (simulator.campbell), in
    both directions at bearing 1 (the ramp crosses the ~1100 r/min and ~1250 r/min criticals)."""
    from rotordiag.features import ProbeChannel, Recording
    from rotordiag.features.transient import track_orders
    from rotordiag.simulator import Plant
    from rotordiag.simulator.campbell import campbell, critical_speeds

    crit = critical_speeds(campbell(Plant.default(), np.arange(800, 1601, 25.0)))
    assert crit, "no lightly damped critical between 800 and 1600 r/min"
    with DatasetReader(runups[0]) as ds:
        for i in ds.indices:
            s = ds.transient_sample(i)
            rec = Recording(sample_rate_hz=s.sample_rate_hz, keyphasor_times_s=s.keyphasor_times_s[1:],
                            channels=[ProbeChannel(b, a, "um", s.waveforms_um[k].astype(float))
                                      for k, (b, a) in enumerate(s.channels)])
            track = track_orders(rec)
            assert track.kind == "run-up" and track.phase_referenced
            peaks = {(p["bearing"], p["angle_deg"]): p["speed_rpm"] for p in track.peaks(1)}
            for probe in ((1, 0.0), (1, 90.0)):
                assert probe in peaks, (i, probe, track.peaks(1))
                nearest = min(crit, key=lambda c: abs(c.speed_rpm - peaks[probe]))
                assert abs(peaks[probe] - nearest.speed_rpm) <= 0.5 * nearest.half_power_width_rpm, \
                    (i, probe, peaks[probe], nearest)


def test_steady_and_transient_readers_refuse_each_others_files(runups, tmp_path):
    from rotordiag.models.dataset import load_feature_table
    from rotordiag.simulator.dataset.read import recorded_runout_um

    with DatasetReader(runups[0]) as ds:
        for call in (lambda: ds.waveforms(0), lambda: next(ds.iter_waveforms()), lambda: ds.runout_um(0),
                     lambda: recorded_runout_um(ds.f, 0)):
            with pytest.raises(StoreError, match="reads steady samples .* holds run-ups or coast-downs"):
                call()
    with pytest.raises(ValueError, match="the feature table .* holds run-ups or coast-downs"):
        load_feature_table(runups[0], cache=False)
    steady = tmp_path / "steady.h5"
    generate(write_spec(tmp_path / "steady.toml", n_samples=1), steady, n_workers=0, progress=False)
    with DatasetReader(steady) as ds:
        assert ds.kind == "steady" and ds.waveforms(0).shape[0] == 8
        with pytest.raises(StoreError, match="reads run-up / coast-down samples; .* holds steady samples"):
            ds.transient_sample(0)
    from rotordiag.simulator.dataset import merge

    with pytest.raises(StoreError, match="not of the same family"):
        merge([steady, runups[0]], tmp_path / "mixed.h5")
    assert not (tmp_path / "mixed.h5").exists()
    merge([runups[0], runups[2]], tmp_path / "both.h5")          # two run-up sets of one profile: one file
    with DatasetReader(tmp_path / "both.h5") as ds, DatasetReader(runups[2]) as c:
        assert ds.kind == "transient" and len(ds) == 6
        assert np.array_equal(ds.transient_sample(3).waveforms_um, c.transient_sample(0).waveforms_um)
        with pytest.raises(StoreError, match="holds run-ups or coast-downs"):
            ds.waveforms(0)


BASE = RUNUP_SPEC.format(seed=46)


def test_a_coast_down_from_a_table_profile(tmp_path):
    """A table profile (a coast-down 1600 → 1000 r/min with a knee at 2 s): stored as given, the keyphasor marks
    are the profile's and spread out as the shaft slows, and the example spec is valid."""
    from rotordiag.simulator.dataset import load_spec
    from rotordiag.simulator.transient import SpeedProfile

    assert load_spec(Path(__file__).parents[1] / "examples" / "dataset_runup.toml").spec.is_transient
    text = (BASE.replace("n_samples = 3", "n_samples = 1")
            .replace("start_rpm = 800\nend_rpm = 1600\nduration_s = 16",
                     "times_s = [0, 2, 4]\nspeeds_rpm = [1600, 1200, 1000]"))
    spec = tmp_path / "coast.toml"
    spec.write_text(text)
    assert generate(spec, tmp_path / "coast.h5", n_workers=0, progress=False).status_counts == {"ok": 1}
    with DatasetReader(tmp_path / "coast.h5") as ds:
        smp = ds.transient_sample(0)
    assert smp.profile_times_s.tolist() == [0.0, 2.0, 4.0] and smp.profile_speeds_rpm.tolist() == [1600, 1200, 1000]
    marks = SpeedProfile.table([0, 2, 4], [1600, 1200, 1000]).revolution_times_s()
    assert np.allclose(smp.keyphasor_times_s, marks[:smp.keyphasor_times_s.size], atol=1e-12)
    assert smp.keyphasor_times_s.size == marks.size - 1 or smp.keyphasor_times_s.size == marks.size
    period = np.diff(smp.keyphasor_times_s)
    assert period[0] == pytest.approx(60 / 1600, rel=0.01) and period[-1] == pytest.approx(60 / 1000, rel=0.02)
    assert np.all(np.diff(period) > -1e-12)                    # each revolution longer than the one before


@pytest.mark.parametrize("old, new, fragment", [
    ("start_rpm = 800\nend_rpm = 1600\nduration_s = 16",
     "times_s = [0, 8, 16]\nspeeds_rpm = [800, 1600, 1200]", "speed profile reverses at t = 8 s"),
    ("start_rpm = 800", "start_rpm = 0", "0 r/min at t = 0 s is outside the model's range 100–6000 r/min"),
    ("end_rpm = 1600", "end_rpm = 7000", "outside the model's range"),
    ("sample_rate_hz = 2560.0", "sample_rate_hz = 300000.0", "4800000 points per channel is too many (max 4194304)"),
    ("duration_s = 16", "duration_s = 3600", "longer than the 600 s simulated"),
    ("end_rpm = 1600", "end_rpm = 800", "the speed never changes"),
    ("duration_s = 16\n", "", "the speed profile lacks duration_s"),
    ("settle_revs = 100", "settle_revs = 100\ntimes_s = [0, 1]", "not both"),
    ("[operating]", "[operating]\nspeed_rpm = 1500", "operating.speed_rpm: a run-up's or coast-down's speed"),
    ("sample_rate_hz = 2560.0", "sample_rate_hz = 2560.0\nduration_s = 4", "measurement.duration_s: a transient"),
    ("sample_rate_hz = 2560.0", "sample_rate_hz = 2560.0\nspeed_fluctuation = 0.01",
     "measurement.speed_fluctuation: a transient sample's speed is its profile's"),
    ("sample_rate_hz = 2560.0", "sample_rate_hz = 200.0", "the transient simulator needs ≥ 213.333 Hz"),
    ("[measurement]", "[simulation]\ntransient_revs = 50\n[measurement]",
     "simulation.transient_revs applies to steady samples"),
])
def test_bad_transient_specs_are_refused_before_anything_is_written(tmp_path, old, new, fragment):
    from rotordiag.cli import app

    text = BASE.replace(old, new)
    assert text != BASE
    with pytest.raises(SpecError) as info:
        parse_spec(text)
    assert fragment in str(info.value)
    spec = tmp_path / "bad.toml"
    spec.write_text(text)
    out = tmp_path / "bad.h5"
    r = CliRunner().invoke(app, ["dataset", "generate", str(spec), "--out", str(out), "--workers", "0"])
    assert r.exit_code == 2 and fragment in r.output, r.output
    assert list(tmp_path.iterdir()) == [spec]  # no file, no lock, no temporary


def test_a_transient_spec_through_the_service_door_is_sized_and_refused_clearly():
    from rotordiag.service.errors import InputError
    from rotordiag.service.work import check_job_size

    check_job_size(parse_spec(BASE))                              # 3 short run-ups: within a job's bounds
    big = BASE.replace("n_samples = 3", "n_samples = 1000").replace("duration_s = 16", "duration_s = 300")
    with pytest.raises(InputError, match="points per channel"):
        check_job_size(parse_spec(big))
    from rotordiag.service.work import _validate_spec_text  # what POST /datasets runs on the body's spec

    reverses = BASE.replace("start_rpm = 800\nend_rpm = 1600\nduration_s = 16",
                            "times_s = [0, 8, 16]\nspeeds_rpm = [800, 1600, 1200]")
    with pytest.raises(InputError, match="speed profile reverses at t = 8 s"):
        _validate_spec_text(reverses)


def test_a_steady_spec_keeps_its_hash():
    """Adding [transient] changed nothing for steady specs: dataset_small.toml hashes as it did before (the value
    computed with the code before this change; a moved hash would refuse to resume every stored dataset)."""
    from rotordiag.simulator.dataset import load_spec

    r = load_spec(Path(__file__).parents[1] / "examples" / "dataset_small.toml")
    assert not r.spec.is_transient
    assert r.spec_hash == "72e266c746a5bdbddeab68b92faa6eabaa8e1f35e71e68f1187087f66671a57a"


TRAIN_RUNUP_SPEC = """\
[design]
method = "sobol"
n_samples = 2
seed = 46

[plant]
model = "train"
preset = "gen200_2pole"

[operating]
misalignment = 0.0
unbalance_phase_rad = [0.0, 3.0]
mechanism = "rigid"

[transient]
start_rpm = 1050
end_rpm = 1400
duration_s = 7
settle_revs = 60

[measurement]
probe_angles_deg = [0.0, 90.0]
sample_rate_hz = 2560.0
snr_db = 40.0
"""


@pytest.mark.slow
def test_train_runups_in_a_dataset_peak_at_the_trains_criticals(tmp_path):
    """Two run-ups of the 200 MW shaft train (``plant.model = "train"``, its G2.5 balance grade at the top speed)
    at 50 r/min/s: they read back with their keyphasor, and every journal's 1X (order-tracked from the stored
    probes) peaks within ζ·n_c of a 1X crossing of a lightly damped mode of the linearised full train (as
    tests/test_train_transient.py checks the simulator alone)."""
    from rotordiag.features import ProbeChannel, Recording
    from rotordiag.features.transient import track_orders
    from rotordiag.simulator import shaftline as sl
    from rotordiag.simulator.train.shaftline import train_from_shaftline
    from tests.test_train_transient import _lightly_damped_crossings

    spec = tmp_path / "train.toml"
    spec.write_text(TRAIN_RUNUP_SPEC)
    s = generate(spec, tmp_path / "train.h5", n_workers=0, progress=False)
    assert s.status_counts == {"ok": 2}, s
    crit = _lightly_damped_crossings(train_from_shaftline(sl.preset("gen200_2pole")), np.arange(1050.0, 1401.0, 25.0))
    assert crit
    with DatasetReader(tmp_path / "train.h5") as ds:
        assert ds.kind == "transient" and list(ds.labels()["mechanism"]) == ["aligned", "aligned"]
        assert np.all(ds.parameters("labels/unbalance_kg_m") > 0)
        for i in ds.indices:
            smp = ds.transient_sample(i)
            assert smp.n_valid_points == smp.waveforms_um.shape[1] and len(smp.channels) == 8
            rec = Recording(sample_rate_hz=smp.sample_rate_hz, keyphasor_times_s=smp.keyphasor_times_s[1:],
                            channels=[ProbeChannel(b, a, "um", smp.waveforms_um[k].astype(float))
                                      for k, (b, a) in enumerate(smp.channels)])
            peaks = track_orders(rec).peaks(1)
            assert len(peaks) >= 6, peaks                      # most of the 8 probes show a resonance peak
            for p in peaks:
                assert 1100 < p["speed_rpm"] < 1350, p
                n_c, zeta = min(crit, key=lambda c: abs(c[0] - p["speed_rpm"]))
                assert abs(p["speed_rpm"] - n_c) <= zeta * n_c, (i, p, crit)
